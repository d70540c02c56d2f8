"""load / replace / run: sources, variants, result arrays, sweeps."""

from __future__ import annotations

import math

import numpy as np
import pytest

import anholonomy
from conftest import REPO, SCENARIOS

DISK_PATH = SCENARIOS / "disk_paper.toml"

DISK_DICT = {
    "description": "disk_paper as a dict",
    "start": [0.0, 0.0, 0.0, 0.0],
    "goal": [-0.4, 1.0, 180.0, 22.5],
    "model": {"kind": "rolling_disk", "radius": 0.25, "urdf": REPO / "models" / "rolling_disk.urdf"},
    "planner": {"kind": "stokes_disk", "algorithm": "singularity_avoiding"},
    "sim": {"dt": 0.001, "friction": 1.0},
    "thresholds": {"ideal_goal_position": 1e-9, "sim_goal_position": 0.003},
}


def same_metrics(a, b) -> bool:
    return a.keys() == b.keys() and all(
        x == y or (math.isnan(x) and math.isnan(y)) for x, y in zip(a.values(), b.values())
    )


def test_path_text_and_dict_load_the_same_scenario(disk):
    assert repr(disk) == f'Scenario("disk_paper", model="rolling_disk", planner="stokes_disk", file="{DISK_PATH}")'
    from_str_path = anholonomy.load(str(DISK_PATH))
    from_text = anholonomy.load(DISK_PATH.read_text(), path=DISK_PATH)
    from_dict = anholonomy.load(DISK_DICT, path=SCENARIOS / "disk_dict.toml")
    assert from_dict.name == "disk_dict" and from_text.name == "disk_paper"
    assert from_str_path.name == "disk_paper"
    ref = anholonomy.run(disk)
    for s in (from_str_path, from_text, from_dict):
        assert np.array_equal(s.start, disk.start) and np.array_equal(s.goal, disk.goal)
        r = anholonomy.run(s)
        assert np.array_equal(r.sim.q, ref.sim.q)
    assert same_metrics(anholonomy.run(from_text).metrics, ref.metrics)
    # Goal angles were given in degrees.
    assert disk.goal[2] == math.radians(180.0)
    assert disk.state_names == ["x", "y", "theta", "alpha"]
    assert disk.input_names == ["theta_rate", "alpha_rate"]
    assert disk.to_dict()["sim"]["dt"] == 0.001 and disk.dt == 0.001


def test_replace_makes_variants_with_sweep_key_paths(disk):
    slippery = disk.replace({"sim.friction": 0.05})
    assert slippery.to_dict()["sim"]["friction"] == 0.05
    assert disk.to_dict()["sim"]["friction"] == 1.0  # the original is unchanged
    r0, r1 = anholonomy.run(disk), anholonomy.run(slippery)
    assert r1.metrics["sim_goal_position"] != r0.metrics["sim_goal_position"]
    # Whole arrays, elements, integers, keys the file leaves at their default.
    v = disk.replace({"goal": np.array([-0.3, 0.9, 170.0, 20.0]), "start[1]": 0.05})
    assert v.goal[2] == math.radians(170.0) and v.start[1] == 0.05
    v = disk.replace({"sim.solver_iterations": 2, "sim.settle": 0.5, "limits.ramp": 0.1})
    d = v.to_dict()
    assert (d["sim"]["solver_iterations"], d["sim"]["settle"], d["ramp"]) == (2, 0.5, 0.1)
    # Changes chain, later ones win.
    w = v.replace({"sim.settle": 0.25})
    assert w.to_dict()["sim"]["settle"] == 0.25 and w.to_dict()["sim"]["solver_iterations"] == 2
    assert anholonomy.run(w).sim.t[-1] == pytest.approx(w.duration + 0.25)
    # A replaced float that is a whole number stays a float (sim.dt is a float).
    assert disk.replace({"sim.settle": 1.0}).to_dict()["sim"]["settle"] == 1.0


def test_result_arrays(disk):
    r = anholonomy.run(disk)
    n, m = 4, 2
    assert r.kind == "run" and r.name == "disk_paper" and r.planner == "stokes_disk"
    assert r.passed and r.failures == ()
    for tr in (r.ideal, r.sim):
        assert tr.t.dtype == np.float64 and tr.t.shape == (len(tr),)
        assert tr.q.shape == (len(tr), n) and tr.u.shape == (len(tr), m)
        assert tr.names == ("x", "y", "theta", "alpha")
        assert np.array_equal(tr["alpha"], tr.q[:, 3]) and np.array_equal(tr["theta_rate"], tr.u[:, 0])
        assert tr.label.shape == (len(tr),) and tr.label.max() < len(tr.labels)
    assert np.array_equal(r.ideal.q[0], disk.start)
    assert r.sim.final == {k: float(v) for k, v in zip(r.sim.names, r.sim.q[-1])}
    assert r.plan.duration == disk.duration and r.plan.hold_period is None
    assert [s[0] for s in r.plan.segments] == [r.plan.labels[i] for i in _runs(r.ideal.label)][: len(r.plan.segments)]
    assert r.steps == len(r.sim.t) - 1
    assert set(r.timings) >= {"plan", "ideal", "physics", "analysis", "logs", "total"}
    for name, v in r.channels.items():
        assert v.shape == r.sim.t.shape, name
    assert r.log_dir is None
    assert "passed" in repr(r)
    # Arrays are the caller's.
    r.sim.q[0, 0] = 42.0


def _runs(labels):
    out = []
    for x in labels:
        if not out or out[-1] != x:
            out.append(x)
    return out


def test_channels_and_series_of_a_rover():
    r = anholonomy.run(SCENARIOS / "rover_behind.toml")
    assert r.channels, "the rover reports wheel slip"
    for v in r.channels.values():
        assert v.shape == r.sim.t.shape


def test_a_sweep_runs_its_variants(tmp_path):
    s = anholonomy.load(SCENARIOS / "rover_sweep.toml").replace({"sweep.count": 4})
    assert s.is_sweep
    r = anholonomy.run(s, logs=tmp_path)
    assert r.kind == "sweep" and r.ideal is None and r.sim is None
    assert r.metrics["sweep_variants"] == 4.0
    assert r.summary is not None and (tmp_path / "rover_sweep" / "sweep.json").is_file()
    assert "variants" in r.table
