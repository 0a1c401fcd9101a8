"""Writing a design to disk: the designed model file (edge).

The model a problem file flies (its model file with ``[model_overrides]`` merged in) with
the values the optimiser chose (ocp/design.py), written so that ``lightcraft simulate``
flies it: the craft's launch mass and moments (the rotor's dry values with the liner ring
put back, layout/designed.py), the launch spin, the liner's offset, the carrier's mass
and position, the impulse per pulse, each in SI with the unit in the key
(files/model_edits.py); a designed Rayleigh range goes into a copy of the laser file
beside it. The designed model passes the model's own checks before anything is written.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.files.design_tables import DESIGN_QUANTITY
from lightcraft_opt.files.model_edits import EditedModel
from lightcraft_opt.files.problem import ProblemFile
from lightcraft_opt.files.schema import QUANTITIES
from lightcraft_opt.layout.designed import LAUNCH_SPIN, model_with_parameters
from lightcraft_opt.model import Model
from lightcraft_opt.ocp.result import OcpResult

__all__ = ["DESIGNED_MODEL", "design_summary", "designed_model", "write_designed_model"]

#: The designed model file's name in an optimize run's folder.
DESIGNED_MODEL = "designed_model.toml"

#: Design entry -> (file, table path, SCHEMA table, field) its value is written to.
_WRITTEN: Mapping[str, tuple[str, tuple[str, ...], str, str]] = {
    "rotor_mass_dry": ("model", ("craft",), "craft", "mass"),
    "rotor_axial_inertia_dry": ("model", ("craft",), "craft", "inertia_axial"),
    "rotor_transverse_inertia_dry": ("model", ("craft",), "craft", "inertia_transverse"),
    LAUNCH_SPIN: ("model", ("craft",), "craft", "spin"),
    "liner_offset": ("model", ("craft", "liner"), "liner", "axial_offset"),
    "carrier_mass": ("model", ("craft", "carrier"), "carrier", "mass"),
    "carrier_position_B": ("model", ("craft", "carrier"), "carrier", "position_B"),
    "impulse_per_pulse": ("model", ("flight",), "flight", "impulse_per_pulse"),
    "beam_rayleigh_range": ("laser", (), "laser", "rayleigh_range"),
}


def design_summary(result: OcpResult) -> dict[str, float]:
    """{design variable with its SI unit in the key (``rotor_mass_dry_kg``): value}, for
    summary.json."""
    out = {}
    for label, value in result.design.items():
        kind = DESIGN_QUANTITY[result.design_units[label]]
        si = next(u for u, factor in QUANTITIES[kind].items() if factor == "1")
        out[f"{label}_{si}"] = float(value)
    return out


def designed_model(problem_file: ProblemFile, result: OcpResult) -> Model:
    """The problem's model with the design of ``result`` put in (the model's checks run:
    a ParameterError names the field a design breaks)."""
    layout = problem_file.problem.design_layout
    values = layout.dict_of(np.array([result.design[label] for label in layout.labels]))
    return model_with_parameters(problem_file.problem.model, values)


def _value(model: Model, name: str) -> Any:
    """The designed model's value of the field ``name`` is written to [SI]."""
    craft = model.craft
    match name:
        case "rotor_mass_dry":
            return craft.mass
        case "rotor_axial_inertia_dry":
            return craft.inertia_axial
        case "rotor_transverse_inertia_dry":
            return craft.inertia_transverse
        case "launch_spin":
            return craft.spin
        case "liner_offset":
            assert craft.liner is not None
            return craft.liner.axial_offset
        case "carrier_mass":
            assert craft.carrier is not None
            return craft.carrier.mass
        case "carrier_position_B":
            assert craft.carrier is not None
            return list(craft.carrier.position_B)
        case "impulse_per_pulse":
            return model.flight.impulse_per_pulse
        case _:
            return model.laser.rayleigh_range


def write_designed_model(problem_file: ProblemFile, result: OcpResult, path: Path) -> Path:
    """Write the designed model file ``path`` (module docstring) of ``result``, a solve
    of ``problem_file`` with a design. Returns ``path``."""
    if problem_file.model_file is None:
        raise ValueError("the problem was not read from a file: no model file to start from")
    model = designed_model(problem_file, result)
    source = problem_file.model_file
    edited = EditedModel(source, problem_file.model_tables())
    names = {v.name for v in problem_file.problem.design}
    shown = ", ".join(f"{k} = {v:.6g} {result.design_units[k]}" for k, v in result.design.items())
    header = [
        f"# Designed by lightcraft optimize from {problem_file.source.name} "
        f"({result.status.value}): {shown}",
        f"# The model: {source.name} with the problem's model_overrides and the design.",
        "",
    ]
    for name in sorted(names, key=list(_WRITTEN).index):
        file, where, table, field = _WRITTEN[name]
        edited.put(file, where, table, field, _value(model, name), "designed (lightcraft optimize)")
    if "impulse_per_pulse" in names and model.craft.engine.spent_coupling is not None:
        spent = model.craft.engine.spent_coupling
        where = ("craft", "engine")
        edited.put("model", where, "engine", "spent_coupling", spent, "held at the flight's")
    return edited.write(path, header, "designed")
