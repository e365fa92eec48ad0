#!/usr/bin/env python3
"""Runs rsd with NOTIFY_SOCKET pointing at a test socket and checks that READY=1, STATUS=,
WATCHDOG=1 and STOPPING=1 arrive, that SIGHUP reloads (RELOADING=1 with MONOTONIC_USEC, then
READY again), and that SIGTERM stops it within 500 ms."""
import os, signal, socket, subprocess, sys, tempfile, time

rsd = sys.argv[1]
with tempfile.TemporaryDirectory() as d:
    path = os.path.join(d, "notify.sock")
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(path)
    sock.settimeout(0.2)
    env = dict(os.environ, NOTIFY_SOCKET=path, WATCHDOG_USEC="400000", LCM_DEFAULT_URL="memq://")
    proc = subprocess.Popen([rsd, "--quiet"], env=env)
    got, deadline = [], time.time() + 20
    while time.time() < deadline and not ("READY=1" in got and "WATCHDOG=1" in got and any(m.startswith("STATUS=") for m in got)):
        try:
            got += sock.recv(4096).decode().split("\n")
        except socket.timeout:
            pass
    # SIGHUP reloads: the service says RELOADING, applies what changed, and says READY again.
    ready_before = got.count("READY=1")
    proc.send_signal(signal.SIGHUP)
    deadline = time.time() + 20
    while time.time() < deadline and got.count("READY=1") == ready_before:
        try:
            got += sock.recv(4096).decode().split("\n")
        except socket.timeout:
            pass
    reloaded = got.count("READY=1") > ready_before and "RELOADING=1" in got and any(m.startswith("MONOTONIC_USEC=") for m in got)
    print("reloaded on SIGHUP:", reloaded)
    t0 = time.time()
    proc.send_signal(signal.SIGTERM)
    rc = proc.wait(timeout=10)
    stop_s = time.time() - t0
    while True:
        try:
            got += sock.recv(4096).decode().split("\n")
        except socket.timeout:
            break
    print("received:", sorted(set(m.split("=")[0] + "=" for m in got if m)))
    ok = "READY=1" in got and "WATCHDOG=1" in got and "STOPPING=1" in got and any(m.startswith("STATUS=") for m in got)
    print(f"exit status {rc}, stopped {stop_s * 1000:.0f} ms after SIGTERM")
    if not ok or not reloaded or rc != 0 or stop_s > 0.5:
        print("FAILED")
        sys.exit(1)
    print("OK")
