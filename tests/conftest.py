"""Shared fixtures; the helpers they use live in the importable ``support`` package.

The suite steps the interpreted Φ unless a test asks for the compiled one
(``LIGHTCRAFT_COMPILE=0`` below): each model structure would cost a 10-20 s gcc run in a
clean CI cache, and most tests fly structures of their own. tests/test_compiled.py checks
the compiled path and that the two agree to round-off.
"""

from __future__ import annotations

import os

import pytest
from support.models import table1_flight5

from lightcraft_opt.model import Model

os.environ.setdefault("LIGHTCRAFT_COMPILE", "0")


@pytest.fixture
def flight5() -> Model:
    return table1_flight5()
