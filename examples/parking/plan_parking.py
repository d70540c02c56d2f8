#!/usr/bin/env python3
"""Plan a parallel-parking manoeuvre for anholonomy's `car` model and write
it as a plan file (CSV) that `[planner] kind = "file"` replays.

The car (kinematic bicycle: rear-axle midpoint (x, y), heading theta,
steering angle phi; inputs v and phi') waits in the lane with its rear
axle at the origin, heading +x. The parking spot is behind it, on its
right: the goal is (GOAL_X, GOAL_Y) with heading 0 and the wheels straight.

The manoeuvre, three arcs joined by steering while stopped:
  1. steer right to -PHI (stopped),
  2. reverse along an arc of radius R = L / tan(PHI): the rear swings into
     the spot,
  3. steer left to +PHI (stopped),
  4. reverse along the mirror arc: the car straightens out,
  5. steer back to 0 (stopped),
  6. drive forward to centre in the spot.
Two equal reversing arcs of angle a move the car 2 R (1 - cos a) sideways
and 2 R sin a backwards, so a and the final forward distance follow from the
goal in closed form.

Every motion follows a smooth speed profile (quintic ramps: acceleration
and jerk start and end at zero) within MAX_SPEED, MAX_STEER_RATE and the
ramp times. The CSV holds the inputs at SAMPLE_PERIOD, each the average of
the continuous profile over its sample (so zero-order hold covers exactly
the planned distance and steering), each motion a whole number of samples.
The last row (inputs zero) marks the end of the plan.

Usage: python3 plan_parking.py [OUT.csv]    (default: parking.csv here)
Needs numpy only.
"""

import math
import sys
from pathlib import Path

import numpy as np

# The car: models/car.urdf and the `car` model's defaults.
WHEELBASE = 0.32  # m
MAX_STEER = math.radians(25.0)  # the model's steering limit

# The task.
GOAL_X, GOAL_Y = -0.95, -0.35  # m, rear-axle midpoint in the spot
PHI = math.radians(20.0)  # steering angle of both reversing arcs (below the limit)

# Limits of the plan.
MAX_SPEED = 0.2  # m/s
MAX_STEER_RATE = 0.4  # rad/s
DRIVE_RAMP = 0.8  # s, speed ramps
STEER_RAMP = 0.3  # s, steering-rate ramps
SAMPLE_PERIOD = 0.01  # s (a multiple of the scenario's sim.dt)


def ramp_integral(x):
    """Integral of the quintic smoothstep 10x^3 - 15x^4 + 6x^5 from 0 to x."""
    return 2.5 * x**4 - 3.0 * x**5 + x**6


class Motion:
    """One input moving its integral by `amount` (m or rad) from rest to
    rest: quintic ramps of `ramp` s around a cruise at most `max_rate`,
    lasting a whole number of samples."""

    def __init__(self, index, amount, max_rate, ramp, label):
        self.index, self.amount, self.ramp, self.label = index, amount, ramp, label
        size = abs(amount)
        raw = max(size / max_rate, ramp) + ramp
        self.samples = math.ceil(raw / SAMPLE_PERIOD - 1e-9)
        self.duration = self.samples * SAMPLE_PERIOD
        # Slower than the limit by the rounding up; never faster.
        self.rate = size / (self.duration - ramp)
        assert self.rate <= max_rate * (1 + 1e-12), (label, self.rate)

    def integral(self, tau):
        """How far the input's integral has moved at local time tau (signed)."""
        d, r, v = self.duration, self.ramp, self.rate
        tau = np.clip(tau, 0.0, d)
        up = v * r * ramp_integral(np.clip(tau / r, 0.0, 1.0))
        cruise = v * np.clip(tau - r, 0.0, d - 2 * r)
        down = v * r * (0.5 - ramp_integral(np.clip((d - tau) / r, 0.0, 1.0)))
        down = np.where(tau > d - r, down, 0.0)
        return math.copysign(1.0, self.amount) * (up + cruise + down)


