"""The fit-parameter catalogue of a calibration: what each ``--fit`` name selects, its SI
unit, default bounds and scale (docs/calibration.md). How each one enters the flight is
:func:`lightcraft_opt.calibration.problem.apply_fit`; where it is written in a model file,
:data:`lightcraft_opt.files.calibration_outputs.MODEL_KEYS`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from lightcraft_opt.errors import ParameterError

__all__ = ["FIT_GROUPS", "FORMER_NAMES", "FitComponent", "fit_components"]


@dataclass(frozen=True)
class FitComponent:
    """One scalar that a calibration can fit.

    Attributes
    ----------
    name : its name in results and reports (``cm``, ``launch_offset_x`` ...).
    group : the ``--fit`` name that selects it (``offset`` selects two components).
    unit : SI unit of its value.
    lower, upper : default bounds (physically meaningful) [unit].
    scale : typical size of a change [unit]: the fit works in θ / scale, and the
        identifiability test compares a standard deviation with max(|value|, scale).
    target : the PARAMETERS slot it sets, or ``"x0"`` for the initial state.
    description : what it is, one line.
    """

    name: str
    group: str
    unit: str
    lower: float
    upper: float
    scale: float
    target: str
    description: str


def _c(
    name: str,
    group: str,
    unit: str,
    bounds: tuple[float, float],
    scale: float,
    target: str,
    text: str,
) -> FitComponent:
    return FitComponent(name, group, unit, bounds[0], bounds[1], scale, target, text)


_PI = math.pi
#: ``--fit`` name -> the components it selects, in order.
FIT_GROUPS: dict[str, tuple[FitComponent, ...]] = {
    "cm": (
        _c(
            "cm",
            "cm",
            "N s/J",
            (1e-6, 1e-3),
            1e-5,
            "impulse_per_pulse",
            "coupling coefficient: impulse_per_pulse / reference_pulse_energy",
        ),
    ),
    "overheating": (
        _c(
            "health_pulse",
            "overheating",
            "-",
            (1.0, 1e4),
            10.0,
            "health_pulse",
            "pulse number of the air-mode overheating step",
        ),
        _c(
            "health_floor",
            "overheating",
            "-",
            (0.0, 1.0),
            0.1,
            "health_floor",
            "thrust fraction left once the engine has overheated",
        ),
    ),
    "divergence": (
        _c(
            "divergence",
            "divergence",
            "rad",
            (0.0, 0.1),
            1e-3,
            "beam_divergence",
            "full-angle growth of the beam side with range (linear size model)",
        ),
    ),
    "blast_angle": (
        _c(
            "blast_angle",
            "blast_angle",
            "rad",
            (-1.5, 1.5),
            0.05,
            "blast_angle",
            "radial tilt of each sector's reaction (sector impulse model)",
        ),
    ),
    "lateral_gain": (
        _c(
            "lateral_gain",
            "lateral_gain",
            "-",
            (-5.0, 5.0),
            0.05,
            "lateral_gain",
            "restoring lateral impulse gain k_L (kernel impulse model)",
        ),
    ),
    "tipping_gain": (
        _c(
            "tipping_gain",
            "tipping_gain",
            "-",
            (-5.0, 5.0),
            0.05,
            "tipping_gain",
            "tipping angular impulse gain k_M (kernel impulse model)",
        ),
    ),
    "offset": (
        _c(
            "launch_offset_x",
            "offset",
            "m",
            (-0.5, 0.5),
            0.01,
            "x0",
            "initial position of the mass centre along L x (east of the pad)",
        ),
        _c(
            "launch_offset_y",
            "offset",
            "m",
            (-0.5, 0.5),
            0.01,
            "x0",
            "initial position of the mass centre along L y (north of the pad)",
        ),
    ),
    "tilt": (
        _c(
            "launch_tilt_x",
            "tilt",
            "rad",
            (-0.5, 0.5),
            0.01,
            "x0",
            "initial lean of the axis b1 toward +x (east): rotation about L y",
        ),
        _c(
            "launch_tilt_y",
            "tilt",
            "rad",
            (-0.5, 0.5),
            0.01,
            "x0",
            "initial lean of the axis b1 toward +y (north): rotation about L -x",
        ),
    ),
    "wind": (
        _c(
            "wind_speed",
            "wind",
            "m/s",
            (0.0, 30.0),
            0.5,
            "wind_speed_ref",
            "mean wind speed at the reference height",
        ),
        _c(
            "wind_direction",
            "wind",
            "rad",
            (-4 * _PI, 4 * _PI),
            0.2,
            "wind_direction_from",
            "direction the wind blows from, clockwise from north (undefined in calm air)",
        ),
    ),
    "cd": (
        _c("cd_scale", "cd", "-", (0.0, 5.0), 0.1, "cd_scale", "factor on the drag coefficient"),
    ),
}


#: Components renamed (issue 19: one name per quantity across outputs; L components are
#: x, y, z as in docs/outputs.md): old name -> new name, refused with the new one.
FORMER_NAMES: dict[str, str] = {
    "offset_east": "launch_offset_x",
    "offset_north": "launch_offset_y",
    "tilt_east": "launch_tilt_x",
    "tilt_north": "launch_tilt_y",
}


def fit_components(fit: Sequence[str]) -> tuple[FitComponent, ...]:
    """The components selected by the ``--fit`` names ``fit`` (each once, in order).

    Raises
    ------
    ParameterError
        ``fit``: empty, an unknown name (the allowed names listed) or a repeated one.
    """
    if isinstance(fit, str):
        fit = [f for f in fit.split(",") if f.strip()]
    names = [str(f).strip() for f in fit]
    if not names:
        raise ParameterError("fit", f"name at least one of {sorted(FIT_GROUPS)}")
    unknown = [n for n in names if n not in FIT_GROUPS]
    if unknown:
        raise ParameterError(
            "fit", f"unknown fit parameter(s) {unknown}; allowed: {', '.join(FIT_GROUPS)}"
        )
    if len(set(names)) != len(names):
        raise ParameterError("fit", f"names a parameter twice: {names}")
    return tuple(c for n in names for c in FIT_GROUPS[n])
