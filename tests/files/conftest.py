"""Fixtures shared by the tests of result files: Flight 5 and a short flight of it."""

from __future__ import annotations

import pytest
from support.paths import REPO_ROOT

import lightcraft_opt as lc


@pytest.fixture(scope="module")
def model() -> lc.Model:
    """models/flight5.toml."""
    return lc.load_model(REPO_ROOT / "models" / "flight5.toml")


@pytest.fixture(scope="module")
def flight(model: lc.Model) -> lc.SimulationResult:
    """0.3 s of Flight 5, a pulse in five dropped (seed 1 drops pulse 1: a NaN beam gap in
    pulses.csv)."""
    return lc.simulate(model, 0.3, compiled=False, dropout_rate=0.2, seed=1)
