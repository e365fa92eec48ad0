# Sourced by the fault-matrix scripts: a process's resident memory, and the bound it must keep.
#   rss_kb PID             resident set size in kB (0 when the process is gone)
#   rss_bounded RSS0 RSS1  true when RSS1 <= 2 x RSS0 + 20 MB: what a leak per frame, per event
#                          or per reload would cross within the scripts' runs, while the
#                          allocator's own growth (and a sanitizer's quarantine) stays below it
rss_kb() { awk '/^VmRSS/ {print $2; found=1} END {if (!found) print 0}' "/proc/$1/status" 2>/dev/null || echo 0; }
rss_bounded() { [ "$2" -le $(($1 * 2 + 20000)) ]; }
