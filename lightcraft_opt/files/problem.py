"""Problem files: TOML in ``problems/`` read into an optimal control problem and its options.

The edge of :mod:`lightcraft_opt.ocp.problem` (what to solve) and
:class:`~lightcraft_opt.ocp.options.OcpOptions` (how), as :mod:`lightcraft_opt.files.model` is
the edge of the model: the same units and spellings (its :data:`QUANTITIES`), converted to
SI here and nowhere else. Every table and key, with an example: docs/files/problem.md;
:mod:`lightcraft_opt.files.problem_tables` reads the objective, constraint and control
tables. Any problem raises one :class:`~lightcraft_opt.errors.ProblemFileError` naming the
file and the key as written in it.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, fields, replace
from dataclasses import field as dataclass_field
from enum import Enum
from pathlib import Path
from typing import Any, get_type_hints

import numpy as np

from lightcraft_opt.errors import (
    HardwareLimitError,
    ModelFileError,
    OptionError,
    ParameterError,
    ProblemFileError,
)
from lightcraft_opt.files import model as mf
from lightcraft_opt.files import schema
from lightcraft_opt.files.design_tables import read_design
from lightcraft_opt.files.problem_tables import (
    BLOCKS,
    CONSTRAINTS,
    CONTROL,
    OBJECTIVES,
    SLOT,
    Table,
    read_array,
    read_item,
    read_kind,
    read_table,
    si_note,
    slot_spec,
)
from lightcraft_opt.files.scenario_tables import read_scenarios, scenario_key
from lightcraft_opt.files.schema import INTEGER, NUMBER, SWITCH, TEXT, Spec, choice, quantity
from lightcraft_opt.layout import RcsProfile, initial_state, parameter_values
from lightcraft_opt.model import Model
from lightcraft_opt.ocp.design import DesignLayout
from lightcraft_opt.ocp.options import (
    OCP_PULSE_MAP,
    HessianApproximation,
    LinearSolver,
    OcpOptions,
    OcpSolver,
    OcpStart,
    PredictionMap,
    WarmHessian,
)
from lightcraft_opt.ocp.problem import (
    OcpProblem,
    check_horizon,
)
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

__all__ = [
    "TABLES",
    "ProblemFile",
    "as_problem_file_errors",
    "initial_state_from_table",
    "load_problem",
    "model_with_overrides",
    "objective_names",
]

_TABLES = (
    "model_overrides",
    "initial",
    "initial_guess",
    "objective",
    "constraint",
    "control",
    "design",
    "scenarios",
    "solver",
    "pulse_map",
)
_TOP: Mapping[str, Spec] = {
    "title": TEXT,
    "model": TEXT,
    "horizon_pulses": INTEGER,
    "t0": quantity("time"),
    "rcs_profile": choice(RcsProfile),
    "rcs_subintervals": INTEGER,
}
_INITIAL: Mapping[str, Spec] = {
    "position_L": quantity("length", "list", 3),
    "velocity_L": quantity("speed", "list", 3),
    "tilt": quantity("angle"),
    "tilt_azimuth": quantity("angle"),
    "w_B": quantity("angular rate", "list", 3),
    "spin": quantity("angular rate"),
}
_SOLVER: Mapping[str, Spec] = {
    "name": choice(OcpSolver),
    "hessian": choice(HessianApproximation),
    "max_iter": INTEGER,
    "tol": NUMBER,
    "move_blocking": BLOCKS,
    "threads": INTEGER,
    "print_level": INTEGER,
    "wind_ramp": INTEGER,
    "prediction": choice(PredictionMap),
    "start": choice(OcpStart),
    "grow_pulses": INTEGER,
    "convex_iterations": INTEGER,
    "warm_hessian": choice(WarmHessian),
    "linear_solver": choice(LinearSolver),
    "mumps_pivtol": NUMBER,
    "time_limit": quantity("time"),
    "stall_iterations": INTEGER,
    "sensitivities": SWITCH,
}


def _options_schema(cls: type, skip: str) -> dict[str, Spec]:
    """Keys of an options dataclass whose fields are choices (Enums), integers or numbers,
    but those starting with ``skip``: the file follows the dataclass as fields arrive."""
    hints = get_type_hints(cls)
    schema: dict[str, Spec] = {}
    for f in fields(cls):
        if f.name.startswith(skip):
            continue
        kind = hints[f.name]
        if isinstance(kind, type) and issubclass(kind, Enum):
            schema[f.name] = choice(kind)
        elif kind is int:
            schema[f.name] = INTEGER
        elif kind is float:
            schema[f.name] = NUMBER
    return schema


#: ``[pulse_map]``: the fields of PulseMapOptions (scheme, substeps, dense ...) but the RCS
#: profile, which is the problem's (it sets the decision variables), not the map's.
_PULSE_MAP: Mapping[str, Spec] = _options_schema(PulseMapOptions, skip="rcs_")
#: The plain tables of a problem file as written ("" the top level) -> their keys. The
#: arrays are problem_tables' OBJECTIVES, CONSTRAINTS and CONTROL; ``[initial_guess]`` takes
#: the map-input slots (``energy_j``), ``[model_overrides]`` a model file's tables. Every
#: table and key with its unit, default and range: docs/files/problem.md.
TABLES: Mapping[str, Mapping[str, Spec]] = {
    "": _TOP,
    "initial": _INITIAL,
    "solver": _SOLVER,
    "pulse_map": _PULSE_MAP,
}
#: Table of a model file -> its model_files.SCHEMA entry (to merge overrides by field; an
#: array of tables, [[craft.rcs.thrusters]], is replaced whole).
_MODEL_TABLES: Mapping[tuple[str, ...], str] = {
    tuple(path.split(".")) if path else (): name
    for path, name in mf.TABLES.items()
    if name != "thruster"
}


@dataclass(frozen=True, eq=False)
class ProblemFile:
    """A problem file as read: what to solve, how, under which title, from where.

    Attributes
    ----------
    problem : the optimal control problem, everything in SI.
    options : transcription and solver options.
    guess_inputs : ``[initial_guess]``: map-input slot -> values held over the horizon
        in the initial guess (:meth:`initial_guess`).
    title : the file's ``title`` (default: the file name without ``.toml``).
    source : the file read.
    model_file : the model file it names (None when built otherwise).
    model_overrides : its ``[model_overrides]`` tables as written.
    """

    problem: OcpProblem
    options: OcpOptions
    title: str
    source: Path
    guess_inputs: Mapping[str, tuple[float, ...]] = dataclass_field(default_factory=dict)
    model_file: Path | None = None
    model_overrides: Mapping[str, Any] = dataclass_field(default_factory=dict)

    def model_tables(self) -> dict[str, Any]:
        """The model file's tables with ``[model_overrides]`` merged in, as written (units
        in the keys): the model this problem flies."""
        if self.model_file is None:
            raise ParameterError("model_file", "this problem was not read from a file")
        _, data = schema.read_toml(self.model_file)
        return dict(merge_model_tables(data, self.model_overrides))

    def initial_guess(self) -> np.ndarray | None:
        """(N, map-input size) inputs to roll out as the initial guess: the problem's
        nominal input with the file's ``[initial_guess]`` values, clipped to the bounds;
        None without that table (the solver then rolls out its nominal policy)."""
        if not self.guess_inputs:
            return None
        pr = self.problem
        u = pr.nominal_input()
        for name, value in self.guess_inputs.items():
            u[pr.inputs.index(name)] = value
        return np.tile(np.clip(u, pr.lower, pr.upper), (pr.horizon, 1))


# --------------------------------------------------------------------------- public API
def load_problem(
    path: str | Path,
    *,
    horizon: int | None = None,
    solver: str | None = None,
    max_iter: int | None = None,
    time_limit: float | None = None,
) -> ProblemFile:
    """Read a problem file (docs/files/problem.md) and the model file it names.

    Parameters
    ----------
    path : the problem file.
    horizon, solver, max_iter, time_limit : replace the file's ``horizon_pulses``
        [pulses], ``solver.name``, ``solver.max_iter`` and ``solver.time_limit_s`` [s]
        (quick runs from the command line).

    Returns
    -------
    ProblemFile
        The validated problem and options, in SI.

    Raises
    ------
    ProblemFileError
        Naming the file and the key as written in it, for any problem with the file, the
        model file or the values they give.
    """
    file = Path(path)
    with as_problem_file_errors():
        src, data = schema.read_toml(file)
    overrides = (
        ("horizon_pulses", horizon),
        ("name", solver),
        ("max_iter", max_iter),
        ("time_limit_s", time_limit),
    )
    for key, value in overrides:
        if value is not None:
            table = data if key == "horizon_pulses" else data.setdefault("solver", {})
            if isinstance(table, dict):
                if key == "time_limit_s":  # the file's limit in whatever unit it was given
                    for given in [k for k in table if k.startswith("time_limit")]:
                        del table[given]
                table[key] = value
    with as_problem_file_errors():
        return _problem_file(src, file, data)


def objective_names(problem: OcpProblem) -> tuple[str, ...]:
    """A name per objective term, in order (:meth:`OcpProblem.term_names`): the file's term
    name, its slot or reference in brackets, ``#2`` ... for repeats."""
    return problem.term_names()


