"""The pulse jump's derivatives through the optic's quadrature, point by point.

casadi's SX Hessian of the whole jump (pulse_map_derivatives.py) differentiates each of the
optic's n_r x N quadrature points in every direction of v = (x, pulse): with the model
files' 8 x 32 optic under the waist beam that is 542k instructions, over what gcc compiles
in reasonable time, and 1-3 ms a call interpreted. Yet a point's fluence F depends on five
numbers only, s = (xi, eta, z, focus, energy), and those are affine in the optic's pose

    y = (xi0, eta0, z0, b2_L, b3_L, focus, energy, π),   π = |b1 . z_L|     (12 numbers)

(:func:`~lightcraft_opt.symbolic.terms.engine.optic_pose`): s_jk = A_jk y with
xi = xi0 + r_j (cos φ_k b2_L[0] + sin φ_k b3_L[0]) and likewise eta, z (A_jk's entries 1,
r_j cos φ_k, r_j sin φ_k). The SECTOR model reads the sector energies E_k = c π S_k
(S_k = Σ_j w_j F_jk, c = 2π/N) only through three moments M = c π Σ_k S_k (1, cos φ_k,
sin φ_k): E_cap and the dipole. So the jump is cut in three,

    y(v),   M(y),   E_ref(focus),
    K(v, M, E_ref): the rest of the jump, given sector energies with those moments
                    (engine_impulse's ``energies``: E_k = (M_0 + 2 M_1 cos φ_k + 2 M_2 sin φ_k)/N),

and differentiated by the chain rule, ρ the outputs' adjoint:

    ∂out/∂v = K_v + K_M M_y Y + K_r E_ref' e_f
    ∇²(ρᵀ out) = Gᵀ ∇²(ρᵀ K) G + Yᵀ ∇²(βᵀ M) Y + ∇²(γᵀ y(v)) + β_r E_ref'' e_f e_fᵀ

with Y = ∂y/∂v, G = [I; M_y Y; E_ref' e_fᵀ], β = K_Mᵀ ρ, β_r = K_rᵀ ρ, γ = M_yᵀ β (held
fixed in ∇²(γᵀ y)), e_f the focus's column of v and, from each point's gradient g_jk and
Hessian H_jk of F in s (casadi's AD of one point) and β̃_k = β_0 + β_1 cos φ_k + β_2 sin φ_k,

    ∂S_k/∂y = Σ_j w_j A_jkᵀ g_jk,   Σ_k β̃_k ∇²S_k = Σ_jk β̃_k w_j A_jkᵀ H_jk A_jk,
    ∇²(βᵀ M) = c (π Σ_k β̃_k ∇²S_k + d e_πᵀ + e_π dᵀ),   d = Σ_k β̃_k ∂S_k/∂y.

E_ref, the same quadrature for a centred upright craft, depends on v through the beam's size
at the ring's height, a function of the focus alone. Nothing is derived by hand but the cut:
every derivative is casadi's AD of a piece. The Functions have the names, inputs and outputs
of the plain pieces and equal them to rounding (tests/symbolic/test_jump_derivatives.py);
at 8 x 32 the Hessian has 43 % of the instructions (bench/README.md). With designed entries
of p (an OCP's design, v = (x, pulse, p[design])) those the fluence reads (beam parameters)
join s and y, the rest reach the pose, K and E_ref through casadi's AD as x does. The SECTOR
impulse model only (the KERNEL model evaluates the quadrature twice, at the craft and on the
axis), and not with the optic's radii designed (they move the quadrature's points):
:func:`structured_jump_derivatives` returns None, and the chain keeps the whole jump's AD.
The reduced map Ψ's jump, the pulse's at lift(project(x)) (reduced_map.py), takes the same
cut and then the chain rule through that manifold (``manifold``): its Hessian at the 8 x 32
optic under the waist beam is 247k instructions where AD of the composition gives 756k.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from lightcraft_opt.layout import ENGINE, PARAMETERS, PULSE_INPUT, STATE
from lightcraft_opt.model import ImpulseModel, Model
from lightcraft_opt.symbolic.maps.pulse_jump import pulse_jump
from lightcraft_opt.symbolic.terms.beam import beam_side, fluence
from lightcraft_opt.symbolic.terms.engine import (
    PROJECTION_EPS,
    optic_pose,
    optic_quadrature,
    point_fluence,
)

__all__ = ["structured_jump_derivatives"]

_SX_OPTIONS = {"cse": True}
#: The pose y's entries: (xi0, eta0, z0) 0-2, b2_L 3-5, b3_L 6-8, focus 9, energy 10,
#: the projection 11, then the designed entries of p the fluence reads.
_FOCUS, _ENERGY, _PROJECTION, _NY = 9, 10, 11, 12
#: Entries of p that place the quadrature's points: a design of them keeps the whole AD.
_RADII = ("shadow_radius", "capture_radius")


def _point_derivatives(model: Model, reads: tuple[int, ...]) -> ca.Function:
    """``optic_point(s, p) -> (F, g, H)``: the fluence [J/m^2] at s = (xi, eta, z, focus,
    energy, p[reads]) and its gradient and Hessian in s (``reads``: designed entries of p
    the fluence reads, taken from s instead of p)."""
    s = ca.SX.sym("s", 5 + len(reads))
    p = ca.SX.sym("p", PARAMETERS.size)
    F = point_fluence(s[0], s[1], s[2], s[3], s[4], _replaced(p, reads, s[5:]), model)
    H, g = ca.hessian(F, s)
    return ca.Function("optic_point", [s, p], [F, g, H], ["s", "p"], ["F", "g", "H"], _SX_OPTIONS)


def _replaced(p: ca.SX, entries: tuple[int, ...], values: ca.SX) -> ca.SX:
    """``p`` with its ``entries`` replaced by ``values``."""
    out = ca.SX(p)
    for k, i in enumerate(entries):
        out[i] = values[k]
    return out


def _pose_index(i: int, a: int) -> int:
    """Index in y of the coefficient i of s's spatial entry a (i: 0 the centre, 1 b2_L,
    2 b3_L; a: 0 xi, 1 eta, 2 z)."""
    return 3 * i + a


def _accumulate_point(
    hess: list[list[ca.SX]],
    grad: list[ca.SX],
    coef: tuple[ca.SX, ca.SX, ca.SX],
    alpha: ca.SX,
    weight: ca.SX,
    g: ca.SX,
    H: ca.SX,
    plain: list[tuple[int, int]],
) -> None:
    """Add a point's alpha A_jkᵀ H A_jk to ``hess`` (the upper triangle, nested lists) and
    weight A_jkᵀ g to ``grad``: A_jk's spatial rows hold ``coef`` = (1, r cos φ, r sin φ) at
    the columns :func:`_pose_index` (A_jkᵀ H A_jk's entry of (i, a), (j, b) is coef_i coef_j
    H_ab); its other rows are 1 at ``plain``'s (index in y, index in s), in y's order."""
    aH = alpha * H
    for i in range(3):
        for a in range(3):
            grad[_pose_index(i, a)] += weight * coef[i] * g[a]
    for at_y, at_s in plain:
        grad[at_y] += weight * g[at_s]
    spatial = [(i, a) for i in range(3) for a in range(3)]
    for m, (i, a) in enumerate(spatial):
        row = _pose_index(i, a)
        for j, b in spatial[m:]:
            col = _pose_index(j, b)
            lo, hi = min(row, col), max(row, col)
            hess[lo][hi] += coef[i] * coef[j] * aH[a, b]
        for at_y, at_s in plain:
            hess[row][at_y] += coef[i] * aH[a, at_s]
    for m, (row, s_row) in enumerate(plain):
        for col, s_col in plain[m:]:
            hess[row][col] += aH[s_row, s_col]


def _symmetric(upper: list[list[ca.SX]]) -> ca.SX:
    """The symmetric matrix whose upper triangle ``upper`` holds."""
    n = len(upper)
    M = ca.SX.zeros(n, n)
    for i in range(n):
        for j in range(i, n):
            M[i, j] = upper[i][j]
            M[j, i] = upper[i][j]
    return M


def _fluence_reads(model: Model, p: ca.SX, design: tuple[int, ...]) -> tuple[int, ...]:
    """The entries of ``design`` that a point's fluence reads (beam parameters)."""
    s = ca.SX.sym("s", 5)
    F = point_fluence(s[0], s[1], s[2], s[3], s[4], p, model)
    return tuple(i for i in design if ca.depends_on(F, p[i]))


