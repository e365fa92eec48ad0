#!/bin/sh
# systemd-analyze verify on rsd's unit files (with ExecStart pointed at the built binary).
# It exits 0 even on bad values, so any output at all is a failure.
set -eu
rsd_bin=$1; units_dir=$2; work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
sed "s|/usr/local/bin/rsd|$rsd_bin|" "$units_dir/rsd.service" > "$work/rsd.service"
sed "s|/usr/local/bin/rsd|$rsd_bin|" "$units_dir/rsd@.service" > "$work/rsd@cam0.service"
cd "$work"
out=$(systemd-analyze verify ./rsd.service ./rsd@cam0.service 2>&1 || true)
if [ -n "$out" ]; then echo "systemd-analyze verify complained:"; echo "$out"; exit 1; fi
echo "units verified: rsd.service rsd@.service"
