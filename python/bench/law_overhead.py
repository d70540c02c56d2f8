"""Per-sample overhead of a trivial Python feedback law (a timing script).

The law ``lambda t, q: (0.0, 0.0)`` runs on ``disk_paper`` sampled at every
step (``period = sim.dt``) for ``--horizon`` seconds, ideal and physics
runs. Two measures, each the median of ``--repeats`` runs:

* in the harness: law calls / wall time of those calls (attaching to the
  interpreter, the fresh numpy array for q, the call, reading u back), as
  the package times them (``Result.timings["law"]``);
* end to end: (run time with the law sampled every step − run time with
  the law sampled once) / (the difference in calls), runs interleaved.

For reference it also times the bare Python call ``law(t, np.array(q))``
in a Python loop. Usage: python bench/law_overhead.py [--horizon 20]
[--repeats 5]. The machine may be shared: quote medians with the load.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

import anholonomy

REPO = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--horizon", type=float, default=20.0)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--scenario", default=str(REPO / "scenarios" / "disk_paper.toml"))
    args = ap.parse_args()

    s = anholonomy.load(args.scenario)
    law = lambda t, q: (0.0, 0.0)  # noqa: E731
    every, once = [], []
    in_harness = []
    calls_every = calls_once = 0
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        r = anholonomy.run(s, law=law, period=s.dt, horizon=args.horizon)
        every.append(time.perf_counter() - t0)
        calls_every = r.law_calls
        in_harness.append(r.law_calls / r.timings["law"])
        t0 = time.perf_counter()
        r1 = anholonomy.run(s, law=law, period=args.horizon, horizon=args.horizon)
        once.append(time.perf_counter() - t0)
        calls_once = r1.law_calls

    q = s.start.copy()
    n = 200_000
    t0 = time.perf_counter()
    for k in range(n):
        law(k * 1e-3, np.array(q))
    bare = n / (time.perf_counter() - t0)

    med_every, med_once = statistics.median(every), statistics.median(once)
    per_call = (med_every - med_once) / (calls_every - calls_once)
    print(f"scenario {s.name}, horizon {args.horizon} s at dt {s.dt} s, {args.repeats} repeats, load {os.getloadavg()[0]:.2f}")
    print(f"law calls per run: {calls_every} (every step) vs {calls_once} (once)")
    print(f"in the harness: median {statistics.median(in_harness):,.0f} calls/s "
          f"(min {min(in_harness):,.0f}, max {max(in_harness):,.0f})")
    print(f"end to end: run {med_every:.3f} s vs {med_once:.3f} s -> {per_call * 1e6:.2f} us per call, "
          f"{1 / per_call:,.0f} calls/s")
    print(f"bare Python loop law(t, np.array(q)): {bare:,.0f} calls/s")


if __name__ == "__main__":
    main()
