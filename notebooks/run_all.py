"""Rebuild every notebook from its jupytext twin and execute it, outputs included.

    python notebooks/run_all.py               # all notebooks, quick size (about 3 min)
    python notebooks/run_all.py monte_carlo   # one notebook
    LIGHTCRAFT_FULL=1 python notebooks/run_all.py   # full size (tens of minutes)

The ``.py`` twin (jupytext percent format) is the source: each ``notebooks/<name>.ipynb`` is
rebuilt from it, executed from ``notebooks/`` (as Jupyter opened there runs it) and written
back with its outputs, so a reader on a forge sees the figures. Needs the ``notebooks`` or
``test`` extra (jupytext, nbclient, ipykernel). A cell that raises stops the run with its
traceback and leaves that ``.ipynb`` untouched.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import jupytext
import nbformat
from nbclient import NotebookClient

HERE = Path(__file__).resolve().parent
CELL_TIMEOUT_S = 3600


def run(twin: Path) -> Path:
    """Execute ``twin`` (a jupytext .py) from ``notebooks/`` and write its .ipynb."""
    nb = jupytext.read(twin)
    nb.metadata["jupytext"] = {"formats": "ipynb,py:percent"}
    client = NotebookClient(
        nb,
        timeout=CELL_TIMEOUT_S,
        kernel_name="python3",
        resources={"metadata": {"path": str(HERE)}},
    )
    client.execute()
    path = twin.with_suffix(".ipynb")
    nbformat.write(nb, path)
    return path


def main(names: list[str]) -> int:
    twins = [HERE / f"{n}.py" for n in names] or sorted(
        p for p in HERE.glob("*.py") if p.with_suffix(".ipynb").exists()
    )
    for twin in twins:
        start = time.perf_counter()
        path = run(twin)
        print(f"{path.name}: {time.perf_counter() - start:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
