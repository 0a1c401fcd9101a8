"""The public API (docs/architecture.md#rule-14): every name a package exports is the object
it names, and importing the package does not pay for python-control."""

from __future__ import annotations

import importlib
import inspect
import subprocess
import sys

import pytest

PACKAGES = [
    "lightcraft_opt",
    "lightcraft_opt.simulation",
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
    """A lazily loaded name that is also a submodule's name (closed_loop, simulate, solve)
    must still give the function, however the submodule was imported."""
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


def test_importing_the_package_leaves_python_control_unloaded() -> None:
    """python-control loads with the controllers and linearize/, not with the package."""
    code = (
        "import sys, lightcraft_opt, lightcraft_opt.files, lightcraft_opt.campaign;"
        "print('control' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == "False"


def test_every_result_type_summarises_plots_and_saves_itself() -> None:
    """Each result type has summary(), plot() and save() (issue 19), its plot and save
    registered by lightcraft_opt/outputs.py when the package is imported, and
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
