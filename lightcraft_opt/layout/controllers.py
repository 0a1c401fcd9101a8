"""The layouts of the controllers' own vectors (control/): what the nutation MPC's
prediction model linearises, and the director's quadratic programme (control/director.py,
docs/director.md): its states, inputs, stage variables, objective outputs and learnt
disturbance.

Built from the model's layouts (:mod:`lightcraft_opt.layout.vectors`) where they share
slots, so a slot's unit and frame have one owner. Frames: docs/frames.md.
"""

from __future__ import annotations

from collections.abc import Sequence

from lightcraft_opt.layout.vector_layout import VectorLayout
from lightcraft_opt.layout.vectors import (
    B123,
    EAST_NORTH,
    PULSE_INPUT,
    REDUCED_STATE,
    RcsProfile,
    map_input_layout,
)

__all__ = [
    "CONING_ERROR_STATE",
    "DIRECTOR_DISTURBANCE",
    "DIRECTOR_INPUT",
    "DIRECTOR_OUTPUT",
    "DIRECTOR_STAGE",
    "DIRECTOR_STATE",
    "DIRECTOR_TERMINAL_OUTPUT",
    "coning_input_layout",
    "mpc_diagnostics_layout",
    "mpc_memory_layout",
]

Spec = list[tuple[str, int, str, str, tuple[str, ...]]]


def _spec(layout: VectorLayout, names: Sequence[str]) -> Spec:
    """The spec rows of ``layout``'s slots ``names``, in that order (unit, frame and
    components as ``layout`` has them)."""
    return [(s.name, s.size, s.unit, s.frame, s.components) for s in map(layout.slot, names)]


#: The error-state entries (ERROR_STATE) the nutation controllers' prediction model is
#: linearised in (control/prediction_model.py): the lateral position and velocity and the
#: transverse attitude and rate, the counterparts, in order, of the coning coordinates
#: r_Y, v_Y, h_Y, c_B (CONING). Left out: the vertical channel, the turn about b1 and its
#: rate (a gauge), the spin and the bookkeeping.
CONING_ERROR_STATE = VectorLayout(
    "coning error state",
    [
        ("r_L", 2, "m", "L", EAST_NORTH),
        ("v_L", 2, "m/s", "L", EAST_NORTH),
        ("theta_B", 2, "rad", "B", B123[1:]),
        ("w_B", 2, "rad/s", "B", B123[1:]),
    ],
)


def coning_input_layout(n_thrusters: int) -> VectorLayout:
    """The map-input slots the nutation controllers' prediction model takes, in order: the
    beam's ``pointing_L`` (2) [m] and the phase-locked RCS's ``rcs_thrust``, ``rcs_cos``,
    ``rcs_sin`` (``n_thrusters`` each) [N] (:func:`~.vectors.map_input_layout`,
    PHASE_LOCKED)."""
    full = map_input_layout(n_thrusters, False, RcsProfile.PHASE_LOCKED)
    names = ("pointing_L", "rcs_thrust", "rcs_cos", "rcs_sin")
    return VectorLayout("coning input", _spec(full, names))


def mpc_memory_layout(horizon: int, n_w: int, n_a: int) -> VectorLayout:
    """The nutation MPC's memory between pulses (control/mpc_step.py), all zeros before a
    flight: ``plan_w`` (n_w) the primal solution of the latest solve that flew, by stage
    ([z_0, v_0, ..., z_N], control/mpc_qp.py); the warm start of the next solve
    ``warm_w`` (n_w), ``warm_lam_x`` (n_w), ``warm_lam_a`` (n_a): that solution shifted a
    stage a pulse; ``plan_yaw`` [rad] the yaw the plan was made at; ``plan_age`` [pulses]
    since then; ``has_plan`` (1 or 0); the phase tracker's ``phase_correction`` [rad] and
    the coning vector it expects at the next pulse, ``phase_expected`` [rad, B], with
    ``has_expected`` (1 or 0). ``horizon`` N sets no slot's size (n_w and n_a hold it)."""
    if horizon < 1 or n_w < 1 or n_a < 1:
        raise ValueError(f"mpc memory: horizon {horizon}, n_w {n_w}, n_a {n_a} must be >= 1")
    return VectorLayout(
        "mpc memory",
        [
            ("plan_w", n_w, "", "", ()),
            ("warm_w", n_w, "", "", ()),
            ("warm_lam_x", n_w, "", "", ()),
            ("warm_lam_a", n_a, "", "", ()),
            ("plan_yaw", 1, "rad", "L", ()),
            ("plan_age", 1, "", "", ()),
            ("has_plan", 1, "", "", ()),
            ("phase_correction", 1, "rad", "", ()),
            ("phase_expected", 2, "rad", "B", B123[1:]),
            ("has_expected", 1, "", "", ()),
        ],
    )


