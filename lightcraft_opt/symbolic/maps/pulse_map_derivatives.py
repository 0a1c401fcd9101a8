"""Φ's first and second derivatives as an explicit chain over its pieces.

casadi's AD through the composed MX graph of Φ works (tests use it as the reference), but
it is slow in the virtual machine and its generated C is too big to compile in reasonable
time. Here the chain rule is written out over the pieces of pulse_map_pieces.py, each
piece differentiated on its own (small SX Functions with ``{"cse": True}`` that compile in
seconds), in the order the pieces run. The pulse's variables are v = (x, u, p_d), p_d =
p[design] the entries of p an OCP designs (ocp/design.py; ``design`` sorted indices into
PARAMETERS, none by default: v = (x, u)). The pieces that take p (the jump, the substep,
the coning rate) are differentiated also in p_d, whose columns follow their other inputs';
P = [0 0 I] selects p_d from v.

Forward (the Jacobian), s_0 = x_+ the state after the jump, s_k after substep k::

    D_n  = ∂N(x)/∂x [I 0 0]                      (normalised entry state)
    D_y  = [D_n; 0 I_pulse 0; P]                 (the jump's inputs (x_n, pulse, p_d))
    D_0  = J_y D_y,   D_e = E_y D_y              (state after the jump, engine)
    D_{k+1} = A_k D_k + B_k W_k + C_k P          (A_k = ∂S/∂s, B_k = ∂S/∂w, C_k = ∂S/∂p_d;
                                                  W_k = ∂w_k/∂v)
    ∂x_next/∂v = ∂N(s_n)/∂s D_n

where W_k selects u's entries of substep k, plus, for the PHASE_LOCKED profile, the coning
rate ω(x_+, p_d), the only way p enters w: W_k += e_ω ∂ω/∂(x, p_d) [D_0; P].

Backward (the Hessian of the Lagrangian term λᵀ x_next + νᵀ engine): every piece adds
G^T ∇²(ρ^T piece) G, where G is the Jacobian of the piece's inputs with respect to v (from
the forward sweep) and ρ the adjoint of its outputs, swept back from λ and ν::

    ρ_n = ∂N(s_n)/∂sᵀ λ;   ρ_k = A_kᵀ ρ_{k+1};   a_ω += (B_kᵀ ρ_{k+1})_ω
    ρ_jump = (ρ_0 + a_ω ∂ω/∂x_+ᵀ, ν);   ρ_entry = J_y[:, x]ᵀ ρ_jump,x + E_y[:, x]ᵀ ν

with G = [D_k; W_k; P] for substep k, [D_0; P] for ω, D_y for the jump. The selections of
u into w and of p_d from v are linear and add nothing. Each piece's Hessian is casadi's
SX Hessian of ρᵀ piece, so nothing here is a hand derivation: only the chain is.
The backward sweep reads the forward sweep's states and Jacobians: ``jacobian_tape`` returns
them beside the Jacobian as one column a pulse (the tape), and ``hessian_tape`` runs the
backward sweep alone from it, bit for bit the self-contained Hessian (an OCP has the
Jacobians of the point first, ocp/chain.py).
tests/symbolic/test_pulse_map_derivatives.py checks both against casadi's AD through Φ
and against finite differences, tests/symbolic/test_pulse_map_design_derivatives.py with
designed entries of p.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cached_property
from typing import ClassVar, NamedTuple

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import ENGINE, PARAMETERS, PULSE_INPUT, STATE, RcsProfile
from lightcraft_opt.symbolic.maps.jump_derivatives import structured_jump_derivatives
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, substep_inputs
from lightcraft_opt.symbolic.maps.pulse_map_pieces import PulseMapPieces

__all__ = [
    "DerivativePieces",
    "PulseMapDerivatives",
    "build_derivative_pieces",
    "build_pulse_map_derivatives",
    "chain_derivatives",
    "check_design",
]

_SX_OPTIONS = {"cse": True}


@dataclass(frozen=True)
class DerivativePieces:
    """Each piece's ``<piece>_jacobian(inputs...) -> jac`` and ``<piece>_hessian(inputs...,
    adjoint) -> (jac, hess)`` (module docstring), for the normalisation, the jump, the coast
    substep and the coning rate: what gets compiled (compiled/pulse_map.py)."""

    normalise_jacobian: ca.Function
    normalise_hessian: ca.Function | None
    jump_jacobian: ca.Function
    jump_hessian: ca.Function | None
    substep_jacobian: ca.Function
    substep_hessian: ca.Function | None
    coning_rate_jacobian: ca.Function
    coning_rate_hessian: ca.Function | None

    @property
    def has_hessians(self) -> bool:
        return all(getattr(self, f.name) is not None for f in fields(self))

    def functions(self) -> tuple[ca.Function | None, ...]:
        """The eight Functions (None for Hessians not built), in field order."""
        return tuple(getattr(self, f.name) for f in fields(self))

    @classmethod
    def of(cls, functions: tuple[ca.Function | None, ...]) -> DerivativePieces:
        """From eight Functions in field order (e.g. compiled ones)."""
        return cls(*functions)


@dataclass(frozen=True)
class PulseMapDerivatives:
    """Φ's derivatives with respect to v = (x, u, p[design]) of one pulse.

    Attributes
    ----------
    values : casadi.Function ``pulse_map_values(x, u, p, t) -> (x_next, engine)``: Φ
        itself composed over the same pieces (compiled pieces: Φ at compiled speed).
    jacobian : casadi.Function ``pulse_map_jacobian(x, u, p, t) -> (x_next, engine,
        dx_next_dv, dengine_dv)``; the Jacobians are (STATE.size, nv) and (ENGINE.size, nv)
        with nv = STATE.size + u's size + len(design), columns x first, then u, then the
        designed entries of p.
    hessian : casadi.Function ``pulse_map_hessian(x, u, p, t, lam_x, lam_e) -> hess_v_v``:
        the (nv, nv) Hessian of lam_xᵀ x_next + lam_eᵀ engine; None when the pieces were
        built without Hessians (Jacobians only: linearisation).
    pieces : the pieces' derivative Functions the chain calls.
    design : sorted indices into PARAMETERS of the entries of p in v (the OCP's designed
        entries, ocp/design.py); () for v = (x, u).
    jacobian_tape : ``pulse_map_jacobian_tape(x, u, p, t) -> (x_next, engine, dx_next_dv,
        dengine_dv, tape)``: ``jacobian``'s outputs and the forward sweep's quantities the
        backward sweep needs (the substeps' states and input Jacobians, the exit
        normalisation's and the jump's Jacobians), one column; None without Hessians.
    hessian_tape : ``pulse_map_hessian_tape(x, u, p, t, tape, lam_x, lam_e) -> hess_v_v``:
        ``hessian`` from the tape of ``jacobian_tape`` at the same (x, u, p, t), so the
        backward sweep alone: the same bits, without the forward sweep again (an OCP has
        the Jacobians of its accepted point already, ocp/chain.py); None without Hessians.
    """

    values: ca.Function
    jacobian: ca.Function
    hessian: ca.Function | None
    pieces: DerivativePieces
    design: tuple[int, ...] = ()
    jacobian_tape: ca.Function | None = None
    hessian_tape: ca.Function | None = None
    #: The fields :meth:`functions` returns, in order, and how many.
    CHAIN_FIELDS: ClassVar[tuple[str, ...]] = (
        "values",
        "jacobian",
        "hessian",
        "jacobian_tape",
        "hessian_tape",
    )
    CHAIN_FUNCTIONS: ClassVar[int] = len(CHAIN_FIELDS)

    def functions(self) -> list[ca.Function]:
        """The chain's Functions with Hessians, in the order :meth:`of_functions` takes
        (what the disk cache keeps, compiled/pulse_map.py)."""
        out = [getattr(self, name) for name in self.CHAIN_FIELDS]
        if any(f is None for f in out):
            raise ParameterError("derivatives", "built without Hessians: nothing to keep")
        return [f for f in out if f is not None]

    @classmethod
    def of_functions(
        cls, functions: list[ca.Function], pieces: DerivativePieces, design: tuple[int, ...]
    ) -> PulseMapDerivatives:
        """From :meth:`functions`' list (e.g. loaded from the cache)."""
        chain = dict(zip(cls.CHAIN_FIELDS, functions, strict=True))
        return cls(pieces=pieces, design=design, **chain)

    @cached_property
    def n_v(self) -> int:
        return int(self.jacobian.size_out(2)[1])


