"""One feedback law for the rolling disk, run two ways: in process
(``make(seed)``) and as an external law speaking the JSON-lines protocol
(``python parity_law.py SEED``). Plain floats and ``math`` only, so both
compute the same numbers from the same state."""

from __future__ import annotations

import json
import math
import random
import sys


def make(seed: int):
    """u = 2 tanh(K (goal − q)) with random K and goal, a label by distance
    and done after 1.2 s: untuned, bounded, deterministic."""
    rng = random.Random(seed)
    gain = [[rng.uniform(-3.0, 3.0) for _ in range(4)] for _ in range(2)]
    goal = [rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0)]

    def law(t, q):
        e = [goal[i] - float(q[i]) for i in range(4)]
        u = [2.0 * math.tanh(sum(gain[j][i] * e[i] for i in range(4))) for j in range(2)]
        far = math.hypot(e[0], e[1]) > 0.3
        return {"u": u, "label": "far" if far else "near", "done": t >= 1.2}

    return law


def main() -> None:
    law = make(int(sys.argv[1]))
    for line in sys.stdin:
        msg = json.loads(line)
        sys.stdout.write(json.dumps(law(msg["t"], msg["q"])) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
