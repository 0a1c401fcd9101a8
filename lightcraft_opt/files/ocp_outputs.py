"""Writing an optimal control solution to disk: solution.csv, summary.json.

Column names carry their units and match trajectory.csv's (:mod:`.simulation_outputs`):
positions in L (x east, y north, z up, docs/frames.md), impulses in B. A failed solve is
written too: its status is in the summary, its last iterate in the CSV. When that iterate's
dynamics gaps are open, the summary says so (``dynamics_closed`` false): its achieved
figures (final altitude, laser energy ...) are then those of no flyable trajectory.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.files.design_outputs import design_summary
from lightcraft_opt.files.problem import ProblemFile, objective_names
from lightcraft_opt.files.result_archive import write_archive
from lightcraft_opt.files.simulation_outputs import TRAJECTORY_COLUMNS, finite_or_none, model_hash
from lightcraft_opt.layout import ENGINE, PARAMETERS, STATE, VectorLayout
from lightcraft_opt.ocp.problem import (
    EnergyBudget,
    NoGroundContact,
    OcpProblem,
    OffsetLimit,
    RcsEnvelope,
    TerminalAltitude,
    TerminalState,
    TiltLimit,
)
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.ocp.sensitivity import SHOWN
from lightcraft_opt.simulation.flight_measures import flight_result
from lightcraft_opt.simulation.result import PulseRecord, SimulationResult, SimulationStatus
from lightcraft_opt.symbolic.terms.invariants import invariants_map

__all__ = [
    "constraint_margins",
    "engine_columns",
    "input_columns",
    "node_flight",
    "node_tilt",
    "offsets_over_capture_radius",
    "quantity_key",
    "replay_summary",
    "sensitivity_summary",
    "solution_columns",
    "solution_table",
    "write_ocp_summary",
    "write_solution_csv",
]

#: Component names in column names, by the frame suffix of a slot (``offset_L`` -> x, y).
_COMPONENTS = {"L": ("x", "y", "z"), "B": ("b1", "b2", "b3")}


#: A layout unit's suffix in a column name, spelt as the input files spell it
#: (docs/files.md#units: lower case, a product written together, ``_per_`` a quotient).
COLUMN_SUFFIXES: dict[str, str] = {
    "m": "m",
    "m/s": "mps",
    "rad/s": "rad_per_s",
    "kg": "kg",
    "J": "j",
    "N": "n",
    "N m": "nm",
    "N s": "ns",
    "N m s": "nms",
}


def _unit(unit: str) -> str:
    """A layout unit as a column suffix: "N m" -> "_nm", "-" -> "" (:data:`COLUMN_SUFFIXES`)."""
    return "" if unit in ("", "-") else "_" + COLUMN_SUFFIXES[unit]


def _columns(name: str, size: int, unit: str, components: tuple[str, ...] = ()) -> list[str]:
    base, _, frame = name.rpartition("_")
    if frame in _COMPONENTS and size <= 3:
        name, components = base, _COMPONENTS[frame][:size]
    if size == 1:
        return [name + _unit(unit)]
    comps = components or tuple(str(i + 1) for i in range(size))
    return [f"{name}_{c}{_unit(unit)}" for c in comps]


def input_columns(inputs: VectorLayout) -> list[str]:
    """Column names of a map input: pointing_x_m, pointing_y_m, focus_m, energy_j, then
    rcs_thrust_1_n ... and motor_torque_nm when the model has them."""
    return [c for s in inputs.slots for c in _columns(s.name, s.size, s.unit)]


def engine_columns() -> list[str]:
    """Column names of Φ's engine outputs (energy_captured_j, impulse_b1_ns ...,
    offset_x_m, offset_y_m, liner_loss_kg, health), then offset_over_capture_radius."""
    return [c for s in ENGINE.slots for c in _columns(s.name, s.size, s.unit)] + [
        "offset_over_capture_radius"
    ]


def solution_columns(inputs: VectorLayout) -> list[str]:
    """Header of solution.csv: k, trajectory.csv's columns, inputs, engine outputs."""
    return ["k", *TRAJECTORY_COLUMNS, *input_columns(inputs), *engine_columns()]


def offsets_over_capture_radius(result: OcpResult, problem: OcpProblem) -> np.ndarray:
    """(N,) |offset_L| / R_c at each pulse: the beam axis's distance from the optic centre
    over the capture radius (the OffsetLimit measure) [-]."""
    pulses = PulseRecord(result.t[:-1], result.u, result.engine)
    radius = float(problem.p[PARAMETERS.index("capture_radius")][0])
    return np.hypot(*pulses.offset_L.T) / radius


