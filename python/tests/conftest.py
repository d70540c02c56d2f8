"""Shared fixtures: the repository's scenarios and the CLI built beside the
package (`cargo test --release` builds it; else it is built here)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = REPO / "scenarios"


def cli_path() -> Path:
    """The `anholonomy` binary: $ANHOLONOMY_BIN, else target/release/, built
    if missing (the same workspace target/ the package was built in)."""
    env = os.environ.get("ANHOLONOMY_BIN")
    if env:
        return Path(env)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    binary = target / "release" / "anholonomy"
    if not binary.exists():
        subprocess.run(
            ["cargo", "build", "--release", "--locked", "--bin", "anholonomy"],
            cwd=REPO,
            check=True,
        )
    return binary


@pytest.fixture(scope="session")
def cli() -> Path:
    return cli_path()


@pytest.fixture(scope="session")
def disk():
    import anholonomy

    return anholonomy.load(SCENARIOS / "disk_paper.toml")