def _harmonics(phi: np.ndarray) -> ca.DM:
    """(3, N): 1, cos φ_k, sin φ_k of the sectors' azimuths ``phi`` (N,) [rad]."""
    return ca.DM(np.vstack([np.ones(phi.size), np.cos(phi), np.sin(phi)]))


def _quadrature_moments(
    model: Model, p: ca.SX, y: ca.SX, beta: ca.SX, reads: tuple[int, ...]
) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(M (3,) [J], M_y (3, n_y), ∇²(βᵀ M) (n_y, n_y)) in the pose y (module docstring),
    point by point; ``p`` the parameters (the quadrature's radii), ``beta`` (3,) the
    moments' weights, ``reads`` the designed entries of p the fluence reads (y's last)."""
    r, w_r, phi = optic_quadrature(model.craft.engine, p)
    c = 2 * math.pi / len(phi)
    point = _point_derivatives(model, reads)
    n_y = _NY + len(reads)
    plain = [(_FOCUS, 3), (_ENERGY, 4), *((_NY + k, 5 + k) for k in range(len(reads)))]
    S, dS = [], []
    upper = [[ca.SX(0) for _ in range(n_y)] for _ in range(n_y)]  # Σ_k β̃_k ∇²S_k
    for angle in phi:
        harmonics = (1.0, math.cos(angle), math.sin(angle))
        beta_k = sum(h * beta[i] for i, h in enumerate(harmonics))
        S_k, grad = ca.SX(0), [ca.SX(0) for _ in range(n_y)]
        for j in range(r.shape[0]):
            coef = (ca.SX(1), r[j] * harmonics[1], r[j] * harmonics[2])
            s_jk = ca.vertcat(
                *(sum(coef[i] * y[_pose_index(i, a)] for i in range(3)) for a in range(3)),
                *(y[at_y] for at_y, _ in plain),
            )
            F, g, H = point(s_jk, p)
            S_k += w_r[j] * F
            _accumulate_point(upper, grad, coef, beta_k * w_r[j], w_r[j], g, H, plain)
        S.append(S_k)
        dS.append(ca.vertcat(*grad))
    harmonic = _harmonics(phi)
    S_row, dS_cols = ca.horzcat(*S), ca.horzcat(*dS)  # (1, N), (n_y, N)
    projection = y[_PROJECTION]
    e_pi = ca.DM.zeros(n_y)
    e_pi[_PROJECTION] = 1
    M = c * projection * ca.mtimes(harmonic, S_row.T)  # E_cap, D_b2, D_b3 [J]
    M_y = c * (
        projection * ca.mtimes(harmonic, dS_cols.T)
        + ca.mtimes(ca.mtimes(harmonic, S_row.T), e_pi.T)
    )
    weighted_dS = ca.mtimes(dS_cols, ca.mtimes(harmonic.T, beta))  # Σ_k β̃_k ∂S_k/∂y
    hess_M = c * (
        projection * _symmetric(upper)
        + ca.mtimes(weighted_dS, e_pi.T)
        + ca.mtimes(e_pi, weighted_dS.T)
    )
    return M, M_y, hess_M


def _reference_energy(
    model: Model, p: ca.SX, focus: ca.SX, v: ca.SX, design: tuple[int, ...]
) -> tuple[ca.SX, ca.SX, ca.SX]:
    """(E_ref [J], ∂E_ref/∂v (1, n_v), ∂²E_ref/∂v² (n_v, n_v)): a centred, upright craft at
    the pulse's ``focus`` [m] and the reference energy. Its points share the range h (the
    ring's height), so E_ref depends on v through the beam's size a there (a function of the
    focus and of p) and through the designed entries of p the fluence reads: G(a, p[design])
    differentiated in those few numbers, then chained to v (p[design] is v's tail)."""
    r, w_r, phi = optic_quadrature(model.craft.engine, p)
    c = 2 * math.pi / len(phi)
    upright = math.sqrt(1 + PROJECTION_EPS**2)
    u = ca.SX.sym("u", 1 + len(design))  # (a, p[design])
    p_u = _replaced(p, design, u[1:])
    e0 = PARAMETERS.get("reference_pulse_energy", p_u)
    cos_phi, sin_phi = ca.DM(np.cos(phi)).T, ca.DM(np.sin(phi)).T
    F_ref = fluence(ca.mtimes(r, cos_phi), ca.mtimes(r, sin_phi), u[0], e0, p_u, model.laser)
    G = c * upright * ca.sum2(ca.mtimes(w_r.T, F_ref))
    G_uu, G_u = ca.hessian(G, u)
    size = beam_side(PARAMETERS.get("ring_height", p), focus, p, model.laser)
    u_of_v = ca.vertcat(size, p[list(design)]) if design else size
    U = ca.jacobian(u_of_v, v)
    size_vv, _ = ca.hessian(size, v)
    d = ca.mtimes(G_u.T, U)
    dd = ca.mtimes(U.T, ca.mtimes(G_uu, U)) + G_u[0] * size_vv
    at_v = [ca.substitute(q, u, u_of_v) for q in (G, d, dd)]
    return at_v[0], at_v[1], at_v[2]


def structured_jump_derivatives(
    model: Model,
    *,
    hessian: bool = True,
    design: tuple[int, ...] = (),
    manifold: ca.Function | None = None,
) -> tuple[ca.Function, ca.Function | None] | None:
    """``pulse_jump_jacobian(x, pulse, p) -> jac`` and (with ``hessian``)
    ``pulse_jump_hessian(x, pulse, p, adjoint) -> (jac, hess)`` of the jump in v = (x,
    pulse, p[design]) (module docstring; ``design`` sorted indices into PARAMETERS), as the
    plain pieces of pulse_map_derivatives.py; None for a model whose impulse model is not
    SECTOR, whose optic has fewer than three sectors (three moments need them) or whose
    designed entries include the optic's radii (they move the quadrature's points).

    ``manifold``: ``m(x, p) -> x_m`` (STATE), for a jump that is the pulse's at m(x, p) (the
    reduced map Ψ's, at lift(project(x)): symbolic/maps/reduced_map.py). Its derivatives
    are then ``reduced_pulse_jump_jacobian`` and ``reduced_pulse_jump_hessian``, the chain
    rule through m over the cut: with w(v) = (m(x, p), pulse, p[design]) and W = ∂w/∂v,
    jac = J(w) W and hess = Wᵀ H(w) W + ∇²(λᵀ m) (λ = J_xᵀ ρ, the jump's adjoint on its
    state, held fixed)."""
    jacobian, second = _cut(model, hessian, design) or (None, None)
    if jacobian is None or manifold is None:
        return None if jacobian is None else (jacobian, second)
    return _through_manifold(jacobian, second, manifold, design)


def _through_manifold(
    jacobian: ca.Function,
    second: ca.Function | None,
    manifold: ca.Function,
    design: tuple[int, ...],
) -> tuple[ca.Function, ca.Function | None]:
    """The cut's ``jacobian`` and ``second`` composed with x -> ``manifold(x, p)``
    (:func:`structured_jump_derivatives`)."""
    x = ca.SX.sym("x", STATE.size)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    v = ca.vertcat(x, pulse, p[list(design)]) if design else ca.vertcat(x, pulse)
    x_m = manifold(x, p)
    w = ca.vertcat(x_m, pulse, p[list(design)]) if design else ca.vertcat(x_m, pulse)
    W = ca.jacobian(w, v)
    jac = ca.densify(ca.mtimes(jacobian(x_m, pulse, p), W))
    composed = ca.Function(
        "reduced_pulse_jump_jacobian",
        [x, pulse, p],
        [jac],
        ["x", "pulse", "p"],
        ["jac"],
        _SX_OPTIONS,
    )
    if second is None:
        return composed, None
    rho = ca.SX.sym("adjoint", second.size1_in(3))
    jac_m, hess_m = second(x_m, pulse, p, rho)
    lam = ca.SX.sym("lambda", STATE.size)  # J_xᵀ ρ, a symbol until the end
    curvature, _ = ca.hessian(ca.dot(lam, x_m), v)
    curvature = ca.substitute(curvature, lam, ca.mtimes(jac_m[:, : STATE.size].T, rho))
    hess = ca.mtimes(W.T, ca.mtimes(hess_m, W)) + curvature
    composed_second = ca.Function(
        "reduced_pulse_jump_hessian",
        [x, pulse, p, rho],
        [ca.densify(ca.mtimes(jac_m, W)), ca.densify(hess)],
        ["x", "pulse", "p", "adjoint"],
        ["jac", "hess"],
        _SX_OPTIONS,
    )
    return composed, composed_second


def _cut(
    model: Model, hessian: bool, design: tuple[int, ...]
) -> tuple[ca.Function, ca.Function | None] | None:
    """The jump's derivatives through the cut (:func:`structured_jump_derivatives` without
    a manifold)."""
    engine = model.craft.engine
    if engine.impulse_model is not ImpulseModel.SECTOR or engine.quadrature_azimuthal < 3:
        return None
    if {PARAMETERS.slot(name).start for name in _RADII} & set(design):
        return None
    x = ca.SX.sym("x", STATE.size)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    v = ca.vertcat(x, pulse, p[list(design)]) if design else ca.vertcat(x, pulse)

    # the pose y(v), with the designed entries of p the fluence reads, and its Jacobian
    pose = optic_pose(x, pulse, p)
    focus, energy = PULSE_INPUT.get("focus", pulse), PULSE_INPUT.get("energy", pulse)
    reads = _fluence_reads(model, p, design)
    y_of_v = ca.vertcat(*pose.centre, pose.R_LB[:, 1], pose.R_LB[:, 2], focus, energy)
    y_of_v = ca.vertcat(y_of_v, pose.projection, *(p[i] for i in reads))
    Y = ca.jacobian(y_of_v, v)

    y = ca.SX.sym("y", y_of_v.numel())
    beta = ca.SX.sym("beta", 3)  # K_Mᵀ ρ, a symbol until the end
    M, M_y, hess_M = _quadrature_moments(model, p, y, beta, reads)
    E_ref, ref_v, ref_vv = _reference_energy(model, p, focus, v, design)
    phi = optic_quadrature(engine, p)[2]
    harmonic = _harmonics(phi)

    # K: the rest of the jump, given the moments. The SECTOR model reads the sector
    # energies through E_cap = Σ E_k and the dipole Σ E_k (cos φ_k, sin φ_k) only, and
    # E_k = (M_0 + 2 M_1 cos φ_k + 2 M_2 sin φ_k) / N has exactly these sums (N >= 3)
    M_sym = ca.SX.sym("M", 3)
    E_of_M = ca.mtimes(M_sym.T, harmonic * ca.DM([[1.0], [2.0], [2.0]])) / phi.size
    E_ref_sym = ca.SX.sym("E_ref")
    x_plus, eng = pulse_jump(x, pulse, p, model, (E_of_M, E_ref_sym))
    out = ca.vertcat(x_plus, *(ca.vec(eng[name]) for name in ENGINE.names))
    K_v = ca.jacobian(out, v)
    K_M = ca.jacobian(out, M_sym)
    K_r = ca.jacobian(out, E_ref_sym)
    M_v = ca.mtimes(M_y, Y)  # (3, n_v)
    jac = K_v + ca.mtimes(K_M, M_v) + ca.mtimes(K_r, ref_v)

    def substituted(expr: ca.SX) -> ca.SX:
        """``expr`` at the point: M = M(y), E_ref = E_ref(v), then y = y(v)."""
        at_y = ca.substitute([expr], [M_sym, E_ref_sym], [M, E_ref])[0]
        return ca.substitute(at_y, y, y_of_v)

    jacobian = ca.Function(
        "pulse_jump_jacobian",
        [x, pulse, p],
        [ca.densify(substituted(jac))],
        ["x", "pulse", "p"],
        ["jac"],
        _SX_OPTIONS,
    )
    if not hessian:
        return jacobian, None

    rho = ca.SX.sym("adjoint", out.numel())
    w = ca.vertcat(v, M_sym, E_ref_sym)
    hess_K, _ = ca.hessian(ca.dot(rho, out), w)
    G = ca.vertcat(ca.DM.eye(v.numel()), M_v, ref_v)
    beta_of = ca.mtimes(K_M.T, rho)
    beta_ref = ca.dot(K_r, rho)
    gamma = ca.SX.sym("gamma", y.numel())
    hess_y, _ = ca.hessian(ca.dot(gamma, y_of_v), v)
    gamma_of = ca.mtimes(M_y.T, beta)
    hess = (
        ca.mtimes(G.T, ca.mtimes(hess_K, G))
        + ca.mtimes(Y.T, ca.mtimes(hess_M, Y))
        + hess_y
        + beta_ref * ref_vv
    )
    hess = ca.substitute(hess, gamma, gamma_of)
    hess = ca.substitute(hess, beta, beta_of)
    second = ca.Function(
        "pulse_jump_hessian",
        [x, pulse, p, rho],
        [ca.densify(substituted(jac)), ca.densify(substituted(hess))],
        ["x", "pulse", "p", "adjoint"],
        ["jac", "hess"],
        _SX_OPTIONS,
    )
    return jacobian, second