def max_offset_over_capture_radius(result: OcpResult, problem: OcpProblem) -> float:
    """The largest of :func:`offsets_over_capture_radius` [-], 0 without a pulse."""
    offsets = offsets_over_capture_radius(result, problem)
    return float(np.max(offsets)) if offsets.size else 0.0


def solution_table(result: OcpResult, problem: OcpProblem) -> dict[str, np.ndarray]:
    """solution.csv as {column: (N + 1,) values}, columns :func:`solution_columns`: the
    state at node k (with mass, tilt and coning as in trajectory.csv), then pulse k's
    inputs and engine outputs, NaN on the last node (no pulse fires there)."""
    n = len(result.t)
    _, _, tilt, coning, mass = invariants_map(n)(result.x.T, problem.p)
    nodes = np.column_stack(
        [
            result.t,
            result.x,
            np.asarray(mass).ravel(),
            np.degrees(np.asarray(tilt).ravel()),
            np.degrees(np.asarray(coning).ravel()),
        ]
    )
    pulses = np.column_stack(
        [result.u, result.engine, offsets_over_capture_radius(result, problem)]
    )
    pulses = np.vstack([pulses, np.full((1, pulses.shape[1]), np.nan)])
    columns = [np.arange(n), *nodes.T, *pulses.T]
    return dict(zip(solution_columns(result.inputs), columns, strict=True))


def write_solution_csv(result: OcpResult, problem: OcpProblem, path: Path) -> None:
    """One row per node k = 0..N, columns :func:`solution_columns`
    (:func:`solution_table`); pulse k's cells are empty on the last node."""
    table = solution_table(result, problem)
    columns = list(table.values())
    at_nodes = 1 + len(TRAJECTORY_COLUMNS)  # k, then the state's columns
    n = len(result.t)
    lines = [",".join(table)]
    for k in range(n):
        cells = [_cell(columns[0][k], integer=True)]
        cells += [_cell(c[k]) for c in columns[1:at_nodes]]
        cells += (
            [_cell(c[k]) for c in columns[at_nodes:]]
            if k < n - 1
            else [""] * (len(columns) - at_nodes)
        )
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


def _cell(value: float, *, integer: bool = False) -> str:
    return str(int(value)) if integer else f"{value:.12g}"


def node_tilt(result: OcpResult, problem: OcpProblem) -> np.ndarray:
    """(N + 1,) angle of b1 from L up at the nodes [rad]."""
    _, _, tilt, _, _ = invariants_map(len(result.t))(result.x.T, problem.p)
    return np.asarray(tilt).ravel()


def node_flight(result: OcpResult, problem: OcpProblem) -> SimulationResult:
    """The solve's nodes as a flight sampled at the node times, with their angular
    momentum H_L, tilt, coning and mass under the problem's parameters, and its pulses
    (inputs and engine outputs) fired at t[:-1]: what the per-pulse plots read
    (trajectory.png's tilt band, :mod:`lightcraft_opt.plots.per_pulse`)."""
    return flight_result(
        problem.model,
        result.t,
        result.x,
        problem.p,
        SimulationStatus.DURATION_REACHED,
        "the optimal control solve's nodes",
        pulses=PulseRecord(result.t[:-1], result.u, result.engine),
    )


def constraint_margins(result: OcpResult, problem: OcpProblem) -> list[dict[str, Any]]:
    """Each constraint of ``problem`` with its margin at the returned iterate: the smallest
    slack over the horizon (positive: met with room to spare, negative: violated), in the
    unit named by ``unit``. The path constraints are read where the transcription poses
    them: tilt and ground clearance at nodes 1..N, the beam offset over the capture
    radius at every pulse, the RCS envelope at every pulse and thruster
    (:func:`rcs_envelope_margin`)."""
    z = result.state("r_L")[:, 2]
    out: list[dict[str, Any]] = []
    for con in problem.constraints:
        margin: float | None
        match con:
            case OffsetLimit():
                f = offsets_over_capture_radius(result, problem)
                name, unit = "offset_limit", "-"
                margin = float(con.max_offset_over_capture_radius - np.max(f)) if f.size else None
            case TiltLimit():
                name, unit = "tilt_limit", "deg"
                margin = math.degrees(con.max_tilt - float(np.max(node_tilt(result, problem)[1:])))
            case NoGroundContact():
                name, unit = "no_ground_contact", "m"
                margin = float(np.min(z[1:]) - con.clearance)
            case TerminalAltitude():
                name, unit = "terminal_altitude", "m"
                margin = float(min(z[-1] - con.minimum, con.maximum - z[-1]))
            case TerminalState():
                name, unit = f"terminal_state_{con.slot}", STATE.slot(con.slot).unit
                x = np.atleast_1d(result.state(con.slot)[-1])
                slack = np.minimum(x - np.array(con.lower), np.array(con.upper) - x)
                margin = float(np.min(slack))
            case EnergyBudget():
                name, unit = "energy_budget", "J"
                margin = float(con.total - result.laser_energy)
            case RcsEnvelope():
                name, unit, margin = "rcs_envelope", "N", rcs_envelope_margin(result, problem)
        value = None if margin is None else finite_or_none(margin)  # inf: unbounded
        out.append({"constraint": name, "margin": value, "unit": unit})
    return out