def plan(goal_x=GOAL_X, goal_y=GOAL_Y, phi=PHI):
    """The motions of the manoeuvre and the arc angle a."""
    if not 0.0 < phi < MAX_STEER:
        raise SystemExit(f"steering angle {math.degrees(phi)} deg is not inside the limit")
    radius = WHEELBASE / math.tan(phi)
    cos_a = 1.0 - abs(goal_y) / (2.0 * radius)
    if not -1.0 < cos_a < 1.0 or goal_y >= 0.0:
        raise SystemExit(f"a spot {goal_y} m to the right cannot be reached with arcs of {radius:.3f} m")
    a = math.acos(cos_a)
    arc = radius * a
    forward = goal_x + 2.0 * radius * math.sin(a)
    if forward < 0.0:
        raise SystemExit(f"the spot is {-forward:.3f} m too far back for arcs of {radius:.3f} m")
    drive = lambda s, label: Motion(0, s, MAX_SPEED, DRIVE_RAMP, label)
    steer = lambda d, label: Motion(1, d, MAX_STEER_RATE, STEER_RAMP, label)
    motions = [
        steer(-phi, "steer_right"),
        drive(-arc, "reverse_in"),
        steer(2.0 * phi, "steer_left"),
        drive(-arc, "reverse_straighten"),
        steer(-phi, "steer_straight"),
        drive(forward, "forward"),
    ]
    return motions, a


def samples(motions):
    """Rows (t, v, steer_rate, label): per-sample averages of each motion."""
    rows, t0 = [], 0
    for m in motions:
        edges = m.integral(np.arange(m.samples + 1) * SAMPLE_PERIOD)
        rates = np.diff(edges) / SAMPLE_PERIOD
        for k, rate in enumerate(rates):
            u = [0.0, 0.0]
            u[m.index] = float(rate)
            rows.append((sample_time(t0 + k), u[0], u[1], m.label))
        t0 += m.samples
    rows.append((sample_time(t0), 0.0, 0.0, motions[-1].label))
    return rows


def sample_time(k):
    """Time of sample k, rounded to the nearest ns (so it is the double
    closest to the decimal time, on the simulation's step grid)."""
    return round(k * SAMPLE_PERIOD, 9)


def end_pose(motions):
    """Where the bicycle ends: steering while stopped turns only phi, each
    drive at constant phi is an exact arc."""
    x = y = theta = phi = 0.0
    for m in motions:
        if m.index == 1:
            phi += m.amount
            continue
        s, k = m.amount, math.tan(phi) / WHEELBASE
        if abs(k) < 1e-15:
            x, y = x + s * math.cos(theta), y + s * math.sin(theta)
        else:
            x += (math.sin(theta + k * s) - math.sin(theta)) / k
            y -= (math.cos(theta + k * s) - math.cos(theta)) / k
            theta += k * s
    return x, y, theta, phi


def main():
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).with_name("parking.csv")
    motions, a = plan()
    rows = samples(motions)
    v = np.array([r[1] for r in rows])
    w = np.array([r[2] for r in rows])
    assert np.abs(v).max() <= MAX_SPEED * (1 + 1e-12)
    assert np.abs(w).max() <= MAX_STEER_RATE * (1 + 1e-12)
    with open(out, "w") as f:
        f.write("t,v,steer_rate,label\n")
        for t, vi, wi, label in rows:
            # repr: the shortest text that reads back as the same double.
            f.write(f"{t!r},{vi!r},{wi!r},{label}\n")
    x, y, theta, phi = end_pose(motions)
    print(
        f"{out}: {len(rows)} rows, {rows[-1][0]:.2f} s; arcs of {math.degrees(a):.2f} deg "
        f"at radius {WHEELBASE / math.tan(PHI):.4f} m; ends at x = {x:.12f} m, "
        f"y = {y:.12f} m, theta = {math.degrees(theta):.3g} deg, phi = {math.degrees(phi):.3g} deg"
    )


if __name__ == "__main__":
    main()
