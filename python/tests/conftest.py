"""Shared fixtures: the project's root (scenario files, robots) and the hexsim binary, for the
round trips against the command line."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def hexsim_bin():
    """The command-line hexsim of this checkout (built if missing): $HEXSIM_BIN, else
    target/release/hexsim."""
    path = os.environ.get("HEXSIM_BIN") or str(ROOT / "target" / "release" / "hexsim")
    if not os.path.exists(path):
        subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
    return path