def mpc_diagnostics_layout(horizon: int) -> VectorLayout:
    """What the nutation MPC's step Function tells besides its input (control/mpc_step.py):
    ``cost`` of the QP that flies; ``finite`` (1: the solution is finite, 0: the
    fallback's outputs were chosen); ``solves`` (QP solves made: 2 on a pulse without a
    plan, 0 in the fallback Function); ``phase_correction`` [rad] the tracker's, used
    this pulse; ``coning_expected`` (N) |c| [-] at each pulse of the horizon the last QP
    was posed with; ``z`` (8) the measured coning coordinates (layout CONING);
    ``used_up`` (1: the fallback flies the operating input)."""
    return VectorLayout(
        "mpc diagnostics",
        [
            ("cost", 1, "", "", ()),
            ("finite", 1, "", "", ()),
            ("solves", 1, "", "", ()),
            ("phase_correction", 1, "rad", "", ()),
            ("coning_expected", horizon, "", "", ()),
            ("z", 8, "", "", ()),
            ("used_up", 1, "", "", ()),
        ],
    )


#: The director QP's states (11 entries): the head of Ψ's state REDUCED_STATE, whose
#: bookkeeping (liner, RCS propellant, pulse count) is no decision: it follows Ψ's own
#: prediction, and leaving it out of the QP makes each Riccati step (cubic in the states)
#: about half as dear.
DIRECTOR_STATE = VectorLayout(
    "director state", _spec(REDUCED_STATE, ("r_L", "v_L", "H_L", "coning"))
)

#: The director QP's inputs (6 entries): the beam's pointing, the focus's vergence κ = 1/f
#: [1/m] (the beam's side is nearly affine in it, where f spans 2-500 m), the pulse energy
#: and the RCS's transverse torque held over the pulse interval (zero without an RCS in
#: "tilt" mode).
DIRECTOR_INPUT = VectorLayout(
    "director input",
    [
        *_spec(PULSE_INPUT, ("pointing_L",)),
        ("vergence", 1, "1/m", "L", ()),
        *_spec(PULSE_INPUT, ("energy",)),
        ("torque_B", 2, "N m", "B", B123[1:]),
    ],
)

#: The director QP's variables of one stage, [δz_j; δu_j]: its states, then its inputs.
DIRECTOR_STAGE = VectorLayout(
    "director stage",
    _spec(DIRECTOR_STATE, DIRECTOR_STATE.names) + _spec(DIRECTOR_INPUT, DIRECTOR_INPUT.names),
)

#: The outputs y = C [z; u] of the director's least-squares objective a stage (16 entries,
#: each weighted by its DirectorWeights field): the beam's offset from the mass centre
#: r_L - pointing_L, the drift r_L from the pad axis, the lateral velocity, the coning
#: offset, the tilt of H (H_L over the launch's |H|, east and north), and the inputs.
DIRECTOR_OUTPUT = VectorLayout(
    "director output",
    [
        ("offset_L", 2, "m", "L", EAST_NORTH),
        ("drift_L", 2, "m", "L", EAST_NORTH),
        ("velocity_L", 2, "m/s", "L", EAST_NORTH),
        *_spec(REDUCED_STATE, ("coning",)),
        ("tilt_L", 2, "rad", "L", EAST_NORTH),
        *_spec(DIRECTOR_INPUT, DIRECTOR_INPUT.names),
    ],
)

#: The outputs of the director's terminal objective (8 entries): the state's outputs at
#: the end of the horizon (the drift there weighted as offset and drift together).
DIRECTOR_TERMINAL_OUTPUT = VectorLayout(
    "director terminal output",
    _spec(DIRECTOR_OUTPUT, ("drift_L", "velocity_L", "coning", "tilt_L")),
)

#: What the director learns a pulse of the plant's disturbance (4 entries): the increments
#: a pulse of the lateral velocity [m/s] and of the lateral angular momentum [kg m²/s] that
#: Ψ misses, added to every predicted stage.
DIRECTOR_DISTURBANCE = VectorLayout(
    "director disturbance",
    [("v_L", 2, "m/s", "L", EAST_NORTH), ("H_L", 2, "kg m^2/s", "L", EAST_NORTH)],
)