def rcs_envelope_margin(result: OcpResult, problem: OcpProblem) -> float | None:
    """How far the RCS thrust stays inside [0, max_thrust] over the horizon [N]: the least
    of thrust_i - 0 and max_i - thrust_i at every pulse, thruster and instant. A
    phase-locked thrust mean_i + cos_i cos(ωτ) + sin_i sin(ωτ) spans mean_i ± its amplitude
    sqrt(cos_i² + sin_i²); a held or sub-interval level is its own value. None without an
    RCS."""
    rcs = problem.model.craft.rcs
    if rcs is None or "rcs_thrust" not in problem.inputs.names:
        return None
    top = np.array([thruster.max_thrust for thruster in rcs.thrusters])
    levels = np.reshape(result.input("rcs_thrust"), (result.u.shape[0], -1, top.size))
    amplitude = np.zeros((levels.shape[0], 1, top.size))
    if "rcs_cos" in problem.inputs.names:
        cos, sin = (np.reshape(result.input(n), (-1, 1, top.size)) for n in ("rcs_cos", "rcs_sin"))
        amplitude = np.hypot(cos, sin)
    slack = np.minimum(levels - amplitude, top - levels - amplitude)
    return float(np.min(slack)) if slack.size else None


def replay_summary(result: OcpResult) -> dict[str, Any]:
    """summary.json's replay keys (:class:`~lightcraft_opt.ocp.result.PlanReplay`): how the
    simulator's flight of the plan ended, whether it flies and stays in the beam, the
    largest position gap from the prediction [m] and its node, final altitude [m] and
    largest beam offset over the capture radius, replayed and planned, and the faults;
    every value null when the result was not replayed."""
    r = result.replay
    if r is None:
        keys = (
            "status flies stays_in_beam pulses max_position_gap_m max_gap_node "
            "final_altitude_m planned_final_altitude_m max_offset_over_capture_radius "
            "planned_max_offset_over_capture_radius pulse_map quadrature faults"
        )
        return {f"replay_{k}": None for k in keys.split()}
    return {
        "replay_status": r.status.value,
        "replay_flies": r.flies,
        "replay_stays_in_beam": r.stays_in_beam,
        "replay_pulses": r.pulses,
        "replay_max_position_gap_m": r.max_position_gap,
        "replay_max_gap_node": r.max_gap_node,
        "replay_final_altitude_m": r.final_altitude,
        "replay_planned_final_altitude_m": r.planned_final_altitude,
        "replay_max_offset_over_capture_radius": r.max_offset_over_capture_radius,
        "replay_planned_max_offset_over_capture_radius": r.planned_max_offset_over_capture_radius,
        "replay_pulse_map": f"{r.pulse_map.scheme.value}, {r.pulse_map.substeps} substeps",
        "replay_quadrature": list(r.quadrature),
        "replay_faults": list(r.faults),
    }


#: An SI unit of p or x0 (layout/vectors.py) as a key suffix (docs/files.md#units).
_KEY_UNITS: dict[str, str] = {
    **COLUMN_SUFFIXES,
    "-": "",
    "s": "s",
    "rad": "rad",
    "rad/m": "rad_per_m",
    "kg m^2": "kg_m2",
    "kg/J": "kg_per_j",
    "N s/J": "ns_per_j",
    "kg m^2/s": "kg_m2_per_s",
}


def quantity_key(name: str, unit: str) -> str:
    """A named quantity's key with its SI unit last (docs/files.md#units):
    ``gust_L[east]``, m/s -> ``gust_L_east_mps``; ``coning[e1]``, - -> ``coning_e1``."""
    suffix = _KEY_UNITS[unit]
    return name.replace("[", "_").rstrip("]") + (f"_{suffix}" if suffix else "")


