"""The work-precision study: its committed numbers, the docs made from them, its scripts.

* The JSONs in docs/src/images are one complete run: every engine at every dt with all its
  repeats, no CPU time of zero (a timer that did not tick).
* The tables page is what `scripts/work_precision.py --table` prints from them, and the
  README and the performance page carry the same tables: a claim there cannot drift from
  the measured numbers. These need matplotlib only and run in CI (.ci/run).
* A short rerun of the study (the disk and the sphere at the shipped dt and 8 times it,
  every engine, the converged references, MuJoCo's settings search) must reproduce the
  committed errors and MuJoCo's chosen configurations. Skipped where mujoco or Drake is not
  installed (CI installs neither: Drake is ~220 MB installed); run it in the study's venv:

    VENV=/tmp/wp/venv scripts/work_precision_env.sh ...   # or any venv with the pinned packages
    /tmp/wp/venv/bin/python -m pytest scripts/test_work_precision.py
"""

import importlib.util
import json
import math
import os
import statistics
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
IMAGES = os.path.join(ROOT, "docs", "src", "images")
sys.path.insert(0, os.path.join(ROOT, "scripts"))

import work_precision_report as rep  # noqa: E402

RESULTS = rep.load_results(IMAGES)


def read(*path):
    with open(os.path.join(ROOT, *path)) as f:
        return f.read()


def test_every_system_has_a_complete_run():
    assert list(RESULTS) == [key for key, *_ in rep.SYSTEMS]
    for key, res in RESULTS.items():
        assert set(rep.ENGINES) <= set(res["engines"]), key
        assert len(res["rows"]) == 9, key
        for row in res["rows"]:
            for eng in res["engines"]:
                cell = row[eng]
                # Drake's hydroelastic line runs once per dt (secondary).
                n = 1 if eng == "drake_hydro" else res["repeats"]
                assert len(cell["cpu_all"]) == n, (key, row["dt"], eng)
                assert all(c > 0 for c in cell["cpu_all"]), (key, row["dt"], eng, cell["cpu_all"])
                assert cell["cpu_s"] == statistics.median(cell["cpu_all"]), (key, row["dt"], eng)
                if cell["stable"]:
                    assert "ideal" in cell and "converged" in cell, (key, row["dt"], eng)
        # The frontier uses MuJoCo's best configuration at every dt: one per dt in the sweep.
        best = [e for e in res["mujoco_sweep"] if e.get("best")]
        assert sorted(e["dt"] for e in best) == sorted(r["dt"] for r in res["rows"]), key
        for row in res["rows"]:
            (b,) = [e for e in best if e["dt"] == row["dt"]]
            assert b["config"] == row["mujoco_config"], (key, row["dt"])


def test_tables_page_is_generated_from_the_jsons():
    assert read("docs", "src", "work_precision_tables.md") == rep.tables_page(RESULTS), (
        "run `python3 scripts/work_precision.py --table > docs/src/work_precision_tables.md`")


@pytest.mark.parametrize("doc,tables", [
    (("README.md",), ["readme_table"]),
    (("docs", "src", "performance.md"), ["frontier_table", "gate_table"]),
])
def test_docs_carry_the_measured_tables(doc, tables):
    text = read(*doc)
    for name in tables:
        assert getattr(rep, name)(RESULTS) in text, (
            f"{'/'.join(doc)}: its {name} is not the one on docs/src/work_precision_tables.md")


def test_frontier_marks_extrapolated_cells():
    # A frontier cell that no measured run supports must be marked ≈ ... extrapolated.
    res = {"rows": [
        {"dt": dt, "harness": {"cpu_s": 1e-3 / dt * 1e-3, "cpu_all": [1e-6 / dt] * 3,
                               "ideal": {"tracking_theta0_deg_max": 0.2 * (dt / 1e-3) ** 2}}}
        for dt in (1e-3, 2e-3)]}
    cell = rep.frontier_cell("space", res, "harness", "ideal", {"base attitude": 0.01})
    assert not cell["measured"] and math.isclose(cell["p"], 2.0)
    assert math.isclose(cell["dt"], 1e-3 * math.sqrt(0.05))
    assert rep.fmt_cpu(cell["cpu_s"], cell["dt"], True).startswith("≈ ")
    measured = rep.frontier_cell("space", res, "harness", "ideal", {"base attitude": 1.0})
    assert measured["measured"] and measured["dt"] == 2e-3


def have(*modules):
    return all(importlib.util.find_spec(m) is not None for m in modules)


@pytest.mark.skipif(not have("mujoco", "pydrake", "mcap", "zstandard"),
                    reason="mujoco, drake, mcap or zstandard not installed (scripts/work_precision_env.sh)")
def test_a_short_rerun_reproduces_the_committed_errors(tmp_path):
    binary = os.path.join(ROOT, "target", "release", "anholonomy")
    if not os.path.exists(binary):
        pytest.skip("target/release/anholonomy not built")
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "work_precision.py"), "--systems", "disk,sphere",
                    "--factors", "1,8", "--repeats", "1", "--no-hydro", "--out", str(tmp_path)],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for key in ("disk", "sphere"):
        with open(tmp_path / f"work_precision_{key}.json") as f:
            new = json.load(f)
        old = RESULTS[key]
        for row in new["rows"]:
            (ref,) = [r for r in old["rows"] if math.isclose(r["dt"], row["dt"])]
            assert row["mujoco_config"] == ref["mujoco_config"], (key, row["dt"])
            for eng in rep.ENGINES:
                for against in ("ideal", "converged"):
                    a, b = row[eng][against], ref[eng][against]
                    for metric, v in b.items():
                        # Relative 1e-6: the same pinned builds on another x86-64 CPU may
                        # differ in the last bits; a change to a model, a drive, a setting
                        # or a metric moves these by far more.
                        assert math.isclose(a[metric], v, rel_tol=1e-6, abs_tol=1e-12), (
                            key, row["dt"], eng, against, metric, a[metric], v)
        # The search visits the same configurations with the same errors.
        for dt in {r["dt"] for r in new["rows"]}:
            got = [(e["setting"], e["value"], e["errors"]) for e in new["mujoco_sweep"] if e["dt"] == dt]
            want = [(e["setting"], e["value"], e["errors"]) for e in old["mujoco_sweep"]
                    if math.isclose(e["dt"], dt)]
            assert [g[:2] for g in got] == [w[:2] for w in want], (key, dt)
            for (s, v, eg), (_s, _v, ew) in zip(got, want):
                for q, x in ew.items():
                    assert (eg[q] is None) == (x is None), (key, dt, s, v, q)
                    if x is not None:
                        assert math.isclose(eg[q], x, rel_tol=1e-6, abs_tol=1e-12), (key, dt, s, v, q, eg[q], x)