# --------------------------------------------------------------------------- the file
def _problem_file(src: str, file: Path, data: dict[str, Any]) -> ProblemFile:
    top = read_table(src, data, "", _TOP, required=("model", "horizon_pulses"), tables=_TABLES)
    model = model_with_overrides(src, file, top.values["model"], data.get("model_overrides"))
    horizon = top.values["horizon_pulses"]
    try:
        check_horizon("horizon_pulses", horizon)
    except ParameterError as err:
        raise ProblemFileError(src, top.key("horizon_pulses"), err.reason) from None
    t0 = top.values.get("t0", 0.0)
    x0 = initial_state_from_table(src, model, data.get("initial"))
    times = t0 + np.arange(horizon + 1) / model.flight.pulse_rate if horizon > 0 else None
    items: dict[str, list[Table]] = {"objective": [], "constraints": [], "controls": []}
    made: dict[str, list[Any]] = {"objective": [], "constraints": [], "controls": []}
    for table, field, kinds, tag in (
        ("objective", "objective", OBJECTIVES, "term"),
        ("constraint", "constraints", CONSTRAINTS, "kind"),
        ("control", "controls", None, ""),
    ):
        for i, raw in enumerate(read_array(src, data, table)):
            where = f"{table}[{i}]"
            kind = CONTROL if kinds is None else read_kind(src, raw, where, tag, kinds)
            item, value = read_item(src, file, raw, where, kind, tag, times)
            items[field].append(item)
            made[field].append(value)
    design, design_tables = read_design(src, data)
    try:
        DesignLayout(model, design)
    except ParameterError as err:
        i = next((i for i, v in enumerate(design) if err.field in (v.name, f"design[{i}]")), 0)
        raise ProblemFileError(src, f"{design_tables[i]}.parameter", err.reason) from err
    scenarios = read_scenarios(src, data.get("scenarios"), parameter_values(model), horizon)
    try:
        problem = OcpProblem(
            model,
            horizon,
            tuple(made["objective"]),
            tuple(made["constraints"]),
            tuple(made["controls"]),
            x0=x0,
            t0=t0,
            rcs_profile=top.values.get("rcs_profile", RcsProfile.HOLD),
            rcs_subintervals=top.values.get("rcs_subintervals", 1),
            design=design,
            scenarios=scenarios,
        )
    except HardwareLimitError as err:
        key = _problem_key(err.field, top, items)
        unit = key.rpartition(".")[2].partition("_")[2]  # upper_cm -> cm
        factor = schema.QUANTITIES.get(schema.SI_QUANTITY.get(err.unit, ""), {}).get(unit)
        shown = err.message(float(factor), schema.unit_symbol(unit)) if factor else err.reason
        raise ProblemFileError(src, key, shown) from err
    except ParameterError as err:
        key = _problem_key(scenario_key(err.field, scenarios), top, items)
        raise ProblemFileError(src, key, si_note(key, err.reason)) from err
    options = _options(src, data, problem.horizon)
    title = top.values.get("title", file.stem)
    guess = _guess_inputs(src, problem, data.get("initial_guess"))
    return ProblemFile(
        problem=problem,
        options=options,
        title=title,
        source=file,
        guess_inputs=guess,
        model_file=Path(os.path.normpath(file.parent / top.values["model"])),
        model_overrides=dict(data.get("model_overrides") or {}),
    )


