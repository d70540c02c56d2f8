"""Feedback laws as Python callables: sampled where the harness samples any
feedback law, checked against an independent integrator; failures raise."""

from __future__ import annotations

import math
import traceback

import numpy as np
import pytest

import anholonomy
from conftest import SCENARIOS

PERIOD = 0.02


def saturating_law(gain: np.ndarray, goal: np.ndarray, calls: list):
    """u = 2 tanh(K (goal − q)): untuned, smooth, bounded."""

    def law(t: float, q: np.ndarray):
        calls.append((t, q))
        return 2.0 * np.tanh(gain @ (goal - q))

    return law


def disk_rk4(q0: np.ndarray, law, n_steps: int, dt: float, per: int, r: float):
    """An independent ideal run of the rolling disk (x' = r sin α θ',
    y' = r cos α θ', θ' = u0, α' = u1): classical RK4, the law sampled every
    `per` steps and held."""

    def f(q, u):
        return np.array([r * math.sin(q[3]) * u[0], r * math.cos(q[3]) * u[0], u[0], u[1]])

    qs = [q0.copy()]
    q = q0.copy()
    u = None
    for k in range(n_steps):
        if k % per == 0:
            u = np.asarray(law(k * dt, q.copy()), dtype=float)
        k1 = f(q, u)
        k2 = f(q + 0.5 * dt * k1, u)
        k3 = f(q + 0.5 * dt * k2, u)
        k4 = f(q + dt * k3, u)
        q = q + (k1 + 2 * k2 + 2 * k3 + k4) * (dt / 6)
        qs.append(q)
    return np.array(qs)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_law_matches_an_independent_integrator(disk, seed):
    rng = np.random.default_rng(seed)
    gain = rng.uniform(-3.0, 3.0, size=(2, 4))
    goal = np.concatenate([rng.uniform(-0.5, 0.5, 2), rng.uniform(-math.pi, math.pi, 2)])
    calls: list = []
    horizon = 1.5
    r = anholonomy.run(disk, law=saturating_law(gain, goal, calls), period=PERIOD, horizon=horizon)
    assert r.planner == "python" and r.plan.hold_period == PERIOD
    dt = disk.dt
    per = round(PERIOD / dt)
    n = round(horizon / dt)
    assert len(r.ideal.t) == n + 1
    # The ideal run, then the physics run, each from t = 0: the law is asked
    # once per sample on the grid (as an external law is); the ideal run
    # also asks for the command in force at its end.
    grid = list(range(0, n, per))
    ideal_times = [r.ideal.t[k] for k in grid] + [r.ideal.t[n]]
    sim_times = [r.sim.t[k] for k in grid]
    assert [t for t, _ in calls] == ideal_times + sim_times
    sim_calls = calls[len(ideal_times) :]
    # The law sees the simulated state in the physics run, bit for bit.
    for j, (t, q) in enumerate(sim_calls):
        assert np.array_equal(q, r.sim.q[j * per]), t
    # ... and what it returned is applied and held until the next sample.
    for j, (t, q) in enumerate(sim_calls):
        u = 2.0 * np.tanh(gain @ (goal - q))
        held = r.sim.u[j * per : (j + 1) * per]
        assert np.array_equal(held, np.broadcast_to(u, held.shape)), t
    # The ideal run agrees with an independent RK4 of the disk.
    want = disk_rk4(disk.start, saturating_law(gain, goal, []), n, dt, per, r=0.25)
    assert want.shape == r.ideal.q.shape
    np.testing.assert_allclose(r.ideal.q, want, rtol=0, atol=1e-9)


def constant(value):
    return lambda t, q: value


@pytest.mark.parametrize(
    "value",
    [
        [0.5, -0.25],
        (0.5, -0.25),
        np.array([0.5, -0.25]),
        np.array([0.5, -0.25], dtype=np.float32),
        [np.float64(0.5), -0.25],
        {"u": [0.5, -0.25]}.get("u"),
    ],
    ids=["list", "tuple", "float64", "float32", "numpy-scalars", "nested"],
)
def test_sequences_and_arrays_give_the_same_run(disk, value):
    ref = anholonomy.run(disk, law=constant([0.5, -0.25]), period=PERIOD, horizon=0.5)
    r = anholonomy.run(disk, law=constant(value), period=PERIOD, horizon=0.5)
    assert np.array_equal(r.sim.q, ref.sim.q) and r.metrics.keys() == ref.metrics.keys()
    assert all(
        (math.isnan(a) and math.isnan(b)) or a == b
        for a, b in zip(r.metrics.values(), ref.metrics.values())
    )


