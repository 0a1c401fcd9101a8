"""The house rules (docs/architecture.md) as tests: import-linter contracts, ruff and mypy
(pyproject.toml).

The capability order (docs/architecture.md#contracts) is import-linter contracts in
``[tool.importlinter]``; a wrong arrow fails here instead of in review.
``test_contracts_catch_a_wrong_arrow`` checks the contracts are not vacuous by planting
wrong imports in a copy of the package.
"""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "lightcraft_opt"


def _require(module: str) -> None:
    if importlib.util.find_spec(module) is None:
        pytest.skip(f"{module} is not installed (pip install -e '.[test]')")


def _lint_imports() -> list[str]:
    """The ``lint-imports`` console script of this interpreter (not whatever is first on PATH)."""
    _require("importlinter")
    name = "lint-imports.exe" if sys.platform == "win32" else "lint-imports"
    script = Path(sysconfig.get_path("scripts")) / name
    if script.exists():
        return [str(script)]
    found = shutil.which("lint-imports")
    if found is None:
        pytest.skip("import-linter is installed but its lint-imports script is not found")
    return [found]


def _run(cmd: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        cmd, cwd=cwd, capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=120
    )


def _report(proc: subprocess.CompletedProcess[str]) -> str:
    return f"$ {' '.join(proc.args)}\nexit {proc.returncode}\n{proc.stdout}\n{proc.stderr}"


def _assert_clean(proc: subprocess.CompletedProcess[str]) -> None:
    if proc.returncode != 0:
        pytest.fail(_report(proc), pytrace=False)


def test_import_contracts_kept() -> None:
    proc = _run([*_lint_imports(), "--no-cache"], ROOT)
    _assert_clean(proc)
    assert "0 broken" in proc.stdout, _report(proc)


@pytest.mark.parametrize(
    ("where", "line", "broken"),
    [
        ("symbolic/_wrong_arrow.py", "import matplotlib\n", "symbolic/ imports no matplotlib"),
        (
            "symbolic/terms/gravity.py",
            "import lightcraft_opt.symbolic.maps.coast\n",
            "symbolic/: the maps",
        ),
        ("model/craft.py", "import casadi\n", "The vocabulary (errors, model"),
        ("model/checks.py", "import lightcraft_opt.model.craft\n", "model/: the whole over"),
        ("simulation/simulate.py", "import lightcraft_opt.plots\n", "Capabilities point down"),
        ("control/mpc.py", "from lightcraft_opt import cli\n", "Capabilities point down"),
        ("calibration/fit.py", "import lightcraft_opt.campaign.run\n", "Capabilities point down"),
        ("control/mpc.py", "import lightcraft_opt.ocp.solve\n", "Capabilities point down"),
        ("calibration/fit.py", "import lightcraft_opt.control.mpc\n", "Capabilities point down"),
        ("simulation/result.py", "import control\n", "Only linearize.state_space, modes"),
        ("linear/riccati.py", "import control\n", "Only linearize.state_space, modes"),
        ("linearize/stability_grid.py", "import control\n", "Only linearize.state_space, modes"),
        ("control/mpc.py", "import lightcraft_opt.linearize\n", "Capabilities point down"),
        ("_unplaced.py", "import math\n", "Capabilities point down"),
        ("ocp/problem.py", "import lightcraft_opt.ocp.transcription\n", "ocp/: the what"),
        ("control/result.py", "import lightcraft_opt.control.mpc\n", "control/: options and"),
        ("ocp/result.py", "import casadi\n", "numpy-only: no casadi"),
        ("layout/defaults.py", "import casadi\n", "The vocabulary (errors, model"),
        (
            "layout/vectors.py",
            "from lightcraft_opt.layout.defaults import initial_state\n",
            "layout/: the layouts never import",
        ),
        ("layout/vector_layout.py", "import lightcraft_opt.model\n", "A layout knows no model"),
        (
            "compiled/cache/entries.py",
            "import lightcraft_opt.compiled.cache.compiler\n",
            "compiled/cache/: the C compiler",
        ),
        (
            "compiled/cache/functions.py",
            "import lightcraft_opt.compiled.cache.compiler\n",
            "compiled/cache/: the C compiler",
        ),
        (
            "compiled/cache/compiler.py",
            "import lightcraft_opt.symbolic.terms.rcs\n",
            "compiled/cache/ is about",
        ),
        ("compiled/cache/entries.py", "import lightcraft_opt.compiled.memo\n", "compiled/: the"),
        ("compiled/pulse_map.py", "import lightcraft_opt.compiled.memo\n", "compiled/: the"),
        ("symbolic/maps/options.py", "import casadi\n", "numpy-only: no casadi"),
        ("files/outputs.py", "import lightcraft_opt.cli.main\n", "Capabilities point down"),
        ("plots/figures.py", "import lightcraft_opt.files.outputs\n", "Capabilities point down"),
    ],
)
def test_contracts_catch_a_wrong_arrow(tmp_path: Path, where: str, line: str, broken: str) -> None:
    """A copy of the package with one wrong import added breaks the named contract."""
    lint = _lint_imports()
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    shutil.copytree(
        PACKAGE, tmp_path / "lightcraft_opt", ignore=shutil.ignore_patterns("__pycache__")
    )
    target = tmp_path / "lightcraft_opt" / where
    with target.open("a", encoding="utf-8") as f:
        f.write("\n" + line)
    # lint-imports puts its working directory first on sys.path, so it analyses the copy.
    proc = _run([*lint, "--no-cache"], tmp_path)
    assert proc.returncode != 0, _report(proc)
    _, _, broken_section = proc.stdout.partition("Broken contracts")
    assert broken in broken_section, _report(proc)
    module = "lightcraft_opt." + where.removesuffix(".py").replace("/", ".")
    assert module in proc.stdout, f"the copy was not analysed\n{_report(proc)}"