def _guess_inputs(src: str, problem: OcpProblem, raw: Any) -> dict[str, tuple[float, ...]]:
    """``[initial_guess]``: one number or one per component for map-input slots, in a unit
    of the slot's quantity (``energy_j``, ``pointing_L_cm``)."""
    schema = {name: slot_spec(SLOT, name) for name in problem.inputs.names}
    table = read_table(src, raw or {}, "initial_guess", schema)
    out: dict[str, tuple[float, ...]] = {}
    for name, value in table.values.items():
        size = problem.inputs.slot(name).size
        v = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
        if v.size not in (1, size) or not np.all(np.isfinite(v)):
            raise ProblemFileError(
                src, table.key(name), f"needs 1 or {size} finite numbers, got {value!r}"
            )
        out[name] = tuple(np.broadcast_to(v, (size,)).tolist())
    return out


def model_with_overrides(src: str, file: Path, name: str, overrides: Any) -> Model:
    """The model file ``name`` (relative to the problem file) with ``overrides`` merged in."""
    overrides = _overrides_table(src, overrides)
    target = Path(os.path.normpath(file.parent / name))
    try:
        model_src, data = schema.read_toml(target)
        return mf.model_from_tables(model_src, target, merge_model_tables(data, overrides))
    except ModelFileError as err:
        written = _override_key(err.field, overrides) if err.path == str(target) else None
        if written is not None:
            raise ProblemFileError(src, f"model_overrides.{written}", err.reason) from err
        raise ProblemFileError(src, "model", str(err)) from err


