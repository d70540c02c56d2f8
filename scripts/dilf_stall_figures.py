#!/usr/bin/env python3
"""Figures of the seed-004 pair stalls from `examples/dilf_trace` CSVs.

    python3 scripts/dilf_stall_figures.py TRACE.csv TITLE OUT.png

Four panels over the ideal run: ln V and its factors; each robot's distance
and heading error; robot 1's gradient of ln V along and across its
heading and d/dtheta, with the factors that dominate them; the hold guard's input scale
and the rod's wrench ratio (1 = the bound).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FACTORS = ["dipole", "goal", "robots", "beam_parts", "admissible"]


def main():
    path, title, out = sys.argv[1:4]
    rows = list(csv.DictReader(open(path)))
    t = [float(r["t"]) for r in rows]

    def col(name):
        return [float(r[name]) if r[name] not in ("", "NaN") else float("nan") for r in rows]

    fig, ax = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    ax[0].plot(t, col("ln_v"), "k", lw=2, label="ln V")
    for f in FACTORS:
        ax[0].plot(t, col(f), lw=1, label=f)
    ax[0].set_ylabel("ln V and its factors")
    ax[0].legend(fontsize=7, ncol=3)
    for r in (1, 2):
        ax[1].plot(t, col(f"dist_{r}"), label=f"robot {r} distance, m")
    a2 = ax[1].twinx()
    for r, s in ((1, "--"), (2, ":")):
        a2.plot(t, col(f"dth_{r}"), s, label=f"robot {r} heading error, deg")
    a2.set_ylabel("deg")
    ax[1].set_ylabel("m")
    ax[1].legend(fontsize=7, loc="upper left")
    a2.legend(fontsize=7, loc="upper right")
    ax[2].plot(t, col("along_1"), "k", lw=2, label="d lnV / along heading (total)")
    ax[2].plot(t, col("across_1"), "b", lw=2, label="across heading (total)")
    ax[2].plot(t, col("dtheta_1"), "r", lw=2, label="d lnV / d theta (total)")
    for f in ("dipole", "goal", "admissible"):
        ax[2].plot(t, col(f"{f}.along_1"), lw=0.8, label=f"{f}: along")
        ax[2].plot(t, col(f"{f}.dtheta_1"), "--", lw=0.8, label=f"{f}: d/dtheta")
    ax[2].set_ylabel("robot 1 gradient")
    ax[2].set_ylim(-40, 40)
    ax[2].legend(fontsize=7, ncol=2)
    ax[3].plot(t, col("guard_scale"), label="hold guard: applied / Eq. 18 input")
    ax[3].plot(t, col("wrench_ratio"), label="rod wrench / bound")
    ax[3].plot(t, [abs(x) for x in col("v_1")], lw=0.6, label="|v_1|, m/s")
    ax[3].set_ylabel("ratio")
    ax[3].set_xlabel("t, s (ideal run)")
    ax[3].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main()
