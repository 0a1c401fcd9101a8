"""Writing a closed-loop flight to disk: steps.csv and summary.json (the edge).

The flight itself goes to trajectory.csv and pulses.csv by :mod:`.simulation_outputs` (the
same columns as ``lightcraft simulate``'s); here the controller's side: one row per
pulse with what it did and how long it took (with an estimator, its estimate's errors
against the truth too), and a summary of the acceptance measures. Column names carry
their units.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.control.result import SLOW_TRUTHS, ClosedLoopResult, ControllerStatus
from lightcraft_opt.files.closed_loop import ClosedLoopProblem
from lightcraft_opt.files.result_archive import write_archive
from lightcraft_opt.files.simulation_outputs import finite_or_none, flight_measures, model_hash

__all__ = [
    "ESTIMATE_COLUMNS",
    "STEP_COLUMNS",
    "steps_table",
    "write_closed_loop_summary",
    "write_steps_csv",
]

STEP_COLUMNS = (
    "k",
    "t_s",
    "status",
    "solve_time_ms",
    "step_time_ms",
    "iterations",
    "coning_deg",
    "tilt_deg",
    "offset_m",
    "rcs_used_kg",
    "dropped",
    "message",
)


#: steps.csv's columns after :data:`STEP_COLUMNS` when an estimator told the controller
#: the state (:class:`~lightcraft_opt.control.result.EstimationLog`): the estimate minus the
#: truth before pulse k (position and velocity in L, tilt, coning, spin), the estimate's
#: own position standard deviation, the estimator's step time and the readings it got,
#: then the slow states' errors (the mean wind at the reference height in L, the
#: coupling; nan for an estimator that carries none).
ESTIMATE_COLUMNS = (
    "error_x_m",
    "error_y_m",
    "error_z_m",
    "error_vx_mps",
    "error_vy_mps",
    "error_vz_mps",
    "error_tilt_deg",
    "error_coning_deg",
    "error_spin_rad_per_s",
    "sigma_x_m",
    "sigma_y_m",
    "sigma_z_m",
    "estimator_time_ms",
    "readings",
    "error_wind_east_mps",
    "error_wind_north_mps",
    "error_coupling_ns_per_j",
)


def steps_table(result: ClosedLoopResult) -> dict[str, np.ndarray]:
    """steps.csv as {column: (n,) values}, columns :data:`STEP_COLUMNS`: one row per
    pulse k, the controller's status, solve and step time, iterations, then the coning
    and tilt before pulse k, the beam offset at it, the propellant used before it,
    whether the laser dropped it, and the solver's message (commas replaced); then, with
    an estimator, :data:`ESTIMATE_COLUMNS`."""
    log, pulses = result.log, range(result.pulses_commanded)
    columns = [
        np.arange(result.pulses_commanded),
        np.array([result.pulse_t[k] for k in pulses], dtype=float),
        np.array([log.status[k].value for k in pulses], dtype=object),
        np.array([log.solve_time[k] * 1e3 for k in pulses], dtype=float),
        np.array([log.step_time[k] * 1e3 for k in pulses], dtype=float),
        np.array([int(log.iterations[k]) for k in pulses], dtype=int),
        np.array([math.degrees(result.coning[k]) for k in pulses], dtype=float),
        np.array([math.degrees(result.tilt[k]) for k in pulses], dtype=float),
        np.array([result.offset[k] for k in pulses], dtype=float),
        np.array([result.rcs_used[k] for k in pulses], dtype=float),
        np.array([int(result.dropped[k]) for k in pulses], dtype=int),
        np.array([log.messages[k].replace(",", ";") for k in pulses], dtype=object),
    ]
    table = dict(zip(STEP_COLUMNS, columns, strict=True))
    est = result.estimation
    if est is not None:
        estimate = [
            *est.error_r_L.T,
            *est.error_v_L.T,
            np.degrees(est.error_tilt),
            np.degrees(est.error_coning),
            est.error_spin,
            *est.sigma_r_L.T,
            1e3 * est.seconds,
            est.readings.astype(int),
            *(est.error_slow.get(n, np.full(len(est.readings), np.nan)) for n in SLOW_TRUTHS),
        ]
        table.update(zip(ESTIMATE_COLUMNS, estimate, strict=True))
    return table


#: How steps.csv writes each column of :func:`steps_table`, in its order.
_STEP_CELLS = ("{}", "{:.9g}", "{}", "{:.6g}", "{:.6g}", "{}", *["{:.9g}"] * 4, "{}", "{}")
_ESTIMATE_CELLS = (*["{:.9g}"] * 12, "{:.6g}", "{}", *["{:.9g}"] * 3)


def write_steps_csv(result: ClosedLoopResult, path: Path) -> None:
    """One row per pulse k, columns :data:`STEP_COLUMNS`, then :data:`ESTIMATE_COLUMNS`
    with an estimator (:func:`steps_table`)."""
    table = steps_table(result)
    columns = list(table.values())
    formats = (*_STEP_CELLS, *_ESTIMATE_CELLS)[: len(columns)]
    lines = [",".join(table)]
    for k in range(result.pulses_commanded):
        cells = (cell.format(c[k]) for cell, c in zip(formats, columns, strict=True))
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


def write_closed_loop_summary(
    result: ClosedLoopResult, problem: ClosedLoopProblem | None, path: Path
) -> dict[str, Any]:
    """summary.json: which problem and controller, how the flight ended, the coning
    measures (first pulse from which it stays below 0.5 degrees, largest after pulse 25,
    largest), tilt and offset, the flight's apogee time, top and landing speed, capture
    margin and energy captured (:func:`~.simulation_outputs.flight_measures`), propellant,
    and the controller's statistics (counts by status, fallbacks, solve time median /
    99th percentile / max). Without ``problem`` its entries (title, file, hash,
    duration, faults) are null. Beside it, result.json and result.npz: the exact result
    (:mod:`.result_archive`)."""
    log = result.log
    settled = result.first_pulse_below(math.radians(0.5))
    times = {
        k: v * 1e3 if math.isfinite(v) else None for k, v in log.solve_time_percentiles().items()
    }
    flight = flight_measures(result.flight)
    summary: dict[str, Any] = {
        "title": None if problem is None else problem.title,
        "problem_file": None if problem is None else str(problem.source),
        "model": result.flight.model_name,
        "model_hash": None if problem is None else model_hash(problem.model),
        "controller": result.controller,
        "status": result.flight.status.value,
        "message": result.flight.message,
        "pulses_commanded": result.pulses_commanded,
        "pulses_fired": result.pulses_fired,
        "pulses_dropped": result.pulses_dropped,
        "duration_s": None if problem is None else problem.duration,
        "coning_initial_deg": math.degrees(result.coning[0]),
        "coning_final_deg": math.degrees(result.coning[-1]),
        "coning_below_0.5deg_from_pulse": settled,
        "max_coning_after_pulse_25_deg": (
            math.degrees(result.max_coning_after_rad(25)) if result.coning.size > 25 else None
        ),
        "max_coning_deg": finite_or_none(math.degrees(result.max_coning_rad)),
        "max_tilt_deg": finite_or_none(math.degrees(result.max_tilt_rad)),
        "final_tilt_deg": math.degrees(result.tilt[-1]),
        "max_offset_m": float(np.max(result.offset)) if result.offset.size else None,
        **{
            k: flight[k]
            for k in (
                "apogee_m",
                "apogee_time_s",
                "top_speed_mps",
                "landing_speed_mps",
                "energy_captured_j",
                "capture_margin_m",
            )
        },
        "rcs_used_kg": float(result.rcs_used[-1]),
        "final_position_m": result.flight.state("r_L")[-1].tolist(),
        "steps_by_status": {s.value: log.count(s) for s in ControllerStatus if log.count(s)},
        "fallbacks": int(np.sum(log.fallbacks)),
        "faults_injected": None if problem is None else len(problem.loop.faults),
        "solve_time_ms": times,
        "step_time_median_ms": (
            float(np.median(log.step_time)) * 1e3 if log.step_time.size else None
        ),
        "iterations_max": int(np.max(log.iterations)) if log.iterations.size else 0,
    }
    if result.estimation is not None:  # only with an estimator: the file is as before without
        summary.update(_estimation_summary(result))
    path.write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n")
    write_archive(result, path.parent)
    return summary


def _estimation_summary(result: ClosedLoopResult) -> dict[str, Any]:
    """summary.json's estimator entries: its name, the RMS of the position error's norm
    and the largest, the position's NEES per axis (EstimationLog.position_nees: 1 when
    consistent), and the median and largest step time."""
    log = result.estimation
    assert log is not None
    error = np.linalg.norm(log.error_r_L, axis=1)
    seconds = log.seconds
    return {
        "estimator": log.estimator,
        "position_error_rms_m": finite_or_none(log.rms_position_error()),
        "position_error_max_m": finite_or_none(np.max(error)) if error.size else None,
        "position_nees": finite_or_none(log.position_nees()),
        "estimator_time_median_ms": float(np.median(seconds)) * 1e3 if seconds.size else None,
        "estimator_time_max_ms": float(np.max(seconds)) * 1e3 if seconds.size else None,
    }
