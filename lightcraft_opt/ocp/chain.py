"""The NLP's derivatives from Φ's explicit chain, not casadi's AD through Φ.

Given Φ's explicit-chain derivatives (symbolic/maps/pulse_map_derivatives.py, compiled
pieces), :func:`chain_nlp` builds the gradient, constraint Jacobian and Lagrangian Hessian
of a :class:`~lightcraft_opt.ocp.transcription.MultipleShooting` NLP from them. The NLP is
written a second time with Φ's outputs as free symbols Y (ℓ(w, Y) = λ_f f + λ_gᵀ g, cheap
to differentiate: :meth:`~lightcraft_opt.ocp.transcription.MultipleShooting.nlp_of_outputs`),
and at the point w̄

    L(w) ≈ ℓ(w, Y(w̄) + J(w̄) (z(w) - z(w̄))) + Σ_k ½ (z_k(w) - z_k(w̄))ᵀ H_k(w̄) (z_k(w) - z_k(w̄))

(z_k = (x_k, u_k, d_p) the physical arguments of pulse k, d_p the designed entries of p,
affine in w; J the chain's Jacobian in them; H_k the chain's Hessian of μ_kᵀ Φ with μ_k =
∂ℓ/∂Y_k) has L's gradient and Hessian at w̄ exactly; casadi differentiates that
surrogate, never Φ.

Φ over the horizon is evaluated once per primal point and shared (ocp/evaluation.py): its
values by f and g, its values and Jacobians by ∇f, ∂g/∂w and the Hessian's multipliers;
the chain's Hessian blocks once per iterate, as the backward sweep alone over the tape of
the Jacobians' forward sweep (``PulseMapDerivatives.hessian_tape``). Every other piece is
an SX Function (the NLP with Φ's outputs as symbols, and the surrogate), a few microseconds a
pulse in casadi's SX machine; those are pure structure, kept on disk
(:func:`build_surrogate`).
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, fields

import casadi as ca
import numpy as np

from lightcraft_opt.compiled.cache import (
    BuildReport,
    load_functions,
    save_functions,
    source_digest,
    structure_key,
)
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE
from lightcraft_opt.ocp import transcription
from lightcraft_opt.ocp.evaluation import ConvexBlocks, KeptBlocks, SharedEvaluation, horizon_map
from lightcraft_opt.ocp.transcription import MultipleShooting
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["SURROGATE_CACHE", "ChainNlp", "Surrogate", "build_surrogate", "chain_nlp"]

#: Name of the cache files of the surrogates (compiled/cache/functions.py).
SURROGATE_CACHE = "ocp_surrogate"
_THIS_MODULE = sys.modules[__name__]


@dataclass(frozen=True)
class Surrogate:
    """The SX Functions around Φ's shared evaluations in the chain's NLP (module
    docstring), pure structure.

    Attributes
    ----------
    outputs_nlp : ``ocp_nlp_of_outputs(w, Y_x, Y_e, P) -> (f, g)``, the NLP with Φ's outputs
        as symbols.
    multipliers : ``ocp_output_multipliers(w, Y_x, Y_e, P, lam_f, lam_g) -> (mu_x, mu_e)``,
        ∂ℓ/∂Y.
    arguments : ``ocp_pulse_arguments(w, P) -> Z``, Φ's arguments (x_k, u_k, d_p) side by side.
    grad_f, jac_g, hess : the surrogate's ``(w, P, z_bar, x_next_bar, engine_bar, dx_bar,
        de_bar) -> (f, ∇f)``, ``-> (g, ∂g/∂w)`` and ``(..., hess_bar, lam_f, lam_g) -> H``.
    """

    outputs_nlp: ca.Function
    multipliers: ca.Function
    arguments: ca.Function
    grad_f: ca.Function
    jac_g: ca.Function
    hess: ca.Function


@dataclass(frozen=True)
class ChainNlp:
    """nlpsol's NLP and derivatives from Φ's chain, with the evaluations they share.

    Attributes
    ----------
    nlp : ``ocp_nlp(x, p) -> (f, g)``, to pass to nlpsol in place of the transcription's
        expressions (it is not differentiable: nlpsol's ``no_nlp_grad``).
    grad_f, jac_g : ``nlp_grad_f(x, p) -> (f, grad_f_x)``, ``nlp_jac_g(x, p) -> (g, jac_g_x)``.
    hess_lag : ``nlp_hess_l(x, p, lam_f, lam_g) -> hess_gamma_x_x``, exact (the upper
        triangle when built with ``upper``).
    hess_lag_convex : the same with each pulse's block μᵀ∇²Φ projected on the positive
        semidefinite cone (HessianApproximation.CONVEX, and the convex phase of a cold
        solve).
    shared : Φ's values and Jacobians over the horizon (ocp/evaluation.py), whose counters
        say how often each was evaluated; they must outlive the solver.
    convex_blocks : the projection's Callback, kept alive likewise.
    kept_blocks : the chain's Hessian blocks of the last evaluation (ocp/evaluation.py),
        frozen for a warm re-solve that reuses them.
    """

    nlp: ca.Function
    grad_f: ca.Function
    jac_g: ca.Function
    hess_lag: ca.Function
    hess_lag_convex: ca.Function
    shared: tuple[SharedEvaluation, SharedEvaluation]
    convex_blocks: ConvexBlocks
    kept_blocks: KeptBlocks

    def derivatives(self, *, convex: bool = False) -> dict[str, ca.Function]:
        """nlpsol's options ``grad_f``, ``jac_g`` and ``hess_lag`` (the convexified Hessian
        with ``convex``)."""
        hess = self.hess_lag_convex if convex else self.hess_lag
        return {"grad_f": self.grad_f, "jac_g": self.jac_g, "hess_lag": hess}


def _since(start: float) -> str:
    return f"{time.perf_counter() - start:.1f} s"


def chain_nlp(
    tr: MultipleShooting,
    *,
    upper: bool = True,
    report: BuildReport | None = None,
    surrogate: Surrogate | None = None,
) -> ChainNlp:
    """The NLP of ``tr`` and its derivatives from Φ's explicit chain (module docstring).
    The exact ones equal casadi's AD of the NLP to rounding
    (tests/ocp/test_chain_derivatives.py). ``upper``: the Hessians' upper triangles (IPOPT);
    ``report`` hears whether the surrogate was built or loaded; ``surrogate``: the one
    :func:`build_surrogate` gave for ``tr`` and ``upper`` already (a robust problem's
    scenarios share it), else built or loaded here."""
    der = tr.derivatives
    if der is None or der.hessian_tape is None or der.jacobian_tape is None:
        raise ParameterError(
            "derivatives", "the chain's NLP needs Φ's chain derivatives with Hessians"
        )
    N, nx, nu = tr.problem.horizon, STATE.size, tr.problem.inputs.size
    design = tuple(int(i) for i in np.sort(tr.design.p_index))
    if der.design != design:
        raise ParameterError(
            "derivatives",
            f"Φ's chain derivatives are in the design entries {der.design} of p, the problem "
            f"designs {design}",
        )
    w, P = tr.nlp["x"], tr.P
    s = surrogate or build_surrogate(tr, upper=upper, report=report)
    # Φ over the horizon, once per point (ocp/evaluation.py), then the surrogate at w̄ = w
    values = SharedEvaluation("ocp_pulse_values", horizon_map(der.values, N, tr.threads))
    # the Jacobians with the forward sweep's tape, which the Hessian's backward sweep reads
    jacobians = SharedEvaluation(
        "ocp_pulse_jacobians", horizon_map(der.jacobian_tape, N, tr.threads)
    )
    times = tr.pulse_times()
    z = s.arguments(w, P)
    # each pulse's p: the problem's, its designed entries from z's last rows
    p = _pulse_parameters(tr.parameters.get("p", P), np.array(design), z[nx + nu :, :])
    x_z, u_z = z[:nx, :], z[nx : nx + nu, :]
    nlp = ca.Function(
        "ocp_nlp",
        [w, P],
        s.outputs_nlp(w, *values(x_z, u_z, p, times), P),
        ["x", "p"],
        ["f", "g"],
    )
    *first_order, tape = jacobians(x_z, u_z, p, times)
    point = [z, *first_order]
    grad_f = ca.Function(
        "nlp_grad_f", [w, P], s.grad_f.call([w, P, *point]), ["x", "p"], ["f", "grad_f_x"]
    )
    jac_g = ca.Function(
        "nlp_jac_g", [w, P], s.jac_g.call([w, P, *point]), ["x", "p"], ["g", "jac_g_x"]
    )
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", tr.lbg.size)
    _, xn, en, _, _ = point
    mu_x, mu_e = s.multipliers(w, xn, en, P, lam_f, lam_g)
    # the chain's Hessian blocks, kept for re-solves that reuse them (OcpOptions.warm_hessian)
    # (the accepted point's Jacobians and tape are in memory: only the backward sweep runs)
    kept = KeptBlocks("ocp_pulse_hessians", horizon_map(der.hessian_tape, N, tr.threads))
    Hb = kept(x_z, u_z, ca.repmat(p, 1, N) if p.size2() == 1 else p, times, tape, mu_x, mu_e)
    # each pulse's μᵀ∇²Φ made positive semidefinite (ocp/evaluation.py)
    psd = ConvexBlocks("ocp_convex_blocks", der.n_v, N)
    hess_lag, hess_convex = (
        ca.Function(
            name,
            [w, P, lam_f, lam_g],
            [s.hess(w, P, *point, blocks, lam_f, lam_g)],
            ["x", "p", "lam_f", "lam_g"],
            ["hess_gamma_x_x"],
        )
        for name, blocks in (("nlp_hess_l", Hb), ("nlp_hess_l_convex", psd(Hb)))
    )
    return ChainNlp(nlp, grad_f, jac_g, hess_lag, hess_convex, (values, jacobians), psd, kept)


def build_surrogate(
    tr: MultipleShooting, *, upper: bool = True, report: BuildReport | None = None
) -> Surrogate:
    """The SX Functions of :func:`chain_nlp` (module docstring), from the disk cache
    (compiled/cache/functions.py) when this structure was built before, else built (casadi's AD and
    expansion: seconds at a hundred pulses) and saved. The key is the graph they are built
    from: the NLP with Φ's outputs as symbols and Φ's arguments (both before expansion),
    Φ's sparsity patterns, the sizes, ``upper`` and the source of this module and of the
    transcription; never run-time values."""
    der = tr.derivatives
    assert der is not None
    N, nx = tr.problem.horizon, STATE.size
    ne = int(der.jacobian.size_out(1)[0])
    nv = der.n_v
    w, P = tr.nlp["x"], tr.P
    # the NLP with Φ's outputs as symbols: ℓ is cheap to differentiate
    Yx, Ye = ca.MX.sym("Y_x", nx, N), ca.MX.sym("Y_e", ne, N)
    f_y, g_y = tr.nlp_of_outputs(Yx, Ye)
    tilde = ca.Function("ocp_nlp_of_outputs", [w, Yx, Ye, P], [f_y, g_y])
    # Φ's arguments z_k = (x_k, u_k, d_p), affine in w
    Z = tr.pulse_arguments()
    z_of = ca.Function("ocp_pulse_arguments", [w, P], [Z])
    # Φ's structural zeros (casadi's sparsity propagation through Φ), so the NLP's
    # Jacobian and Hessian keep the sparsity AD would give them
    design = np.sort(tr.design.p_index)
    jac_sp, hess_sp = _phi_sparsity(tr.phi, nx, ne, nv, design)
    key = structure_key(
        SURROGATE_CACHE,
        tilde,
        z_of,
        jac_sp,
        hess_sp,
        repr((N, nx, ne, nv, upper)),
        source_digest(_THIS_MODULE),
        source_digest(transcription),
    )
    start = time.perf_counter()
    loaded = load_functions(SURROGATE_CACHE, key)
    if loaded is not None and len(loaded) == len(fields(Surrogate)):
        if report is not None:
            report(f"the NLP's derivatives: loaded from the cache in {_since(start)}")
        return Surrogate(*loaded)
    if report is not None:
        report(f"building the NLP's derivatives ({N} pulses, {tr.n_w} variables) ...")
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", tr.lbg.size)
    ell_y = lam_f * f_y + ca.dot(lam_g, g_y)
    multipliers = ca.Function(
        "ocp_output_multipliers",
        [w, Yx, Ye, P, lam_f, lam_g],
        [ca.gradient(ell_y, Yx), ca.gradient(ell_y, Ye)],
    ).expand()
    tilde = tilde.expand()
    # the surrogate at w̄, whose Φ quantities enter as symbols: casadi differentiates it
    # in w without ever differentiating Φ or its chain
    Zb = ca.MX.sym("z_bar", nv, N)
    XN, EN = ca.MX.sym("x_next_bar", nx, N), ca.MX.sym("engine_bar", ne, N)
    pattern = ca.DM(jac_sp, 1)
    DX = ca.MX.sym("dx_bar", ca.repmat(pattern[:nx, :], 1, N).sparsity())
    DE = ca.MX.sym("de_bar", ca.repmat(pattern[nx:, :], 1, N).sparsity())
    HB = ca.MX.sym("hess_bar", ca.repmat(ca.DM(hess_sp, 1), 1, N).sparsity())
    dz = Z - Zb
    blocks = range(N)
    lin_x = ca.horzcat(
        *(XN[:, k] + ca.mtimes(DX[:, k * nv : (k + 1) * nv], dz[:, k]) for k in blocks)
    )
    lin_e = ca.horzcat(
        *(EN[:, k] + ca.mtimes(DE[:, k * nv : (k + 1) * nv], dz[:, k]) for k in blocks)
    )
    f_lin, g_lin = tilde(w, lin_x, lin_e, P)
    quad = sum(0.5 * ca.bilin(HB[:, k * nv : (k + 1) * nv], dz[:, k], dz[:, k]) for k in blocks)
    H = ca.hessian(lam_f * f_lin + ca.dot(lam_g, g_lin) + quad, w)[0]
    H = ca.triu(H) if upper else H
    first = [w, P, Zb, XN, EN, DX, DE]
    built = Surrogate(
        outputs_nlp=tilde,
        multipliers=multipliers,
        arguments=z_of.expand(),
        grad_f=ca.Function("ocp_surrogate_grad_f", first, [f_lin, ca.gradient(f_lin, w)]).expand(),
        jac_g=ca.Function("ocp_surrogate_jac_g", first, [g_lin, ca.jacobian(g_lin, w)]).expand(),
        hess=ca.Function("ocp_surrogate_hess", [*first, HB, lam_f, lam_g], [H]).expand(),
    )
    save_functions(SURROGATE_CACHE, key, [getattr(built, f.name) for f in fields(Surrogate)])
    return built


def _pulse_parameters(p: ca.MX, design: np.ndarray, d: ca.MX) -> ca.MX:
    """p (PARAMETERS.size,) with the entries ``design`` (sorted) taken from ``d``
    (len(design), n columns): one column per pulse, or ``p`` itself without a design."""
    if design.size == 0:
        return p
    keep = np.ones(PARAMETERS.size)
    keep[design] = 0.0
    put = np.zeros((PARAMETERS.size, design.size))
    put[design, np.arange(design.size)] = 1.0
    return ca.repmat(ca.DM(keep) * p, 1, d.size2()) + ca.mtimes(ca.DM(put), d)


def _phi_sparsity(
    phi: PulseMap, nx: int, ne: int, nv: int, design: np.ndarray
) -> tuple[ca.Sparsity, ca.Sparsity]:
    """Structural patterns of Φ's Jacobian in v = (x, u, p[design]), (nx + ne, nv), and of
    the Hessian of any λᵀ(x_next, engine), (nv, nv), by sparsity propagation through Φ."""
    v = ca.MX.sym("v", nv)
    p, t = ca.MX.sym("p", PARAMETERS.size), ca.MX.sym("t")
    nu = nv - nx - design.size
    p_v = _pulse_parameters(p, design, v[nx + nu :])
    out = ca.vertcat(*phi.step(v[:nx], v[nx : nx + nu], p_v, t))
    lam = ca.MX.sym("lam", nx + ne)
    return ca.jacobian_sparsity(out, v), ca.jacobian_sparsity(ca.gradient(ca.dot(lam, out), v), v)
