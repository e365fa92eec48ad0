#!/bin/sh
# A command-line check: runs COMMAND and passes only if it exits with STATUS and its output
# (stdout and stderr together) contains every MESSAGE, as fixed text; a MESSAGE "re:R" is an
# extended regular expression some line must match, "!re:R" one no line may match.
#   expect.sh STATUS MESSAGE... -- COMMAND [ARG...]
# The output is echoed so that ctest --output-on-failure shows what the tool said.
if [ $# -lt 3 ]; then echo "usage: expect.sh STATUS MESSAGE... -- COMMAND [ARG...]" >&2; exit 2; fi
status=$1; shift
messages=""
while [ $# -gt 0 ] && [ "$1" != "--" ]; do messages="$messages$1
"; shift; done
[ "$1" = "--" ] || { echo "expect.sh: missing -- before the command" >&2; exit 2; }
shift
out=$("$@" 2>&1); rc=$?
printf '%s\n' "$out"
fail=0
if [ "$rc" -ne "$status" ]; then echo "expect.sh: exit status $rc, expected $status" >&2; fail=1; fi
printf '%s' "$messages" | while IFS= read -r m; do
  [ -z "$m" ] && continue
  case $m in
    re:*) printf '%s\n' "$out" | grep -qE -- "${m#re:}" || { echo "expect.sh: no line matches: ${m#re:}" >&2; exit 1; } ;;
    !re:*) ! printf '%s\n' "$out" | grep -qE -- "${m#!re:}" || { echo "expect.sh: a line matches: ${m#!re:}" >&2; exit 1; } ;;
    *) printf '%s\n' "$out" | grep -qF -- "$m" || { echo "expect.sh: output lacks: $m" >&2; exit 1; } ;;
  esac
done || fail=1
exit $fail
