#!/usr/bin/env python3
"""Sweep throughput, batched against unbatched: variants per CPU-second.

Runs one sweep scenario (default `scenarios/rover_sweep.toml`) with the
harness's default batched stepping and with `--no-batch`, alternating,
`--repeats` times each, without logs, and reports for each mode the median
CPU time (user + system of the child process, both cores counted), the
median wall time, the variants per CPU-second and the ratio batched /
unbatched. It also checks that both modes report the same sweep table (the
batched variants' metrics equal the unbatched ones bit for bit; the test
`batched_sweep_equals_unbatched` checks every metric).

Usage (from the repository root, after `cargo build --release`):

    python3 scripts/sweep_throughput.py [--repeats 5] [--scenario FILE] [--threads N]

CPU time is what a shared or batch-scheduled machine charges; on an idle
machine with two cores the wall time is about half of it.
"""

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(binary, scenario, batched, threads):
    env = dict(os.environ)
    if threads:
        env["RAYON_NUM_THREADS"] = str(threads)
    cmd = [binary, "run", scenario, "--no-logs", "--quiet"]
    if not batched:
        cmd.append("--no-batch")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True, env=env).stdout
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    # The sweep table without its wall time ("(100 variants, 12.3 s)").
    table = [l for l in out.splitlines() if "variants" not in l and "wall" not in l]
    table = [l for l in table if not l.startswith("rover") and not l.startswith("scenario")]
    return cpu, wall, "\n".join(table)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "anholonomy"))
    ap.add_argument("--scenario", default=os.path.join(ROOT, "scenarios", "rover_sweep.toml"))
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=0, help="RAYON_NUM_THREADS (default: all cores)")
    args = ap.parse_args()
    if not os.path.exists(args.bin):
        sys.exit(f"{args.bin} not found: run `cargo build --release` first (or pass --bin)")
    with open(args.scenario, "rb") as f:
        count = tomllib.load(f)["sweep"]["count"]
    print(f"{os.path.relpath(args.scenario, ROOT)}: {count} variants, {args.repeats} alternating runs per mode")
    print("load average (1, 5, 15 min): %.2f %.2f %.2f" % os.getloadavg())
    res = {True: [], False: []}
    tables = set()
    for r in range(args.repeats):
        # Alternate which mode goes first, so a load trend hits both alike.
        for batched in ([True, False] if r % 2 == 0 else [False, True]):
            cpu, wall, table = run(args.bin, args.scenario, batched, args.threads)
            res[batched].append((cpu, wall))
            tables.add(table)
            print(f"  run {r + 1} {'batched  ' if batched else 'unbatched'} cpu {cpu:7.2f} s  wall {wall:7.2f} s",
                  flush=True)
    print("load average at the end: %.2f %.2f %.2f" % os.getloadavg())
    if len(tables) != 1:
        print("WARNING: the modes printed different sweep statistics")
    med = {}
    for batched in (False, True):
        cpu = statistics.median(c for c, _ in res[batched])
        wall = statistics.median(w for _, w in res[batched])
        med[batched] = cpu
        name = "batched" if batched else "unbatched"
        print(f"{name:<10} median CPU {cpu:7.2f} s (range {min(c for c, _ in res[batched]):.2f}-"
              f"{max(c for c, _ in res[batched]):.2f})  wall {wall:7.2f} s  "
              f"{count / cpu:6.2f} variants per CPU-second")
    ratios = [u[0] / b[0] for b, u in zip(res[True], res[False])]
    print(f"batched / unbatched throughput: {med[False] / med[True]:.3f} "
          f"(per pair: {', '.join(f'{x:.3f}' for x in ratios)})")


if __name__ == "__main__":
    main()
