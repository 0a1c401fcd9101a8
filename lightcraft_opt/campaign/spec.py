"""What a Monte Carlo campaign flies, before its draws: the spec every run starts from, and
the columns of its run table (SI, the unit in the column name)."""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from lightcraft_opt.campaign.dispersions import Dispersions
from lightcraft_opt.control.estimation.sensor_options import SensorOptions
from lightcraft_opt.control.options import (
    ClosedLoopOptions,
    ControllerKind,
    DirectorOptions,
    EstimatorKind,
    EstimatorSpec,
    MpcOptions,
)
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import STATE, initial_state
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import checked_duration, checked_vector

__all__ = [
    "DISPERSED_PARAMETER",
    "INTEGER_OUTPUTS",
    "OUTPUT_COLUMNS",
    "TEXT_OUTPUTS",
    "TIMING_COLUMNS",
    "Campaign",
]

#: Outputs of a run, after its index and drawn inputs (SI but angles, in degrees); the
#: estimate's columns are NaN in a run told the truth.
OUTPUT_COLUMNS = (
    "status",
    "message",
    "apogee_m",
    "apogee_time_s",
    "flight_time_s",
    "final_x_m",
    "final_y_m",
    "final_z_m",
    "landing_x_m",
    "landing_y_m",
    "left_beam",
    "pulses_commanded",
    "pulses_fired",
    "pulses_dropped",
    "max_tilt_deg",
    "max_coning_deg",
    "final_coning_deg",
    "max_offset_m",
    "rcs_used_kg",
    "fallbacks",
    "iterations_total",
    "iterations_max",
    "estimate_position_rms_m",
    "estimate_position_nees",
)
#: Outputs written as integers (-1 in an error row), and as text; the others are floats,
#: NaN where a run has no value (an error row; a landing point of a run that did not land).
INTEGER_OUTPUTS = frozenset(
    (
        "left_beam",
        "pulses_commanded",
        "pulses_fired",
        "pulses_dropped",
        "fallbacks",
        "iterations_total",
        "iterations_max",
    )
)
TEXT_OUTPUTS = frozenset(("status", "message"))
#: Wall-clock columns of timings.csv (machine-dependent, never in the run table).
TIMING_COLUMNS = (
    "run",
    "wall_s",
    "solve_time_median_s",
    "solve_time_p99_s",
    "solve_time_max_s",
    "solve_time_total_s",
)
#: The PARAMETERS slot of each dispersed quantity that is a model parameter.
DISPERSED_PARAMETER = {
    "mass": "rotor_mass_dry",
    "inertia_axial": "rotor_axial_inertia_dry",
    "inertia_transverse": "rotor_transverse_inertia_dry",
    "coupling": "impulse_per_pulse",
    "wind_speed": "wind_speed_ref",
    "wind_direction_from": "wind_direction_from",
}


@dataclass(frozen=True, eq=False)
class Campaign:
    """What every run of a campaign flies, before its draws (SI).

    Attributes
    ----------
    model : the controller's model; the plant's before the campaign's draws.
    duration : of each flight [s].
    controller : who flies the runs (:class:`~lightcraft_opt.control.options.ControllerKind`;
        ``NONE``, the default, the open loop).
    x0 : (STATE.size,) state at the first pulse (default: on the pad, upright).
    mpc : the MPC's options (the LQR takes their weights); runs fly them without a
        wall-clock budget (``time_budget=None``, the deterministic mode).
    director : the director's options (with the MPC's for the RCS of a craft that has
        one); runs fly them without a wall-clock budget, as the MPC's.
    loop : the closed loop's noise, relative dispersion, drop-outs and injected faults;
        its ``seed`` is replaced by each run's (:func:`.dispersions.loop_seed`).
    plant_parameters : {PARAMETERS slot: value} the plant has and the controller does not
        (its wind), before the draws.
    dispersions : what each run draws (:class:`~lightcraft_opt.campaign.dispersions.Dispersions`).
    compiled : fly the plant Φ compiled to C (compiled/; cached on disk): True, False,
        or None (default) for compiled unless ``LIGHTCRAFT_COMPILE=0``.
    title : a name for reports.
    estimator : what tells the controller the state in every run (the file's
        ``[estimator]``; default the truth with the loop's noise).
    sensors : what that estimator reads (the file's ``[sensors]``; None: the default
        camera, or nothing with the truth).
    """

    model: Model
    duration: float
    controller: ControllerKind = ControllerKind.NONE
    x0: np.ndarray | None = None
    mpc: MpcOptions = field(default_factory=MpcOptions)
    director: DirectorOptions = field(default_factory=DirectorOptions)
    loop: ClosedLoopOptions = field(default_factory=ClosedLoopOptions)
    plant_parameters: Mapping[str, Any] = field(default_factory=dict)
    dispersions: Dispersions = field(default_factory=Dispersions)
    compiled: bool | None = None
    title: str = "campaign"
    estimator: EstimatorSpec = field(default_factory=EstimatorSpec)
    sensors: SensorOptions | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "duration", checked_duration(self.duration))
        if not isinstance(self.controller, ControllerKind):
            allowed = [c.value for c in ControllerKind]
            raise ParameterError("controller", f"must be one of {allowed}, got {self.controller!r}")
        if not isinstance(self.dispersions, Dispersions):
            raise ParameterError("dispersions", f"must be Dispersions, got {self.dispersions!r}")
        if not isinstance(self.estimator, EstimatorSpec):
            raise ParameterError("estimator", f"must be an EstimatorSpec, got {self.estimator!r}")
        x0 = initial_state(self.model) if self.x0 is None else self.x0
        object.__setattr__(self, "x0", checked_vector("x0", x0, STATE.size).copy())

    @cached_property
    def fingerprint(self) -> str:
        """sha256 of everything a run depends on (not the title): equal fingerprints fly
        equal runs."""
        p = {k: np.ravel(v).tolist() for k, v in sorted(self.plant_parameters.items())}
        parts: tuple[str, ...] = (
            repr(self.model),
            repr(float(self.duration)),
            self.controller.value,
            repr(np.asarray(self.x0).tolist()),
            repr(self.mpc),
            repr(self.director),
            repr(self.loop),
            repr(p),
            repr(self.dispersions),
            repr(self.compiled),
        )
        if self.estimator.kind is not EstimatorKind.TRUTH:  # the truth's: as before it
            parts += (repr(self.estimator), repr(self.sensors))
        return hashlib.sha256("\0".join(parts).encode()).hexdigest()

    @property
    def input_columns(self) -> tuple[str, ...]:
        """Columns of the drawn inputs, then the run's closed-loop seed."""
        return (*self.dispersions.columns, "loop_seed")

    @property
    def columns(self) -> tuple[str, ...]:
        """The run table's header."""
        return ("run", *self.input_columns, *OUTPUT_COLUMNS)
