"""Shared fixtures; the helpers they use live in the importable ``support`` package."""

from __future__ import annotations

import pytest
from support.models import table1_flight5

from lightcraft_opt.params import Model


@pytest.fixture
def flight5() -> Model:
    return table1_flight5()
