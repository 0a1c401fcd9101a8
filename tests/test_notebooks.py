"""Every notebook runs headless, in its quick size (docs/architecture.md#rule-13).

Each ``notebooks/<name>.ipynb`` has a jupytext twin ``notebooks/<name>.py`` (percent
format), the form reviewed in diffs; the test checks that both hold the same cells and
that the committed notebook carries its outputs (figures included: what a reader on a
forge sees; ``python notebooks/run_all.py`` makes them), then executes the notebook from
``notebooks/``, as Jupyter opened there runs it: the notebooks find the repository root
themselves. Notebooks run their quick size unless ``LIGHTCRAFT_FULL=1``, which the test
removes. A cell that raises fails the test with the cell's traceback.
"""

from __future__ import annotations

from pathlib import Path

import jupytext
import nbformat
import pytest
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
CELL_TIMEOUT_S = 600


def _sources(nb: nbformat.NotebookNode) -> list[tuple[str, str]]:
    return [(c.cell_type, c.source.strip()) for c in nb.cells if c.source.strip()]


def test_there_are_notebooks():
    assert NOTEBOOKS, "notebooks/ holds no .ipynb"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_matches_its_jupytext_twin(path: Path):
    twin = path.with_suffix(".py")
    assert twin.exists(), f"{path.name} has no jupytext twin {twin.name}"
    nb = nbformat.read(path, as_version=4)
    py = jupytext.read(twin)
    assert _sources(nb) == _sources(py), (
        f"{path.name} and {twin.name} differ: regenerate with `jupytext --to ipynb {twin}`"
    )


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_is_committed_with_its_outputs(path: Path):
    nb = nbformat.read(path, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(c.get("execution_count") for c in code), (
        f"{path.name} has cells never run: `python notebooks/run_all.py {path.stem}`"
    )
    outputs = [o for c in code for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    assert any("image/png" in o.get("data", {}) for o in outputs), f"{path.name}: no figure"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs_in_its_quick_size(path: Path, tmp_path: Path, monkeypatch):
    monkeypatch.delenv("LIGHTCRAFT_FULL", raising=False)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("LIGHTCRAFT_NOTEBOOK_OUT", str(tmp_path))
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(
        nb,
        timeout=CELL_TIMEOUT_S,
        kernel_name="python3",
        resources={"metadata": {"path": str(ROOT / "notebooks")}},
    )
    client.execute()
    errors = [
        o
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.get("outputs", [])
        if o.get("output_type") == "error"
    ]
    assert not errors