def _piece_derivatives(
    f: ca.Function, wrt: tuple[int, ...], hessian: bool = True, design: tuple[int, ...] = ()
) -> tuple[ca.Function, ca.Function | None]:
    """``<f>_jacobian(inputs of f...) -> jac`` and ``<f>_hessian(inputs..., adjoint) ->
    (jac, hess)``: the Jacobian of f's outputs (stacked) with respect to its inputs ``wrt``
    (stacked) and, after them, the entries ``design`` of its input ``p``; and the Hessian
    of adjointᵀ outputs with respect to the same (None unless ``hessian``: its symbolic
    construction is the slow part)."""
    args = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    outs = ca.vertcat(*(ca.vec(o) for o in f.call(args)))
    z = ca.vertcat(*(args[i] for i in wrt))
    if design:
        z = ca.vertcat(z, args[f.index_in("p")][list(design)])
    rho = ca.SX.sym("adjoint", outs.numel())
    jac = ca.densify(ca.jacobian(outs, z))
    jacobian = ca.Function(f"{f.name()}_jacobian", args, [jac], f.name_in(), ["jac"], _SX_OPTIONS)
    if not hessian:
        return jacobian, None
    hess, _ = ca.hessian(ca.dot(rho, outs), z)
    second = ca.Function(
        f"{f.name()}_hessian",
        [*args, rho],
        [jac, ca.densify(hess)],
        [*f.name_in(), "adjoint"],
        ["jac", "hess"],
        _SX_OPTIONS,
    )
    return jacobian, second


