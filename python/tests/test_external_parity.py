"""A law in process equals the same law through `[planner] kind =
"external"` (a subprocess speaking JSON lines), bit for bit, and the CLI
gives the same metrics."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import anholonomy
from conftest import REPO, SCENARIOS
import parity_law

LAW = REPO / "python" / "tests" / "parity_law.py"


def external_scenario(tmp_path, seed: int):
    text = (SCENARIOS / "disk_paper.toml").read_text()
    head, _, _ = text.partition("[planner]")
    _, _, tail = text.partition("[sim]")
    head = head.replace("../models/", str(REPO / "models") + "/")
    planner = (
        "[planner]\n"
        'kind = "external"\n'
        f"command = [{json.dumps(sys.executable)}, {json.dumps(str(LAW))}, \"{seed}\"]\n"
        "period = 0.02\n"
        "horizon = 2.0\n\n"
    )
    path = tmp_path / f"parity_{seed}.toml"
    # The law is not tuned to pass the paper's gates: none here.
    tail = tail.split("[thresholds]")[0]
    path.write_text(f'name = "parity_{seed}"\n' + head + planner + "[sim]" + tail)
    return path


def bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_python_law_equals_the_external_law_bit_for_bit(cli, tmp_path, seed):
    path = external_scenario(tmp_path, seed)
    s = anholonomy.load(path)
    assert s.planner == "external"
    ext = anholonomy.run(s)
    py = anholonomy.run(s, law=parity_law.make(seed))  # period and horizon: the scenario's
    assert py.planner == "python" and ext.planner == "external"
    for which in ("ideal", "sim"):
        a, b = getattr(ext, which), getattr(py, which)
        assert a.t.shape == b.t.shape, which
        for field in ("t", "q", "u"):
            assert np.array_equal(bits(getattr(a, field)), bits(getattr(b, field))), (which, field)
        # The same labels, named in the same order.
        assert a.labels == b.labels and np.array_equal(a.label, b.label)
    assert set(py.plan.labels) <= {"far", "near"}
    # `done` at 1.2 s ends both runs early (the horizon is 2 s).
    assert py.ideal.t[-1] < 2.0
    assert ext.metrics.keys() == py.metrics.keys()
    for k in ext.metrics:
        assert bits(np.array(ext.metrics[k])) == bits(np.array(py.metrics[k])), k
    # The CLI's run of the external law gives the same metrics.
    out = tmp_path / "logs"
    subprocess.run([str(cli), "run", str(path), "--logs", str(out), "--quiet"], check=True, capture_output=True)
    summary = json.loads((out / f"parity_{seed}" / "summary.json").read_text())
    for k, v in summary["metrics"].items():
        mine = py.metrics[k]
        assert (v is None and math.isnan(mine)) or v == mine, k
    assert summary["sim"]["final_segment"] == py.plan.labels[py.sim.label[-1]]
