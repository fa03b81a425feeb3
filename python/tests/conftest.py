"""Shared fixtures: the repository's examples and the command line to compare with."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"
SLABS = EXAMPLES / "sticky_slabs.toml"


def cli_path() -> Path:
    """The `sticky-lips` binary: $STICKY_LIPS_BIN, else the test build's."""
    return Path(os.environ.get("STICKY_LIPS_BIN", REPO / "target" / "debug" / "sticky-lips"))


@pytest.fixture(scope="session")
def cli() -> Path:
    """The command line; a test needing it is skipped, loudly, where it is not built, unless
    STICKY_LIPS_BIN names it (scripts/test.sh does): then a missing binary fails."""
    path = cli_path()
    if not path.is_file():
        if "STICKY_LIPS_BIN" in os.environ:
            pytest.fail(f"STICKY_LIPS_BIN={path} does not exist")
        pytest.skip(
            f"SKIPPED: no sticky-lips binary at {path} (cargo build -p sticky-lips-cli, or set STICKY_LIPS_BIN)"
        )
    return path


@pytest.fixture(scope="session")
def run_cli(cli: Path):
    """A function running the command line from the repository's root, returning its stdout."""

    def run(*args: str) -> str:
        done = subprocess.run(
            [str(cli), *args], cwd=REPO, capture_output=True, text=True, check=False
        )
        assert done.returncode == 0, f"sticky-lips {' '.join(args)}: {done.stderr}"
        return done.stdout

    return run


@pytest.fixture(scope="session")
def repo() -> Path:
    """The repository's root."""
    return REPO