def check_design(design: tuple[int, ...] | list[int]) -> tuple[int, ...]:
    """``design`` as a tuple of ints: sorted, distinct indices into PARAMETERS
    (ParameterError naming ``design`` otherwise)."""
    out = tuple(int(i) for i in design)
    if list(out) != sorted(set(out)) or any(not 0 <= i < PARAMETERS.size for i in out):
        raise ParameterError(
            "design",
            f"must be sorted, distinct indices into PARAMETERS (0 .. {PARAMETERS.size - 1}), "
            f"got {out}",
        )
    return out


def build_derivative_pieces(
    pieces: PulseMapPieces, *, hessians: bool = True, design: tuple[int, ...] = ()
) -> DerivativePieces:
    """The derivative Functions of Φ's pieces (casadi's SX AD on each piece alone), those
    that take p also with respect to its entries ``design`` (sorted indices into
    PARAMETERS); the Hessians only with ``hessians``. The jump of a model with the SECTOR
    impulse model is differentiated through its optic's quadrature point by point
    (symbolic/maps/jump_derivatives.py; not when the optic's radii are designed): the same
    derivatives, a fraction of the instructions."""
    design = check_design(design)
    jump = None
    if pieces.model is not None:  # through the optic's quadrature
        jump = structured_jump_derivatives(
            pieces.model, hessian=hessians, design=design, manifold=pieces.manifold
        )
    return DerivativePieces(
        *_piece_derivatives(pieces.normalise, (0,), hessians),
        *(jump or _piece_derivatives(pieces.jump, (0, 1), hessians, design)),
        *_piece_derivatives(pieces.substep, (0, 1), hessians, design),
        *_piece_derivatives(pieces.coning_rate, (0,), hessians, design),
    )


def build_pulse_map_derivatives(
    phi: PulseMap, *, hessians: bool = True, design: tuple[int, ...] = ()
) -> PulseMapDerivatives:
    """The explicit-chain Jacobian and (with ``hessians``) Lagrangian Hessian of the
    structured ``phi`` (:func:`~lightcraft_opt.symbolic.maps.pulse_map.build_pulse_map`)
    in v = (x, u, p[design]) (``design``: sorted indices into PARAMETERS), interpreted."""
    if phi.pieces is None:
        raise ParameterError(
            "phi", "the explicit chain needs a Φ from build_pulse_map, with its pieces"
        )
    pieces = build_derivative_pieces(phi.pieces, hessians=hessians, design=design)
    return chain_derivatives(phi, pieces, design=design)