def test_ruff_clean() -> None:
    _require("ruff")
    paths = [p for p in ("lightcraft_opt", "tests", "bench", "docs") if (ROOT / p).exists()]
    proc = _run([sys.executable, "-m", "ruff", "check", "--no-cache", *paths], ROOT)
    _assert_clean(proc)


def test_mypy_clean() -> None:
    _require("mypy")
    proc = _run([sys.executable, "-m", "mypy"], ROOT)  # packages and flags: [tool.mypy]
    _assert_clean(proc)



#: A module may pass this many lines only with a reason in its docstring (rule 11).
MAX_LINES = 700
#: The words that give the reason, in the module docstring.
LONG_REASON = "over 700 lines because"


def _long_without_reason(text: str) -> bool:
    """Whether a module's source is over :data:`MAX_LINES` lines with no reason given."""
    import ast

    doc = ast.get_docstring(ast.parse(text)) or ""
    return text.count("\n") > MAX_LINES and LONG_REASON not in doc.lower()


def test_no_module_passes_700_lines_without_a_reason() -> None:
    """docs/architecture.md#rule-11: aim under 400 lines, never over 700 without saying why
    (``Over 700 lines because ...`` in the module docstring)."""
    long = [
        f"{path.relative_to(ROOT)}: {path.read_text(encoding='utf-8').count(chr(10))} lines"
        for path in sorted(PACKAGE.rglob("*.py"))
        if _long_without_reason(path.read_text(encoding="utf-8"))
    ]
    assert not long, "modules over 700 lines without a reason: " + ", ".join(long)


def test_the_line_rule_bites() -> None:
    """701 lines fail the rule, 700 pass, and a reason in the docstring passes 701."""
    short = '"""A module."""\n' + "x = 1\n" * (MAX_LINES - 1)
    long = short + "x = 1\n"
    reason = long.replace("A module.", "Over 700 lines because: one table.")
    assert not _long_without_reason(short)
    assert _long_without_reason(long)
    assert not _long_without_reason(reason)
