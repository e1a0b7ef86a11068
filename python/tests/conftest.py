"""Shared records of the tests: small simulated ones (fast), and the paper's data set when the
shared data sit beside the repository (as `cargo xtask reproduce` finds them)."""

from __future__ import annotations

import os
import pathlib

import pytest

import hbid

REPO = pathlib.Path(__file__).resolve().parents[2]
PAPER = REPO.parent / "shared" / "fixtures" / "paper_dataset.csv"


@pytest.fixture(scope="session")
def pendulum() -> hbid.Simulation:
    """The paper's pendulum, 3000 samples (120 forcing periods) after 200 periods."""
    return hbid.simulate(samples=3000)


@pytest.fixture(scope="session")
def paper_csv() -> pathlib.Path:
    if not PAPER.is_file():
        pytest.skip(f"the paper's data set is not at {PAPER}")
    return PAPER


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    """The command line `hbid` built by `cargo test` or `cargo build` (for comparisons)."""
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for profile in ("debug", "release"):
        exe = target / profile / "hbid"
        if exe.is_file():
            return exe
    pytest.skip(f"no hbid binary under {target}: build it with `cargo build -p hbid`")
