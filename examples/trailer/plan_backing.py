#!/usr/bin/env python3
"""Record law.py's backing manoeuvre as a plan file: the law run on the
declared model's equations (RK4, 1 ms steps, the law asked every 50 ms),
its commands written to backing.csv (t, v, omega; zero-order hold), so the
same manoeuvre can be replayed open loop. Standard library only.

    python3 plan_backing.py [OUT.csv]
"""

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import law  # noqa: E402

START = (0.0, 0.4, 0.0, 0.0)  # x, y, theta0, theta1 (rad)
SLOT = (-3.0, 0.0)
DT, PERIOD = 0.001, 0.05


def f(q, u):
    x, y, th0, th1 = q
    v, w = u
    return (v * math.cos(th0), v * math.sin(th0), w, v / law.D1 * math.sin(th0 - th1))


def rk4(q, u, h):
    k1 = f(q, u)
    k2 = f([a + h / 2 * b for a, b in zip(q, k1)], u)
    k3 = f([a + h / 2 * b for a, b in zip(q, k2)], u)
    k4 = f([a + h * b for a, b in zip(q, k3)], u)
    return [a + h / 6 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(q, k1, k2, k3, k4)]


def main():
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).with_name("backing.csv")
    q, t, rows = list(START), 0.0, []
    steps = round(PERIOD / DT)
    while t < 60.0:
        u, _, done = law.law(q, SLOT)
        rows.append((round(t, 6), u))
        if done:
            break
        for _ in range(steps):
            q = rk4(q, u, DT)
        t += PERIOD
    with open(out, "w") as fh:
        fh.write("t,v,omega\n")
        for t, (v, w) in rows:
            fh.write(f"{t!r},{v!r},{w!r}\n")
    print(f"{out}: {len(rows)} rows, {rows[-1][0]} s; ends at "
          f"x = {q[0]:.6f}, y = {q[1]:.6f}, theta0 = {math.degrees(q[2]):.4f} deg, "
          f"theta1 = {math.degrees(q[3]):.4f} deg")


if __name__ == "__main__":
    main()
