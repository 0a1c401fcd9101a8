"""One run of a Monte Carlo campaign: the campaign spec (:mod:`.spec`) and an index in, a
table row out.

:func:`run_one` is the picklable, top-level function every engine calls (in this process,
in worker processes, on Dask workers). It draws the run's values
(:func:`~lightcraft_opt.campaign.dispersions.draw`), applies them to the plant's parameters, the
initial state and the drop-out rate, flies :func:`~lightcraft_opt.control.closed_loop.closed_loop`
under the campaign's controller (built by control/factory.py; "none" is the open loop: the
nominal input every pulse), told the state by the campaign's estimator when it names one
and returns the row of the run table (inputs and outputs, SI, unit in the column name) and
a row of wall-clock timings, kept apart so that tables can be compared bit for bit.
:func:`row_problem` checks a row read back from a resumed table against what run_one
writes: a row it refuses is flown again (run_table.py).

The plant Φ and the controller are built once per process and thread (keyed by the
campaign's fingerprint), not per run. Determinism: a wall-clock ``time_budget`` (a
real-time study) would discard solves that overrun it and make a run depend on the
machine's load; campaign runs fly the deterministic mode even where the file sets one
(``time_budget=None``, the controllers' default: a solve is never late, injected ``late``
faults still are), so a run depends only on (campaign, seed, index). A run that raises is
a row with status ``error`` and the message.
"""

from __future__ import annotations

import dataclasses
import math
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from lightcraft_opt.campaign.dispersions import column_value, draw, loop_seed
from lightcraft_opt.campaign.spec import (
    DISPERSED_PARAMETER,
    INTEGER_OUTPUTS,
    OUTPUT_COLUMNS,
    TEXT_OUTPUTS,
    Campaign,
)
from lightcraft_opt.compiled import pulse_map_for
from lightcraft_opt.control.closed_loop import closed_loop, plant_options
from lightcraft_opt.control.controllers import Controller
from lightcraft_opt.control.estimation import Estimator, SensorSuite
from lightcraft_opt.control.factory import build_controller, build_tracker
from lightcraft_opt.control.result import ClosedLoopResult
from lightcraft_opt.layout import (
    STATE,
    parameter_values,
    tilted_attitude,
)
from lightcraft_opt.simulation.result import SimulationStatus
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["RunOutcome", "flight_outputs", "row_problem", "run_one"]

_MAX_DROPOUT = 0.99
#: The statuses a row may hold.
_STATUSES = frozenset({*(s.value for s in SimulationStatus), "error"})


@dataclass(frozen=True)
class RunOutcome:
    """Run ``index``'s row of the run table and of the timings ({column: value})."""

    index: int
    row: dict[str, Any]
    timing: dict[str, Any]


def run_one(campaign: Campaign, seed: int, index: int) -> RunOutcome:
    """Fly run ``index`` of ``campaign`` seeded ``seed`` (module docstring); never raises
    for a failing run: its row has status ``error`` and the exception's message."""
    draws = draw(campaign.dispersions, seed, index)
    names = zip(campaign.dispersions.names, campaign.dispersions.columns, strict=True)
    inputs: dict[str, Any] = {col: column_value(name, draws[name]) for name, col in names}
    inputs["loop_seed"] = loop_seed(seed, index)
    start = time.perf_counter()
    try:
        flyer = _flyer(campaign)  # built once per process and thread: not the run's time
        start = time.perf_counter()
        result = flyer.fly(draws, inputs["loop_seed"])
        outputs = flight_outputs(result)
        solve = result.log.solve_time
    except Exception as err:  # a run's failure is a row, not a crashed campaign
        outputs = {c: math.nan for c in OUTPUT_COLUMNS}
        outputs.update(status="error", message=f"{type(err).__name__}: {err}")
        for c in ("left_beam", "pulses_commanded", "pulses_fired", "pulses_dropped", "fallbacks"):
            outputs[c] = -1
        outputs["iterations_total"] = outputs["iterations_max"] = -1
        solve = np.empty(0)
    wall = time.perf_counter() - start
    nan = math.nan
    timing = {
        "run": index,
        "wall_s": wall,
        "solve_time_median_s": float(np.median(solve)) if solve.size else nan,
        "solve_time_p99_s": float(np.percentile(solve, 99)) if solve.size else nan,
        "solve_time_max_s": float(np.max(solve)) if solve.size else nan,
        "solve_time_total_s": float(np.sum(solve)),
    }
    return RunOutcome(index, {"run": index, **inputs, **outputs}, timing)


