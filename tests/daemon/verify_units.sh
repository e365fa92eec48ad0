#!/bin/sh
# verify_units.sh RSD UNITS_DIR INSTALLED_RSD MANPATH: systemd-analyze verify on rsd's unit files
# as the build configured them (UNITS_DIR), with ExecStart's installed rsd pointed at the built
# one and the built man pages (MANPATH) for the units' Documentation=man:rsd(1).
# It exits 0 even on bad values, so any output at all is a failure.
set -eu
rsd_bin=$1; units_dir=$2; installed=$3; export MANPATH=$4; work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
sed "s|$installed |$rsd_bin |" "$units_dir/rsd.service" > "$work/rsd.service"
sed "s|$installed |$rsd_bin |" "$units_dir/rsd@.service" > "$work/rsd@cam0.service"
cd "$work"
out=$(systemd-analyze verify ./rsd.service ./rsd@cam0.service 2>&1 || true)
if [ -n "$out" ]; then echo "systemd-analyze verify complained:"; echo "$out"; exit 1; fi
echo "units verified: rsd.service rsd@.service"
