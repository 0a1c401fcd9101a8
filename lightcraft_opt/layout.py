"""The one owner of state, input and parameter indices.

Physics code reads ``STATE.get("w_B", x)``, never ``x[10:13]``. Every slot has a
unit and a frame, and :meth:`VectorLayout.labels` turns them into plot and CSV
labels. Slicing works alike on numpy arrays and casadi SX/MX column vectors.

Frames: docs/frames.md. The state vector x (17 entries):

=============  ====  =======  ===================================================
slot           size  unit     meaning
=============  ====  =======  ===================================================
r_L            3     m        system mass centre relative to the pad, L frame
v_L            3     m/s      its velocity relative to the Earth (E), L frame
q_LB           4     -        attitude of B in L, unit quaternion (w, x, y, z)
w_B            3     rad/s    angular velocity of B relative to N, B frame
spin           1     rad/s    rotor spin rate relative to B, about b1
liner_mass     1     kg       Delrin liner left (0 for an air-mode craft)
rcs_mass       1     kg       RCS propellant left (0 without an RCS)
pulses         1     -        laser pulses fired so far (engine health)
=============  ====  =======  ===================================================

Per-pulse inputs (:data:`PULSE_INPUT`): ``pointing_L`` (2) [m], lateral offset of the
vertical beam axis from the pad, east and north; ``focus`` [m], focus distance (waist
beam model); ``energy`` [J], pulse energy.

The RCS inputs of the pulse map depend on :class:`~lightcraft_opt.options.RcsProfile`
(:func:`map_input_layout`; docs/frames.md, "RCS thrust over a pulse interval").
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.options import RcsProfile
from lightcraft_opt.params import Model

__all__ = [
    "CONING",
    "ENGINE",
    "ERROR_STATE",
    "PARAMETERS",
    "PULSE_INPUT",
    "STATE",
    "Slot",
    "VectorLayout",
    "checked_vector",
    "initial_state",
    "input_layout",
    "map_input_layout",
    "nominal_inputs",
    "parameter_values",
    "quaternion_from_tilt",
    "rcs_levels",
    "tilted_attitude",
]

T = TypeVar("T")


@dataclass(frozen=True)
class Slot:
    """A named block of a vector: ``size`` entries from ``start``, with unit and frame."""

    name: str
    start: int
    size: int
    unit: str
    frame: str = ""
    components: tuple[str, ...] = ()

    @property
    def stop(self) -> int:
        return self.start + self.size


class VectorLayout:
    """Named contiguous slots of a flat vector.

    Parameters
    ----------
    name : what the vector is ("state", "input", "parameters").
    spec : (name, size, unit, frame, component names) per slot, in order.
    """

    def __init__(
        self, name: str, spec: Sequence[tuple[str, int, str, str, tuple[str, ...]]]
    ) -> None:
        slots: list[Slot] = []
        start = 0
        for slot_name, size, unit, frame, comps in spec:
            if comps and len(comps) != size:
                raise ValueError(f"{name}.{slot_name}: {len(comps)} component names for {size}")
            slots.append(Slot(slot_name, start, size, unit, frame, comps))
            start += size
        self.name = name
        self.slots: tuple[Slot, ...] = tuple(slots)
        self.size = start
        self._by_name = {s.name: s for s in slots}
        if len(self._by_name) != len(slots):
            raise ValueError(f"{name}: duplicate slot names")

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __repr__(self) -> str:
        return f"VectorLayout({self.name!r}, {[s.name for s in self.slots]}, size={self.size})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, VectorLayout):
            return NotImplemented
        return (self.name, self.slots) == (other.name, other.slots)

    def __hash__(self) -> int:
        return hash((self.name, self.slots))

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.slots)

    def slot(self, name: str) -> Slot:
        try:
            return self._by_name[name]
        except KeyError:
            raise ParameterError(
                f"{self.name}.{name}", f"no such slot; the {self.name} holds {list(self.names)}"
            ) from None

    def index(self, name: str) -> slice:
        """The slice of slot ``name``."""
        s = self.slot(name)
        return slice(s.start, s.stop)

    def get(self, name: str, vector: T) -> T:
        """Slot ``name`` of ``vector`` (numpy array or casadi column); scalars come as 1-vectors
        for casadi and as floats for 1-D numpy."""
        s = self.slot(name)
        if s.size == 1:
            return vector[s.start]  # type: ignore[index]
        return vector[s.start : s.stop]  # type: ignore[index]

    def pack(
        self, values: Mapping[str, Any], default: Mapping[str, Any] | None = None
    ) -> np.ndarray:
        """Flat float vector from ``{slot: value}``; every slot given here or in ``default``."""
        out = np.empty(self.size)
        merged = dict(default or {})
        merged.update(values)
        unknown = set(merged) - set(self._by_name)
        if unknown:
            raise ParameterError(
                f"{self.name}.{sorted(unknown)[0]}",
                f"no such slot; the {self.name} holds {list(self.names)}",
            )
        for s in self.slots:
            if s.name not in merged:
                raise ParameterError(f"{self.name}.{s.name}", "missing")
            v = np.asarray(merged[s.name], dtype=float).reshape(-1)
            if v.size != s.size:
                raise ParameterError(
                    f"{self.name}.{s.name}", f"needs {s.size} values, got {v.size}"
                )
            if not np.all(np.isfinite(v)):
                raise ParameterError(f"{self.name}.{s.name}", "must be finite (got NaN or inf)")
            out[s.start : s.stop] = v
        return out

    def unpack(self, vector: Sequence[float] | np.ndarray) -> dict[str, np.ndarray | float]:
        """``{slot: value}`` from a flat numeric vector (floats for size-1 slots)."""
        v = np.asarray(vector, dtype=float).reshape(-1)
        if v.size != self.size:
            raise ParameterError(self.name, f"needs {self.size} values, got {v.size}")
        return {
            s.name: float(v[s.start]) if s.size == 1 else v[s.start : s.stop].copy()
            for s in self.slots
        }

    def labels(self) -> list[str]:
        """One label per entry, with unit: ``"r_L[east] [m]"``; for plots and CSV headers."""
        out: list[str] = []
        for s in self.slots:
            unit = f" [{s.unit}]" if s.unit else ""
            if s.size == 1:
                out.append(f"{s.name}{unit}")
            else:
                comps = s.components or tuple(str(i) for i in range(s.size))
                out.extend(f"{s.name}[{c}]{unit}" for c in comps)
        return out


ENU = ("east", "north", "up")
B123 = ("b1", "b2", "b3")

STATE = VectorLayout(
    "state",
    [
        ("r_L", 3, "m", "L", ENU),
        ("v_L", 3, "m/s", "L", ENU),
        ("q_LB", 4, "-", "L<-B", ("w", "x", "y", "z")),
        ("w_B", 3, "rad/s", "B", B123),
        ("spin", 1, "rad/s", "B", ()),
        ("liner_mass", 1, "kg", "", ()),
        ("rcs_mass", 1, "kg", "", ()),
        ("pulses", 1, "-", "", ()),
    ],
)

#: The error state δ of linear models (16 entries): STATE with the quaternion q_LB
#: replaced by theta_B, the small rotation of B from the operating attitude (B components;
#: the chart is symbolic/error_state.py). Every other slot is additive.
ERROR_STATE = VectorLayout(
    "error state",
    [
        ("r_L", 3, "m", "L", ENU),
        ("v_L", 3, "m/s", "L", ENU),
        ("theta_B", 3, "rad", "B", B123),
        ("w_B", 3, "rad/s", "B", B123),
        ("spin", 1, "rad/s", "B", ()),
        ("liner_mass", 1, "kg", "", ()),
        ("rcs_mass", 1, "kg", "", ()),
        ("pulses", 1, "-", "", ()),
    ],
)

#: Coning coordinates z of the nutation controllers (symbolic/coning_coordinates.py,
#: docs/frames.md): lateral position and velocity and the tilt of H in the yaw-aligned
#: frame Y, and the coning vector c_B (transverse over axial angular momentum, in B).
CONING = VectorLayout(
    "coning coordinates",
    [
        ("r_Y", 2, "m", "Y", ("y1", "y2")),
        ("v_Y", 2, "m/s", "Y", ("y1", "y2")),
        ("h_Y", 2, "rad", "Y", ("y1", "y2")),
        ("c_B", 2, "rad", "B", ("b2", "b3")),
    ],
)

#: Per-pulse engine quantities, Φ's second output (symbolic/pulse_map.py).
ENGINE = VectorLayout(
    "engine output",
    [
        ("energy_captured", 1, "J", "", ()),
        ("impulse_B", 3, "N s", "B", B123),
        ("angular_impulse_B", 3, "N m s", "B", B123),
        ("offset_L", 2, "m", "L", ("east", "north")),
        ("liner_loss", 1, "kg", "", ()),
        ("health", 1, "-", "", ()),
    ],
)

#: Per-pulse laser inputs: where the beam axis points, where it focuses, how much energy.
PULSE_INPUT = VectorLayout(
    "pulse input",
    [
        ("pointing_L", 2, "m", "L", ("east", "north")),
        ("focus", 1, "m", "L", ()),
        ("energy", 1, "J", "", ()),
    ],
)


def map_input_layout(
    n_thrusters: int,
    has_carrier: bool,
    rcs_profile: RcsProfile = RcsProfile.HOLD,
    rcs_subintervals: int = 1,
) -> VectorLayout:
    """Inputs u[k] of the pulse map: the pulse (:data:`PULSE_INPUT` slots), then the RCS
    thrust over the interval, then the motor torque held over the interval (a gyrostat).

    Parameters
    ----------
    n_thrusters : RCS thrusters of the craft (0: no RCS slots).
    has_carrier : the craft has a despun carrier (adds ``motor_torque`` [N m]).
    rcs_profile : how the thrust varies over the interval (τ = t - t_k, time since the
        pulse [s]; thruster i fires along its fixed direction in B):

        - ``HOLD``: ``rcs_thrust`` (n) [N], level i held for the whole interval.
        - ``SUBINTERVALS``: ``rcs_thrust`` (n * m) [N], m = ``rcs_subintervals`` equal
          sub-intervals, **sub-interval-major**: entry j n + i is thruster i on
          sub-interval j, i.e. on τ in [j T / m, (j + 1) T / m) (T the pulse period);
          :func:`rcs_levels` gives the slice of sub-interval j.
        - ``PHASE_LOCKED``: ``rcs_thrust`` (n) [N], the mean levels, then ``rcs_cos`` (n)
          and ``rcs_sin`` (n) [N]: thrust_i(τ) = rcs_thrust_i + rcs_cos_i cos(ω τ)
          + rcs_sin_i sin(ω τ), ω the coning rate in B right after the pulse
          (:func:`lightcraft_opt.symbolic.coast.coning_rate_B`).

        Φ does not clip the thrust (a smooth map for the optimiser): whoever sets the
        inputs keeps 0 <= thrust_i(τ) <= max_thrust_i at every τ, e.g. for
        ``PHASE_LOCKED`` sqrt(cos_i^2 + sin_i^2) <= min(mean_i, max_i - mean_i)
        (:class:`lightcraft_opt.ocp.problem.RcsEnvelope`).
    rcs_subintervals : m >= 1; more than 1 only with ``SUBINTERVALS``.
    """
    if not isinstance(rcs_profile, RcsProfile):
        raise ParameterError(
            "rcs_profile", f"must be one of {[r.value for r in RcsProfile]}, got {rcs_profile!r}"
        )
    m = rcs_subintervals
    if isinstance(m, bool) or not isinstance(m, int) or m < 1:
        raise ParameterError("rcs_subintervals", f"must be a positive integer, got {m!r}")
    if m > 1 and rcs_profile is not RcsProfile.SUBINTERVALS:
        raise ParameterError(
            "rcs_subintervals", f"must be 1 with rcs_profile {rcs_profile.value!r}, got {m}"
        )
    spec = [(s.name, s.size, s.unit, s.frame, s.components) for s in PULSE_INPUT.slots]
    if n_thrusters and rcs_profile is RcsProfile.SUBINTERVALS:
        comps = tuple(f"sub{j}.thr{i}" for j in range(m) for i in range(n_thrusters))
        spec.append(("rcs_thrust", n_thrusters * m, "N", "", comps))
    elif n_thrusters:
        spec.append(("rcs_thrust", n_thrusters, "N", "", ()))
        if rcs_profile is RcsProfile.PHASE_LOCKED:
            spec.append(("rcs_cos", n_thrusters, "N", "", ()))
            spec.append(("rcs_sin", n_thrusters, "N", "", ()))
    if has_carrier:
        spec.append(("motor_torque", 1, "N m", "B", ()))
    return VectorLayout("map input", spec)


def rcs_levels(layout: VectorLayout, n_thrusters: int, subinterval: int = 0) -> slice:
    """Where the n thrust levels [N] of sub-interval ``subinterval`` sit in a map input of
    ``layout`` (sub-interval-major ``rcs_thrust``, :func:`map_input_layout`); for HOLD
    and PHASE_LOCKED layouts sub-interval 0 is the whole ``rcs_thrust`` slot."""
    slot = layout.slot("rcs_thrust")
    if n_thrusters < 1 or slot.size % n_thrusters:
        raise ParameterError(
            "n_thrusters", f"{n_thrusters} does not split rcs_thrust of size {slot.size}"
        )
    if not 0 <= subinterval < slot.size // n_thrusters:
        raise ParameterError(
            "subinterval", f"must lie in [0, {slot.size // n_thrusters}), got {subinterval}"
        )
    start = slot.start + subinterval * n_thrusters
    return slice(start, start + n_thrusters)


def input_layout(n_thrusters: int, has_carrier: bool) -> VectorLayout:
    """Continuous inputs u: RCS thrust levels [N] and, for a gyrostat, the motor torque
    on the rotor about b1 [N m]."""
    spec: list[tuple[str, int, str, str, tuple[str, ...]]] = []
    if n_thrusters:
        spec.append(("rcs_thrust", n_thrusters, "N", "", ()))
    if has_carrier:
        spec.append(("motor_torque", 1, "N m", "B", ()))
    return VectorLayout("input", spec)


PARAMETERS = VectorLayout(
    "parameters",
    [
        ("rotor_mass_dry", 1, "kg", "", ()),
        ("rotor_axial_inertia_dry", 1, "kg m^2", "B", ()),
        ("rotor_transverse_inertia_dry", 1, "kg m^2", "B", ()),
        ("liner_radius", 1, "m", "", ()),
        ("liner_offset", 1, "m", "B", ()),
        ("carrier_mass", 1, "kg", "", ()),
        ("carrier_inertia", 6, "kg m^2", "B", ("xx", "yy", "zz", "xy", "xz", "yz")),
        ("carrier_position_B", 3, "m", "B", B123),
        ("rcs_isp", 1, "s", "", ()),
        ("rcs_tank_B", 3, "m", "B", B123),
        ("diameter", 1, "m", "", ()),
        ("reference_length", 1, "m", "", ()),
        ("cd_scale", 1, "-", "", ()),
        ("cl_scale", 1, "-", "", ()),
        ("cm_scale", 1, "-", "", ()),
        ("magnus_force_coefficient", 1, "-", "", ()),
        ("magnus_moment_coefficient", 1, "-", "", ()),
        ("spin_time_constant", 1, "s", "", ()),
        ("disk_faces", 1, "-", "", ()),
        ("site_latitude", 1, "rad", "", ()),
        ("site_longitude", 1, "rad", "", ()),
        ("site_height", 1, "m", "", ()),
        ("wind_speed_ref", 1, "m/s", "L", ()),
        ("wind_height_ref", 1, "m", "L", ()),
        ("wind_roughness_height", 1, "m", "L", ()),
        ("wind_shear_exponent", 1, "-", "", ()),
        ("wind_direction_from", 1, "rad", "L", ()),
        ("wind_veer", 1, "rad/m", "L", ()),
        ("gust_L", 3, "m/s", "L", ENU),
        ("gust_start", 1, "s", "", ()),
        ("gust_duration", 1, "s", "", ()),
        ("beam_side", 1, "m", "", ()),
        ("beam_divergence", 1, "rad", "", ()),
        ("beam_hole_ratio", 1, "-", "", ()),
        ("beam_edge_width", 1, "m", "", ()),
        ("beam_rayleigh_range", 1, "m", "", ()),
        ("impulse_per_pulse", 1, "N s", "", ()),
        ("reference_pulse_energy", 1, "J", "", ()),
        ("capture_radius", 1, "m", "B", ()),
        ("shadow_radius", 1, "m", "B", ()),
        ("ring_radius", 1, "m", "B", ()),
        ("ring_height", 1, "m", "B", ()),
        ("blast_angle", 1, "rad", "", ()),
        ("lateral_gain", 1, "-", "", ()),
        ("tipping_gain", 1, "-", "", ()),
        ("kernel_offset", 1, "m", "", ()),
        ("health_floor", 1, "-", "", ()),
        ("health_pulse", 1, "-", "", ()),
        ("health_width", 1, "-", "", ()),
        ("ablation", 1, "kg/J", "", ()),
        ("spent_coupling", 1, "N s/J", "", ()),
    ],
)


def checked_vector(name: str, value: Sequence[float] | np.ndarray, size: int) -> np.ndarray:
    """``value`` as a flat float vector of ``size`` finite entries, or a ParameterError
    naming ``name``."""
    try:
        v = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(name, f"must be {size} numbers, got {value!r}") from None
    if v.size != size:
        raise ParameterError(name, f"needs {size} values, got {v.size}")
    if not np.all(np.isfinite(v)):
        raise ParameterError(name, "must be finite (got NaN or inf)")
    return v


def parameter_values(
    model: Model, overrides: Mapping[str, float | Sequence[float]] | None = None
) -> np.ndarray:
    """The numeric parameter vector p of ``model`` (SI, order of :data:`PARAMETERS`), with
    ``overrides`` {PARAMETERS slot: value (SI, the slot's frame)} set on top: the one way
    a problem, a closed loop or a campaign changes the model's parameters (wind, gusts,
    aerodynamics ...). An unknown slot or a wrong size raises a ParameterError naming
    ``parameters.<slot>``."""
    p = _model_parameter_values(model)
    for name, value in (overrides or {}).items():
        if name not in PARAMETERS:
            raise ParameterError(
                f"parameters.{name}", f"no such parameter; see {list(PARAMETERS.names)}"
            )
        size = PARAMETERS.slot(name).size
        p[PARAMETERS.index(name)] = checked_vector(f"parameters.{name}", np.ravel(value), size)
    return p


def _model_parameter_values(model: Model) -> np.ndarray:
    craft = model.craft
    j_dry, i_dry = craft.dry_rotor_inertia()
    liner = craft.liner
    carrier = craft.carrier
    rcs = craft.rcs
    wind = model.environment.wind
    engine = craft.engine
    return PARAMETERS.pack(
        {
            "rotor_mass_dry": craft.mass - (liner.mass if liner else 0.0),
            "rotor_axial_inertia_dry": j_dry,
            "rotor_transverse_inertia_dry": i_dry,
            "liner_radius": liner.radius if liner else 0.0,
            "liner_offset": liner.axial_offset if liner else 0.0,
            "carrier_mass": carrier.mass if carrier else 0.0,
            "carrier_inertia": carrier.inertia if carrier else (0.0,) * 6,
            "carrier_position_B": carrier.position_B if carrier else (0.0,) * 3,
            "rcs_isp": rcs.isp if rcs else 1.0,
            "rcs_tank_B": rcs.tank_position_B if rcs else (0.0,) * 3,
            "diameter": craft.diameter,
            "reference_length": craft.reference_length,
            "cd_scale": craft.aero.cd_scale,
            "cl_scale": craft.aero.cl_scale,
            "cm_scale": craft.aero.cm_scale,
            "magnus_force_coefficient": craft.aero.magnus_force_coefficient,
            "magnus_moment_coefficient": craft.aero.magnus_moment_coefficient,
            "spin_time_constant": craft.spin_decay.time_constant,
            "disk_faces": craft.spin_decay.disk_faces,
            "site_latitude": model.site.latitude,
            "site_longitude": model.site.longitude,
            "site_height": model.site.height,
            "wind_speed_ref": wind.speed_ref,
            "wind_height_ref": wind.height_ref,
            "wind_roughness_height": wind.roughness_height,
            "wind_shear_exponent": wind.shear_exponent,
            "wind_direction_from": wind.direction_from,
            "wind_veer": wind.veer,
            "gust_L": wind.gust_L,
            "gust_start": wind.gust_start,
            "gust_duration": wind.gust_duration,
            "beam_side": model.flight.beam_side,
            "beam_divergence": model.laser.divergence,
            "beam_hole_ratio": model.laser.hole_ratio,
            "beam_edge_width": model.laser.edge_width,
            "beam_rayleigh_range": model.laser.rayleigh_range,
            "impulse_per_pulse": model.flight.impulse_per_pulse,
            "reference_pulse_energy": model.flight.pulse_energy,
            "capture_radius": engine.capture_radius,
            "shadow_radius": engine.shadow_radius,
            "ring_radius": engine.ring_radius,
            "ring_height": engine.ring_height,
            "blast_angle": engine.blast_angle,
            "lateral_gain": engine.lateral_gain,
            "tipping_gain": engine.tipping_gain,
            "kernel_offset": engine.kernel_offset,
            "health_floor": engine.health_floor,
            "health_pulse": engine.health_pulse,
            "health_width": engine.health_width,
            "ablation": engine.ablation,
            "spent_coupling": (
                model.flight.coupling_coefficient
                if engine.spent_coupling is None
                else engine.spent_coupling
            ),
        }
    )


def nominal_inputs(model: Model, layout: VectorLayout | None = None) -> np.ndarray:
    """The map input of an unsteered flight: beam on the pad axis, focus at the far end of
    the laser's range, the flight's pulse energy, RCS and motor off. ``layout``: the map
    input layout (a pulse map's ``inputs``); default the model's with held RCS levels."""
    craft = model.craft
    lay = layout or map_input_layout(craft.thruster_count, craft.has_carrier)
    values: dict[str, object] = {
        "pointing_L": (0.0, 0.0),
        "focus": model.laser.focus_range[1],
        "energy": model.flight.pulse_energy,
    }
    values.update({s.name: np.zeros(s.size) for s in lay.slots if s.name not in values})
    return lay.pack(values)


def quaternion_from_tilt(tilt: float = 0.0, azimuth: float = 0.0) -> np.ndarray:
    """Attitude q_LB (w, x, y, z) of a craft whose axis b1 is tilted from up.

    Parameters
    ----------
    tilt : angle between b1 and the local vertical (L up) [rad].
    azimuth : direction the axis leans toward, clockwise from north [rad].

    At zero tilt b1 = up, b2 = east, b3 = north. The tilt rotates B about the
    horizontal axis perpendicular to the lean direction.
    """
    # Upright: R_LB = [up, east, north] as columns, i.e. q0 = (1/2)(1, -1, -1, -1).
    return tilted_attitude(np.array([0.5, -0.5, -0.5, -0.5]), tilt, azimuth)


def _launch_angles(tilt: float, azimuth: float) -> tuple[float, float]:
    """(tilt, azimuth) [rad] checked: both finite, 0 <= tilt < pi/2 (at 90 degrees the
    craft lies on its side and no beam reaches its optic)."""
    for name, value in (("tilt", tilt), ("tilt_azimuth", azimuth)):
        if not math.isfinite(value):
            raise ParameterError(name, f"must be finite, got {value}")
    if not 0.0 <= tilt < math.pi / 2:
        raise ParameterError(
            "tilt",
            f"must lie in [0, 90) degrees, got {math.degrees(tilt):.6g}: lean toward the "
            "opposite azimuth instead of a negative tilt; at 90 the craft lies on its side",
        )
    return float(tilt), float(azimuth)


def tilted_attitude(q_LB: np.ndarray, tilt: float, azimuth: float = 0.0) -> np.ndarray:
    """The attitude q_LB (w, x, y, z) turned in L by a lean of ``tilt`` [rad] toward
    ``azimuth`` [rad, clockwise from north]: about the horizontal L axis perpendicular to
    the lean, so an upright b1 ends tilted by ``tilt`` toward ``azimuth``."""
    q = np.asarray(q_LB, dtype=float)
    if tilt == 0.0:
        return q
    lean_L = np.array([math.sin(azimuth), math.cos(azimuth), 0.0])
    axis_L = np.cross(np.array([0.0, 0.0, 1.0]), lean_L)  # rotating up toward lean
    h = 0.5 * tilt
    q_tilt = np.concatenate([[math.cos(h)], math.sin(h) * axis_L])
    return _quat_mul(q_tilt, q)


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ]
    )


def initial_state(
    model: Model,
    *,
    r_L: Sequence[float] = (0.0, 0.0, 0.0),
    v_L: Sequence[float] = (0.0, 0.0, 0.0),
    tilt: float = 0.0,
    tilt_azimuth: float = 0.0,
    w_B: Sequence[float] = (0.0, 0.0, 0.0),
    spin: float | None = None,
) -> np.ndarray:
    """Launch state of ``model``: at the pad, upright, spinning at the craft's spin rate.

    Parameters
    ----------
    r_L, v_L : position [m] and velocity [m/s] of the mass centre, L frame.
    tilt, tilt_azimuth : see :func:`quaternion_from_tilt` [rad].
    w_B : angular velocity of B relative to N, B frame [rad/s].
    spin : rotor spin relative to B [rad/s]; default ``model.craft.spin``.
    """
    tilt, tilt_azimuth = _launch_angles(tilt, tilt_azimuth)
    for name, vec in (("r_L", r_L), ("v_L", v_L), ("w_B", w_B)):
        if not np.all(np.isfinite(np.asarray(vec, dtype=float))):
            raise ParameterError(name, f"must be finite, got {list(np.asarray(vec, float))}")
    if spin is not None and not math.isfinite(spin):
        raise ParameterError("spin", f"must be finite, got {spin}")
    craft = model.craft
    return STATE.pack(
        {
            "r_L": r_L,
            "v_L": v_L,
            "q_LB": quaternion_from_tilt(tilt, tilt_azimuth),
            "w_B": w_B,
            "spin": craft.spin if spin is None else spin,
            "liner_mass": craft.liner.mass if craft.liner else 0.0,
            "rcs_mass": craft.rcs.propellant_mass if craft.rcs else 0.0,
            "pulses": 0.0,
        }
    )