def row_problem(campaign: Campaign, seed: int, row: Mapping[str, str]) -> str | None:
    """Why ``row`` ({column: text as written}, with a run index) cannot be run
    ``row["run"]``'s row of ``campaign`` seeded ``seed``, or None: a drawn input that is
    not a finite number or not the run's draw, a loop seed that is not the run's, an
    unknown status, an integer output that is not an integer, a float output that is not
    a number (NaN is one). Numbers must be spelt as run_one's table writes them
    (``repr``): ``1.50`` or ``1_5`` is refused too."""
    index = int(row["run"])
    draws = draw(campaign.dispersions, seed, index)
    for name, column in zip(campaign.dispersions.names, campaign.dispersions.columns, strict=True):
        text = row[column]
        value = _float(text)
        if value is None or not math.isfinite(value):
            return f"{column}: {text!r} is not a finite number"
        if value != column_value(name, draws[name]):
            return f"{column}: {text} is not run {index}'s draw {column_value(name, draws[name])!r}"
    if row["loop_seed"] != str(loop_seed(seed, index)):
        return f"loop_seed: {row['loop_seed']!r} is not run {index}'s {loop_seed(seed, index)}"
    for column in OUTPUT_COLUMNS:
        text = row[column]
        if column == "status" and text not in _STATUSES:
            return f"status: {text!r} is not one of {sorted(_STATUSES)}"
        if column in INTEGER_OUTPUTS and not _is_integer(text):
            return f"{column}: {text!r} is not an integer"
        if column not in INTEGER_OUTPUTS | TEXT_OUTPUTS and _float(text) is None:
            return f"{column}: {text!r} is not a number"
    return None


def _is_integer(text: str) -> bool:
    try:
        return str(int(text)) == text
    except ValueError:
        return False


def _float(text: str) -> float | None:
    """The float ``text`` is as a run writes it (``repr``: the one spelling), else None."""
    try:
        value = float(text)
    except ValueError:
        return None
    return value if repr(value) == text else None


def flight_outputs(result: ClosedLoopResult) -> dict[str, Any]:
    """A run's :data:`~lightcraft_opt.campaign.spec.OUTPUT_COLUMNS` from its closed loop
    (the result's own properties: the same figures as its summary.json)."""
    flight = result.flight
    r = flight.state("r_L")
    k = int(np.argmax(r[:, 2]))
    landed = flight.status is SimulationStatus.LANDED
    log, est = result.log, result.estimation
    counted = bool(np.all(log.iterations >= 0))
    return {
        "status": flight.status.value,
        "message": flight.message,
        "apogee_m": float(r[k, 2]),
        "apogee_time_s": float(flight.t[k]),
        "flight_time_s": flight.air_time,
        "final_x_m": float(r[-1, 0]),
        "final_y_m": float(r[-1, 1]),
        "final_z_m": float(r[-1, 2]),
        "landing_x_m": float(r[-1, 0]) if landed else math.nan,
        "landing_y_m": float(r[-1, 1]) if landed else math.nan,
        "left_beam": int(flight.status is SimulationStatus.LEFT_BEAM),
        "pulses_commanded": result.pulses_commanded,
        "pulses_fired": result.pulses_fired,
        "pulses_dropped": result.pulses_dropped,
        "max_tilt_deg": math.degrees(result.max_tilt_rad),
        "max_coning_deg": math.degrees(result.max_coning_rad),
        "final_coning_deg": math.degrees(float(result.coning[-1])),
        "max_offset_m": float(np.max(result.offset)) if result.offset.size else math.nan,
        "rcs_used_kg": float(result.rcs_used[-1]),
        "fallbacks": int(np.sum(log.fallbacks)),
        # -1: a controller that does not say (a step Function: the director)
        "iterations_total": int(np.sum(log.iterations)) if counted else -1,
        "iterations_max": (int(np.max(log.iterations)) if log.iterations.size else 0)
        if counted
        else -1,
        # the estimator's, NaN for a controller told the truth
        "estimate_position_rms_m": est.rms_position_error() if est is not None else math.nan,
        "estimate_position_nees": est.position_nees() if est is not None else math.nan,
    }


