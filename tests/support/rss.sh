# Sourced by the fault-matrix scripts: a process's resident memory, and the bound it must keep.
#   rss_kb PID             resident set size in kB (0 when the process is gone)
#   rss_bounded RSS0 RSS1  true when RSS1 <= 2 x RSS0 + 20 MB: what a leak per frame, per event
#                          or per reload would cross within the scripts' runs, while the
#                          allocator's own growth stays below it. Under AddressSanitizer 256 MB
#                          more: its quarantine keeps that much freed memory resident (a SIGHUP
#                          storm's reloads filled it: 173 -> 325 MB in one run, over the bound in
#                          another), so there the normal tree's run is the leak check.
rss_kb() { awk '/^VmRSS/ {print $2; found=1} END {if (!found) print 0}' "/proc/$1/status" 2>/dev/null || echo 0; }
rss_bounded() {
  quarantine=0
  case ${RSD_TEST_SANITIZER:-} in *address*) quarantine=262144 ;; esac
  [ "$2" -le $(($1 * 2 + 20000 + quarantine)) ]
}
