#!/usr/bin/env python3
"""A minimal external feedback law for anholonomy (standard library only).

The harness starts this program once per run and writes one JSON line per
control sample to its stdin:

    {"t": 0.0, "q": [0.0, 0.0, 0.0, 0.0], "names": ["x", "y", "theta", "alpha"]}
    {"t": 0.02, "q": [...]}

(`names`, the state coordinates, only on the first line). For each line the
law writes one JSON line to its stdout and flushes it:

    {"u": [2.0, 0.5], "label": "steer", "done": false}

This law is for the rolling disk (inputs theta_rate, alpha_rate): roll at a
constant rate and steer the heading alpha to 90 degrees with a proportional
law; report done after 3 s. Anything printed for debugging goes to stderr
(stdout carries the answers only). The law ends when its stdin closes.
"""

import json
import math
import sys

ROLL_RATE = 2.0  # rad/s
HEADING_GOAL = math.pi / 2  # rad
GAIN = 2.0  # 1/s
DONE_AFTER = 3.0  # s


def law(t, q, names):
    """The input vector, a label and whether the task is done."""
    alpha = q[names.index("alpha")]
    steer = -GAIN * (alpha - HEADING_GOAL)
    return [ROLL_RATE, steer], "steer", t >= DONE_AFTER


def main():
    names = None
    while True:
        line = sys.stdin.readline()
        if not line:  # the harness closed stdin: the run is over
            return
        msg = json.loads(line)
        names = msg.get("names", names)
        u, label, done = law(msg["t"], msg["q"], names)
        sys.stdout.write(json.dumps({"u": u, "label": label, "done": done}) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
