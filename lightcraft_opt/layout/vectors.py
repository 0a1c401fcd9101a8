"""Every vector layout: the one owner of state, input, parameter and output indices.

Each layout is a :class:`~lightcraft_opt.layout.vector_layout.VectorLayout` of named
slots with unit and frame; a layout whose size depends on the craft (its RCS thrusters, a
carrier) is built by a function here. A model's default values in these layouts are in
:mod:`lightcraft_opt.layout.defaults`.

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

The RCS inputs of the pulse map depend on :class:`RcsProfile`
(:func:`map_input_layout`; docs/frames.md, "RCS thrust over a pulse interval").
"""

from __future__ import annotations

from enum import Enum

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout.vector_layout import VectorLayout

__all__ = [
    "B123",
    "CONING",
    "EAST_NORTH",
    "ENGINE",
    "ENU",
    "ERROR_STATE",
    "PARAMETERS",
    "PULSE_INPUT",
    "REDUCED_STATE",
    "STATE",
    "RcsProfile",
    "input_layout",
    "map_input_layout",
    "rcs_levels",
    "substep_input_layout",
    "thruster_numbers",
]

#: Components of an L vector (docs/frames.md): east, north, up.
ENU = ("east", "north", "up")
#: Components of a B vector: along the craft's axis b1, and across it, b2 and b3.
B123 = ("b1", "b2", "b3")
#: The horizontal components of an L vector.
EAST_NORTH = ENU[:2]

#: The state x (17 entries; docs/frames.md#state-vector). ``engine_load`` is not a count of
#: pulses: it is the laser energy delivered so far over the reference pulse energy E_ref
#: (each pulse adds E / E_ref, a dropped one 0; 0.723 after one pulse of 0.723 E_ref), the
#: heat load the engine's health reads (docs/physics.md#health). Pulses fired are counted
#: by a result (``SimulationResult.pulses_fired``).
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
        ("engine_load", 1, "-", "", ()),
    ],
)

#: The error state δ of linear models (16 entries): STATE with the quaternion q_LB
#: replaced by theta_B, the small rotation of B from the operating attitude (B components;
#: the chart is symbolic/maps/error_state.py). Every other slot is additive.
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
        ("engine_load", 1, "-", "", ()),
    ],
)

#: The state z of the coning-aware reduced map Ψ (14 entries; symbolic/maps/reduced_map.py,
#: docs/beam_riding.md#reduced-map): the mass centre's position and velocity, the system
#: angular momentum H_L about the mass centre (its direction the cone's mean axis), the
#: coning offset: b1's components across Ĥ along e1, e2 of the frame T_H = [e1 e2 Ĥ] (L's
#: east and north turned by the smallest rotation that takes up onto Ĥ), and Φ's
#: bookkeeping.
REDUCED_STATE = VectorLayout(
    "reduced state",
    [
        ("r_L", 3, "m", "L", ENU),
        ("v_L", 3, "m/s", "L", ENU),
        ("H_L", 3, "kg m^2/s", "L", ENU),
        ("coning", 2, "-", "T_H", ("e1", "e2")),
        ("liner_mass", 1, "kg", "", ()),
        ("rcs_mass", 1, "kg", "", ()),
        ("engine_load", 1, "-", "", ()),
    ],
)

#: Coning coordinates z of the nutation controllers (symbolic/maps/coning_coordinates.py,
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

#: Per-pulse engine quantities, Φ's second output (symbolic/maps/pulse_map.py).
ENGINE = VectorLayout(
    "engine output",
    [
        ("energy_captured", 1, "J", "", ()),
        ("impulse_B", 3, "N s", "B", B123),
        ("angular_impulse_B", 3, "N m s", "B", B123),
        ("offset_L", 2, "m", "L", EAST_NORTH),
        ("liner_loss", 1, "kg", "", ()),
        ("health", 1, "-", "", ()),
    ],
)

#: Per-pulse laser inputs: where the beam axis points, where it focuses, how much energy.
PULSE_INPUT = VectorLayout(
    "pulse input",
    [
        ("pointing_L", 2, "m", "L", EAST_NORTH),
        ("focus", 1, "m", "L", ()),
        ("energy", 1, "J", "", ()),
    ],
)


class RcsProfile(Enum):
    """How the RCS thrust varies over one pulse interval (layout.map_input_layout).

    ``HOLD``: one level per thruster, held from pulse to pulse. ``SUBINTERVALS``: one
    level per thruster on each of ``rcs_subintervals`` equal sub-intervals of the
    interval. ``PHASE_LOCKED``: a mean level plus a cosine and a sine at the coning
    (nutation) rate seen in B, so the torque can turn with the ~216 Hz coning mode
    (docs/frames.md, "RCS thrust over a pulse interval").
    """

    HOLD = "hold"
    SUBINTERVALS = "subintervals"
    PHASE_LOCKED = "phase_locked"


def thruster_numbers(n_thrusters: int) -> tuple[str, ...]:
    """The thrusters' names as people number them, "1" to "n": the components of the RCS
    slots (``rcs_thrust[1]``), the columns ``rcs_thrust_1_n`` and the plots' legends.
    Python's array indices into them stay 0-based."""
    return tuple(str(i + 1) for i in range(n_thrusters))


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
          (:func:`lightcraft_opt.symbolic.maps.coast.coning_rate_B`).

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
        comps = tuple(f"sub{j + 1}.thr{i}" for j in range(m) for i in thruster_numbers(n_thrusters))
        spec.append(("rcs_thrust", n_thrusters * m, "N", "", comps))
    elif n_thrusters:
        spec.append(("rcs_thrust", n_thrusters, "N", "", thruster_numbers(n_thrusters)))
        if rcs_profile is RcsProfile.PHASE_LOCKED:
            spec.append(("rcs_cos", n_thrusters, "N", "", thruster_numbers(n_thrusters)))
            spec.append(("rcs_sin", n_thrusters, "N", "", thruster_numbers(n_thrusters)))
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
        spec.append(("rcs_thrust", n_thrusters, "N", "", thruster_numbers(n_thrusters)))
    if has_carrier:
        spec.append(("motor_torque", 1, "N m", "B", ()))
    return VectorLayout("input", spec)


def substep_input_layout(n_thrusters: int, has_carrier: bool, profile: RcsProfile) -> VectorLayout:
    """Inputs w of Φ's coast substep (symbolic/maps/pulse_map_pieces.py) by RCS profile.

    HOLD and SUBINTERVALS: the continuous inputs (:func:`input_layout`: the thrust levels of
    the substep's sub-interval [N], the motor torque [N m]). PHASE_LOCKED: the mean, cosine
    and sine amplitudes ``rcs_thrust``, ``rcs_cos``, ``rcs_sin`` (n each) [N], the motor
    torque [N m], the coning rate ω [rad/s, B] and the pulse time t_k [s] (the phase is
    ω (t - t_k)).
    """
    if profile is not RcsProfile.PHASE_LOCKED:
        return input_layout(n_thrusters, has_carrier)
    spec: list[tuple[str, int, str, str, tuple[str, ...]]] = [
        ("rcs_thrust", n_thrusters, "N", "", thruster_numbers(n_thrusters)),
        ("rcs_cos", n_thrusters, "N", "", thruster_numbers(n_thrusters)),
        ("rcs_sin", n_thrusters, "N", "", thruster_numbers(n_thrusters)),
    ]
    if has_carrier:
        spec.append(("motor_torque", 1, "N m", "B", ()))
    spec += [("coning_rate", 1, "rad/s", "B", ()), ("pulse_time", 1, "s", "", ())]
    return VectorLayout("substep input", spec)


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