def merge_model_tables(
    base: Mapping[str, Any], over: Mapping[str, Any], at: tuple[str, ...] = ()
) -> Any:
    """``base`` (a model file's tables, or a ``[model_overrides]`` table) with ``over``
    merged in, table by table; a key replaces the base's keys for the same field in any unit
    (``speed_ref_kmh`` replaces ``speed_ref_mps``)."""
    out = dict(base)
    schema = mf.SCHEMA.get(_MODEL_TABLES.get(at, ""))
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge_model_tables(out[key], value, (*at, key))
            continue
        field = _model_field(key, schema) if schema else None
        for old in [k for k in out if field and k != key and _model_field(k, schema) == field]:
            del out[old]
        out[key] = value
    return out


def with_model_overrides(
    src: str, data: dict[str, Any], extra: Mapping[str, Any] | None
) -> dict[str, Any]:
    """A problem file's tables ``data`` with ``extra`` (model-file tables, units in the keys)
    merged into its ``[model_overrides]`` (:func:`merge_model_tables`); ``data`` itself when
    ``extra`` is None.

    Raises
    ------
    ProblemFileError : the file's ``model_overrides`` is not a table.
    ParameterError : ``extra`` is not a mapping.
    """
    if extra is None:
        return data
    written = _overrides_table(src, data.get("model_overrides"))
    if not isinstance(extra, Mapping):
        raise ParameterError(
            "model_overrides", f"must be a mapping of model-file tables, got {extra!r}"
        )
    return {**data, "model_overrides": dict(merge_model_tables(written, extra))}


def _overrides_table(src: str, raw: Any) -> dict[str, Any]:
    """A problem file's ``[model_overrides]`` as read (absent: empty); ProblemFileError when
    it is not a table."""
    if raw is None:
        return {}
    if not isinstance(raw, dict):
        raise ProblemFileError(src, "model_overrides", f"must be a table, got {raw!r}")
    return raw


def _model_field(key: str, schema: Any) -> str | None:
    """The model-file field ``key`` stands for (``speed_ref_mps`` -> ``speed_ref``)."""
    if key in schema:
        return key
    fields = [
        f
        for f in schema
        if key.startswith(f + "_") and key[len(f) + 1 :] in mf.QUANTITIES.get(schema[f].kind, {})
    ]
    return max(fields, key=len, default=None)


