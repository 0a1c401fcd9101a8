"""Every example is a test (docs/architecture.md#rule-15): each ```python block of README.md
and docs/*.md runs, in the order written, in one namespace per file, as a reader would type
it at the repository root: from a folder of pytest's that holds the repository's files (by
links, all but runs/), so what an example writes under runs/ starts afresh and lands there.
Quick sizes through LIGHTCRAFT_QUICK where a page has them.
"""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import pytest
from support.paths import REPO_ROOT

matplotlib.use("Agg")

PAGES = [REPO_ROOT / "README.md", *sorted((REPO_ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def python_blocks(page: Path) -> list[str]:
    """The ```python blocks of ``page``, in order."""
    return BLOCK.findall(page.read_text(encoding="utf-8"))


def test_the_pages_have_examples() -> None:
    """The README holds an example per capability: the collector finds them."""
    assert len(python_blocks(REPO_ROOT / "README.md")) >= 3


@pytest.mark.parametrize(
    "page",
    [p for p in PAGES if python_blocks(p)],
    ids=lambda p: str(p.relative_to(REPO_ROOT)),
)
def test_page_examples_run(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    for entry in REPO_ROOT.iterdir():
        if entry.name not in ("runs", ".git"):
            (tmp_path / entry.name).symlink_to(entry, target_is_directory=entry.is_dir())
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("LIGHTCRAFT_QUICK", "1")
    namespace: dict[str, object] = {"__name__": "__docs__"}
    for i, block in enumerate(python_blocks(page)):
        code = compile(block, f"{page.name}, python block {i + 1}", "exec")
        exec(code, namespace)
