"""Closed-loop problem files: TOML in ``problems/`` read into a closed-loop flight to run.

The sibling of :mod:`lightcraft_opt.files.problem`: the same conventions and machinery (the
model file with ``[model_overrides]``, ``[initial]``, model_files' units in the keys, errors
naming the key as written) for what a closed loop needs instead of an objective: the
controller it flies (``controller``) and its options (``[mpc]``, ``[director]``), what
happens to the plant (``[plant]``) and what tells the controller the state
(``[estimator]``). Every table and key, with an example, and the rule that
picks the controller: docs/files/closed_loop.md.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.control.estimation.curvature import entry_indices
from lightcraft_opt.control.estimation.psi_model import estimated_names
from lightcraft_opt.control.estimation.sensor_options import (
    CameraKind,
    CameraOptions,
    GyroOptions,
    SensorOptions,
    SpinSensorOptions,
)
from lightcraft_opt.control.options import (
    ClosedLoopOptions,
    ControllerFault,
    ControllerKind,
    ControlWeights,
    DirectorOptions,
    DirectorRcs,
    DirectorWeights,
    EstimatorKind,
    EstimatorSpec,
    MeasurementNoise,
    MpcOptions,
    MpcSolver,
    PlantDispersion,
)
from lightcraft_opt.errors import ModelFileError, OptionError, ProblemFileError, renamed
from lightcraft_opt.files import model as mf
from lightcraft_opt.files import schema

# problem_files' own readers of the model and [initial] tables: one convention for both
from lightcraft_opt.files.problem import (
    as_problem_file_errors,
    initial_state_from_table,
    model_with_overrides,
    with_model_overrides,
)
from lightcraft_opt.files.problem_tables import NUMBERS, Table, read_table
from lightcraft_opt.files.schema import INTEGER, NUMBER, TEXT, Spec, choice, quantity
from lightcraft_opt.layout import PARAMETERS, STATE, coning_rates
from lightcraft_opt.model import FocusSchedule, Model, Wind

__all__ = ["TABLES", "ClosedLoopProblem", "closed_loop_from_tables", "load_closed_loop"]

_TABLES = ("model_overrides", "initial", "mpc", "director", "plant", "sensors", "estimator")
_TOP: dict[str, Spec] = {
    "title": TEXT,
    "model": TEXT,
    "duration": quantity("time"),
    "controller": choice(ControllerKind),
}
#: The controller each options table configures: a file without ``controller`` flies the
#: one whose table it has.
_TABLE_OF: dict[str, ControllerKind] = {
    "mpc": ControllerKind.MPC,
    "director": ControllerKind.DIRECTOR,
}
_CONING: dict[str, Spec] = {"coning": quantity("angle"), "coning_azimuth": quantity("angle")}
_SWITCH = Spec("switch")
_MPC: dict[str, Spec] = {
    "horizon_pulses": INTEGER,
    "solver": choice(MpcSolver),
    "max_iter": INTEGER,
    "tol": NUMBER,
    "time_budget": quantity("time"),
    "envelope_directions": INTEGER,
    "max_offset_over_capture_radius": NUMBER,
    "warm_start": _SWITCH,
    "propellant_weight": NUMBER,
}
#: Keys of ``[mpc]`` and ``[director]`` renamed: old -> new, refused with the new.
_FORMER: dict[str, dict[str, str]] = {
    "mpc": {"capture_fraction": "max_offset_over_capture_radius"},
    "director": {},
}
#: ``[mpc.tolerances]``: ControlWeights field -> quantity of its tolerance.
_TOLERANCES: dict[str, Spec] = {
    "coning": quantity("angle"),
    "tilt": quantity("angle"),
    "offset": quantity("length"),
    "drift": quantity("length"),
    "velocity": quantity("speed"),
    "pointing": quantity("length"),
    "rcs": quantity("force"),
}
_DIRECTOR: dict[str, Spec] = {
    "horizon_pulses": INTEGER,
    "solver": choice(MpcSolver),
    "max_iter": INTEGER,
    "tol": NUMBER,
    "time_budget": quantity("time"),
    "relinearize": INTEGER,
    "focus_schedule": choice(FocusSchedule),
    "matched_side": quantity("length"),
    "energy_range": quantity("dimensionless", "list", 2),
    "disturbance_gain": NUMBER,
    "rcs": choice(DirectorRcs),
    "warm_start": _SWITCH,
}
#: ``[director.tolerances]``: DirectorWeights field -> quantity of its tolerance.
_DIRECTOR_TOLERANCES: dict[str, Spec] = {
    "offset": quantity("length"),
    "drift": quantity("length"),
    "velocity": quantity("speed"),
    "coning": quantity("angle"),
    "tilt": quantity("angle"),
    "pointing": quantity("length"),
    "move": quantity("length"),
    "move_vergence": quantity("inverse length"),
    "vergence": quantity("inverse length"),
    "energy": quantity("energy"),
    "torque": quantity("torque"),
}
_PLANT: dict[str, Spec] = {
    "dropout_rate": NUMBER,
    "seed": INTEGER,
    "fault_pulses": NUMBERS,
    "fault": choice(ControllerFault),
}
_NOISE: dict[str, Spec] = {
    "position": quantity("length"),
    "velocity": quantity("speed"),
    "attitude": quantity("angle"),
    "rate": quantity("angular rate"),
    "spin": quantity("angular rate"),
}
#: ``[estimator]``: the kind, then the options its EstimatorSpec carries (SI; the field
#: is the key without ``_pulses`` for the horizon).
_ESTIMATOR: dict[str, Spec] = {
    "kind": choice(EstimatorKind),
    "prior_position": quantity("length"),
    "prior_velocity": quantity("speed"),
    "prior_coning": quantity("angle"),
    "prior_wind": quantity("speed"),
    "noise_scale": NUMBER,
    "horizon_pulses": INTEGER,
    "max_iter": INTEGER,
    "relinearize": INTEGER,
    "second_order": Spec("switch or names"),
}
#: ``[sensors.camera]``: CameraOptions field -> what the file holds (``lost_percent`` is
#: lost_rate in percent). A stereo camera's noise is an angle (:data:`_STEREO_NOISE`).
_CAMERA: dict[str, Spec] = {
    "kind": choice(CameraKind),
    "noise": quantity("length"),
    "frame_rate": quantity("frequency"),
    "latency_pulses": INTEGER,
    "lost_percent": NUMBER,
    "sites": quantity("length", "rows", 3),
}
_STEREO_NOISE = quantity("angle")
_RATE_SENSOR: dict[str, Spec] = {"noise": quantity("angular rate"), "latency_pulses": INTEGER}
_SENSORS = ("camera", "gyro", "spin")
#: Wind fields the parameter vector carries (the tables are structure: not here).
_WIND_PARAMETERS = {
    "speed_ref": "wind_speed_ref",
    "height_ref": "wind_height_ref",
    "roughness_height": "wind_roughness_height",
    "shear_exponent": "wind_shear_exponent",
    "direction_from": "wind_direction_from",
    "veer": "wind_veer",
    "gust_L": "gust_L",
    "gust_start": "gust_start",
    "gust_duration": "gust_duration",
}

#: The tables of a closed-loop file as written ("" the top level) -> their keys:
#: ``[initial]`` has problem files' keys (files/problem.py TABLES) and the coning's,
#: ``[plant.dispersion]`` the names of layout.PARAMETERS, ``[model_overrides]`` a model
#: file's tables. Every table and key: docs/files/closed_loop.md.
TABLES: dict[str, dict[str, Spec]] = {
    "": _TOP,
    "initial": _CONING,
    "mpc": _MPC,
    "mpc.tolerances": _TOLERANCES,
    "director": _DIRECTOR,
    "director.tolerances": _DIRECTOR_TOLERANCES,
    "plant": _PLANT,
    "plant.noise": _NOISE,
    "plant.wind": {field: mf.SCHEMA["wind"][field] for field in _WIND_PARAMETERS},
    "estimator": _ESTIMATOR,
    "sensors.camera": _CAMERA,
    "sensors.gyro": _RATE_SENSOR,
    "sensors.spin": _RATE_SENSOR,
}


@dataclass(frozen=True, eq=False)
class ClosedLoopProblem:
    """A closed-loop file as read, everything in SI.

    Attributes
    ----------
    model : the controller's model (and the plant's, before its wind and dispersion).
    x0 : (STATE.size,) state at the first pulse.
    duration : [s].
    controller : who flies (``controller``, else by the tables: module docstring).
    mpc : the MPC's options (the LQR takes their weights).
    director : the director's options (``[director]``).
    loop : noise, dispersion, drop-outs, injected faults, seed.
    plant_parameters : {PARAMETERS slot: value} the plant has and the controller does
        not (its wind).
    title : the file's ``title`` (default: the file name).
    source : the file read.
    sensors : what the tracker sees (``[sensors]``), or None: the file has no ``[sensors]``
        (and no estimator: the controller is told the state with ``[plant.noise]``).
    estimator : what tells the controller the state (``[estimator]``; default the truth
        with ``[plant.noise]``: :class:`~lightcraft_opt.control.options.EstimatorSpec`);
        one other than the truth reads ``sensors``.
    """

    model: Model
    x0: np.ndarray
    duration: float
    controller: ControllerKind
    mpc: MpcOptions
    director: DirectorOptions
    loop: ClosedLoopOptions
    plant_parameters: dict[str, Any]
    title: str
    source: Path
    sensors: SensorOptions | None = None
    estimator: EstimatorSpec = dataclasses.field(default_factory=EstimatorSpec)


def load_closed_loop(
    path: str | Path,
    *,
    duration: float | None = None,
    model_overrides: Mapping[str, Any] | None = None,
) -> ClosedLoopProblem:
    """Read a closed-loop file (docs/files/closed_loop.md) and the model file it names.

    Parameters
    ----------
    path : the file.
    duration : replaces the file's ``duration`` [s] (quick runs from the command line).
    model_overrides : tables merged into the file's ``[model_overrides]``, keyed as in a
        file, units in the keys: ``{"craft": {"spin_rpm": 8200.0}}`` (a key replaces the
        file's key for the same field in any unit); a bad key is named as if written there.

    Raises
    ------
    ProblemFileError naming the file and the key as written, for any problem with the
    file, the model file or the values they give.
    """
    file = Path(path)
    with as_problem_file_errors():
        src, data = schema.read_toml(file)
        data = with_model_overrides(src, data, model_overrides)
        return closed_loop_from_tables(src, file, data, duration)


def closed_loop_from_tables(
    src: str,
    file: Path,
    data: dict[str, Any],
    duration: float | None,
    absent: ControllerKind = ControllerKind.MPC,
) -> ClosedLoopProblem:
    """The closed-loop problem of the parsed file ``data`` (``src`` its path as text,
    ``file`` its path, relative model paths resolved from it); ``duration`` [s] overrides
    the file's; ``absent`` is the controller of a file that names none and has neither
    controller table. Shared with campaign files, which are closed-loop files with more
    tables."""
    if isinstance(data.get("controller"), dict):
        raise ProblemFileError(
            src,
            "controller",
            f"{renamed('[controller]', '[mpc]')}: write [mpc] and [mpc.tolerances], their "
            'keys unchanged; controller = "mpc" (a top-level key, before the first table) '
            "names the controller the file flies",
        )
    top = read_table(src, data, "", _TOP, required=("model", "duration"), tables=_TABLES)
    model = model_with_overrides(src, file, top.values["model"], data.get("model_overrides"))
    t_end = top.values["duration"] if duration is None else duration
    if not (math.isfinite(t_end) and t_end > 0):
        raise ProblemFileError(src, top.key("duration"), f"must be positive, got {t_end} s")
    x0 = _initial(src, model, data.get("initial"))
    plant = data.get("plant", {})
    director = _director_options(src, data.get("director", {}))
    _check_energy_range(src, model, director)
    estimator = _estimator(src, data.get("estimator", {}), plant, "sensors" in data)
    return ClosedLoopProblem(
        model=model,
        x0=x0,
        duration=float(t_end),
        controller=_controller(src, top, data, absent),
        mpc=_mpc_options(src, data.get("mpc", {})),
        director=director,
        loop=_loop_options(src, plant),
        plant_parameters=_plant_wind(src, plant),
        title=top.values.get("title", file.stem),
        source=file,
        sensors=_sensor_options(src, data.get("sensors")),
        estimator=estimator,
    )


def _check_energy_range(src: str, model: Model, director: DirectorOptions) -> None:
    """The director's highest pulse energy within the laser's: refused beyond it."""
    flight, most = model.flight.pulse_energy, model.laser.pulse_energy_max
    high = director.energy_range[1] * flight
    if high > most * (1 + 1e-12):
        raise ProblemFileError(
            src,
            "director.energy_range",
            f"its highest, {director.energy_range[1]:g} of the flight's {flight:g} J = "
            f"{high:g} J, is beyond the laser's pulse energy (laser.pulse_energy_max): "
            f"0 to {most:g} J",
        )


def _controller(
    src: str, top: Table, data: dict[str, Any], absent: ControllerKind
) -> ControllerKind:
    """The controller the file names (``controller``), else the one whose options table it
    has, else ``absent``; with both tables and no name, an error naming ``controller``."""
    named = top.values.get("controller")
    if named is not None:
        return named
    tables = [name for name in _TABLE_OF if name in data]
    if len(tables) > 1:
        allowed = ", ".join(f'"{k.value}"' for k in ControllerKind)
        raise ProblemFileError(
            src,
            "controller",
            "missing: the file has both [mpc] and [director], so name the one it flies, "
            f'e.g. controller = "director" (one of {allowed}; a top-level key, before the '
            "first table)",
        )
    return _TABLE_OF[tables[0]] if tables else absent


def _initial(src: str, model: Model, raw: Any) -> np.ndarray:
    """problem_files' [initial] with the coning keys: w_B's transverse part set so that
    tan(coning) = A |w_⊥| / H1 at w_B[b1] = 0 (H1 = J (w1 + spin), A the transverse
    moment: the craft's own inertia, for a centred rotor; layout.coning_rates, as
    ``initial_state(model, coning=...)``)."""
    raw = dict(raw or {})
    table = read_table(src, {k: raw.pop(k) for k in list(raw) if k.startswith("coning")},
                       "initial", _CONING)  # fmt: skip
    coning = table.values
    x0 = initial_state_from_table(src, model, raw)
    if coning:
        angle = coning.get("coning", 0.0)
        if not 0.0 <= angle < math.pi / 2:
            raise ProblemFileError(
                src,
                table.key("coning"),
                f"must lie in [0, 90) degrees, got {math.degrees(angle):.6g}: the angle from "
                "the spin axis b1 to H (set its direction with coning_azimuth_deg)",
            )
        w = STATE.index("w_B")
        if abs(x0[w][0]) > 0 and coning.get("coning", 0.0):
            raise ProblemFileError(src, "initial.coning", "needs w_B[b1] = 0 (w_B_rad_per_s[0])")
        spin = float(x0[STATE.index("spin")][0])
        if angle and spin == 0.0:
            raise ProblemFileError(src, table.key("coning"), "a craft without spin cannot cone")
        phase = coning.get("coning_azimuth", 0.0)
        x0[w.start + 1 : w.start + 3] += coning_rates(model, angle, phase, spin)
    return x0


def _mpc_options(src: str, raw: Any) -> MpcOptions:
    raw, unlimited = _without_budget(src, raw, "mpc")
    table, tol, weights = _weighted_tables(src, raw, "mpc", _MPC, _TOLERANCES)
    values = dict(table.values)
    if unlimited:
        values["time_budget"] = None
    if "propellant_weight" in values:
        weights["propellant"] = values.pop("propellant_weight")
    try:
        return MpcOptions(**_renamed(values), weights=ControlWeights(**weights))
    except OptionError as err:
        message = str(err)
        key = (
            table.key("propellant_weight")
            if "ControlWeights.propellant" in message
            else _option_key(message, (table, _MPC), (tol, _TOLERANCES), "MpcOptions")
        )
        raise ProblemFileError(src, key, message) from err


def _director_options(src: str, raw: Any) -> DirectorOptions:
    raw, unlimited = _without_budget(src, raw, "director")
    table, tol, weights = _weighted_tables(src, raw, "director", _DIRECTOR, _DIRECTOR_TOLERANCES)
    kwargs = _renamed(table.values)
    if unlimited:
        kwargs["time_budget"] = None
    if "energy_range" in kwargs:
        kwargs["energy_range"] = tuple(float(v) for v in kwargs["energy_range"])
    try:
        return DirectorOptions(**kwargs, weights=DirectorWeights(**weights))
    except OptionError as err:
        message = str(err)
        key = _option_key(
            message, (table, _DIRECTOR), (tol, _DIRECTOR_TOLERANCES), "DirectorOptions"
        )
        raise ProblemFileError(src, key, message) from err


def _without_budget(src: str, raw: Any, name: str) -> tuple[Any, bool]:
    """The table ``name`` without a ``time_budget`` key written as "none" (any unit
    suffix), and whether it had one: no wall-clock budget, the deterministic mode. Another
    text there is an error naming the key."""
    if not isinstance(raw, dict):
        return raw, False
    for key, value in raw.items():
        if key.startswith("time_budget") and isinstance(value, str):
            if value.strip().lower() != "none":
                raise ProblemFileError(
                    src,
                    f"{name}.{key}",
                    'must be a time or "none" (no wall-clock budget: the deterministic '
                    f"mode), got {value!r}",
                )
            return {k: v for k, v in raw.items() if k != key}, True
    return raw, False


def _weighted_tables(
    src: str, raw: Any, name: str, schema: dict[str, Spec], tolerances: dict[str, Spec]
) -> tuple[Table, Table, dict[str, float]]:
    """The table ``name`` and its ``[name.tolerances]`` read, and the weights of the
    tolerances, 1 / tolerance^2 by field (a tolerance must be positive)."""
    table = read_table(src, raw, name, schema, tables=("tolerances",), former=_FORMER[name])
    tol = read_table(src, raw.get("tolerances", {}), f"{name}.tolerances", tolerances)
    weights: dict[str, float] = {}
    for field, v in tol.values.items():
        if not 0 < v < 1e100:
            raise ProblemFileError(
                src,
                tol.key(field),
                f"a tolerance must be positive and below 1e100 (its weight is 1 / tolerance^2), "
                f"got {v:g}",
            )
        weights[field] = 1.0 / v**2
    return table, tol, weights


def _renamed(values: dict[str, Any]) -> dict[str, Any]:
    """A controller table's values by option field: ``horizon_pulses`` is ``horizon``."""
    return {("horizon" if k == "horizon_pulses" else k): v for k, v in values.items()}


def _option_key(
    message: str,
    options: tuple[Table, dict[str, Spec]],
    tolerances: tuple[Table, dict[str, Spec]],
    owner: str,
) -> str:
    """The key an OptionError's ``Class.field`` was written as: a field of ``owner`` (the
    options class) in the table, a field of its weights (its ``weights`` class, named in
    the message as ``...Weights.field``) in the tolerances, else the table itself."""
    (table, schema), (tol, tol_schema) = options, tolerances
    for field in (*schema, "horizon"):
        if f"{owner}.{field} " in message:
            return table.key("horizon_pulses" if field == "horizon" else field)
    for field in tol_schema:
        if f"Weights.{field} " in message:
            return tol.key(field)
    return table.where


def _loop_options(src: str, raw: Any) -> ClosedLoopOptions:
    if not isinstance(raw, dict):
        raise ProblemFileError(src, "plant", f"must be a table [plant], got {raw!r}")
    table = read_table(src, raw, "plant", _PLANT, tables=("noise", "dispersion", "wind"))
    noise = read_table(src, raw.get("noise", {}), "plant.noise", _NOISE)
    schema = {name: NUMBER for name in PARAMETERS.names}
    dispersion = read_table(src, raw.get("dispersion", {}), "plant.dispersion", schema)
    values = dict(table.values)
    faults = values.pop("fault_pulses", ())
    faults = (faults,) if not isinstance(faults, tuple) else faults
    if any(not float(k).is_integer() for k in faults):
        raise ProblemFileError(src, table.key("fault_pulses"), f"needs pulse numbers, got {faults}")
    try:
        return ClosedLoopOptions(
            noise=MeasurementNoise(**noise.values),
            dispersion=PlantDispersion(tuple(dispersion.values.items())),
            faults=tuple(int(k) for k in faults),
            **values,
        )
    except OptionError as err:
        message = str(err)
        key = "plant"
        for t, prefix in ((noise, "MeasurementNoise."), (table, "ClosedLoopOptions.")):
            for name in t.keys:
                if f"{prefix}{name}" in message:
                    key = t.key(name)
        if "PlantDispersion.relative[" in message:
            key = "plant.dispersion"
        if "ClosedLoopOptions.faults" in message:
            key = table.key("fault_pulses")
        raise ProblemFileError(src, key, message) from err


def _estimator(src: str, raw: Any, plant: Any, sensed: bool) -> EstimatorSpec:
    """``[estimator]`` read into an EstimatorSpec (SI); an estimator beside ``[plant.noise]``
    (the noise on the truth a controller is told without one) is refused naming it, and
    one without ``[sensors]`` (``sensed`` False: nothing to read) naming ``sensors``."""
    table = read_table(src, raw, "estimator", _ESTIMATOR)
    options = dict(table.values)
    kind = options.pop("kind", EstimatorKind.TRUTH)
    if "horizon_pulses" in options:
        options["horizon"] = options.pop("horizon_pulses")
    if kind is not EstimatorKind.TRUTH and isinstance(plant, dict) and "noise" in plant:
        raise ProblemFileError(
            src,
            "plant.noise",
            f"is the noise on the true state the controller is told without an estimator; "
            f'with kind = "{kind.value}" the controller is told the estimate, and the '
            "sensors' noise applies ([sensors]): remove [plant.noise]",
        )
    curved = options.get("second_order")
    if isinstance(curved, tuple):  # the names the factory's estimator will match
        try:
            entry_indices(estimated_names(), curved, "EstimatorSpec.options[second_order]")
        except OptionError as err:
            raise ProblemFileError(src, table.key("second_order"), str(err)) from err
    try:
        spec = EstimatorSpec(kind, options)
    except OptionError as err:
        message = str(err)
        key = table.where
        for field in options:
            if f"options[{field}]" in message:
                key = table.key("horizon_pulses" if field == "horizon" else field)
        raise ProblemFileError(src, key, message) from err
    if kind is not EstimatorKind.TRUTH and not sensed:
        raise ProblemFileError(
            src,
            "sensors",
            f"missing: the {kind.value} estimator reads the sensors; write [sensors.camera] "
            "(or an empty [sensors]: the 5 mm position camera)",
        )
    return spec


def _plant_wind(src: str, raw: Any) -> dict[str, Any]:
    """[plant.wind] read as a model file's [environment.wind], as parameter overrides."""
    wind = raw.get("wind") if isinstance(raw, dict) else None
    if wind is None:
        return {}
    try:
        values, keys = schema.read_fields(src, wind, "plant.wind", mf.SCHEMA["wind"], Wind)
        structural = [k for k in values if k not in _WIND_PARAMETERS]
        if structural:
            raise ProblemFileError(
                src,
                f"plant.wind.{keys[structural[0]]}",
                "wind tables are structure of the pulse map, not parameters: give them in "
                "[model_overrides.environment.wind] (the controller then knows them too)",
            )
        built = schema.build(src, {"wind": ("plant.wind", keys)}, Wind, values)
    except ModelFileError as err:
        raise ProblemFileError(src, err.field, err.reason) from err
    return {_WIND_PARAMETERS[f]: getattr(built, f) for f in _WIND_PARAMETERS}


def _sensor_options(src: str, raw: Any) -> SensorOptions | None:
    """``[sensors]`` read (docs/files/closed_loop.md#keys-sensors-camera); None without it.
    Without ``[sensors.camera]`` the camera is CameraOptions' (positions at 5 mm)."""
    if raw is None:
        return None
    read_table(src, raw, "sensors", {}, tables=_SENSORS)
    gyro = spin = None
    if "gyro" in raw:
        table = read_table(src, raw["gyro"], "sensors.gyro", _RATE_SENSOR)
        gyro = _built(src, table, GyroOptions, table.values)
    if "spin" in raw:
        table = read_table(src, raw["spin"], "sensors.spin", _RATE_SENSOR)
        spin = _built(src, table, SpinSensorOptions, table.values)
    return SensorOptions(_camera_options(src, raw.get("camera", {})), gyro, spin)


def _camera_options(src: str, raw: Any) -> CameraOptions:
    """``[sensors.camera]``: its noise a length, or an angle for ``kind = "stereo"`` (then
    required); ``lost_percent`` is CameraOptions.lost_rate in percent."""
    stereo = isinstance(raw, dict) and raw.get("kind") == CameraKind.STEREO.value
    table = read_table(
        src, raw, "sensors.camera", {**_CAMERA, "noise": _STEREO_NOISE} if stereo else _CAMERA
    )
    if stereo and "noise" not in table.values:
        raise ProblemFileError(
            src,
            "sensors.camera.noise",
            "missing: a stereo camera's noise is an angle; write noise_mrad (or noise_rad, "
            "noise_deg)",
        )
    values = dict(table.values)
    if "lost_percent" in values:
        values["lost_rate"] = values.pop("lost_percent") / 100.0
    if "sites" in values:
        values["sites"] = tuple(tuple(row) for row in values["sites"])
    return _built(src, table, CameraOptions, values)


def _built(src: str, table: Table, cls: type, values: dict[str, Any]) -> Any:
    """``cls(**values)``; its OptionError becomes a ProblemFileError naming the key as
    written in ``table`` (``lost_rate``: ``lost_percent``; a site: ``sites_m[i]``)."""
    try:
        return cls(**values)
    except OptionError as err:
        message = str(err)
        found = re.search(rf"{cls.__name__}\.(\w+)(\[\d+\])?", message)
        if not found:
            raise ProblemFileError(src, table.where, message) from err
        if found[1] == "lost_rate":
            message += " (lost_percent / 100)"
        field = "lost_percent" if found[1] == "lost_rate" else found[1]
        raise ProblemFileError(src, table.key(field) + (found[2] or ""), message) from err
