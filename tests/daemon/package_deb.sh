#!/bin/sh
# package_deb.sh BUILD_DIR: builds the Debian package with CPack, unpacks it into a temporary
# root (dpkg-deb -x) and checks it as an installation: the file list (programs, units, the
# conffile, man pages, the LCM type jar, rsd-spy, docs; no test binaries), the conffile mark,
# the installed programs' --version, the installed configuration through the installed rsd's
# --check-config, a video written through the installed video module, and systemd-analyze
# verify of the installed units against that root (it exits 0 even on bad values, so any output
# at all is a failure), and their exposure in
# systemd-analyze security --offline=true: at most 2.0 (--threshold=20) for each.
set -eu
build=$(cd "$1" && pwd); work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
fail() { echo "package: $*"; exit 1; }
(cd "$build" && cpack -G DEB -B "$work/out" >"$work/cpack.log" 2>&1) || { cat "$work/cpack.log"; fail "cpack failed"; }
deb=$(ls "$work"/out/rsd_*.deb 2>/dev/null | head -n 1)
[ -n "$deb" ] || fail "no rsd_*.deb in $work/out"
echo "built $(basename "$deb")"
dpkg-deb -c "$deb" | awk '{print $NF}' | sed 's|^\./|/|' > "$work/list"
for f in /usr/bin/rsd /usr/bin/rsd-extract /usr/bin/rsd-diagnose /usr/bin/rsd-diagnose-suite /usr/bin/rsd-sim \
         /usr/bin/rsd-calib /usr/bin/rsd-replay /usr/bin/rsd-spy /etc/rsd/rsd.yaml \
         /usr/lib/systemd/system/rsd.service /usr/lib/systemd/system/rsd@.service \
         /usr/share/man/man1/rsd.1.gz /usr/share/man/man1/rsd-diagnose.1.gz /usr/share/man/man1/rsd-extract.1.gz \
         /usr/share/java/rsd_lcmtypes.jar /usr/share/doc/rsd/deploy.md /usr/share/doc/rsd/README.md; do
  grep -qx "$f" "$work/list" || fail "missing $f"
done
if grep -E '/test_|/tests/|bench_' "$work/list"; then fail "test or benchmark files in the package"; fi
dpkg-deb -f "$deb" Depends | grep -q 'libc6' || fail "Depends lacks the shared libraries (dpkg-shlibdeps)"
dpkg-deb --ctrl-tarfile "$deb" | tar -xO ./conffiles | grep -qx /etc/rsd/rsd.yaml || fail "/etc/rsd/rsd.yaml is not a conffile"
root="$work/root"
dpkg-deb -x "$deb" "$root"
"$root/usr/bin/rsd" --version | grep -q '^rsd [0-9]' || fail "rsd --version"
"$root/usr/bin/rsd-diagnose" --version | grep -q '^rsd-diagnose [0-9]' || fail "rsd-diagnose --version"
"$root/usr/bin/rsd-spy" --version | grep -q '^rsd-spy [0-9]' || fail "rsd-spy --version"
"$root/usr/bin/rsd" --check-config --config "$root/etc/rsd/rsd.yaml" || fail "the installed rsd.yaml does not check"
# The video module is in the library folder, and the installed programs find it there (from
# their own folder, not the build tree's): the installed rsd replays the reference log into a video.
grep -Eq '^/usr/lib/([^/]+/)?rsd/rsd_video_opencv\.so$' "$work/list" || fail "missing the video module rsd_video_opencv.so"
"$root/usr/bin/rsd" --replay "$(dirname "$0")/../data/reference-sim-96x72.lcmlog" --speed fast \
  --output-video "$work/out.avi" >"$work/video.log" 2>&1 || { cat "$work/video.log"; fail "the installed rsd wrote no video"; }
[ -s "$work/out.avi" ] || fail "the installed rsd wrote an empty video"
grep -q "^ExecStart=/usr/bin/rsd --config /etc/rsd/rsd.yaml" "$root/usr/lib/systemd/system/rsd.service" ||
  fail "rsd.service does not run the installed rsd on the installed configuration"
# Against the root, systemd-analyze finds everything there: give it what a Debian 12 system has
# beneath the package (systemd's targets, /bin -> usr/bin with kill for ExecReload) and the
# package's own man pages for the units' Documentation=man:rsd(1).
cp -a /usr/lib/systemd/system/*.target "$root/usr/lib/systemd/system/"
mkdir -p "$root/usr/bin" && cp /usr/bin/kill "$root/usr/bin/kill" && ln -s usr/bin "$root/bin"
verify() {
  out=$(MANPATH="$root/usr/share/man" systemd-analyze verify --root="$root" "$@" 2>&1 || true)
  [ -z "$out" ] || { echo "$out"; fail "systemd-analyze verify complained about $*"; }
}
verify /usr/lib/systemd/system/rsd.service
cp "$root/usr/lib/systemd/system/rsd@.service" "$root/usr/lib/systemd/system/rsd@cam0.service"
verify /usr/lib/systemd/system/rsd@cam0.service
for unit in rsd.service rsd@cam0.service; do
  report=$(systemd-analyze security --offline=true --threshold=20 --root="$root" "/usr/lib/systemd/system/$unit" 2>&1) ||
    { echo "$report" | grep -E '✗|Overall'; fail "$unit is exposed above 2.0"; }
  echo "$report" | grep 'Overall exposure'
done
echo "package verified: $(wc -l < "$work/list") paths"
