"""A model's default vectors: its parameters p, the map input u of an unsteered flight and
its launch state x, each laid out as :mod:`lightcraft_opt.layout.vectors` says.

- :func:`parameter_values`: p of a model, with overrides by slot name: the one way a
  problem, a closed loop or a campaign changes the model's parameters;
- :func:`nominal_inputs`: u of an unsteered flight, the one nominal-input policy;
- :func:`initial_state`: x at launch, and the attitudes it is made of
  (:func:`quaternion_from_tilt`, :func:`tilted_attitude`) and the body rates of a coning
  craft (:func:`coning_rates`).

Frames: docs/frames.md. All values SI.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout.vector_layout import VectorLayout
from lightcraft_opt.layout.vectors import PARAMETERS, STATE, map_input_layout
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import checked_vector

__all__ = [
    "coning_rates",
    "initial_state",
    "nominal_inputs",
    "parameter_values",
    "quaternion_from_tilt",
    "tilted_attitude",
]


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
    _quarter_turn(
        ("tilt", tilt),
        ("tilt_azimuth", azimuth),
        "lean toward the opposite azimuth instead of a negative tilt; at 90 the craft lies "
        "on its side",
    )
    return float(tilt), float(azimuth)


def _quarter_turn(angle: tuple[str, float], azimuth: tuple[str, float], hint: str) -> None:
    """Check an (angle, azimuth) pair [rad], each given as (name, value): both finite, the
    angle in [0, 90) degrees; the error names the argument and ends with ``hint``."""
    for name, value in (angle, azimuth):
        if not math.isfinite(value):
            raise ParameterError(name, f"must be finite, got {value}")
    name, value = angle
    if not 0.0 <= value < math.pi / 2:
        raise ParameterError(
            name, f"must lie in [0, 90) degrees, got {math.degrees(value):.6g}: {hint}"
        )


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


def coning_rates(
    model: Model, coning: float, azimuth: float = 0.0, spin: float | None = None
) -> np.ndarray:
    """w_B[b2], w_B[b3] [rad/s] of a craft coning by ``coning`` [rad] (the angle from its
    axis b1 to its angular momentum H) with H's transverse part at ``azimuth`` [rad] from
    b2 toward b3, spinning at ``spin`` [rad/s] (default the craft's) with w_B[b1] = 0:
    tan(coning) = A |w_⊥| / (J spin), A and J the craft's transverse and axial moments
    (exact for a centred rotor)."""
    _quarter_turn(
        ("coning", coning),
        ("coning_azimuth", azimuth),
        "the angle from the spin axis b1 to H (set its direction with coning_azimuth)",
    )
    craft = model.craft
    spin = craft.spin if spin is None else spin
    if coning and spin == 0.0:
        raise ParameterError("coning", "a craft without spin cannot cone")
    w_t = craft.inertia_axial * spin * math.tan(coning) / craft.inertia_transverse
    return np.array([w_t * math.cos(azimuth), w_t * math.sin(azimuth)])


def initial_state(
    model: Model,
    *,
    r_L: Sequence[float] = (0.0, 0.0, 0.0),
    v_L: Sequence[float] = (0.0, 0.0, 0.0),
    tilt: float = 0.0,
    tilt_azimuth: float = 0.0,
    w_B: Sequence[float] = (0.0, 0.0, 0.0),
    spin: float | None = None,
    coning: float = 0.0,
    coning_azimuth: float = 0.0,
) -> np.ndarray:
    """Launch state of ``model``: at the pad, upright, spinning at the craft's spin rate.

    Parameters
    ----------
    r_L, v_L : position [m] and velocity [m/s] of the mass centre, L frame.
    tilt, tilt_azimuth : see :func:`quaternion_from_tilt` [rad].
    w_B : angular velocity of B relative to N, B frame [rad/s].
    spin : rotor spin relative to B [rad/s]; default ``model.craft.spin``.
    coning, coning_azimuth : coning angle [rad] (b1 to H) and the direction of H's
        transverse part in B [rad, from b2 toward b3], added to ``w_B`` as
        :func:`coning_rates` (needs w_B[b1] = 0): what a closed-loop file's
        ``[initial] coning_deg`` sets. ``initial_state(model, coning=math.radians(5))``
        is the 5 degrees the nutation controllers are measured from (docs/mpc.md).
    """
    tilt, tilt_azimuth = _launch_angles(tilt, tilt_azimuth)
    for name, vec in (("r_L", r_L), ("v_L", v_L), ("w_B", w_B)):
        if not np.all(np.isfinite(np.asarray(vec, dtype=float))):
            raise ParameterError(name, f"must be finite, got {list(np.asarray(vec, float))}")
    if spin is not None and not math.isfinite(spin):
        raise ParameterError("spin", f"must be finite, got {spin}")
    craft = model.craft
    spin = craft.spin if spin is None else spin
    w = np.array(w_B, dtype=float)
    if coning or coning_azimuth:
        rates = coning_rates(model, coning, coning_azimuth, spin)
        if w.size == 3:  # else STATE.pack says w_B needs 3 values
            if coning and w[0] != 0.0:
                raise ParameterError("coning", f"needs w_B[b1] = 0, got {w[0]} rad/s")
            w[1:] += rates
    return STATE.pack(
        {
            "r_L": r_L,
            "v_L": v_L,
            "q_LB": quaternion_from_tilt(tilt, tilt_azimuth),
            "w_B": w,
            "spin": spin,
            "liner_mass": craft.liner.mass if craft.liner else 0.0,
            "rcs_mass": craft.rcs.propellant_mass if craft.rcs else 0.0,
            "engine_load": 0.0,
        }
    )
