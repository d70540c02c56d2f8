#!/usr/bin/env python3
"""How far metrics moved between two baseline directories.

usage: compare_baselines.py DIR_A DIR_B

For every scenario present in both: how many metrics differ at all, the
largest relative change |a - b| / max(|a|, |b|) and the largest absolute
change (with the metric). Used to choose the default regression tolerance
(README, "Baselines"): write the two directories with
`anholonomy baseline scenarios/ --baseline DIR --no-logs --quiet` from two
builds, or with RAYON_NUM_THREADS=1 and =2.
"""
import json
import math
import pathlib
import sys


def load(d):
    out = {}
    for p in sorted(pathlib.Path(d).glob("*.json")):
        doc = json.loads(p.read_text())
        out[doc["scenario"]] = doc["metrics"]
    return out


def main():
    a, b = load(sys.argv[1]), load(sys.argv[2])
    worst_rel = 0.0
    print(f"{'scenario':<30} {'metrics':>7} {'differ':>6} {'max rel':>10} {'max abs':>10}  worst metric")
    for name in sorted(set(a) & set(b)):
        ma, mb = a[name], b[name]
        differ, rel, ab, which = 0, 0.0, 0.0, "-"
        for k in sorted(set(ma) | set(mb)):
            x, y = ma.get(k), mb.get(k)
            if x is None and y is None:
                continue
            if x is None or y is None or (isinstance(x, float) and math.isnan(x)):
                differ += x != y
                continue
            if x == y:
                continue
            differ += 1
            d = abs(x - y)
            r = d / max(abs(x), abs(y))
            if r > rel:
                rel, which = r, k
            ab = max(ab, d)
        worst_rel = max(worst_rel, rel)
        print(f"{name:<30} {len(ma):>7} {differ:>6} {rel:>10.3g} {ab:>10.3g}  {which}")
    missing = sorted(set(a) ^ set(b))
    if missing:
        print("only in one directory:", ", ".join(missing))
    print(f"largest relative change: {worst_rel:.3g}")


if __name__ == "__main__":
    main()
