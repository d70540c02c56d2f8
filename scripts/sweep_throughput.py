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

    python3 scripts/sweep_throughput.py [--repeats 5] [--scenario FILE] [--threads N] [--sizes 2 4]

`--sizes` adds batched runs with at most that many variants per shared world
(`ANHOLONOMY_BATCH_MAX`), to see whether the group size matters.

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


def run(binary, scenario, mode, threads):
    """One run; `mode` is 0 for --no-batch, else the most variants per world."""
    env = dict(os.environ)
    if threads:
        env["RAYON_NUM_THREADS"] = str(threads)
    cmd = [binary, "run", scenario, "--no-logs", "--quiet"]
    if mode == 0:
        cmd.append("--no-batch")
    elif mode != "default":
        env["ANHOLONOMY_BATCH_MAX"] = str(mode)
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


def name(mode):
    return "unbatched" if mode == 0 else "batched" if mode == "default" else f"batch<={mode}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "anholonomy"))
    ap.add_argument("--scenario", default=os.path.join(ROOT, "scenarios", "rover_sweep.toml"))
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=0, help="RAYON_NUM_THREADS (default: all cores)")
    ap.add_argument("--sizes", type=int, nargs="*", default=[],
                    help="also run batched with at most these many variants per world "
                         "(ANHOLONOMY_BATCH_MAX)")
    args = ap.parse_args()
    if not os.path.exists(args.bin):
        sys.exit(f"{args.bin} not found: run `cargo build --release` first (or pass --bin)")
    with open(args.scenario, "rb") as f:
        count = tomllib.load(f)["sweep"]["count"]
    modes = ["default", 0] + args.sizes
    print(f"{os.path.relpath(args.scenario, ROOT)}: {count} variants, {args.repeats} rounds of "
          f"{', '.join(name(m) for m in modes)}")
    print("load average (1, 5, 15 min): %.2f %.2f %.2f" % os.getloadavg())
    res = {m: [] for m in modes}
    tables = set()
    for r in range(args.repeats):
        # Rotate which mode goes first, so a load trend hits every mode alike.
        order = modes[r % len(modes):] + modes[:r % len(modes)]
        for mode in order:
            cpu, wall, table = run(args.bin, args.scenario, mode, args.threads)
            res[mode].append((cpu, wall))
            tables.add(table)
            print(f"  round {r + 1} {name(mode):<10} cpu {cpu:7.2f} s  wall {wall:7.2f} s", flush=True)
    print("load average at the end: %.2f %.2f %.2f" % os.getloadavg())
    if len(tables) != 1:
        print("WARNING: the modes printed different sweep statistics")
    base = statistics.median(c for c, _ in res[0])
    for mode in modes:
        cpus = [c for c, _ in res[mode]]
        cpu = statistics.median(cpus)
        wall = statistics.median(w for _, w in res[mode])
        # Per round: the unbatched run of the same round over this mode's.
        rounds = [u[0] / b[0] for b, u in zip(res[mode], res[0])]
        print(f"{name(mode):<10} median CPU {cpu:7.2f} s (range {min(cpus):.2f}-{max(cpus):.2f})  "
              f"wall {wall:7.2f} s  {count / cpu:6.2f} variants per CPU-second  "
              f"x{base / cpu:.3f} (per round: {', '.join(f'{x:.3f}' for x in rounds)}, "
              f"median {statistics.median(rounds):.3f})")


if __name__ == "__main__":
    main()