def chain_derivatives(
    phi: PulseMap,
    derivatives: DerivativePieces,
    pieces: PulseMapPieces | None = None,
    *,
    design: tuple[int, ...] = (),
) -> PulseMapDerivatives:
    """The chain (module docstring) over given piece Functions: ``derivatives`` (built with
    the same ``design``, sorted indices into PARAMETERS) and the value ``pieces`` (default
    ``phi.pieces``), interpreted or compiled alike."""
    pieces = pieces or phi.pieces
    opts, ulay = phi.options, phi.inputs
    if pieces is None or opts is None or ulay is None:
        raise ParameterError(
            "phi", "the explicit chain needs a Φ from build_pulse_map, with its pieces"
        )
    design = check_design(design)
    nx, nu, ne, npulse = STATE.size, ulay.size, ENGINE.size, PULSE_INPUT.size
    nd = len(design)
    nv = nx + nu + nd
    if derivatives.jump_jacobian.size2_out(0) != nx + npulse + nd:
        raise ParameterError(
            "design",
            f"{design} does not match the derivative pieces "
            f"(built for {derivatives.jump_jacobian.size2_out(0) - nx - npulse} entries of p)",
        )
    d = derivatives
    jN, hN, jJ, hJ = d.normalise_jacobian, d.normalise_hessian, d.jump_jacobian, d.jump_hessian
    jS, hS, jW, hW = (
        d.substep_jacobian,
        d.substep_hessian,
        d.coning_rate_jacobian,
        d.coning_rate_hessian,
    )
    nw = pieces.substep_inputs.size
    phase_locked = opts.rcs_profile is RcsProfile.PHASE_LOCKED
    i_omega = pieces.substep_inputs.slot("coning_rate").start if phase_locked else -1

    x = ca.MX.sym("x", nx)
    u = ca.MX.sym("u", nu)
    p = ca.MX.sym("p", PARAMETERS.size)
    t = ca.MX.sym("t")
    lam_x = ca.MX.sym("lam_x", nx)
    lam_e = ca.MX.sym("lam_e", ne)

    # ------------------------------------------------------------ forward sweep
    pulse_select = np.zeros((npulse, nv))
    pulse_select[:, nx : nx + npulse] = np.eye(npulse)
    # p[design] in v: the pieces' Jacobians have its columns after their other inputs
    design_select = np.zeros((nd, nv))
    design_select[:, nx + nu :] = np.eye(nd)

    def with_design(D: ca.MX) -> ca.MX:
        """A piece's inputs' Jacobian in v: ``D`` (its other inputs') and p[design]'s."""
        return ca.vertcat(D, ca.DM(design_select)) if nd else D

    def entry(x: ca.MX) -> tuple[ca.MX, ca.MX]:
        """The normalised entry state x_n and the Jacobian D_y of the jump's inputs in v."""
        D_n = ca.horzcat(jN(x), ca.MX.zeros(nx, nu + nd))
        return pieces.normalise(x), with_design(ca.vertcat(D_n, ca.DM(pulse_select)))

    xn, D_y = entry(x)
    x_plus, engine = pieces.jump(xn, u[:npulse], p)
    J_y = jJ(xn, u[:npulse], p)
    D_0 = ca.mtimes(J_y[:nx, :], D_y)
    D_e = ca.mtimes(J_y[nx:, :], D_y)
    W_inputs, W_u = _substep_input_map(phi, pieces, u, p, t, x_plus, nd)
    if phase_locked:
        omega_x = jW(x_plus, p)
        d_omega = ca.mtimes(omega_x, with_design(D_0))  # (1, nv)
    states, Gs = [x_plus], []
    s, D = x_plus, D_0
    for k in range(opts.substeps):
        t_k = t + pieces.step_length * k
        w_k = W_inputs[:, k]
        Dw = ca.MX(ca.DM(W_u[k]))
        if phase_locked:
            Dw = Dw + ca.mtimes(ca.DM(_unit(nw, i_omega)), d_omega)
        jac_k = jS(s, w_k, p, t_k)
        A_k, B_k = jac_k[:, :nx], jac_k[:, nx : nx + nw]
        Gs.append(with_design(ca.vertcat(D, Dw)))
        D = ca.mtimes(A_k, D) + ca.mtimes(B_k, Dw)
        if nd:  # the substep's own dependence on p[design]
            D = D + ca.horzcat(ca.MX.zeros(nx, nx + nu), jac_k[:, nx + nw :])
        s = pieces.substep(s, w_k, p, t_k)
        states.append(s)
    x_next = pieces.normalise(s)
    Nx_out = jN(s)
    dx_next = ca.mtimes(Nx_out, D)
    names_in = ["x", "u", "p", "t"]
    jacobian_out = ["x_next", "engine", "dx_next_dv", "dengine_dv"]
    jacobian = ca.Function(
        "pulse_map_jacobian", [x, u, p, t], [x_next, engine, dx_next, D_e], names_in, jacobian_out
    )
    values = ca.Function(
        "pulse_map_values", [x, u, p, t], [x_next, engine], names_in, ["x_next", "engine"]
    )

    if hN is None or hJ is None or hS is None or hW is None:
        return PulseMapDerivatives(values, jacobian, None, derivatives, design)

    # ------------------------------------------------------------ backward sweep
    def backward(
        x: ca.MX,
        xn: ca.MX,
        D_y: ca.MX,
        W_inputs: ca.MX,
        tape: _Tape,
        lam_x: ca.MX,
        lam_e: ca.MX,
    ) -> ca.MX:
        """The Hessian of lam_xᵀ x_next + lam_eᵀ engine from the forward sweep's tape."""
        states, Gs, D, Nx_out, J_y = tape
        x_plus, s = states[0], states[-1]
        _, H_out = hN(s, lam_x)
        H = ca.mtimes([D.T, H_out, D])
        rho = ca.mtimes(Nx_out.T, lam_x)
        a_omega = ca.MX(0)
        for k in reversed(range(opts.substeps)):
            t_k = t + pieces.step_length * k
            jac_k, H_k = hS(states[k], W_inputs[:, k], p, t_k, rho)
            H = H + ca.mtimes([Gs[k].T, H_k, Gs[k]])
            if phase_locked:
                a_omega = a_omega + ca.mtimes(jac_k[:, nx + i_omega].T, rho)
            rho = ca.mtimes(jac_k[:, :nx].T, rho)
        if phase_locked:
            omega_x, H_omega = hW(x_plus, p, a_omega)
            rho = rho + a_omega * omega_x[:, :nx].T
            G_omega = with_design(Gs[0][:nx, :])  # D_0
            H = H + ca.mtimes([G_omega.T, H_omega, G_omega])
        _, H_jump = hJ(xn, u[:npulse], p, ca.vertcat(rho, lam_e))
        H = H + ca.mtimes([D_y.T, H_jump, D_y])
        entry_adjoint = ca.mtimes(J_y[:nx, :nx].T, rho) + ca.mtimes(J_y[nx:, :nx].T, lam_e)
        _, H_in = hN(x, entry_adjoint)
        return H + ca.diagcat(H_in, ca.MX.zeros(nu + nd, nu + nd))

    tape = _Tape(states, Gs, D, Nx_out, J_y)
    hessian_in = [*names_in, "lam_x", "lam_e"]
    hessian = ca.Function(
        "pulse_map_hessian",
        [x, u, p, t, lam_x, lam_e],
        [backward(x, xn, D_y, W_inputs, tape, lam_x, lam_e)],
        hessian_in,
        ["hess_v_v"],
    )
    jacobian_tape = ca.Function(
        "pulse_map_jacobian_tape",
        [x, u, p, t],
        [x_next, engine, dx_next, D_e, tape.packed()],
        names_in,
        [*jacobian_out, "tape"],
    )
    # the same backward sweep from a tape given as an input: nothing forward but the
    # entry's normalisation and the substeps' inputs, both cheap and bit for bit the same
    tape_in = ca.MX.sym("tape", tape.size)
    given = tape.unpacked(tape_in)
    W_given = substep_inputs(pieces, opts, ulay, u, t, given.states[0], p)
    hessian_tape = ca.Function(
        "pulse_map_hessian_tape",
        [x, u, p, t, tape_in, lam_x, lam_e],
        [backward(x, *entry(x), W_given, given, lam_x, lam_e)],
        [*names_in, "tape", "lam_x", "lam_e"],
        ["hess_v_v"],
    )
    return PulseMapDerivatives(
        values, jacobian, hessian, derivatives, design, jacobian_tape, hessian_tape
    )