class _Flyer:
    """The plant Φ and the controller of one campaign, built once (per process and
    thread): ``fly(draws, seed)`` makes a run."""

    def __init__(self, campaign: Campaign) -> None:
        self.campaign = c = campaign
        # the closed loop's plant; a craft without RCS: Φ's defaults (no RCS profile)
        options = plant_options(c.model)
        interpreted = pulse_map_for(c.model, options, compiled=False)
        assert interpreted.inputs is not None  # build_pulse_map always records it
        # the deterministic mode: no wall-clock budget (module docstring)
        self.controller: Controller = build_controller(
            c.controller,
            c.model,
            interpreted,
            mpc=dataclasses.replace(c.mpc, time_budget=None),
            director=dataclasses.replace(c.director, time_budget=None),
            compiled=c.compiled,
        )
        self.plant: PulseMap = pulse_map_for(c.model, options, compiled=c.compiled)
        # the sensors and the estimator, reset by each flight (None, None: the truth)
        self.sensors: SensorSuite | None
        self.estimator: Estimator | None
        self.sensors, self.estimator = build_tracker(c.estimator, c.model, c.sensors)

    def fly(self, draws: Mapping[str, float], seed: int) -> ClosedLoopResult:
        c = self.campaign
        parameters = dict(c.plant_parameters)
        for name, slot in DISPERSED_PARAMETER.items():
            if name in draws:
                parameters[slot] = draws[name]
        parameter_values(c.model, parameters)  # a bad value: ParameterError naming it
        x0 = np.array(c.x0, dtype=float)
        r = STATE.index("r_L")
        x0[r.start] += draws.get("launch_offset_x", 0.0)
        x0[r.start + 1] += draws.get("launch_offset_y", 0.0)
        q = STATE.index("q_LB")  # the drawn lean, turning x0's attitude in L
        x0[q] = tilted_attitude(x0[q], draws.get("tilt", 0.0), draws.get("tilt_azimuth", 0.0))
        loop = dataclasses.replace(c.loop, seed=seed)
        if "dropout_rate" in draws:
            rate = min(max(draws["dropout_rate"], 0.0), _MAX_DROPOUT)
            loop = dataclasses.replace(loop, dropout_rate=rate)
        return closed_loop(
            c.model,
            self.controller,
            c.duration,
            x0=x0,
            parameters=parameters,
            pulse_map=self.plant,
            options=loop,
            sensors=self.sensors,
            estimator=self.estimator,
        )


_BUILT = threading.local()


def _flyer(campaign: Campaign) -> _Flyer:
    """This thread's flyer of ``campaign`` (the last one built is kept; so is a failure to
    build it, raised again for every run rather than built again)."""
    cached = getattr(_BUILT, "flyer", None)
    if cached is None or cached[0] != campaign.fingerprint:
        try:
            cached = (campaign.fingerprint, _Flyer(campaign))
        except Exception as err:
            cached = (campaign.fingerprint, err)
        _BUILT.flyer = cached
    if isinstance(cached[1], Exception):
        raise cached[1]
    return cached[1]
