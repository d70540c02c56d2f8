"""Goal error against ground friction: one scenario, varied in a loop.

Runs scenarios/disk_paper.toml with `sim.friction` from 0.02 to 1.0, plots
the simulated goal error (and the worst tracking error) against friction,
and saves the figure. Usage, from the repository:

    python examples/python/friction_sweep.py [--out friction_sweep.png] [--points 12]

Needs the package (`pip install ./python`) and matplotlib.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt
import numpy as np

import anholonomy

REPO = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default=REPO / "scenarios" / "disk_paper.toml")
    ap.add_argument("--out", default="friction_sweep.png")
    ap.add_argument("--points", type=int, default=12)
    args = ap.parse_args()

    base = anholonomy.load(args.scenario)
    frictions = np.geomspace(0.02, 1.0, args.points)
    goal_error, tracking_max, passed = [], [], []
    for mu in frictions:
        r = anholonomy.run(base.replace({"sim.friction": float(mu)}))
        goal_error.append(r.metrics["sim_goal_position"])
        tracking_max.append(r.metrics["tracking_position_max"])
        passed.append(r.passed)
        print(f"friction {mu:6.3f}: goal error {goal_error[-1]:.4g} m, "
              f"tracking max {tracking_max[-1]:.4g} m, {'PASS' if r.passed else 'FAIL'}")

    fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
    ax.loglog(frictions, goal_error, "o-", label="goal error (sim)")
    ax.loglog(frictions, tracking_max, "s--", label="tracking error, max")
    gate = base.to_dict()["thresholds"].get("sim_goal_position")
    if gate is not None:
        ax.axhline(gate, color="gray", lw=0.8, ls=":", label=f"gate sim_goal_position = {gate} m")
    failed = [f for f, ok in zip(frictions, passed) if not ok]
    if failed:
        ax.plot(failed, [goal_error[list(frictions).index(f)] for f in failed], "x",
                color="red", ms=9, label="breaks a threshold")
    ax.set_xlabel("Coulomb friction coefficient sim.friction")
    ax.set_ylabel("error, m")
    ax.set_title(f"{base.name}: does the plan survive less friction?")
    ax.legend()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
