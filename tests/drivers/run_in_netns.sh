#!/bin/sh
# Runs a command in a private network namespace whose only interface is loopback, up.
# The GigE Vision tests run their fake camera on 127.0.0.1 there: nothing they or Aravis send
# can leave the namespace, and no other process's camera on the host's 127.0.0.1 answers.
# Usage: run_in_netns.sh COMMAND [ARG...]
set -eu

if [ $# -lt 1 ]; then
  echo "usage: run_in_netns.sh COMMAND [ARG...]" >&2
  exit 2
fi
for tool in unshare ip; do
  if ! command -v "$tool" >/dev/null 2>&1 && [ ! -x "/usr/sbin/$tool" ] && [ ! -x "/sbin/$tool" ]; then
    echo "run_in_netns: '$tool' not found (Debian packages util-linux, iproute2)" >&2
    exit 1
  fi
done
PATH="$PATH:/usr/sbin:/sbin"

# As root a plain network namespace; otherwise one inside a user namespace, where we are root.
if unshare -n true 2>/dev/null; then
  flags=-n
elif unshare -r -n true 2>/dev/null; then
  flags="-r -n"
else
  echo "run_in_netns: cannot make a network namespace: unshare -n needs root or unprivileged user namespaces" >&2
  exit 1
fi

# shellcheck disable=SC2086  # $flags is one or two options
exec unshare $flags sh -c 'ip link set lo up && exec "$@"' run_in_netns "$@"
