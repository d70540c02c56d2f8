#!/usr/bin/env python3
"""Wall and CPU time of `check scenarios/ --baseline baselines/` with logs, two checkouts interleaved.

Each checkout (a directory with scenarios/, baselines/ and a release build in
target/release/anholonomy, or --bin-a/--bin-b) runs its own suite with logs
into a fresh temporary directory (what .ci/run does, without the HTML report),
alternating A and B `--repeats` times. Prints every run and the medians.

Usage:

    python3 scripts/suite_time.py --a /path/to/main --b . [--repeats 5]

The exit status of each check is printed too (0: all thresholds met and no
regression).
"""

import argparse
import os
import resource
import statistics
import subprocess
import tempfile
import time


def run(repo, binary):
    with tempfile.TemporaryDirectory() as logs:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        p = subprocess.run(
            [binary, "check", "scenarios/", "--baseline", "baselines/", "--logs", logs, "--quiet"],
            cwd=repo,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, p.returncode


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--a", required=True, help="checkout A (e.g. the one before a change)")
    ap.add_argument("--b", required=True, help="checkout B")
    ap.add_argument("--bin-a")
    ap.add_argument("--bin-b")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    sides = {}
    for name, repo, binary in (("A", args.a, args.bin_a), ("B", args.b, args.bin_b)):
        repo = os.path.abspath(repo)
        binary = os.path.abspath(binary or os.path.join(repo, "target", "release", "anholonomy"))
        sides[name] = (repo, binary, [])
        print(f"{name}: {repo} ({binary})")
    print("load average (1, 5, 15 min): %.2f %.2f %.2f" % os.getloadavg())
    for r in range(args.repeats):
        order = ["A", "B"] if r % 2 == 0 else ["B", "A"]
        for name in order:
            repo, binary, res = sides[name]
            wall, cpu, rc = run(repo, binary)
            res.append((wall, cpu))
            print(f"  run {r + 1} {name}: wall {wall:6.2f} s  cpu {cpu:6.2f} s  exit {rc}", flush=True)
    print("load average at the end: %.2f %.2f %.2f" % os.getloadavg())
    for name, (_repo, _binary, res) in sides.items():
        walls = [w for w, _ in res]
        cpus = [c for _, c in res]
        print(f"{name}: median wall {statistics.median(walls):6.2f} s (range {min(walls):.2f}-{max(walls):.2f}), "
              f"median CPU {statistics.median(cpus):6.2f} s")


if __name__ == "__main__":
    main()
