"""Ψ's chain for the estimator: its value and the Jacobians an estimator needs, called
through casadi's buffers (psi_model.py).

An estimator needs of Ψ (z⁺ = jump(z, pulse), then ``substeps`` coast substeps with the RCS
levels w held) ∂z_next/∂z, the column of the pulse's energy (the coupling's column is
exact from it, psi_model.py), and the columns of the entries of p the slow states move
(the wind's speed and direction, the rotor's moments); not the pointing's, the focus's or
the RCS levels' columns the director plans with. Its pieces differentiate in those alone
(19 columns of the jump's Jacobian instead of 22, 18 of a substep's instead of 22, and one
matrix product fewer a substep than Ψ's full chain, symbolic/maps/reduced_map_derivatives.py,
with the slow states' columns added: 7 % off the EKF's step in the closed loop):

- :func:`estimator_jump`, :func:`estimator_substep`: the pieces, SX with ``cse``,
  compiled once per structure;
- :func:`estimator_stage`: their chain, its outputs side by side;
- :func:`prediction_function`, :func:`measurement_function`: F's rows and a sensor's H in
  s (the slow states' columns through their charts), one call each a step;
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca

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
    "SlowColumns",
    "estimator_jump",
    "estimator_stage",
    "estimator_substep",
    "measurement_function",
    "prediction_function",
]

_NZ = REDUCED_STATE.size
_ENERGY = PULSE_INPUT.slot("energy").start
_LOAD = REDUCED_STATE.slot("engine_load").start


@functools.lru_cache(maxsize=8)
def estimator_jump(
    psi_model: Model, substeps: int, dense: int, entries: tuple[int, ...], compiled: bool
) -> ca.Function:
    """Ψ's pulse jump with its Jacobians in z, the pulse's energy and the entries
    ``entries`` of p (``reduced_jump_estimator(z, pulse, p) -> (z_plus, J_z, J_energy,
    J_p)``, J_energy (14, 1), J_p (14, len(entries))), compiled unless ``compiled`` is
    False (once per structure: disk cache)."""
    psi = build_reduced_map(psi_model, ReducedMapOptions(substeps, dense))
    z = ca.SX.sym("z", _NZ)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    z_plus, _ = psi.jump(z, pulse, p)
    chosen = ca.vertcat(*(p[i] for i in entries))
    f = ca.Function(
        "reduced_jump_estimator",
        [z, pulse, p],
        [
            z_plus,
            ca.jacobian(z_plus, z),
            ca.jacobian(z_plus, pulse[_ENERGY]),
            ca.jacobian(z_plus, chosen),
        ],
        ["z", "pulse", "p"],
        ["z_plus", "J_z", "J_energy", "J_p"],
        {"cse": True},
    )
    return _compiled(f, compiled, "Ψ's jump for the estimator")


@functools.lru_cache(maxsize=8)
def estimator_substep(
    psi_model: Model, substeps: int, dense: int, entries: tuple[int, ...], compiled: bool
) -> ca.Function:
    """Ψ's coast substep with its Jacobians in z and the entries ``entries`` of p
    (``reduced_substep_estimator(z, w, p, t) -> (z_next, S_z, S_p)``, S_p (14,
    len(entries)); w, the RCS levels, held), compiled unless ``compiled`` is False (once
    per structure: disk cache)."""
    psi = build_reduced_map(psi_model, ReducedMapOptions(substeps, dense))
    nw = psi.inputs.size - PULSE_INPUT.size
    z = ca.SX.sym("z", _NZ)
    w = ca.SX.sym("w", nw)
    p = ca.SX.sym("p", PARAMETERS.size)
    t = ca.SX.sym("t")
    z_next = psi.substep(z, w, p, t)
    chosen = ca.vertcat(*(p[i] for i in entries))
    f = ca.Function(
        "reduced_substep_estimator",
        [z, w, p, t],
        [z_next, ca.jacobian(z_next, z), ca.jacobian(z_next, chosen)],
        ["z", "w", "p", "t"],
        ["z_next", "S_z", "S_p"],
        {"cse": True},
    )
    return _compiled(f, compiled, "Ψ's substep for the estimator")


def _compiled(f: ca.Function, compiled: bool, what: str) -> ca.Function:
    if not compiled:
        return f
    done, _ = compile_all(
        [(f, DERIVATIVE_FLAGS)], max_instructions=DERIVATIVE_INSTRUCTION_LIMIT, what=what
    )
    return done[0]


def estimator_stage(psi: ReducedMap, jump: ca.Function, substep: ca.Function) -> ca.Function:
    """``psi_estimator_stage(z, u, p, t) -> [z_next A b_energy S_p]``: Ψ's value and its
    Jacobians in z (A, 14 x 14), the pulse's energy (b_energy, 14 x 1) and the entries of
    p the pieces (:func:`estimator_jump`, :func:`estimator_substep`) differentiate in
    (S_p), side by side, chained over the pieces:

        A = S_n ... S_1 J_z,  b_energy = S_n ... S_1 J_energy,
        S_p = S_n ... S_1 J_p + Σ_i S_n ... S_{i+1} S_p,i
    """
    n_pulse = PULSE_INPUT.size
    nw = psi.inputs.size - n_pulse
    h = psi.period / psi.options.substeps
    zm, um = ca.MX.sym("z", _NZ), ca.MX.sym("u", n_pulse + nw)
    pm, tm = ca.MX.sym("p", PARAMETERS.size), ca.MX.sym("t")
    z_i, A, b, S = jump(zm, um[:n_pulse], pm)
    for i in range(psi.options.substeps):
        z_i, S_z, S_p = substep(z_i, um[n_pulse:], pm, tm + float(h * i))
        A, b, S = ca.mtimes(S_z, A), ca.mtimes(S_z, b), ca.mtimes(S_z, S) + S_p
    return ca.Function(
        "psi_estimator_stage",
        [zm, um, pm, tm],
        [ca.horzcat(z_i, A, b, S)],
        ["z", "u", "p", "t"],
        ["z_A_b_S"],
    )


@dataclass(frozen=True)
class SlowColumns:
    """Where the slow states sit in s (psi_model.py; None: not estimated), in the order
    wind (east, north), coupling, moments (transverse, axial), and the constants their
    columns of F and H take: the reference pulse energy E_ref [J] and the model's
    rotor moments [kg m²] the ``inertia`` states scale."""

    wind: int | None
    coupling: int | None
    inertia: int | None
    reference_energy: float
    moments: tuple[float, float]


def prediction_function(stage: ca.Function, slow: SlowColumns) -> ca.Function:
    """``psi_prediction(z, u, p, t, chart, gain) -> [z_next F_z]``: Ψ's value and the rows
    of F (14 x n) in s's order (psi_model.py's module docstring), from the stage's
    (:func:`estimator_stage`) [z_next A b_energy S_p]: A; the wind's columns S_p[:, :2]
    ``chart`` (2 x 2, ∂(speed, direction)/∂(east, north)); the coupling's (b_energy - e_load /
    E_ref) ``gain`` (E / C); the moments' S_p times the model's moments. One call where
    numpy took a dozen."""
    z, u = ca.MX.sym("z", _NZ), ca.MX.sym("u", stage.size1_in(1))
    p, t = ca.MX.sym("p", PARAMETERS.size), ca.MX.sym("t")
    chart, gain = ca.MX.sym("chart", 2, 2), ca.MX.sym("gain")
    out = stage(z, u, p, t)
    columns, k = [out[:, 1 : 1 + _NZ]], 2 + _NZ  # k: the next column of S_p
    if slow.wind is not None:
        columns.append(ca.mtimes(out[:, k : k + 2], chart))
        k += 2
    if slow.coupling is not None:
        load = ca.DM.zeros(_NZ)
        load[_LOAD] = 1.0 / slow.reference_energy
        columns.append((out[:, 1 + _NZ] - load) * gain)
    if slow.inertia is not None:
        columns += [out[:, k + j] * slow.moments[j] for j in range(2)]
    return ca.Function(
        "psi_prediction",
        [z, u, p, t, chart, gain],
        [ca.horzcat(out[:, 0], *columns)],
        ["z", "u", "p", "t", "chart", "gain"],
        ["z_F"],
    )


def measurement_function(measure: ca.Function, slow: SlowColumns) -> ca.Function:
    """``<name>_in_s(z, p, dt, chart) -> [y H]``: a sensor's reading and its Jacobian in s
    (m x n), from ``measure(z, p, dt) -> [y H_z H_p]`` (H_p in p's wind speed, direction
    and impulse a pulse): H_z; the wind's columns H_p[:, :2] ``chart``; the coupling's
    H_p[:, 2] E_ref; zero in the moments (h reads them through the lift only: left out)."""
    z, p, dt = ca.MX.sym("z", _NZ), ca.MX.sym("p", PARAMETERS.size), ca.MX.sym("dt")
    chart = ca.MX.sym("chart", 2, 2)
    out = measure(z, p, dt)
    m = out.size1()
    columns = [out[:, 1 : 1 + _NZ]]
    if slow.wind is not None:
        columns.append(ca.mtimes(out[:, 1 + _NZ : 3 + _NZ], chart))
    if slow.coupling is not None:
        columns.append(out[:, 3 + _NZ] * slow.reference_energy)
    if slow.inertia is not None:
        columns.append(ca.MX.zeros(m, 2))
    return ca.Function(
        f"{measure.name()}_in_s",
        [z, p, dt, chart],
        [ca.horzcat(out[:, 0], *columns)],
        ["z", "p", "dt", "chart"],
        ["y_H"],
    )
