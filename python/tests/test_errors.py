"""Bad input raises InputError with the file, line and key the CLI names
(and the CLI's text); runs that fail raise RuntimeFailure."""

from __future__ import annotations

import contextlib
import math
import pickle
import subprocess
import uuid

import pytest

import anholonomy
from conftest import REPO, SCENARIOS

DISK = (SCENARIOS / "disk_paper.toml").read_text()


def line_of(text: str, needle: str) -> int:
    """1-based line of the first line containing `needle`."""
    for i, line in enumerate(text.splitlines(), 1):
        if needle in line:
            return i
    raise AssertionError(needle)


@contextlib.contextmanager
def scenario_file(text: str):
    """`text` as a scenario file in scenarios/ (so the relative URDF path in
    it resolves), removed afterwards."""
    path = SCENARIOS / f"_pytest_bad_{uuid.uuid4().hex[:8]}.toml"
    path.write_text(text)
    try:
        yield path
    finally:
        path.unlink()


def errors_of(cli, text: str):
    """The InputError of loading `text` from a file, and the CLI's one
    error line (without `error: `) for the same file."""
    with scenario_file(text) as path:
        with pytest.raises(anholonomy.InputError) as e:
            anholonomy.load(path)
        p = subprocess.run([str(cli), "plan", str(path)], cwd=REPO, capture_output=True, text=True)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), p.stderr
    return e.value, lines[0][len("error: "):], path


@pytest.mark.parametrize(
    "old,new,key,needle,words",
    [
        # A value of the wrong type.
        ("dt = 0.001", 'dt = "fast"', "sim.dt", 'dt = "fast"', "invalid type"),
        # NaN.
        ("friction = 1.0", "friction = nan", "sim.friction", "friction = nan", "not a finite number"),
        # An unknown key (a typo).
        ("friction = 1.0", "frction = 1.0", "sim.frction", "frction = 1.0", "unknown key"),
        # A range check made after parsing.
        ("friction = 1.0", "friction = -0.5", "sim.friction", "friction = -0.5", "must be"),
        # A planner refusal (validation plans the scenario).
        ('algorithm = "singularity_avoiding"', 'algorithm = "nope"', "planner.algorithm", 'algorithm = "nope"', "nope"),
    ],
)
def test_input_errors_name_line_and_key(cli, old, new, key, needle, words):
    text = DISK.replace(old, new, 1)
    assert text != DISK
    e, cli_line, path = errors_of(cli, text)
    assert e.key == key, str(e)
    assert e.line == line_of(text, needle), str(e)
    assert e.file == str(path)
    assert words in str(e)
    assert str(e) == cli_line
    # The same text given as a string: the same error, read as from `path`.
    with pytest.raises(anholonomy.InputError) as again:
        anholonomy.load(text, path=path)
    assert (again.value.key, again.value.line, str(again.value)) == (e.key, e.line, str(e))


def test_toml_syntax_error_has_its_line(cli):
    text = DISK.replace("friction = 1.0", "friction = = 1.0", 1)
    e, cli_line, _ = errors_of(cli, text)
    assert e.line == line_of(text, "friction = = 1.0")
    assert "TOML syntax" in str(e)
    assert str(e) == cli_line


def test_input_error_from_a_file_names_it(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(DISK.replace("../models/", str(REPO / "models") + "/").replace("dt = 0.001", "dt = nan"))
    with pytest.raises(anholonomy.InputError) as e:
        anholonomy.run(bad)
    assert e.value.file == str(bad)
    assert e.value.key == "sim.dt"
    assert e.value.line == line_of(bad.read_text(), "dt = nan")
    # An InputError is a ValueError, and survives pickling.
    assert isinstance(e.value, ValueError)
    again = pickle.loads(pickle.dumps(e.value))
    assert (again.file, again.line, again.key, str(again)) == (e.value.file, e.value.line, e.value.key, str(e.value))


def test_replace_errors_name_the_key_and_its_line(disk):
    with pytest.raises(anholonomy.InputError) as e:
        disk.replace({"sim.friction": math.nan})
    assert e.value.key == "sim.friction"
    assert e.value.line == line_of(DISK, "friction = 1.0")
    assert "not a finite number" in str(e.value)

    with pytest.raises(anholonomy.InputError) as e:
        disk.replace({"sim.frction": 0.5})
    assert e.value.key == "sim.frction" and "unknown key" in str(e.value)
    # A key the file leaves at its default points at its table.
    assert e.value.line == line_of(DISK, "[sim]")

    with pytest.raises(anholonomy.InputError) as e:
        disk.replace({"goal": [1.0, 2.0]})
    assert e.value.key == "goal" and "expected 4 values" in str(e.value)
    assert e.value.line == line_of(DISK, "goal = [")

    with pytest.raises(anholonomy.InputError) as e:
        disk.replace({"goal[7]": 1.0})
    assert e.value.key == "goal[7]" and "4 elements" in str(e.value)

    with pytest.raises(anholonomy.InputError) as e:
        disk.replace({"sim..dt": 1.0})
    assert e.value.key == "sim..dt" and "not a key path" in str(e.value)

    # A goal the planner cannot reach is bad input too (the plan is made up front).
    with pytest.raises(anholonomy.InputError):
        disk.replace({"sim.dt": 0.5})


def test_bad_arguments(disk, tmp_path):
    with pytest.raises(anholonomy.InputError) as e:
        anholonomy.run(disk, law=lambda t, q: [0.0, 0.0], period=0.0)
    assert e.value.key == "period"
    with pytest.raises(anholonomy.InputError) as e:
        anholonomy.run(disk, law=lambda t, q: [0.0, 0.0])
    assert e.value.key == "period"
    # Numbers as the CLI prints them: 1e300, not 301 digits.
    with pytest.raises(anholonomy.InputError) as e:
        anholonomy.run(disk, law=lambda t, q: [0.0, 0.0], period=0.01, horizon=1e300)
    assert e.value.key == "horizon"
    assert "1e300 s plus sim.settle" in str(e.value) and "0" * 20 not in str(e.value)
    with pytest.raises(anholonomy.InputError) as e:
        disk.replace({"sim.perturb.command_latency": 1e300})
    assert e.value.key == "sim.perturb.command_latency" and "0" * 20 not in str(e.value)
    with pytest.raises(anholonomy.InputError) as e:
        anholonomy.run(disk, pose_rate=-1.0)
    assert e.value.key == "pose_rate"
    afile = tmp_path / "file"
    afile.write_text("")
    with pytest.raises(anholonomy.InputError) as e:
        anholonomy.run(disk, logs=afile)
    assert e.value.file == str(afile)
    with pytest.raises(anholonomy.InputError):
        anholonomy.load(tmp_path / "missing.toml")
    with pytest.raises(TypeError):
        anholonomy.load(42)  # type: ignore[arg-type]
