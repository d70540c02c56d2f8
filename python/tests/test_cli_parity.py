"""The package runs the CLI's pipeline: the same metrics, bit for bit, and
the same summary.json."""

from __future__ import annotations

import json
import math
import subprocess

import numpy as np

import anholonomy
from conftest import REPO, SCENARIOS


def summary_metrics(summary: dict) -> dict:
    # summary.json writes NaN as null.
    return {k: (math.nan if v is None else v) for k, v in summary["metrics"].items()}


def same_number(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == b


def test_disk_paper_metrics_equal_the_clis_exactly(cli, tmp_path):
    subprocess.run(
        [str(cli), "run", "scenarios/disk_paper.toml", "--logs", str(tmp_path / "cli"), "--quiet"],
        cwd=REPO,
        check=True,
        capture_output=True,
    )
    cli_summary = json.loads((tmp_path / "cli" / "disk_paper" / "summary.json").read_text())
    r = anholonomy.run(SCENARIOS / "disk_paper.toml")
    want = summary_metrics(cli_summary)
    assert set(r.metrics) == set(want)
    for k, v in want.items():
        assert same_number(r.metrics[k], v), (k, r.metrics[k], v)
    assert r.passed == cli_summary["passed"] and r.verdict == cli_summary["verdict"]
    assert list(r.failures) == cli_summary["failures"]
    assert r.steps == cli_summary["sim_steps"]
    # The summary is the CLI's, but for the wall times.
    ours = dict(r.summary)
    theirs = dict(cli_summary)
    for s in (ours, theirs):
        s.pop("wall_time_s")
        s.pop("file")
    # Which log files the CLI kept: only in a written summary.
    assert theirs.pop("logs_kept") == "all" and "logs_kept" not in ours
    assert json.loads(json.dumps(ours)) == theirs


def final_in_display_units(r, which: str) -> dict:
    """The last row of a trajectory as summary.json writes a final state:
    angles in degrees (`x.to_degrees()` in Rust is x * (180 / pi))."""
    tr = getattr(r, which)
    out = {}
    angular = {"theta", "alpha"}
    for name, x in zip(tr.names, tr.q[-1]):
        if name in angular:
            out[f"{name}_deg"] = float(x) * (180.0 / math.pi)
        else:
            out[name] = float(x)
    return out


def test_last_rows_are_summary_final_states(tmp_path):
    r = anholonomy.run(SCENARIOS / "disk_paper.toml", logs=tmp_path)
    assert r.log_dir == tmp_path / "disk_paper"
    on_disk = json.loads((r.log_dir / "summary.json").read_text())
    for which in ("ideal", "sim"):
        want = on_disk[which]["final_state"]
        got = final_in_display_units(r, which)
        assert got == want, which
        tr = getattr(r, which)
        assert tr.t[-1] == on_disk[which]["end_time_s"]
    # Shapes and grid.
    n = len(r.state_names)
    assert r.sim.q.shape == (len(r.sim.t), n) and r.ideal.q.shape == (len(r.ideal.t), n)
    assert r.sim.u.shape == (len(r.sim.t), len(r.input_names))
    assert np.all(np.diff(r.sim.t) > 0) and r.sim.t[0] == 0.0
    assert r.plan.q is r.ideal.u and r.plan.names == tuple(r.input_names)
    # The written summary is the one returned (wall times included).
    assert json.loads(json.dumps(r.summary)) == on_disk
    for f in ("run.mcap", "run.rrd", "series.json", "summary.json"):
        assert (r.log_dir / f).is_file(), f
