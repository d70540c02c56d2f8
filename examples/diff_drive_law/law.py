#!/usr/bin/env python3
"""A Lyapunov go-to-pose law for anholonomy's `diff_drive` model, run
through `[planner] kind = "external"` (one JSON line in, one out, per
control sample; see the external-law protocol page). Standard library only.

The law is Aicardi, Casalino, Bicchi and Balestrino (1995), "Closed loop
steering of unicycle-like vehicles via Lyapunov techniques", IEEE Robotics
& Automation Magazine 2(1). In polar coordinates about the goal pose (goal
frame: goal at the origin, goal heading along +x):

    e     distance from the robot to the goal,
    theta direction of the goal-to-robot line... taken from the robot to
          the goal: theta = atan2(-y, -x) in the goal frame,
    alpha = theta - heading (the goal's bearing seen from the robot).

With v = gamma e cos(alpha) and
    omega = k alpha + gamma cos(alpha) sin(alpha) / alpha * (alpha + h theta),
V = (lambda e^2 + alpha^2 + h theta^2) / 2 decreases along every motion
(gamma, k, h > 0), and (e, alpha, theta) -> 0: the robot reaches the goal
position with the goal heading, without ever turning in place. The inputs
are saturated by one common factor (|v| <= V_MAX, |omega| <= W_MAX): V is
linear in (v, omega), so scaling both keeps it decreasing.

A real drive cannot jump to a new speed: between samples, v and omega
change by at most A_MAX and DW_MAX per second (the law keeps its last
answer; the harness sends the same stream to every run of it).

The law answers done once e < DONE_DISTANCE and the heading is within
DONE_HEADING of the goal's. Usage (the scenario passes the goal):

    python3 law.py GOAL_X GOAL_Y GOAL_HEADING_DEG
"""

import json
import math
import sys

GAMMA = 0.5  # 1/s, the distance gain
K = 1.5  # 1/s, the bearing gain
H = 1.5  # the weight of the approach direction theta
V_MAX = 0.3  # m/s
W_MAX = 1.5  # rad/s
A_MAX = 0.5  # m/s^2, the change of v per second
DW_MAX = 3.0  # rad/s^2, the change of omega per second
DONE_DISTANCE = 0.01  # m
DONE_HEADING = math.radians(1.0)


def wrap(a):
    """The angle in (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


def law(q, goal):
    """(v, omega), the phase label and whether the goal is reached."""
    gx, gy, gh = goal
    # The robot in the goal frame.
    c, s = math.cos(gh), math.sin(gh)
    dx, dy = q[0] - gx, q[1] - gy
    x, y = c * dx + s * dy, -s * dx + c * dy
    heading = wrap(q[2] - gh)
    e = math.hypot(x, y)
    if e < DONE_DISTANCE and abs(heading) < DONE_HEADING:
        return [0.0, 0.0], "arrived", True
    theta = math.atan2(-y, -x)
    alpha = wrap(theta - heading)
    # cos(a) sin(a) / a, continuous at a = 0.
    sinc = math.sin(alpha) / alpha if abs(alpha) > 1e-9 else 1.0
    v = GAMMA * math.cos(alpha) * e
    w = K * alpha + GAMMA * math.cos(alpha) * sinc * (alpha + H * theta)
    scale = min(1.0, V_MAX / max(abs(v), 1e-12), W_MAX / max(abs(w), 1e-12))
    label = "approach" if e > 0.1 else "final"
    return [v * scale, w * scale], label, False


def limit_rate(u, last, dt):
    """u moved towards from `last` by at most the rate limits over dt."""
    out = []
    for value, prev, rate in zip(u, last, (A_MAX, DW_MAX)):
        step = rate * dt
        out.append(min(max(value, prev - step), prev + step))
    return out


def main():
    if len(sys.argv) != 4:
        sys.exit("usage: law.py GOAL_X GOAL_Y GOAL_HEADING_DEG")
    goal = (float(sys.argv[1]), float(sys.argv[2]), math.radians(float(sys.argv[3])))
    last, t_last = [0.0, 0.0], None
    for line in sys.stdin:
        msg = json.loads(line)
        u, label, done = law(msg["q"], goal)
        dt = 0.0 if t_last is None else msg["t"] - t_last
        if not done:
            u = limit_rate(u, last, dt)
        last, t_last = u, msg["t"]
        sys.stdout.write(json.dumps({"u": u, "label": label, "done": done}) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
