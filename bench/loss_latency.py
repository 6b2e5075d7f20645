#!/usr/bin/env python3
"""Measures how fast each side notices the other is gone, on real processes.

  vehicle killed (SIGKILL)      -> haptel reports "vehicle lost" and exits
  vehicle frozen (SIGSTOP)      -> haptel reports "vehicle lost" (state timeout,
                                   the remote-vehicle case: no process to watch)
  mediator frozen (SIGSTOP)     -> the vehicle's watchdog stops the motors
  mediator killed (SIGKILL)     -> the vehicle stops its motors and exits

Usage: bench/loss_latency.py [--runs N] [--json]   (from the repository root,
after a build). Prints a table, writes build/bench/loss_latency.csv.
"""
import argparse, csv, json, os, re, signal, subprocess, sys, threading, time

BIN = os.path.join("build", "bin")


def start(domain):
    p = subprocess.Popen([os.path.join(BIN, "haptel"), "run", "--domain", str(domain),
                          "--database", "build/bench/loss.db"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1)
    lines = []  # (time, stream, text)
    def pump(stream, name):
        for line in stream:
            lines.append((time.monotonic(), name, line.rstrip()))
    for s, n in ((p.stdout, "out"), (p.stderr, "err")):
        threading.Thread(target=pump, args=(s, n), daemon=True).start()
    return p, lines


def wait_line(lines, pattern, timeout, after=0.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        for t, _, text in list(lines):
            if t >= after and re.search(pattern, text):
                return t, text
        time.sleep(0.002)
    return None, None


def one(case, domain):
    p, lines = start(domain)
    _, text = wait_line(lines, r"started, pid (\d+)", 30)
    vehicle = int(re.search(r"pid (\d+)", text).group(1))
    wait_line(lines, r" lap ", 60)  # lap under way
    t0 = time.monotonic()
    if case == "vehicle killed":
        os.kill(vehicle, signal.SIGKILL)
        t1, _ = wait_line(lines, r"error: vehicle .* lost", 10, t0)
    elif case == "vehicle frozen":
        os.kill(vehicle, signal.SIGSTOP)
        t1, _ = wait_line(lines, r"error: vehicle .* lost", 10, t0)
        try:
            os.kill(vehicle, signal.SIGCONT)
        except ProcessLookupError:
            pass
    elif case == "mediator frozen":
        os.kill(p.pid, signal.SIGSTOP)
        t1, _ = wait_line(lines, r"watchdog: .*motors stopped", 10, t0)
        os.kill(p.pid, signal.SIGCONT)
    else:  # mediator killed
        os.kill(p.pid, signal.SIGKILL)
        t1, _ = wait_line(lines, r"stopped: motors off", 10, t0)
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
    try:
        p.wait(20)
    except subprocess.TimeoutExpired:
        p.kill()
    try:
        os.kill(vehicle, signal.SIGKILL)
    except ProcessLookupError:
        pass
    return None if t1 is None else (t1 - t0) * 1e3


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    os.makedirs("build/bench", exist_ok=True)
    cases = ["vehicle killed", "vehicle frozen", "mediator frozen", "mediator killed"]
    # The vehicle's motors stop within 250 ms of the last command (its
    # watchdog is 0.2 s, checked at the control loop's 200 Hz).
    limits = {"vehicle killed": 1000, "vehicle frozen": 1000, "mediator frozen": 250,
              "mediator killed": 250}
    rows = []
    for i, case in enumerate(cases):
        ms = [one(case, 150 + i * 10 + r) for r in range(a.runs)]
        ok = [m for m in ms if m is not None]
        rows.append({"case": case, "runs": a.runs, "detected": len(ok),
                     "ms_min": round(min(ok), 1) if ok else None,
                     "ms_max": round(max(ok), 1) if ok else None,
                     "budget_ms": limits[case]})
    print(f"{'case':18} {'detected':>9} {'min ms':>8} {'max ms':>8} {'budget ms':>10}")
    for r in rows:
        print(f"{r['case']:18} {r['detected']:>4}/{r['runs']:<4} {r['ms_min']!s:>8} {r['ms_max']!s:>8} {r['budget_ms']:>10}")
    with open("build/bench/loss_latency.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    if a.json:
        print(json.dumps({"cases": rows}))


if __name__ == "__main__":
    sys.exit(main())
