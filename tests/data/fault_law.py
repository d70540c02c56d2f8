#!/usr/bin/env python3
"""External laws for tests/external_law.rs: a proportional heading law for
the rolling disk (inputs theta_rate, alpha_rate) that misbehaves on purpose.

Usage: fault_law.py MODE DIR. The process appends its pid to DIR/pids and
every line it receives to DIR/received-<pid>. MODE:
  good          answer every sample
  crash         raise at sample 10 (traceback on stderr, exit status 1)
  crash_second  like good in the first process started in DIR, crash in the next
  sleep         sleep far past the timeout at sample 3
  short         answer u with one number (the disk has two inputs)
  long          answer u with three numbers
  garbage       print a line that is not JSON at sample 2
  exit_quiet    exit with status 0 at sample 5 without a word
  done          report done at t >= 0.5 s
  noread        answer over and over without reading its input
  noread_paced  answer once per request without reading it (it watches how
                many bytes wait on its stdin, shrunk to 4 KB): the pipe fills
  twice         answer every request twice (one write of two lines)
  twice_late    answer every request twice (two writes, the second 20 ms later)
  fork_good     start `sleep 200` (holding stdout and stderr), then like good
  fork_exit     start `sleep 200`, then exit with status 1 at once
  fork_sleep    start `sleep 200`, then like sleep
  fork_crash    start `sleep 200`, then like crash
  ignore_term   ignore SIGTERM, then like sleep (only SIGKILL ends it)
A started `sleep` appends its pid to DIR/grandchildren.
"""

import json
import os
import signal
import subprocess
import sys
import time

mode, out_dir = sys.argv[1], sys.argv[2]
pid = os.getpid()
with open(os.path.join(out_dir, "pids"), "a") as f:
    f.write(f"{pid}\n")
    f.flush()
    starts = sum(1 for _ in open(os.path.join(out_dir, "pids")))
received = open(os.path.join(out_dir, f"received-{pid}"), "w")
print(f"fault_law {mode} started (pid {pid})", file=sys.stderr, flush=True)

if mode.startswith("fork_"):
    # Inherits stdin, stdout and stderr: the pipes stay open after this exits.
    child = subprocess.Popen(["sleep", "200"])
    with open(os.path.join(out_dir, "grandchildren"), "a") as f:
        f.write(f"{child.pid}\n")
    mode = mode[len("fork_"):]
if mode == "exit":
    sys.exit(1)
if mode == "ignore_term":
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    mode = "sleep"
if mode == "noread_paced":
    import array
    import fcntl
    import termios

    try:
        fcntl.fcntl(0, 1031, 4096)  # F_SETPIPE_SZ: fill up after ~50 requests
    except OSError:
        pass
    seen = 0
    while True:
        waiting = array.array("i", [0])
        fcntl.ioctl(0, termios.FIONREAD, waiting)
        if waiting[0] > seen:
            seen = waiting[0]
            sys.stdout.write(json.dumps({"u": [0.1, 0.1]}) + "\n")
            sys.stdout.flush()
        else:
            time.sleep(0.0005)
if mode == "noread":
    while True:
        sys.stdout.write(json.dumps({"u": [0.1, 0.1]}) + "\n")
        sys.stdout.flush()

k = 0
while True:
    line = sys.stdin.readline()
    if not line:
        break
    received.write(line)
    received.flush()
    msg = json.loads(line)
    t, q = msg["t"], msg["q"]
    u = [2.0, -2.0 * (q[3] - 1.5)]
    answer = {"u": u, "label": "steer" if t < 0.3 else "hold", "done": False}
    if (mode == "crash" or (mode == "crash_second" and starts >= 2)) and k == 10:
        raise RuntimeError(f"the law gave up at sample {k}")
    if mode == "sleep" and k == 3:
        time.sleep(60)
    if mode == "short":
        answer["u"] = u[:1]
    if mode == "long":
        answer["u"] = u + [0.0]
    if mode == "garbage" and k == 2:
        sys.stdout.write("hello, this is not JSON\n")
        sys.stdout.flush()
        continue
    if mode == "exit_quiet" and k == 5:
        sys.exit(0)
    if mode == "done" and t >= 0.5:
        answer["done"] = True
    line = json.dumps(answer) + "\n"
    if mode == "twice":
        line += line
    sys.stdout.write(line)
    sys.stdout.flush()
    if mode == "twice_late":
        time.sleep(0.02)
        sys.stdout.write(line)
        sys.stdout.flush()
    k += 1