def sensitivity_summary(result: OcpResult) -> dict[str, Any] | None:
    """summary.json's ``sensitivities`` (ocp/sensitivity.py), None when not asked: each
    held parameter under its name with its SI unit (``rotor_mass_dry_kg``,
    ``gust_L_east_mps``, ``launch_spin_rad_per_s``), largest |elasticity| first, with its
    ``value`` [that unit], ``derivative`` dJ*/dθ [cost units per that unit] and
    ``elasticity`` θ dJ*/dθ [cost units]; ``ranked`` the first few keys; ``reason`` why
    there are none (null when computed); ``evaluation_time_s``."""
    s = result.sensitivities
    if s is None:
        return None
    entries: dict[str, dict[str, float]] = {}
    for item in s.ranked():
        entries[quantity_key(item.name, item.unit)] = {
            "value": item.value,
            "derivative": item.derivative,
            "elasticity": item.elasticity,
        }
    return {
        "reason": s.reason or None,
        "evaluation_time_s": s.evaluation_time,
        "ranked": list(entries)[:SHOWN],
        "parameters": entries,
    }


def write_ocp_summary(result: OcpResult, problem_file: ProblemFile, path: Path) -> dict[str, Any]:
    """summary.json: how the solve went (status, cost and its terms by name, iterations,
    times), what it asked (solver, horizon) and what it achieved (laser energy, final
    altitude, largest beam offset over the capture radius against its limit, largest
    tilt, RCS propellant and liner used, each constraint's margin
    (:func:`constraint_margins`), constraint violation), whether the returned iterate is a
    trajectory of Φ at all (``dynamics_closed``, ``dynamics_gap``: its largest dynamics gap,
    scaled units; when not, the achieved figures keep their keys but are no results), how
    its plan flew when the simulator flew it again (:func:`replay_summary`), and the
    optimum's sensitivities when asked (:func:`sensitivity_summary`). Beside it,
    result.json and result.npz: the exact result (:mod:`.result_archive`)."""
    problem, options = problem_file.problem, problem_file.options
    limits = [
        c.max_offset_over_capture_radius for c in problem.constraints if isinstance(c, OffsetLimit)
    ]
    r_L = result.state("r_L")
    rcs, liner = result.state("rcs_mass"), result.state("liner_mass")
    summary: dict[str, Any] = {
        "title": problem_file.title,
        "problem_file": str(problem_file.source),
        "model": problem.model.name,
        "model_hash": model_hash(problem.model),
        "status": result.status.value,
        "success": result.success,
        "message": result.message,
        "solver": result.solver,
        "hessian": options.hessian.value,
        "cost": result.cost,
        "cost_terms": dict(
            zip(objective_names(problem), map(float, result.cost_terms), strict=False)
        ),
        "iterations": result.iterations,
        "solve_time_s": result.solve_time,
        "build_time_s": result.build_time,
        "dynamics_closed": result.dynamics_closed,
        "dynamics_gap": finite_or_none(result.dynamics_gap),
        "design": design_summary(result),
        "sensitivities": sensitivity_summary(result),
        "horizon_pulses": result.horizon,
        "pulse_period_s": problem.period,
        "laser_energy_j": result.laser_energy,
        "final_altitude_m": float(r_L[-1, 2]),
        "final_position_m": r_L[-1].tolist(),
        "max_drift_m": float(np.max(np.hypot(r_L[:, 0], r_L[:, 1]))),
        "max_offset_over_capture_radius": max_offset_over_capture_radius(result, problem),
        "max_offset_over_capture_radius_limit": min(limits) if limits else None,
        "max_tilt_deg": math.degrees(float(np.max(node_tilt(result, problem)))),
        "propellant_used_kg": float(rcs[0] - rcs[-1]),
        "liner_used_kg": float(liner[0] - liner[-1]),
        "constraint_margins": constraint_margins(result, problem),
        "constraint_violation": finite_or_none(result.constraint_violation),
        **replay_summary(result),
    }
    if result.scenarios:  # a robust problem: each scenario's cost and what it achieved
        energy = problem.inputs.index("energy")
        summary["scenarios"] = {
            o.name: {
                "weight": o.weight,
                "cost": o.cost,
                "laser_energy_j": float(np.sum(o.u[:, energy])),
                "final_altitude_m": float(o.state("r_L")[-1, 2]),
                "max_drift_m": float(np.max(np.hypot(*o.state("r_L")[:, :2].T))),
            }
            for o in result.scenarios
        }
    path.write_text(json.dumps(summary, indent=2) + "\n")
    write_archive(result, path.parent)
    return summary
