#!/bin/sh
# log_output.sh RSD: the daemon's log as a user reads it.
#  - on a plain stderr: a start-up line with a timestamp and the level (even with --quiet, as
#    the unit runs it), naming the driver, size, rate and LCM URL;
#  - with stderr on the journal (JOURNAL_STREAM names stderr's device and inode, as systemd sets
#    it): sd-daemon priority prefixes, no timestamp, no colour, no carriage-return status line;
#  - --log-level warning leaves the start-up line out; a bad level is a usage error (status 2);
#  - a configuration error is said even at --log-level off, and is priority 3 in the journal.
set -eu
rsd=$1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
fail() { echo "log_output: $*"; cat "$work/err"; exit 1; }

"$rsd" --frames 5 --quiet 2>"$work/err"
grep -Eq '^\[[0-9]{2}:[0-9]{2}:[0-9]{2}\.[0-9]{3}\] rsd: info: sim 640x480 mono8 at 30\.0 fps.*LCM memq://' "$work/err" ||
  fail "no timestamped start-up line"

: >"$work/err"
JOURNAL_STREAM=$(stat -c %d:%i "$work/err") "$rsd" --frames 5 2>>"$work/err"
grep -q '^<6>sim 640x480 mono8 at 30\.0 fps' "$work/err" || fail "no journald start-up line with priority <6>"
! grep -q "$(printf '\033')" "$work/err" || fail "colour codes in the journal"
! grep -q "$(printf '\r')" "$work/err" || fail "a carriage-return status line in the journal"
! grep -Eq '^\[[0-9]{2}:' "$work/err" || fail "timestamps in the journal (journald adds its own)"
grep -q '^<[0-7]>' "$work/err" || fail "no priority prefixes"
[ "$(grep -vc '^<[0-7]>' "$work/err")" -eq 0 ] || fail "journal lines without a priority prefix"

"$rsd" --frames 5 --quiet --log-level warning 2>"$work/err"
! grep -q 'info:' "$work/err" || fail "info lines at --log-level warning"

# An error that ends the run is said even at level off, and under a journal as an error (<3>).
printf 'source:\n  driver: sim\n  sim:\n    fps: -1\n' >"$work/bad.yaml"
status=0
"$rsd" --config "$work/bad.yaml" --log-level off 2>"$work/err" || status=$?
[ "$status" -eq 2 ] || fail "a bad configuration exited $status, not 2"
grep -q 'rsd: error: configuration error: .*bad.yaml.*fps' "$work/err" || fail "no configuration error at --log-level off"
: >"$work/err"
status=0
JOURNAL_STREAM=$(stat -c %d:%i "$work/err") "$rsd" --config "$work/bad.yaml" 2>>"$work/err" || status=$?
[ "$status" -eq 2 ] || fail "a bad configuration exited $status under a journal"
grep -q '^<3>configuration error: ' "$work/err" || fail "the configuration error is not priority 3 in the journal"

status=0
"$rsd" --frames 5 --log-level loud 2>"$work/err" || status=$?
[ "$status" -eq 2 ] || fail "--log-level loud exited $status, not 2"
grep -q 'expected trace, debug, info, warning, error, critical or off' "$work/err" || fail "no list of levels"
echo OK
