"""Forward sensitivities of Φ's dense output to the state and the parameters, chained over
its pieces: what calibration differentiates.

A calibration fits a few scalars θ that enter through the parameter vector p and the initial
state x0 (calibration/problem.py), so it needs the dense states X_j of every pulse (the
positions and velocities the track is interpolated from) differentiated in the n directions
of θ. Given the seeds S = ∂x/∂θ (STATE.size, n) at the pulse and Q = ∂p/∂θ
(PARAMETERS.size, n), with the map input u and the time fixed, the chain over the pieces of
pulse_map_pieces.py (in the order they run) is::

    D_n  = N_x(x) S                               (normalised entry state)
    D_0  = J_x D_n + J_p Q                        (state after the jump)
    D_ω  = ω_x D_0 + ω_p Q                        (PHASE_LOCKED: the coning rate)
    D_{k+1} = A_k D_k + B_k e_ω D_ω + P_k Q       (substep k: A = ∂S/∂s, B = ∂S/∂w, P = ∂S/∂p)
    ∂X_j/∂θ = D after the node's substep; the last node N_x(s_n) D_n

Each piece runs in casadi's SX forward mode (``jtimes``) on its own, value and n directions
in one small Function that compiles in seconds (compiled/), so the products above are never
formed as matrices and no AD graph spans the flight: only the chain is written here. n
directions cost about as much as n + 1 evaluations of Φ.
tests/symbolic/test_pulse_map_sensitivities.py checks it against casadi's AD through Φ's
dense output.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, STATE, RcsProfile
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, substep_inputs
from lightcraft_opt.symbolic.maps.pulse_map_pieces import PulseMapPieces

__all__ = ["SensitivityPieces", "build_dense_sensitivity", "build_sensitivity_pieces"]

_SX_OPTIONS = {"cse": True}


@dataclass(frozen=True)
class SensitivityPieces:
    """Each piece in forward mode, n directions at once, value and derivative together (SX
    with ``{"cse": True}``, so they share their subexpressions): what gets compiled
    (compiled/pulse_map.py).

    - ``normalise_attitude_forward(x, dx) -> (x_unit, dx_unit)``;
    - ``pulse_jump_forward(x, pulse, p, dx, dp) -> (x_plus, dx_plus)`` (the pulse input held);
    - ``coast_substep_forward(x, w, p, t, dx, dw, dp) -> (x_next, dx_next)``;
    - ``coning_rate_forward(x, p, dx, dp) -> (omega, domega)``.

    Seeds and derivatives are (rows of the input, n).
    """

    normalise: ca.Function
    jump: ca.Function
    substep: ca.Function
    coning_rate: ca.Function
    n_directions: int

    def functions(self) -> tuple[ca.Function, ...]:
        """The four Functions, in field order."""
        return (self.normalise, self.jump, self.substep, self.coning_rate)

    def replaced(self, functions: tuple[ca.Function, ...]) -> SensitivityPieces:
        """The same with four other Functions in field order (e.g. compiled ones)."""
        normalise, jump, substep, coning_rate = functions
        return SensitivityPieces(normalise, jump, substep, coning_rate, self.n_directions)


def _forward(f: ca.Function, wrt: tuple[int, ...], n: int, outputs: int = 1) -> ca.Function:
    """``<f>_forward(inputs of f..., seeds of the inputs wrt...) -> (values, derivatives)``:
    f's first ``outputs`` outputs and their derivatives in the n directions of the seeds
    (casadi's SX forward mode, ``jtimes``)."""
    args = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    seeds = [ca.SX.sym(f"d{f.name_in(i)}", f.size1_in(i), n) for i in wrt]
    values = f.call(args)[:outputs]
    z = ca.vertcat(*(args[i] for i in wrt))
    dz = ca.vertcat(*seeds)
    out = ca.vertcat(*values)
    derivative = ca.jtimes(out, z, dz)
    names_out = [f.name_out(i) for i in range(outputs)]
    return ca.Function(
        f"{f.name()}_forward",
        [*args, *seeds],
        [out, derivative],
        [*f.name_in(), *(f"d{f.name_in(i)}" for i in wrt)],
        ["_".join(names_out), "d_" + "_".join(names_out)],
        _SX_OPTIONS,
    )


def build_sensitivity_pieces(pieces: PulseMapPieces, n_directions: int) -> SensitivityPieces:
    """The pieces in forward mode, ``n_directions`` at once (casadi's SX AD on each piece)."""
    if isinstance(n_directions, bool) or not isinstance(n_directions, int) or n_directions < 1:
        raise ParameterError("n_directions", f"must be an integer >= 1, got {n_directions!r}")
    n = n_directions
    return SensitivityPieces(
        _forward(pieces.normalise, (0,), n),
        _forward(pieces.jump, (0, 2), n),
        _forward(pieces.substep, (0, 1, 2), n),
        _forward(pieces.coning_rate, (0, 1), n),
        n,
    )


def build_dense_sensitivity(
    phi: PulseMap,
    n_directions: int,
    sensitivities: SensitivityPieces | None = None,
    pieces: PulseMapPieces | None = None,
) -> ca.Function:
    """``pulse_map_dense_sensitivity(x, u, p, t, dx, dp) -> (X, dX)``: Φ's dense output X
    (STATE.size, dense) and its derivative in ``n_directions`` directions (module
    docstring).

    Parameters
    ----------
    phi : a Φ from :func:`~lightcraft_opt.symbolic.maps.pulse_map.build_pulse_map` (with its
        pieces).
    n_directions : n, the columns of the seeds dx = ∂x/∂θ (STATE.size, n) and dp = ∂p/∂θ
        (PARAMETERS.size, n); x in the STATE layout (L and B frames), p in PARAMETERS.
    sensitivities : the pieces in forward mode for n directions, interpreted or compiled
        (default: built from ``phi.pieces``, interpreted).
    pieces : the value pieces (default ``phi.pieces``): only their layout and the substep
        inputs' construction are read.

    Returns
    -------
    casadi.Function whose dX is (STATE.size * dense, n): column i is vec(∂X/∂θ_i), node after
    node (the layout of ``vec(X)``). u and t are held (their sensitivities are not asked).
    """
    pieces = pieces or phi.pieces
    opts, ulay = phi.options, phi.inputs
    if pieces is None or opts is None or ulay is None:
        raise ParameterError(
            "phi", "the sensitivity chain needs a Φ from build_pulse_map, with its pieces"
        )
    if sensitivities is None:
        sensitivities = build_sensitivity_pieces(pieces, n_directions)
    if sensitivities.n_directions != n_directions:
        raise ParameterError(
            "sensitivities",
            f"are built for {sensitivities.n_directions} directions, not {n_directions}",
        )
    nx, n_p, n = STATE.size, PARAMETERS.size, n_directions
    phase_locked = opts.rcs_profile is RcsProfile.PHASE_LOCKED
    wlay = pieces.substep_inputs
    f = sensitivities

    x = ca.MX.sym("x", nx)
    u = ca.MX.sym("u", ulay.size)
    p = ca.MX.sym("p", n_p)
    t = ca.MX.sym("t")
    S = ca.MX.sym("dx", nx, n)
    Q = ca.MX.sym("dp", n_p, n)

    xn, D = f.normalise(x, S)
    x_plus, D = f.jump(xn, u[: PULSE_INPUT.size], p, D, Q)
    W = substep_inputs(pieces, opts, ulay, u, t, x_plus, p)
    dW = ca.MX.zeros(wlay.size, n)
    if phase_locked:  # the coning rate fixed at x_+ feeds every substep
        _, d_omega = f.coning_rate(x_plus, p, D, Q)
        i_omega = wlay.slot("coning_rate").start
        dW = ca.vertcat(dW[:i_omega, :], d_omega, dW[i_omega + 1 :, :])

    every = opts.substeps // opts.dense
    nodes: list[tuple[ca.MX, ca.MX]] = []
    s = x_plus
    for k in range(opts.substeps):
        s, D = f.substep(s, W[:, k], p, t + pieces.step_length * k, D, dW, Q)
        if (k + 1) % every == 0 and k + 1 < opts.substeps:
            nodes.append((s, D))
    nodes.append(f.normalise(s, D))
    X = ca.horzcat(*(node[0] for node in nodes))
    dX = ca.vertcat(*(node[1] for node in nodes))
    return ca.Function(
        "pulse_map_dense_sensitivity",
        [x, u, p, t, S, Q],
        [X, dX],
        ["x", "u", "p", "t", "dx", "dp"],
        ["X", "dX"],
    )
