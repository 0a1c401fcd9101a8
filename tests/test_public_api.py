"""The public API (docs/architecture.md#rule-14): every name a package exports is the object
it names, and importing the package or its controllers does not pay for python-control."""

from __future__ import annotations

import importlib
import inspect
import subprocess
import sys

import pytest

PACKAGES = [
    "lightcraft_opt",
    "lightcraft_opt.simulation",
    "lightcraft_opt.linear",
    "lightcraft_opt.linearize",
    "lightcraft_opt.ocp",
    "lightcraft_opt.control",
    "lightcraft_opt.calibration",
    "lightcraft_opt.campaign",
    "lightcraft_opt.files",
    "lightcraft_opt.layout",
    "lightcraft_opt.model",
]
#: Exported names that are packages on purpose.
PACKAGE_NAMES = {"lightcraft_opt": {"control", "linearize"}}


@pytest.mark.parametrize("package", PACKAGES)
def test_exported_names_are_the_objects_not_their_modules(package: str) -> None:
    """A name that is also a submodule's name (closed_loop, simulate, solve) must still
    give the function, however the submodule was imported."""
    importlib.import_module("lightcraft_opt.campaign.run")  # imports control.closed_loop
    mod = importlib.import_module(package)
    for name in mod.__all__:
        obj = getattr(mod, name)
        if name in PACKAGE_NAMES.get(package, set()):
            assert inspect.ismodule(obj), f"{package}.{name}"
        else:
            assert not inspect.ismodule(obj), f"{package}.{name} is a module: {obj!r}"


def test_the_readme_names_are_reachable_from_the_package() -> None:
    lc = importlib.import_module("lightcraft_opt")
    for name in ("build_pulse_map", "CompiledOcp", "OcpProblem", "MpcController", "linearize"):
        assert name in lc.__all__ and getattr(lc, name) is not None
    loop_module = importlib.import_module("lightcraft_opt.control.closed_loop")
    assert lc.closed_loop is loop_module.closed_loop


#: Everything that flies a controller: none of it may load python-control (module ``control``).
WITHOUT_PYTHON_CONTROL = (
    "lightcraft_opt",
    "lightcraft_opt.files",
    "lightcraft_opt.linear",
    "lightcraft_opt.control",
    "lightcraft_opt.control.controllers",
    "lightcraft_opt.control.prediction_model",
    "lightcraft_opt.control.mpc",
    "lightcraft_opt.control.director",
    "lightcraft_opt.control.closed_loop",
    "lightcraft_opt.control.factory",
    "lightcraft_opt.ocp.start",
    "lightcraft_opt.campaign",
    "lightcraft_opt.campaign.run",
    "lightcraft_opt.cli",
    "lightcraft_opt.cli.main",
)


def _fresh(code: str) -> str:
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    return out.stdout.strip()


def test_the_package_and_its_controllers_leave_python_control_unloaded() -> None:
    """In a fresh interpreter: the package, the controllers, the MPC, the director, the
    closed loop and the campaigns import without python-control (it takes seconds); only
    ``lc.linearize``, the one name loaded on first use, brings it in."""
    imports = "; ".join(f"import {name}" for name in WITHOUT_PYTHON_CONTROL)
    assert _fresh(f"import sys; {imports}; print('control' in sys.modules)") == "False"
    code = "import sys, lightcraft_opt as lc; lc.linearize.lqr; print('control' in sys.modules)"
    assert _fresh(code) == "True"


def test_every_result_type_summarises_plots_and_saves_itself() -> None:
    """Each result type has summary(), plot() and save() (issue 19), its plot and save
    registered by lightcraft_opt/files/outputs.py when the package is imported, and
    load_result reads a folder back."""
    lc = importlib.import_module("lightcraft_opt")
    presenters = importlib.import_module("lightcraft_opt.presenters")
    kinds = ("SimulationResult", "OcpResult", "ClosedLoopResult", "CalibrationResult")
    for cls in (*(getattr(lc, k) for k in kinds), lc.CampaignResult):
        for method in ("summary", "plot", "save"):
            assert callable(getattr(cls, method, None)), f"{cls.__name__}.{method}"
        assert cls in presenters._REGISTRY, cls
        assert "__repr__" in vars(cls), f"{cls.__name__} keeps the dataclass repr"
    assert "load_result" in lc.__all__
    assert lc.load_result is importlib.import_module("lightcraft_opt.files").load_result
