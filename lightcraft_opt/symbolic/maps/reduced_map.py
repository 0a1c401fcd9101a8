"""A coning-aware reduced pulse map for planning and prediction: z[k+1] = Ψ(z[k], u[k], p, t_k).

Φ (pulse_map.py) carries the body's fast rotation: the coning of b1 about the angular
momentum H at |H| / A (216 Hz for Flight 5, 8 turns a pulse interval), which its coast must
resolve with many substeps. A planner needs less: where the craft is, where H points, how
fast it spins, and where b1 sits on its cone *at the next pulse*, since each pulse thrusts
along b1. Ψ keeps exactly that (:data:`lightcraft_opt.layout.REDUCED_STATE`, frames in
docs/frames.md):

- r_L, v_L (3 each) [m, m/s], L frame;
- H_L (3) [kg m²/s]: the system angular momentum about the mass centre, L frame (its
  direction is the averaged axis, its size the spin);
- c (2) [-]: the coning offset, b1's components across Ĥ along e₁, e₂, the L east and north
  axes turned by the smallest rotation that takes up onto Ĥ (the frame T_H = [e₁ e₂ Ĥ]):
  b1 = sqrt(1 - |c|²) Ĥ + c₁ e₁ + c₂ e₂, |c| the sine of the coning angle;
- liner_mass, rcs_mass, pulses: Φ's bookkeeping.

The pulse is Φ's own jump (pulse_jump.py) at the full state ``lift`` builds from z (the
attitude from b1 with the twist about it of the smallest rotation from upright, the body rates
from H in the gauge w_B[b1] = 0), read back by ``project``: the same engine, beam and
optic. The coast splits as Φ's does, but averaged over the cone:

- slow (RK4, ``substeps`` steps a pulse): r, v, H and the propellant under gravity, the
  rotating site frame, wind, aerodynamics, spin decay and the RCS, all from Φ's own
  :func:`~lightcraft_opt.symbolic.maps.coast_rhs.coast_terms` evaluated with b1 on Ĥ (the cone's
  mean axis): dH_L/dt = R_LB M_B − W_L × H_L;
- fast (exact): b1 turns about Ĥ by |H| h / A a step (A the transverse moment), so c turns
  by that angle in T_H.

What it leaves out: the twist of the body about b1 (the square beam's 4-fold symmetry makes
it isotropic to first order), the cone's second-order effect on the mean aerodynamic loads,
and the change of the coning angle by aerodynamic torques within one pulse interval. Its
error against Φ along coning flights is bounded in tests/symbolic/test_reduced_map.py and
given in docs/beam_riding.md#reduced-map. Only the HOLD RCS profile (levels held over the
interval).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import (
    ENGINE,
    PARAMETERS,
    PULSE_INPUT,
    REDUCED_STATE,
    STATE,
    RcsProfile,
    VectorLayout,
    input_layout,
    map_input_layout,
)
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.assemble import assemble
from lightcraft_opt.symbolic.maps.coast import coning_rate_B, rk4_coast
from lightcraft_opt.symbolic.maps.coast_rhs import coast_terms
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_jump import pulse_jump
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, compose_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_pieces import PulseMapPieces
from lightcraft_opt.symbolic.terms.gravity import earth_rate_L
from lightcraft_opt.symbolic.terms.gyrostat import angular_momentum
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.rotation import cross, dcm, quat_multiply

__all__ = [  # REDUCED_STATE re-exported from layout, its owner
    "REDUCED_STATE",
    "ReducedMap",
    "ReducedMapOptions",
    "build_reduced_map",
    "reduced_pulse_map",
]

_SX_OPTIONS = {"cse": True}
_UPRIGHT = ca.DM([0.5, -0.5, -0.5, -0.5])  # b1 up, b2 east, b3 north (layout.quaternion_from_tilt)


@dataclass(frozen=True)
class ReducedMapOptions:
    """How Ψ coasts: ``substeps`` RK4 steps of the slow dynamics a pulse (>= 1); ``dense``
    states a pulse in the full-state form's dense output (:func:`reduced_pulse_map`; divides
    ``substeps``)."""

    substeps: int = 2
    dense: int = 2

    def __post_init__(self) -> None:
        for name in ("substeps", "dense"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int):
                raise OptionError(f"ReducedMapOptions.{name} must be an integer, got {v!r}")
            if v < 1:
                raise OptionError(f"ReducedMapOptions.{name} must be >= 1, got {v}")
        if self.substeps % self.dense:
            raise OptionError(
                f"ReducedMapOptions.dense ({self.dense}) must divide substeps ({self.substeps})"
            )


@dataclass(frozen=True)
class ReducedMap:
    """The reduced map of one model.

    Attributes
    ----------
    step : ``reduced_map(z, u, p, t) -> (z_next, engine)``: z in :data:`REDUCED_STATE`, u in
        :attr:`inputs` (Φ's map input with held RCS levels), engine laid out as
        :data:`~lightcraft_opt.layout.ENGINE`.
    lift : ``reduced_lift(z, p) -> x``: the full state (STATE) Ψ's jump acts on.
    project : ``reduced_project(x, p) -> z``: a full state read as z.
    jump, substep : the named pieces ``reduced_jump(z, pulse, p) -> (z_plus, engine)`` and
        ``reduced_substep(z, w, p, t) -> z_next``.
    period : pulse period T [s].
    inputs : layout of u.
    options : how it was built.
    """

    step: ca.Function
    lift: ca.Function
    project: ca.Function
    jump: ca.Function
    substep: ca.Function
    period: float
    inputs: VectorLayout
    options: ReducedMapOptions


def _smallest_rotation_from_up(n: ca.SX) -> ca.SX:
    """Unit quaternion (w, x, y, z) of the smallest rotation taking L up onto the unit vector
    n (L frame); singular only at n = down."""
    q = ca.vertcat(1 + n[2], -n[1], n[0], 0)
    return q / ca.norm_2(q)


def _lift(z: ca.SX, p: ca.SX) -> ca.SX:
    H = REDUCED_STATE.get("H_L", z)
    c = REDUCED_STATE.get("coning", z)
    h_hat = H / ca.norm_2(H)
    T_H = dcm(_smallest_rotation_from_up(h_hat))  # columns e1, e2, Ĥ
    b1 = ca.mtimes(T_H, ca.vertcat(c, ca.sqrt(1 - ca.sumsqr(c))))
    q = quat_multiply(_smallest_rotation_from_up(b1), _UPRIGHT)
    base = assemble(
        STATE,
        {
            "r_L": REDUCED_STATE.get("r_L", z),
            "v_L": REDUCED_STATE.get("v_L", z),
            "q_LB": q,
            "liner_mass": REDUCED_STATE.get("liner_mass", z),
            "rcs_mass": REDUCED_STATE.get("rcs_mass", z),
            "engine_load": REDUCED_STATE.get("engine_load", z),
        },
    )
    mp = mass_properties(base, p)  # depends on the consumables only
    I_sys = mp.I_B + ca.diag(ca.vertcat(mp.J, mp.I, mp.I))
    H_B = ca.mtimes(dcm(q).T, H)
    # gauge w_B[b1] = 0: H_B = (J spin + I01 w2 + I02 w3, I11 w2 + I12 w3, I21 w2 + I22 w3)
    M = ca.vertcat(
        ca.horzcat(mp.J, I_sys[0, 1], I_sys[0, 2]),
        ca.horzcat(0, I_sys[1, 1], I_sys[1, 2]),
        ca.horzcat(0, I_sys[2, 1], I_sys[2, 2]),
    )
    spin_w = ca.solve(M, H_B)
    return assemble(STATE, {"w_B": ca.vertcat(0, spin_w[1], spin_w[2]), "spin": spin_w[0]}, base)


def _project(x: ca.SX, p: ca.SX) -> ca.SX:
    mp = mass_properties(x, p)
    R_LB = dcm(STATE.get("q_LB", x) / ca.norm_2(STATE.get("q_LB", x)))
    H_B = angular_momentum(STATE.get("w_B", x), STATE.get("spin", x), mp.I_B, mp.J, mp.I)
    H = ca.mtimes(R_LB, H_B)
    T_H = dcm(_smallest_rotation_from_up(H / ca.norm_2(H)))
    c = ca.mtimes(T_H.T, R_LB[:, 0])[:2]
    return assemble(
        REDUCED_STATE,
        {
            "r_L": STATE.get("r_L", x),
            "v_L": STATE.get("v_L", x),
            "H_L": H,
            "coning": c,
            "liner_mass": STATE.get("liner_mass", x),
            "rcs_mass": STATE.get("rcs_mass", x),
            "engine_load": STATE.get("engine_load", x),
        },
    )


def build_reduced_map(model: Model, options: ReducedMapOptions | None = None) -> ReducedMap:
    """Build Ψ for ``model`` (module docstring; structure fixed here, numbers through p)."""
    opts = options or ReducedMapOptions()
    craft = model.craft
    n_thr = craft.thruster_count
    ulay = map_input_layout(n_thr, craft.has_carrier, RcsProfile.HOLD)
    wlay = input_layout(n_thr, craft.has_carrier)
    period = 1.0 / model.flight.pulse_rate
    h = period / opts.substeps

    z = ca.SX.sym("z", REDUCED_STATE.size)
    x = ca.SX.sym("x", STATE.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    t = ca.SX.sym("t")
    w = ca.SX.sym("w", wlay.size)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)

    lift = ca.Function("reduced_lift", [z, p], [_lift(z, p)], ["z", "p"], ["x"], _SX_OPTIONS)
    project = ca.Function(
        "reduced_project", [x, p], [_project(x, p)], ["x", "p"], ["z"], _SX_OPTIONS
    )
    x_plus, eng = pulse_jump(_lift(z, p), pulse, p, model)
    jump = ca.Function(
        "reduced_jump",
        [z, pulse, p],
        [_project(x_plus, p), ca.vertcat(*(eng[name] for name in ENGINE.names))],
        ["z", "pulse", "p"],
        ["z_plus", "engine"],
        _SX_OPTIONS,
    )

    W_L = (
        earth_rate_L(PARAMETERS.get("site_latitude", p))
        if model.environment.earth_rotation
        else ca.SX.zeros(3)
    )

    def slow(tt: ca.SX, zz: ca.SX) -> ca.SX:
        """dz/dt of the cone's mean axis: c held (its turning is the exact fast part)."""
        on_axis = assemble(REDUCED_STATE, {"coning": ca.SX.zeros(2)}, base=zz)
        xx = _lift(on_axis, p)
        terms = coast_terms(tt, xx, w, p, model)
        R_LB = dcm(STATE.get("q_LB", xx))
        M_B = terms["M_aero_B"] + terms["M_rcs_B"] + ca.vertcat(terms["spin_torque"], 0, 0)
        H = REDUCED_STATE.get("H_L", zz)
        return assemble(
            REDUCED_STATE,
            {
                "r_L": REDUCED_STATE.get("v_L", zz),
                "v_L": terms["a_L"],
                "H_L": ca.mtimes(R_LB, M_B) - cross(W_L, H),
                "rcs_mass": STATE.get("rcs_mass", terms["xdot"]),
            },
        )

    z_slow = rk4_coast(slow, t, z, h, 1)[-1]
    # the fast part: b1 turns about Ĥ by |H| h / A (A: the transverse moment, mid-step H)
    mp = mass_properties(_lift(z, p), p)
    A = mp.I_B[1, 1] + mp.I
    H_mid = 0.5 * (REDUCED_STATE.get("H_L", z) + REDUCED_STATE.get("H_L", z_slow))
    angle = ca.norm_2(H_mid) * h / A
    c = REDUCED_STATE.get("coning", z)
    turned = ca.vertcat(
        ca.cos(angle) * c[0] - ca.sin(angle) * c[1], ca.sin(angle) * c[0] + ca.cos(angle) * c[1]
    )
    z_next = assemble(REDUCED_STATE, {"coning": turned}, base=z_slow)
    substep = ca.Function(
        "reduced_substep", [z, w, p, t], [z_next], ["z", "w", "p", "t"], ["z_next"], _SX_OPTIONS
    )

    zm = ca.MX.sym("z", REDUCED_STATE.size)
    um = ca.MX.sym("u", ulay.size)
    pm = ca.MX.sym("p", PARAMETERS.size)
    tm = ca.MX.sym("t")
    z_plus, engine = jump(zm, um[: PULSE_INPUT.size], pm)
    times = tm + ca.DM(h * np.arange(opts.substeps)).T
    coast = substep.mapaccum("reduced_coast", opts.substeps)
    W = ca.repmat(um[PULSE_INPUT.size :], 1, opts.substeps)
    Z = coast(z_plus, W, ca.repmat(pm, 1, opts.substeps), times)
    step = ca.Function(
        "reduced_map",
        [zm, um, pm, tm],
        [Z[:, -1], engine],
        ["z", "u", "p", "t"],
        ["z_next", "engine"],
    )
    return ReducedMap(step, lift, project, jump, substep, period, ulay, opts)


def reduced_pulse_map(model: Model, options: ReducedMapOptions | None = None) -> PulseMap:
    """Ψ in Φ's clothes: a :class:`~lightcraft_opt.symbolic.maps.pulse_map.PulseMap` on full states
    (STATE), ``reduced_pulse_map(x, u, p, t) -> (x_next, engine)`` with x_next =
    lift(Ψ(project(x))) and ``dense`` the lifted substep states, so every consumer of Φ (the
    OCP's transcription, its costs and constraints on r_L, v_L, q_LB, the simulator) can
    predict with Ψ unchanged. It is composed like Φ (:func:`compose_pulse_map`) of pieces on
    full states: the jump ``reduced_pulse_jump`` = Φ's jump at lift(project(x)), the substep
    ``reduced_coast_substep`` = lift ∘ Ψ's substep ∘ project, and the identity for Φ's
    normalisation; so Φ's explicit-chain derivatives and their compilation
    (pulse_map_derivatives.py, compiled/) serve it as they are, the jump's through the
    optic's quadrature and the manifold lift ∘ project (jump_derivatives.py). The states
    it returns lie on Ψ's manifold: the body's twist about b1 is the smallest rotation from
    upright, w_B[b1] = 0. Its ``options`` carry the substeps, dense and the HOLD profile
    (the scheme is not read)."""
    psi = build_reduced_map(model, options)
    opts = psi.options
    craft = model.craft
    n_thr = craft.thruster_count
    wlay = input_layout(n_thr, craft.has_carrier)
    x = ca.SX.sym("x", STATE.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    t = ca.SX.sym("t")
    w = ca.SX.sym("w", wlay.size)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    on_manifold = psi.lift(psi.project(x, p), p)
    manifold = ca.Function("reduced_manifold", [x, p], [on_manifold], ["x", "p"], ["x_m"])
    identity = ca.Function("reduced_identity", [x], [x], ["x"], ["x_unit"])
    x_plus, eng = pulse_jump(on_manifold, pulse, p, model)
    jump = ca.Function(
        "reduced_pulse_jump",
        [x, pulse, p],
        [x_plus, ca.vertcat(*(eng[name] for name in ENGINE.names))],
        ["x", "pulse", "p"],
        ["x_plus", "engine"],
        _SX_OPTIONS,
    )
    substep = ca.Function(
        "reduced_coast_substep",
        [x, w, p, t],
        [psi.lift(psi.substep(psi.project(x, p), w, p, t), p)],
        ["x", "w", "p", "t"],
        ["x_next"],
        _SX_OPTIONS,
    )
    coning_rate = ca.Function(
        "coning_rate", [x, p], [coning_rate_B(x, p)], ["x", "p"], ["omega"], _SX_OPTIONS
    )
    pieces = PulseMapPieces(
        identity,
        jump,
        substep,
        coning_rate,
        opts.substeps,
        psi.period / opts.substeps,
        wlay,
        n_thr,
        craft.has_carrier,
        model,  # the jump is Φ's at the manifold: its derivatives take the optic's cut
        manifold,
    )
    map_options = PulseMapOptions(
        substeps=opts.substeps, dense=opts.dense, rcs_profile=RcsProfile.HOLD
    )
    return compose_pulse_map(pieces, map_options, psi.inputs, psi.period, "reduced_pulse_map")
