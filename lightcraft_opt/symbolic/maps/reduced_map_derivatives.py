"""Ψ's pulse-to-pulse Jacobians by an explicit chain over small SX pieces.

The director (control/director.py) linearises the reduced map Ψ (reduced_map.py) along its
plan every pulse. AD through Ψ's MX composition (the jump, then ``substeps`` coast steps) is
slow to run and to compile (minutes of gcc for a 10-stage map of it; figures:
bench/README.md#where-a-steps-time-goes-and-the-other-flights). Here each piece
differentiates itself in SX (``cse``), and a short MX graph chains them:

    z⁺ = jump(z, pulse),  z_{i+1} = substep(z_i, w),
    A = S_n ... S_1 J_z,  B = [S_n ... S_1 J_pulse,  Σ_i S_n ... S_{i+1} S_w,i]

with J and S the pieces' Jacobians (w, the RCS levels, held over the interval). The chain
compiles piece by piece (each SX body once) in seconds to a minute, and evaluates a stage in
a fraction of a millisecond; tests/control/test_director.py checks it against
casadi's AD through Ψ.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, REDUCED_STATE
from lightcraft_opt.symbolic.maps.reduced_map import ReducedMap

__all__ = ["ReducedMapDerivatives", "build_reduced_map_derivatives", "value_stage"]

_SX_OPTIONS = {"cse": True}


@dataclass(frozen=True)
class ReducedMapDerivatives:
    """Ψ's Jacobians of one model.

    Attributes
    ----------
    jump : ``reduced_jump_jacobian(z, pulse, p) -> (z_plus, engine, J_z, J_pulse)``.
    substep : ``reduced_substep_jacobian(z, w, p, t) -> (z_next, S_z, S_w)``.
    value_jump, value_substep : Ψ's own value pieces (``reduced_jump``, ``reduced_substep``).
    value : ``reduced_stage(z, u, p, t) -> (z_next, engine)``: Ψ's value, chained likewise.
    stage : ``reduced_stage_jacobian(z, u, p, t) -> (z_next, engine, A, B)``: Ψ's value at
        (z, u) and its Jacobians A = ∂z_next/∂z (14, 14), B = ∂z_next/∂u (14, nu), the
        chain of the two pieces above (an MX Function calling them).

    substeps : coast steps a pulse; period : pulse period T [s].
    """

    jump: ca.Function
    substep: ca.Function
    value_jump: ca.Function
    value_substep: ca.Function
    value: ca.Function
    stage: ca.Function
    substeps: int
    period: float

    def pieces(self) -> tuple[ca.Function, ca.Function, ca.Function, ca.Function]:
        """(jump, substep, value_jump, value_substep): what :meth:`replaced` takes."""
        return self.jump, self.substep, self.value_jump, self.value_substep

    def replaced(
        self, pieces: tuple[ca.Function, ca.Function, ca.Function, ca.Function]
    ) -> ReducedMapDerivatives:
        """The same chains over other (e.g. compiled) pieces of the same signatures, in the
        order of :meth:`pieces`."""
        return _chain(*pieces, self.substeps, self.period)


def build_reduced_map_derivatives(psi: ReducedMap) -> ReducedMapDerivatives:
    """The explicit-chain Jacobians of ``psi`` (module docstring)."""
    nz = REDUCED_STATE.size
    nw = psi.inputs.size - PULSE_INPUT.size
    z = ca.SX.sym("z", nz)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    t = ca.SX.sym("t")
    w = ca.SX.sym("w", nw)
    z_plus, engine = psi.jump(z, pulse, p)
    jump = ca.Function(
        "reduced_jump_jacobian",
        [z, pulse, p],
        [z_plus, engine, ca.jacobian(z_plus, z), ca.jacobian(z_plus, pulse)],
        ["z", "pulse", "p"],
        ["z_plus", "engine", "J_z", "J_pulse"],
        _SX_OPTIONS,
    )
    z_next = psi.substep(z, w, p, t)
    substep = ca.Function(
        "reduced_substep_jacobian",
        [z, w, p, t],
        [z_next, ca.jacobian(z_next, z), ca.jacobian(z_next, w)],
        ["z", "w", "p", "t"],
        ["z_next", "S_z", "S_w"],
        _SX_OPTIONS,
    )
    return _chain(jump, substep, psi.jump, psi.substep, psi.options.substeps, psi.period)


def value_stage(
    value_jump: ca.Function, value_substep: ca.Function, substeps: int, period: float
) -> ca.Function:
    """``reduced_stage(z, u, p, t) -> (z_next, engine)``: Ψ's value, the jump
    ``reduced_jump(z, pulse, p)`` then ``substeps`` coast steps ``reduced_substep(z, w, p,
    t)`` over the ``period`` [s] (interpreted or compiled pieces alike), u = (pulse, w)."""
    nz, n_pulse = REDUCED_STATE.size, PULSE_INPUT.size
    zm = ca.MX.sym("z", nz)
    um = ca.MX.sym("u", n_pulse + value_substep.size1_in(1))
    pm, tm = ca.MX.sym("p", PARAMETERS.size), ca.MX.sym("t")
    h = period / substeps
    z_v, engine_v = value_jump(zm, um[:n_pulse], pm)
    for i in range(substeps):
        z_v = value_substep(z_v, um[n_pulse:], pm, tm + float(h * i))
    return ca.Function(
        "reduced_stage",
        [zm, um, pm, tm],
        [z_v, engine_v],
        ["z", "u", "p", "t"],
        ["z_next", "engine"],
    )


def _chain(
    jump: ca.Function,
    substep: ca.Function,
    value_jump: ca.Function,
    value_substep: ca.Function,
    substeps: int,
    period: float,
) -> ReducedMapDerivatives:
    nz = REDUCED_STATE.size
    n_pulse = PULSE_INPUT.size
    nw = substep.size1_in(1)
    zm = ca.MX.sym("z", nz)
    um = ca.MX.sym("u", n_pulse + nw)
    pm = ca.MX.sym("p", PARAMETERS.size)
    tm = ca.MX.sym("t")
    h = period / substeps
    z_i, engine, A, B_pulse = jump(zm, um[:n_pulse], pm)
    B_w = ca.MX.zeros(nz, nw)
    for i in range(substeps):
        z_i, S_z, S_w = substep(z_i, um[n_pulse:], pm, tm + float(h * i))
        A = ca.mtimes(S_z, A)
        B_pulse = ca.mtimes(S_z, B_pulse)
        B_w = ca.mtimes(S_z, B_w) + S_w if nw else B_w
    stage = ca.Function(
        "reduced_stage_jacobian",
        [zm, um, pm, tm],
        [z_i, engine, A, ca.horzcat(B_pulse, B_w)],
        ["z", "u", "p", "t"],
        ["z_next", "engine", "A", "B"],
    )
    value = value_stage(value_jump, value_substep, substeps, period)
    return ReducedMapDerivatives(
        jump, substep, value_jump, value_substep, value, stage, substeps, period
    )
