#!/usr/bin/env python3
"""Back a tractor's on-axle trailer into a slot: a feedback law for the
declared model of examples/trailer/ (states x, y, theta0, theta1; inputs v,
omega), run through `[planner] kind = "external"`. Standard library only.

Backing, the trailer is the vehicle and the tractor steers it through the
hitch angle phi = theta0 - theta1 (on-axle hitch, trailer axle D1 behind):

    trailer axle p1 = (x - D1 cos theta1, y - D1 sin theta1),
    theta1' = v / D1 sin(phi),      phi' = omega - v / D1 sin(phi).

A cascade, outer to inner: the trailer's heading is steered towards the
slot's centre line (lateral error e), the hitch angle towards the one that
turns the trailer that way, and omega makes the hitch angle follow
(backing, phi is unstable on its own: the inner loop is what keeps the
trailer from jackknifing). The hitch angle is kept within PHI_MAX.

    python3 law.py SLOT_X SLOT_Y      (the trailer axle's goal; heading 0)
"""

import json
import math
import sys

D1 = 0.6  # m, hitch to trailer axle
V_BACK = 0.15  # m/s, backing speed
K_LAT = 2.0  # rad/m, trailer heading per metre off the centre line
TH_MAX = 0.5  # rad, the trailer heading's bound
K_TH = 1.0  # 1/s, trailer heading rate per radian of heading error
PHI_MAX = 0.6  # rad, the hitch angle's bound
K_PHI = 3.0  # 1/s, hitch angle rate per radian of hitch error
W_MAX = 1.5  # rad/s
DONE = 0.01  # m, along the slot


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def clamp(x, m):
    return max(-m, min(m, x))


def law(q, slot):
    x, y, th0, th1 = q
    x1, y1 = x - D1 * math.cos(th1), y - D1 * math.sin(th1)
    along = x1 - slot[0]  # > 0: still short of the slot's end
    if along < DONE:
        return [0.0, 0.0], "parked", True
    # Slow down over the last 0.3 m.
    v = -V_BACK * min(1.0, max(0.2, along / 0.3))
    e = y1 - slot[1]
    th1_des = clamp(K_LAT * e, TH_MAX)
    # theta1' = v/D1 sin(phi) = K_TH (th1_des - th1), v < 0.
    s = clamp(D1 * K_TH * wrap(th1_des - th1) / v, math.sin(PHI_MAX))
    phi_des = math.asin(s)
    phi = wrap(th0 - th1)
    w = v / D1 * math.sin(phi) + K_PHI * (phi_des - phi)
    return [v, clamp(w, W_MAX)], "backing", False


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: law.py SLOT_X SLOT_Y")
    slot = (float(sys.argv[1]), float(sys.argv[2]))
    for line in sys.stdin:
        msg = json.loads(line)
        u, label, done = law(msg["q"], slot)
        sys.stdout.write(json.dumps({"u": u, "label": label, "done": done}) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