def _override_key(field: str | None, overrides: Mapping[str, Any]) -> str | None:
    """``field`` (a model-file key path) if ``overrides`` wrote it, else None."""
    if not field:
        return None
    first = field.split(", ")[0]
    node: Any = overrides
    for part in first.split("."):
        match = re.fullmatch(r"(\w+)((?:\[\d+\])*)", part)
        if not match or not isinstance(node, dict) or match[1] not in node:
            return None
        node = node[match[1]]
        for index in re.findall(r"\[(\d+)\]", match[2]):
            if not isinstance(node, list) or int(index) >= len(node):
                break
            node = node[int(index)]
    return first


def initial_state_from_table(src: str, model: Model, raw: Any) -> np.ndarray:
    """(STATE.size,) launch state of ``model`` from an ``[initial]`` table ``raw`` (position
    and velocity in L, tilt and its azimuth, w_B in B, spin; layout.initial_state's defaults
    where a key is absent)."""
    v = read_table(src, raw or {}, "initial", _INITIAL).values
    try:
        return initial_state(
            model,
            r_L=v.get("position_L", (0.0, 0.0, 0.0)),
            v_L=v.get("velocity_L", (0.0, 0.0, 0.0)),
            tilt=v.get("tilt", 0.0),
            tilt_azimuth=v.get("tilt_azimuth", 0.0),
            w_B=v.get("w_B", (0.0, 0.0, 0.0)),
            spin=v.get("spin"),
        )
    except ParameterError as err:
        raise ProblemFileError(src, "initial", str(err)) from err


def _options(src: str, data: Mapping[str, Any], horizon: int) -> OcpOptions:
    solver = read_table(src, data.get("solver", {}), "solver", _SOLVER)
    pulse = read_table(src, data.get("pulse_map", {}), "pulse_map", _PULSE_MAP)
    values = {("solver" if k == "name" else k): v for k, v in solver.values.items()}
    if "stall_iterations" in values:  # 0 in a file: no stall rule (None in OcpOptions)
        window = values["stall_iterations"]
        if window < 0:
            raise ProblemFileError(
                src,
                solver.key("stall_iterations"),
                f"must be an integer >= 1 (iterations), or 0 for no stall rule, got {window!r}",
            )
        values["stall_iterations"] = window or None
    try:
        pulse_map = replace(OCP_PULSE_MAP, **pulse.values)
        options = OcpOptions(**values, pulse_map=pulse_map)
        options.blocks(horizon)
    except OptionError as err:
        found = re.search(r"\b(OcpOptions|PulseMapOptions)\.(\w+)", str(err))
        key = "solver"
        if found:
            table = pulse if found[1] == "PulseMapOptions" else solver
            key = table.key("name" if found[2] == "solver" else found[2])
        raise ProblemFileError(src, key, str(err)) from err
    return options


# --------------------------------------------------------------------------- errors
def _problem_key(field: str, top: Table, items: Mapping[str, list[Table]]) -> str:
    """An OcpProblem field ("controls[1].lower", "horizon") as the file wrote it."""
    found = re.fullmatch(r"(objective|constraints|controls)\[(\d+)\]\.?(\w*)(.*)", field)
    if found and int(found[2]) < len(items[found[1]]):
        table = items[found[1]][int(found[2])]
        attr = {"slot": "input" if "input" in table.keys else "state"}.get(found[3], found[3])
        return (table.key(attr) if attr else table.where) + found[4]
    simple = {
        "horizon": top.key("horizon_pulses"),
        "t0": top.key("t0"),
        "x0": "initial",
        "constraints": "constraint",
        "controls": "control",
    }
    return simple.get(field, field)


@contextmanager
def as_problem_file_errors() -> Iterator[None]:
    """model_files' errors about the problem file become ProblemFileErrors."""
    try:
        yield
    except ModelFileError as err:
        raise ProblemFileError(err.path, err.field, err.reason) from err
