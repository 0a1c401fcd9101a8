"""Operating points of the pulse map Φ, its Jacobians and the error-state chart.

Operating points. :func:`trim_hover` finds the pulse energy and the vertical speed
before the pulse at which altitude and vertical speed repeat pulse to pulse (a true
fixed point of Φ in z, v_z; the horizontal states are not trimmed and drift by the
small horizontal terms of gravity and the Earth's rotation). :func:`climb_point` is a
point of a climb, not a fixed point: its linearisation is one step of a time-varying
model, and its multipliers are frozen-time growth rates, meaningful while the climb
changes little over the modes' time scale (a few pulses).

Error state. :func:`error_state` gives δ = x ⊖ x_op, the minimal error state of
:mod:`lightcraft_opt.symbolic.maps.error_state` (the chart the linear models of
:mod:`.linear_model` are written in).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

import casadi as ca
import numpy as np

from lightcraft_opt.layout import (
    PULSE_INPUT,
    STATE,
    VectorLayout,
    initial_state,
    map_input_layout,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.linear.signal_names import select_entries
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import checked_vector
from lightcraft_opt.symbolic.maps.error_state import ERROR_STATE, build_error_state
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import build_pulse_map_derivatives


class PointStatus(Enum):
    """What an operating point is."""

    TRIMMED = "trimmed"  # z and v_z repeat pulse to pulse
    TRAJECTORY = "trajectory"  # a point of a flight, not a fixed point
    NO_TRIM = "no_trim"  # the laser cannot hold the craft there
    NOT_CONVERGED = "not_converged"  # Newton stopped without meeting the tolerance


# --------------------------------------------------------------------------- Jacobians
@dataclass(frozen=True)
class PulseMapJacobian:
    """Φ with its Jacobians, built once and reused by every call here.

    Attributes
    ----------
    pulse_map : Φ.
    function : casadi.Function ``pulse_map_jacobian(x, u, p, t) -> (x_next, A, B)``,
        A = ∂x_next/∂x (STATE.size square), B = ∂x_next/∂u (exact AD).
    """

    pulse_map: PulseMap
    function: ca.Function

    def __call__(
        self, x: np.ndarray, u: np.ndarray, p: np.ndarray, t: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x_next, A, B = (np.asarray(v) for v in self.function(x, u, p, t))
        return x_next.ravel(), A, B


def pulse_map_jacobian(pulse_map: PulseMap) -> PulseMapJacobian:
    """Φ's value and Jacobians in one casadi.Function: the explicit chain over Φ's pieces
    (symbolic/maps/pulse_map_derivatives.py; a few seconds to build at the default 32 substeps,
    faster to evaluate than AD through Φ: bench/README.md#compile-cost-and-compiler-flags) when
    the map has them, else casadi's AD.
    Build once, pass it as ``pulse_map`` to the functions here."""
    if pulse_map.pieces is None:
        f = pulse_map.step.factory(
            "pulse_map_jacobian",
            ["x", "u", "p", "t"],
            ["x_next", "jac:x_next:x", "jac:x_next:u"],
        )
        return PulseMapJacobian(pulse_map, f)
    chain = build_pulse_map_derivatives(pulse_map, hessians=False).jacobian
    x, u, p, t = (ca.MX.sym(chain.name_in(i), chain.sparsity_in(i)) for i in range(4))
    x_next, _, dx_next, _ = chain(x, u, p, t)
    n = STATE.size
    f = ca.Function(
        "pulse_map_jacobian",
        [x, u, p, t],
        [x_next, dx_next[:, :n], dx_next[:, n:]],
        ["x", "u", "p", "t"],
        ["x_next", "jac_x_next_x", "jac_x_next_u"],
    )
    return PulseMapJacobian(pulse_map, f)


def jacobian_for(
    model: Model, pulse_map: PulseMap | PulseMapJacobian | None, options: PulseMapOptions | None
) -> PulseMapJacobian:
    """``pulse_map`` when it is already a :class:`PulseMapJacobian`, else the Jacobian
    Functions of it (or of Φ built for ``model`` with ``options`` when it is None)."""
    if isinstance(pulse_map, PulseMapJacobian):
        return pulse_map
    return pulse_map_jacobian(pulse_map or build_pulse_map(model, options))


@functools.cache
def error_state_chart() -> tuple[ca.Function, ca.Function, ca.Function]:
    """(local, ∂retract/∂δ, ∂local/∂x) of the error-state chart, built on first use."""
    retract, local = build_error_state()
    return (
        local,
        retract.factory("retract_jacobian", ["x_op", "dx"], ["jac:x:dx"]),
        local.factory("local_jacobian", ["x_op", "x"], ["jac:dx:x"]),
    )


def error_state_step(
    jacobian: PulseMapJacobian, x: np.ndarray, u: np.ndarray, p: np.ndarray, t: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One pulse of Φ from ``x`` (STATE.size,) under ``u`` and its Jacobians in the
    error-state chart: (x_next, A, B) with A = L(x_next) ∂Φ/∂x E(x) (ERROR_STATE.size
    square) and B = L(x_next) ∂Φ/∂u, E the chart's retraction Jacobian at x and L its
    inverse's at x_next (:mod:`lightcraft_opt.symbolic.maps.error_state`)."""
    x_next, A, B = jacobian(x, u, p, t)
    _, retract_jac, local_jac = error_state_chart()
    E = np.asarray(retract_jac(x, np.zeros(ERROR_STATE.size)))
    L = np.asarray(local_jac(x_next, x_next))
    return x_next, L @ A @ E, L @ B


def error_state(
    point: OperatingPoint | np.ndarray, x: np.ndarray, states: Sequence[str] | None = None
) -> np.ndarray:
    """δ = x ⊖ x_op: the error state of ``x`` about ``point`` (its x, or a state).

    Parameters
    ----------
    point : operating point (or a (STATE.size,) state x_op).
    x : (STATE.size,) state.
    states : error-state entries to return (default all of ERROR_STATE).

    Returns
    -------
    (len(states),) error state: r_L [m, L], v_L [m/s, L], theta_B [rad, B], w_B [rad/s,
    B], spin [rad/s], liner_mass, rcs_mass [kg], pulses, in the order asked.
    """
    x_op = point.x if isinstance(point, OperatingPoint) else point
    dx = np.asarray(error_state_chart()[0](x_op, checked_vector("x", x, STATE.size))).ravel()
    return dx[select_entries(ERROR_STATE, states, "states")]


# --------------------------------------------------------------------------- operating points
@dataclass(frozen=True)
class OperatingPoint:
    """A state and input to linearise Φ about.

    Attributes
    ----------
    x : (STATE.size,) state just before the pulse (docs/frames.md).
    u : (map-input size,) pulse-map input (pointing_L [m], focus [m], energy [J], ...).
    p : (PARAMETERS.size,) parameters.
    t : pulse time [s].
    x_next : (STATE.size,) Φ(x, u, p, t).
    status : trimmed, a trajectory point, or why no trim was found.
    message : more about the status.
    iterations : Newton iterations of a trim.
    inputs : layout of ``u``: the ``inputs`` of the pulse map the point was found with
        (its RCS profile: held, sub-intervals or phase-locked); None means the model's
        layout with held RCS levels.
    """

    x: np.ndarray
    u: np.ndarray
    p: np.ndarray
    t: float
    x_next: np.ndarray
    status: PointStatus
    message: str = ""
    iterations: int = 0
    inputs: VectorLayout | None = None

    def input_layout(self, model: Model) -> VectorLayout:
        """The layout of ``u``: :attr:`inputs`, or ``model``'s with held RCS levels."""
        if self.inputs is not None:
            return self.inputs
        craft = model.craft
        return map_input_layout(craft.thruster_count, craft.has_carrier)

    @property
    def success(self) -> bool:
        """True for a trim that met its tolerance and for a trajectory point."""
        return self.status in (PointStatus.TRIMMED, PointStatus.TRAJECTORY)

    @property
    def drift(self) -> np.ndarray:
        """(ERROR_STATE.size,) x_next ⊖ x: what one pulse changes (zero at a fixed point)."""
        return error_state(self.x, self.x_next)

    @property
    def residual(self) -> np.ndarray:
        """(2,) change of altitude [m] and vertical speed [m/s] over one pulse."""
        return self.drift[[_Z, _VZ]]


_Z = ERROR_STATE.slot("r_L").start + 2
_VZ = ERROR_STATE.slot("v_L").start + 2
_ENERGY = PULSE_INPUT.slot("energy").start  # the map input starts with the pulse slots
_FOCUS = PULSE_INPUT.slot("focus").start


def climb_point(
    model: Model,
    altitude: float,
    speed: float,
    *,
    offset_L: Sequence[float] = (0.0, 0.0),
    spin: float | None = None,
    energy: float | None = None,
    focus: float | None = None,
    t: float = 0.0,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
) -> OperatingPoint:
    """A point of a climb in the beam: NOT a fixed point of Φ.

    The craft upright at ``altitude`` [m] above the pad, moving up at ``speed`` [m/s]
    just before the pulse, ``offset_L`` (east, north) [m] from the beam axis (the beam
    on the pad axis), spinning at ``spin`` [rad/s] (default the craft's), under the
    nominal inputs with pulse ``energy`` [J] (default the flight's) and the director's
    ``focus`` distance [m] (default its farthest; the ``waist`` beam only). Since Φ(x) ≠ x,
    the linearisation here is one step of a time-varying model (status ``TRAJECTORY``).
    """
    x = initial_state(
        model,
        r_L=(*checked_vector("offset_L", offset_L, 2), altitude),
        v_L=(0.0, 0.0, speed),
        spin=spin,
    )
    if isinstance(pulse_map, PulseMapJacobian):
        pulse_map = pulse_map.pulse_map
    phi = pulse_map or build_pulse_map(model, options)
    u = nominal_inputs(model, phi.inputs)
    if energy is not None:
        u[_ENERGY] = energy
    if focus is not None:
        u[_FOCUS] = focus
    p = parameter_values(model)
    x_next = np.asarray(phi.step(x, u, p, t)[0]).ravel()
    msg = "a climb, not a fixed point"
    return OperatingPoint(x, u, p, t, x_next, PointStatus.TRAJECTORY, msg, inputs=phi.inputs)


def trim_hover(
    model: Model,
    altitude: float,
    *,
    spin: float | None = None,
    t: float = 0.0,
    max_energy: float | None = None,
    tol: float = 1e-12,
    max_iter: int = 30,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
) -> OperatingPoint:
    """Hover in the beam: the pulse energy and pre-pulse vertical speed that repeat
    altitude and vertical speed pulse to pulse.

    The craft is centred on the beam axis (on the pad axis), upright, spinning at
    ``spin`` [rad/s] (default the craft's), at ``altitude`` [m] just before the pulse.
    Newton on (energy, v_z) with Φ's exact Jacobian solves
    ``Φ(x)[z] = z, Φ(x)[v_z] = v_z``: each pulse adds the velocity the coast loses, so
    v_z ≈ -g T / 2 before the pulse and +g T / 2 after it (a 1.8 mm hop for Flight 5).
    The other states are not trimmed (see the module docstring).

    Parameters
    ----------
    max_energy : largest pulse energy [J] (default the laser's ``pulse_energy_max``).
    tol : on |Δz| [m] and T |Δv_z| [m] over one pulse.

    Returns
    -------
    OperatingPoint with status ``TRIMMED``; ``NO_TRIM`` when the hover needs more than
    ``max_energy`` or the optic catches nothing there (the point then holds the last
    iterate); ``NOT_CONVERGED`` when Newton ran out of iterations.
    """
    jac = jacobian_for(model, pulse_map, options)
    e_max = model.laser.pulse_energy_max if max_energy is None else max_energy
    period = jac.pulse_map.period
    x = initial_state(model, r_L=(0.0, 0.0, altitude), spin=spin)
    lay = jac.pulse_map.inputs
    u = nominal_inputs(model, lay)
    p = parameter_values(model)
    iz, iv = STATE.slot("r_L").start + 2, STATE.slot("v_L").start + 2
    g_guess = 9.81
    x[iv] = -0.5 * g_guess * period
    u[_ENERGY] = 0.2 * min(e_max, model.flight.pulse_energy)
    for k in range(max_iter + 1):
        x_next, A, B = jac(x, u, p, t)
        r = np.array([x_next[iz] - x[iz], (x_next[iv] - x[iv]) * period])
        if np.all(np.abs(r) <= tol):
            status, msg = PointStatus.TRIMMED, f"|Δz|, T|Δv_z| <= {tol:g} m"
            if u[_ENERGY] > e_max:
                status = PointStatus.NO_TRIM
                msg = f"hover needs {u[_ENERGY]:.4g} J a pulse, more than {e_max:.4g} J"
            return OperatingPoint(x, u, p, t, x_next, status, msg, k, lay)
        if k == max_iter:
            break
        J = np.array(
            [[A[iz, iv], B[iz, _ENERGY]], [(A[iv, iv] - 1) * period, B[iv, _ENERGY] * period]]
        )
        if abs(B[iv, _ENERGY]) * e_max < 1e-9 * g_guess * period:
            msg = f"the optic catches no energy at {altitude:g} m: no pulse can hold the craft"
            return OperatingPoint(x, u, p, t, x_next, PointStatus.NO_TRIM, msg, k, lay)
        step = np.linalg.solve(J, -r)
        x[iv] += step[0]
        u[_ENERGY] += step[1]
        if u[_ENERGY] > 4 * e_max:
            msg = f"hover needs more than {4 * e_max:.4g} J a pulse (the laser gives {e_max:.4g})"
            return OperatingPoint(x, u, p, t, x_next, PointStatus.NO_TRIM, msg, k + 1, lay)
    msg = f"Newton stopped after {max_iter} iterations, residual {r}"
    return OperatingPoint(x, u, p, t, x_next, PointStatus.NOT_CONVERGED, msg, max_iter, lay)
