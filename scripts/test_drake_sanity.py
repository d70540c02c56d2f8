"""Drake's setup in scripts/drake_engine.py, checked on rolling without slip.

A ball and the disk, driven at a constant rate w on flat ground from rest, must
move r·w per unit time once the drive has taken up the rate: each test measures
the distance over the last second of a 1.5 s run and asks it to be r·w within a
relative 1e-3. Run by scripts/work_precision_env.sh before the study:

    python -m pytest scripts/test_drake_sanity.py
"""

import math
import os
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))

# Skipped where Drake is not installed (CI: it is ~220 MB; scripts/work_precision_env.sh has it).
pytest.importorskip("pydrake", reason="drake not installed (scripts/work_precision_env.sh installs it)")
import drake_engine as de  # noqa: E402

DT = 1e-3
T = 1.5


def summary(radius, friction, max_torque):
    return {"sim_settings": {"friction": friction, "gravity": [0.0, 0.0, -9.81], "motor_max_torque": max_torque},
            "model": {"radius": radius}}


def distance_per_second(run, x, cols):
    """Distance travelled over the run's last second, m."""
    q = run.model_states(x, np.zeros(6))
    n = int(round(1.0 / DT))
    return math.hypot(q[-1, cols[0]] - q[-1 - n, cols[0]], q[-1, cols[1]] - q[-1 - n, cols[1]])


@pytest.mark.parametrize("contact", ["point", "hydroelastic"])
@pytest.mark.parametrize("w", [0.5, 2.0])
def test_sphere_rolls_r_times_w(contact, w):
    a = 1.0
    steps = int(round(T / DT))
    run = de.DrakeRun("sphere", os.path.join(ROOT, "models", "sphere.urdf"), summary(a, 0.8, 20.0),
                      [0.0, 0.0, 0.0, 0.0, 0.0], DT, steps, {"contact": contact})
    wd = np.tile([w, 0.0, 0.0], (steps, 1))
    run.build(wd @ run._sphere_K().T)
    x, _cpu, ok = run.run()
    assert ok, getattr(run, "error", "")
    d = distance_per_second(run, x, (0, 1))
    assert abs(d / (a * w) - 1) < 1e-3, (d, a * w)


@pytest.mark.parametrize("contact", ["point", "hydroelastic"])
@pytest.mark.parametrize("w", [1.0, 4.0])
def test_disk_rolls_r_times_w(contact, w):
    r = 0.25
    steps = int(round(T / DT))
    run = de.DrakeRun("disk", os.path.join(ROOT, "models", "rolling_disk.urdf"), summary(r, 1.0, 50.0),
                      [0.0, 0.0, 0.0, 0.0], DT, steps, {"contact": contact})
    t_end = (np.arange(steps) + 1) * DT
    # [wheel angle, yaw angle, wheel rate, yaw rate]: the wheel at w, the heading held.
    rows = np.stack([w * t_end, np.full(steps, math.pi / 2), np.full(steps, w), np.zeros(steps)], axis=1)
    run.build(rows)
    x, _cpu, ok = run.run()
    assert ok, getattr(run, "error", "")
    d = distance_per_second(run, x, (0, 1))
    assert abs(d / (r * w) - 1) < 1e-3, (d, r * w)
