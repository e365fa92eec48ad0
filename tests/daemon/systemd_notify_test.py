#!/usr/bin/env python3
"""Runs rsd with NOTIFY_SOCKET pointing at a test socket and checks that READY=1, STATUS=,
WATCHDOG=1 and STOPPING=1 arrive; that SIGHUP reloads (RELOADING=1 with MONOTONIC_USEC, then
READY again) without ever saying STOPPING=1 (under systemd that starts the stop timeout), both
when nothing changed and when the configuration file changed (the pipeline restarts); and that
SIGTERM stops it within 500 ms."""
import os, signal, socket, subprocess, sys, tempfile, time

rsd = sys.argv[1]


def receive(sock, got, until, timeout_s=20):
    deadline = time.time() + timeout_s
    while time.time() < deadline and not until():
        try:
            got += sock.recv(4096).decode().split("\n")
        except socket.timeout:
            pass


def reload(proc, sock, got):
    """SIGHUP; returns whether RELOADING=1, MONOTONIC_USEC= and READY=1 came, and no STOPPING=1."""
    start, ready_before = len(got), got.count("READY=1")
    proc.send_signal(signal.SIGHUP)
    receive(sock, got, lambda: got.count("READY=1") > ready_before)
    during = got[start:]
    print("  during the reload:", [m for m in during if m and not m.startswith("WATCHDOG") and not m.startswith("STATUS")])
    return ("RELOADING=1" in during and any(m.startswith("MONOTONIC_USEC=") for m in during)
            and "READY=1" in during and "STOPPING=1" not in during)


with tempfile.TemporaryDirectory() as d:
    path = os.path.join(d, "notify.sock")
    config = os.path.join(d, "rsd.yaml")
    with open(config, "w") as f:
        f.write(subprocess.run([rsd, "--print-default-config"], capture_output=True, text=True, check=True).stdout)
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(path)
    sock.settimeout(0.2)
    env = dict(os.environ, NOTIFY_SOCKET=path, WATCHDOG_USEC="400000", LCM_DEFAULT_URL="memq://")
    proc = subprocess.Popen([rsd, "--quiet", "--config", config], env=env)
    got = []
    receive(sock, got, lambda: "READY=1" in got and "WATCHDOG=1" in got and any(m.startswith("STATUS=") for m in got))
    same = reload(proc, sock, got)
    print("reloaded on SIGHUP, nothing changed:", same)
    with open(config, "a") as f:
        f.write("# changed\n")
    changed = reload(proc, sock, got)
    print("reloaded on SIGHUP, the configuration changed:", changed)
    t0 = time.time()
    proc.send_signal(signal.SIGTERM)
    rc = proc.wait(timeout=10)
    stop_s = time.time() - t0
    receive(sock, got, lambda: False, timeout_s=0.5)
    print("received:", sorted(set(m.split("=")[0] + "=" for m in got if m)))
    ok = "READY=1" in got and "WATCHDOG=1" in got and "STOPPING=1" in got and any(m.startswith("STATUS=") for m in got)
    print(f"exit status {rc}, stopped {stop_s * 1000:.0f} ms after SIGTERM")
    # A sanitizer tree runs slower (tests/sanitizers/run.sh sets the factor).
    stop_limit_s = 0.5 * float(os.environ.get("RSD_TEST_TIME_SCALE", "1"))
    if not ok or not same or not changed or rc != 0 or stop_s > stop_limit_s:
        print("FAILED")
        sys.exit(1)
    print("OK")
