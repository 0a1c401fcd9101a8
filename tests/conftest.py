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


#: The suite's heaviest modules, heaviest first (seconds of one worker, `pytest --durations`
#: on a clean clone, 2026-12-07: 253, 164, 142, 93, 87, 71). Collected first, so that the
#: two workers (``--dist loadscope``: a module stays on one worker) start them early and the
#: light modules fill the end, instead of one worker running a notebook alone at the end.
HEAVIEST_FIRST = (
    "test_notebooks.py",
    "ocp/test_beam_tracking_focus.py",
    "test_docs_examples.py",
    "ocp/test_ocp_crosswind.py",
    "files/test_controller_export.py",
    "test_readme_commands.py",
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Put the modules of :data:`HEAVIEST_FIRST` first, in its order; the rest as collected."""

    def rank(item: pytest.Item) -> int:
        path = item.path.as_posix()
        heavy = [i for i, name in enumerate(HEAVIEST_FIRST) if path.endswith("tests/" + name)]
        return heavy[0] if heavy else len(HEAVIEST_FIRST)

    items.sort(key=rank)