class _Tape(NamedTuple):
    """The forward sweep's quantities the backward sweep reads (module docstring): the
    states s_0 = x_+ .. s_n, each substep's input Jacobian G_k, D_n = ∂s_n/∂v, the exit
    normalisation's Jacobian ∂N(s_n)/∂s and the jump's J_y."""

    states: list[ca.MX]
    Gs: list[ca.MX]
    D: ca.MX
    Nx_out: ca.MX
    J_y: ca.MX

    def _parts(self) -> list[ca.MX]:
        return [*self.states, *self.Gs, self.D, self.Nx_out, self.J_y]

    @property
    def size(self) -> int:
        return sum(int(m.numel()) for m in self._parts())

    def packed(self) -> ca.MX:
        """One column: every part's columns in turn."""
        return ca.vertcat(*(ca.vec(m) for m in self._parts()))

    def unpacked(self, column: ca.MX) -> _Tape:
        """A tape of the same shapes read from ``column`` (:meth:`packed`'s layout)."""
        parts, at = [], 0
        for m in self._parts():
            n = int(m.numel())
            parts.append(ca.reshape(column[at : at + n], m.size1(), m.size2()))
            at += n
        k = len(self.states)
        g = len(self.Gs)
        return _Tape(parts[:k], parts[k : k + g], *parts[k + g :])