class Boom(Exception):
    pass


def test_an_exception_in_the_law_propagates_and_the_harness_stays_usable(disk):
    def exploding_law(t, q):
        if t >= 0.1:
            raise Boom(f"at t = {t}")
        return [0.1, 0.0]

    with pytest.raises(Boom, match="at t = 0.1") as e:
        anholonomy.run(disk, law=exploding_law, period=PERIOD, horizon=1.0)
    # The traceback reaches into the law.
    frames = [f.name for f in traceback.extract_tb(e.value.__traceback__)]
    assert frames[-1] == "exploding_law", frames
    # Usable afterwards: a plain run and a law run.
    assert anholonomy.run(disk).passed
    r = anholonomy.run(disk, law=constant([0.1, 0.0]), period=PERIOD, horizon=0.2)
    assert len(r.sim.t) == 201


def test_an_exception_in_the_physics_run_propagates(disk):
    times = []

    def law(t, q):
        times.append(t)
        # The physics run is the second run from t = 0.
        if times.count(0.0) == 2 and t >= 0.04:
            raise KeyError("physics")
        return [0.1, 0.0]

    with pytest.raises(KeyError, match="physics"):
        anholonomy.run(disk, law=law, period=PERIOD, horizon=0.5)
    # Once per sample: t = 0 once in each run.
    assert times[-1] == pytest.approx(0.04) and times.count(0.0) == 2


@pytest.mark.parametrize(
    "value,words",
    [
        ([0.1], "returned 1 values at t = 0 s; the model takes 2 (theta_rate, alpha_rate)"),
        ([0.1, 0.2, 0.3], "returned 3 values"),
        (0.1, "returned a single float"),
        (None, "returned a single NoneType"),
        ("fast", "returned a str"),
        (np.zeros((2, 2)), "returned a ndarray of shape (2, 2)"),
        ([0.1, math.nan], "returned alpha_rate = NaN"),
        ([math.inf, 0.0], "returned theta_rate = inf"),
    ],
)
def test_a_law_returning_something_else_raises_a_clear_error(disk, value, words):
    with pytest.raises(anholonomy.RuntimeFailure) as e:
        anholonomy.run(disk, law=constant(value), period=PERIOD, horizon=0.5)
    assert words in str(e.value), str(e.value)
    assert anholonomy.run(disk, law=constant([0.0, 0.0]), period=PERIOD, horizon=0.1).steps == 100


def test_horizon_defaults_to_the_plan_and_logs_are_written(disk, tmp_path):
    r = anholonomy.run(disk, logs=tmp_path, law=constant([0.0, 0.0]), period=PERIOD)
    assert r.plan.duration == disk.duration
    assert r.sim.t[-1] == pytest.approx(disk.duration)
    assert (r.log_dir / "summary.json").is_file() and (r.log_dir / "run.mcap").is_file()
    assert r.summary["plan"]["details"]["law"] == "python"


def test_a_car_steered_by_angle_takes_v_and_steer(tmp_path):
    """`steering = "angle"`: the law's state is (x, y, theta) and its answer
    (v, steer); held over each period, the ideal run ends at the closed-form
    circles of radius L / tan(steer)."""
    s = anholonomy.load(SCENARIOS.parent / "examples" / "ros_bags" / "ackermann_lane_change.toml")
    steps = [(0.5, 0.0), (0.5, 0.25), (0.25, -0.375), (0.0, 0.125), (-0.375, 0.3125), (0.5, 0.0)]
    seen = []

    def law(t, q):
        seen.append(len(q))
        return steps[min(round(t / 0.25), 5)]

    r = anholonomy.run(s, law=law, period=0.25, horizon=1.5)
    assert set(seen) == {3}
    x, y, th = s.start
    for v, steer in steps:
        w = v * math.tan(steer) / 0.32  # models/car.urdf's wheelbase
        if w == 0.0:
            x, y = x + v * 0.25 * math.cos(th), y + v * 0.25 * math.sin(th)
        else:
            th1 = th + w * 0.25
            x, y = x + v / w * (math.sin(th1) - math.sin(th)), y - v / w * (math.cos(th1) - math.cos(th))
            th = th1
    np.testing.assert_allclose(r.ideal.q[-1], [x, y, th], rtol=0, atol=1e-9)
    assert r.metrics["steer_clipped_fraction"] == 0.0
