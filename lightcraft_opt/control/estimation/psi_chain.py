"""Ψ's chains for the estimator: its value and Jacobians in z, u and the entries of p the
slow states move (the wind's speed and direction, the rotor's moments), called through
casadi's buffers (psi_model.py).

- :func:`parameter_substep`, :func:`parameter_jump`: Ψ's pieces differentiated also in
  chosen entries of p, compiled once per structure;
- :func:`stage_with_parameters`, :func:`stage_packed`: the chains over the pieces (as
  symbolic/maps/reduced_map_derivatives.py), their outputs side by side;
- :class:`Evaluator`: a one-output Function called through its buffers.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from lightcraft_opt.compiled import DERIVATIVE_INSTRUCTION_LIMIT
from lightcraft_opt.compiled.cache import DERIVATIVE_FLAGS, compile_all
from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, REDUCED_STATE
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.reduced_map import (
    ReducedMap,
    ReducedMapOptions,
    build_reduced_map,
)

__all__ = [
    "Evaluator",
    "parameter_jump",
    "parameter_substep",
    "stage_packed",
    "stage_with_parameters",
]

_NZ = REDUCED_STATE.size


@functools.lru_cache(maxsize=8)
def parameter_substep(
    psi_model: Model, substeps: int, dense: int, entries: tuple[int, ...], compiled: bool
) -> ca.Function:
    """Ψ's coast substep with its Jacobians in z, the held RCS levels w and the entries
    ``entries`` of p (``reduced_substep_p_jacobian(z, w, p, t) -> (z_next, S_z, S_w, S_p)``,
    S_p (14, len(entries))), compiled unless ``compiled`` is False (once per structure:
    disk cache)."""
    psi = build_reduced_map(psi_model, ReducedMapOptions(substeps, dense))
    nw = psi.inputs.size - PULSE_INPUT.size
    z = ca.SX.sym("z", _NZ)
    w = ca.SX.sym("w", nw)
    p = ca.SX.sym("p", PARAMETERS.size)
    t = ca.SX.sym("t")
    z_next = psi.substep(z, w, p, t)
    chosen = ca.vertcat(*(p[i] for i in entries))
    f = ca.Function(
        "reduced_substep_p_jacobian",
        [z, w, p, t],
        [z_next, ca.jacobian(z_next, z), ca.jacobian(z_next, w), ca.jacobian(z_next, chosen)],
        ["z", "w", "p", "t"],
        ["z_next", "S_z", "S_w", "S_p"],
        {"cse": True},
    )
    return _compiled(f, compiled, "Ψ's substep in p")


@functools.lru_cache(maxsize=8)
def parameter_jump(
    psi_model: Model, substeps: int, dense: int, entries: tuple[int, ...], compiled: bool
) -> ca.Function:
    """Ψ's pulse jump with its Jacobians in z, the pulse and the entries ``entries`` of p
    (``reduced_jump_p_jacobian(z, pulse, p) -> (z_plus, engine, J_z, J_pulse, J_p)``),
    compiled unless ``compiled`` is False (once per structure: disk cache)."""
    psi = build_reduced_map(psi_model, ReducedMapOptions(substeps, dense))
    z = ca.SX.sym("z", _NZ)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    z_plus, engine = psi.jump(z, pulse, p)
    chosen = ca.vertcat(*(p[i] for i in entries))
    f = ca.Function(
        "reduced_jump_p_jacobian",
        [z, pulse, p],
        [
            z_plus,
            engine,
            ca.jacobian(z_plus, z),
            ca.jacobian(z_plus, pulse),
            ca.jacobian(z_plus, chosen),
        ],
        ["z", "pulse", "p"],
        ["z_plus", "engine", "J_z", "J_pulse", "J_p"],
        {"cse": True},
    )
    return _compiled(f, compiled, "Ψ's jump in p")


def _compiled(f: ca.Function, compiled: bool, what: str) -> ca.Function:
    if not compiled:
        return f
    done, _ = compile_all(
        [(f, DERIVATIVE_FLAGS)], max_instructions=DERIVATIVE_INSTRUCTION_LIMIT, what=what
    )
    return done[0]


def stage_with_parameters(psi: ReducedMap, jump: ca.Function, substep: ca.Function) -> ca.Function:
    """``psi_p_stage(z, u, p, t) -> [z_next A B S_p]``: Ψ's value and Jacobians in z, u
    and the entries of p that ``substep`` (:func:`parameter_substep`) differentiates in,
    side by side, chained over the pieces (as reduced_map_derivatives.py). ``jump`` is
    :func:`parameter_jump` in the same entries, or Ψ's ``reduced_jump_jacobian`` (four
    outputs) where the jump does not see them (the wind)."""
    n_pulse = PULSE_INPUT.size
    nw = psi.inputs.size - n_pulse
    n_p = substep.size2_out(3)
    h = psi.period / psi.options.substeps
    zm, um = ca.MX.sym("z", _NZ), ca.MX.sym("u", n_pulse + nw)
    pm, tm = ca.MX.sym("p", PARAMETERS.size), ca.MX.sym("t")
    out = jump(zm, um[:n_pulse], pm)
    z_i, A, B_pulse = out[0], out[2], out[3]
    S_par = out[4] if len(out) == 5 else ca.MX.zeros(_NZ, n_p)
    B_w = ca.MX.zeros(_NZ, nw)
    for i in range(psi.options.substeps):
        z_i, S_z, S_w, S_p = substep(z_i, um[n_pulse:], pm, tm + float(h * i))
        A, B_pulse = ca.mtimes(S_z, A), ca.mtimes(S_z, B_pulse)
        B_w = ca.mtimes(S_z, B_w) + S_w if nw else B_w
        S_par = ca.mtimes(S_z, S_par) + S_p
    return ca.Function(
        "psi_p_stage",
        [zm, um, pm, tm],
        [ca.horzcat(z_i, A, B_pulse, B_w, S_par)],
        ["z", "u", "p", "t"],
        ["z_A_B_S"],
    )


def stage_packed(stage: ca.Function) -> ca.Function:
    """``psi_stage(z, u, p, t) -> [z_next A B]``: Ψ's chain with its outputs side by side
    (one conversion a call)."""
    zm, um = ca.MX.sym("z", _NZ), ca.MX.sym("u", stage.size1_in(1))
    pm, tm = ca.MX.sym("p", PARAMETERS.size), ca.MX.sym("t")
    z_next, _, A, B = stage(zm, um, pm, tm)
    return ca.Function(
        "psi_stage", [zm, um, pm, tm], [ca.horzcat(z_next, A, B)], ["z", "u", "p", "t"], ["z_A_B"]
    )


class Evaluator:
    """The first output of a casadi Function, called through its buffers
    (``Function.buffer``): the inputs copied into arrays it owns, the output (densified)
    read in place; the other outputs are not computed. A call costs well under a
    microsecond beyond the Function's own work, against some 20 µs for a call from Python
    with its conversions (what keeps the EKF's step inside its 0.3 ms)."""

    def __init__(self, f: ca.Function) -> None:
        rows, cols = f.size_out(0)
        ins = [ca.MX.sym(f.name_in(i), f.size_in(i)) for i in range(f.n_in())]
        first = f.call(ins)[0]
        self.function = ca.Function(
            f.name(), ins, [ca.densify(first)], f.name_in(), [f.name_out(0)]
        )
        self._buffer, self._trigger = self.function.buffer()
        self._args = [np.zeros(f.numel_in(i)) for i in range(f.n_in())]
        for i, a in enumerate(self._args):
            self._buffer.set_arg(i, a.data)
        self._out = np.zeros(rows * cols)
        self._buffer.set_res(0, self._out.data)
        self._shape = (cols, rows)

    def __call__(self, *args: np.ndarray | float) -> np.ndarray:
        """The output (rows, cols), a fresh array."""
        for a, v in zip(self._args, args, strict=True):
            a[...] = np.ravel(v)
        self._trigger()
        return self._out.reshape(self._shape).T.copy()