def _unit(n: int, i: int) -> np.ndarray:
    e = np.zeros((n, 1))
    e[i] = 1.0
    return e


def _substep_input_map(
    phi: PulseMap,
    pieces: PulseMapPieces,
    u: ca.MX,
    p: ca.MX,
    t: ca.MX,
    x_plus: ca.MX,
    nd: int = 0,
) -> tuple[ca.MX, list[np.ndarray]]:
    """The substeps' inputs (w size, substeps) as Φ builds them (with ``pieces``), and for
    each substep the constant part of ∂w_k/∂v (w size, nv), v = (x, u, p[design]) with
    ``nd`` designed entries: the selection of u's entries (the coning rate's dependence on
    x_+ and p[design], the only way p enters w, is added by the caller)."""
    ulay, opts, own = phi.inputs, phi.options, phi.pieces
    assert ulay is not None and opts is not None and own is not None
    W = substep_inputs(pieces, opts, ulay, u, t, x_plus, p)
    # W is linear in u apart from ω and t: read the selection off its Jacobian in u, taken
    # through Φ's own (interpreted, differentiable) pieces
    u_sym = ca.MX.sym("u", ulay.size)
    x_sym = ca.MX.sym("x_plus", STATE.size)
    W_sym = substep_inputs(own, opts, ulay, u_sym, t, x_sym, p)
    select = ca.Function("w_of_u", [u_sym, x_sym, p, t], [ca.jacobian(ca.vec(W_sym), u_sym)])
    nw = own.substep_inputs.size
    S = np.asarray(select(np.zeros(ulay.size), np.ones(STATE.size), np.zeros(PARAMETERS.size), 0))
    out = []
    for k in range(own.substeps):
        rows = S[k * nw : (k + 1) * nw, :]
        out.append(np.hstack([np.zeros((nw, STATE.size)), rows, np.zeros((nw, nd))]))
    return W, out
