"""Linearisation of the pulse map Φ: pulse-to-pulse multipliers, controllability, LQR.

One step of Φ (``x[k+1] = Φ(x[k], u[k], p, t_k)``, symbolic/pulse_map.py) about an
operating point (x_op, u_op) gives the discrete-time linear model

    δ[k+1] = A δ[k] + B δu[k],   A = ∂Φ/∂x,  B = ∂Φ/∂u   (exact casadi AD),

sampled at the pulse period T = 1 / pulse_rate, returned as a ``control.StateSpace``
with ``dt = T`` and the layout's names. Its eigenvalues are the pulse-to-pulse
multipliers (Floquet multipliers of the hybrid flow): |λ| > 1 grows by |λ| a pulse.

Coordinates (:class:`Coordinates`). ``FULL`` differentiates Φ on the 17 raw states
(quaternion components included). ``ERROR_STATE`` (default) works on the minimal error
state δ of :mod:`lightcraft_opt.symbolic.error_state`: x = x_op ⊕ δ, the attitude a
small rotation theta_B of B; A = ∂(Φ(x_op ⊕ δ) ⊖ Φ(x_op))/∂δ at δ = 0, so A maps
errors about x_op to errors about Φ(x_op). The default kept states
(:data:`REDUCED_STATES`) are r_L, v_L, theta_B[b2, b3], w_B[b2, b3]: left out are the
turn about the craft axis theta_B[b1] and the gauge w_B[b1] (only w_B[b1] + spin is
physical, docs/frames.md), spin (no beam input moves it; it decays), and the
consumables liner_mass, rcs_mass, pulses (integrators no input can move). Those
neutral, unreachable multipliers would make (A, B) non-stabilisable for dlqr.

Operating points. :func:`trim_hover` finds the pulse energy and the vertical speed
before the pulse at which altitude and vertical speed repeat pulse to pulse (a true
fixed point of Φ in z, v_z; the horizontal states are not trimmed and drift by the
small horizontal terms of gravity and the Earth's rotation). :func:`climb_point` is a
point of a climb, not a fixed point: its linearisation is one step of a time-varying
model, and its multipliers are frozen-time growth rates, meaningful while the climb
changes little over the modes' time scale (a few pulses).

Modes (:class:`ModeKind`) are classified by participation factors (Pérez-Arriaga,
Verghese & Schweppe 1982, IEEE Trans. PAS 101(9)): p_ki = |l_ki r_ki|, dimensionless,
grouped by the states of each kind; a mode belongs to the group with the largest share.
The beam-riding modes load the lateral offset, lateral velocity and tilt; the coning
(nutation) modes the transverse rates w_B[b2, b3] (216 Hz for Flight 5, aliased at the
26 Hz pulse rate).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import Enum

import casadi as ca
import control
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    PULSE_INPUT,
    STATE,
    VectorLayout,
    checked_vector,
    initial_state,
    map_input_layout,
    parameter_values,
)
from lightcraft_opt.options import PulseMapOptions
from lightcraft_opt.params import Model
from lightcraft_opt.simulate import nominal_inputs
from lightcraft_opt.symbolic.error_state import ERROR_STATE, build_error_state
from lightcraft_opt.symbolic.pulse_map import PulseMap, build_pulse_map

__all__ = [
    "REDUCED_STATES",
    "Controllability",
    "Coordinates",
    "LqrResult",
    "ModeKind",
    "Multipliers",
    "OperatingPoint",
    "PointStatus",
    "PulseMapJacobian",
    "StabilityMap",
    "beam_riding_modes",
    "climb_point",
    "controllability",
    "error_state",
    "linearize",
    "lqr",
    "lqr_policy",
    "multipliers",
    "pulse_map_jacobian",
    "stability_map",
    "trim_hover",
]

#: Error-state entries kept by default: the beam-riding and vertical channels.
REDUCED_STATES = ("r_L", "v_L", "theta_B[b2]", "theta_B[b3]", "w_B[b2]", "w_B[b3]")


class Coordinates(Enum):
    """The states a linear model is written in."""

    FULL = "full"  # layout STATE, quaternion components as they are
    ERROR_STATE = "error_state"  # symbolic/error_state.ERROR_STATE, minimal attitude


class PointStatus(Enum):
    """What an operating point is."""

    TRIMMED = "trimmed"  # z and v_z repeat pulse to pulse
    TRAJECTORY = "trajectory"  # a point of a flight, not a fixed point
    NO_TRIM = "no_trim"  # the laser cannot hold the craft there
    NOT_CONVERGED = "not_converged"  # Newton stopped without meeting the tolerance


class ModeKind(Enum):
    """Which states a pulse-to-pulse mode loads (participation factors)."""

    BEAM_RIDING = "beam_riding"  # lateral offset, lateral velocity, tilt
    CONING = "coning"  # transverse angular velocity w_B[b2, b3] (nutation)
    VERTICAL = "vertical"  # altitude and vertical speed
    AXIAL = "axial"  # spin, turn about b1 and its gauge w_B[b1]
    CONSUMABLE = "consumable"  # liner_mass, rcs_mass, pulses


_KIND_OF_SLOT = {
    "r_L": ModeKind.BEAM_RIDING,
    "v_L": ModeKind.BEAM_RIDING,
    "theta_B": ModeKind.BEAM_RIDING,
    "q_LB": ModeKind.BEAM_RIDING,
    "w_B": ModeKind.CONING,
    "spin": ModeKind.AXIAL,
    "liner_mass": ModeKind.CONSUMABLE,
    "rcs_mass": ModeKind.CONSUMABLE,
    "pulses": ModeKind.CONSUMABLE,
}


def _kind_of(name: str) -> ModeKind:
    slot, _, comp = name.partition("[")
    if slot not in _KIND_OF_SLOT:
        raise ParameterError("sys", f"state {name!r} is not a state of linearize()'s models")
    if comp.startswith("up") and slot in ("r_L", "v_L"):
        return ModeKind.VERTICAL
    if comp.startswith("b1") and slot in ("theta_B", "w_B"):
        return ModeKind.AXIAL
    return _KIND_OF_SLOT[slot]


def _names(layout: VectorLayout) -> list[str]:
    """``slot[component]`` per entry (``slot`` for scalars): the signal names."""
    out: list[str] = []
    for s in layout.slots:
        comps = s.components or tuple(str(i) for i in range(s.size))
        out.extend([s.name] if s.size == 1 else [f"{s.name}[{c}]" for c in comps])
    return out


def _select(layout: VectorLayout, wanted: Sequence[str] | None, what: str) -> list[int]:
    """Indices of ``wanted`` entries (slot names or ``slot[component]``) in ``layout``."""
    names = _names(layout)
    if wanted is None:
        return list(range(layout.size))
    out: list[int] = []
    for w in wanted:
        if w in layout:
            out.extend(range(layout.slot(w).start, layout.slot(w).stop))
        elif w in names:
            out.append(names.index(w))
        else:
            raise ParameterError(what, f"no entry {w!r}; the {layout.name} holds {names}")
    if len(set(out)) != len(out):
        raise ParameterError(what, f"lists an entry twice: {list(wanted)}")
    return out


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
    """Φ's value and Jacobians in one casadi.Function (a few seconds to build at the
    default 32 substeps: build once, pass it as ``pulse_map`` to the functions here)."""
    f = pulse_map.step.factory(
        "pulse_map_jacobian",
        ["x", "u", "p", "t"],
        ["x_next", "jac:x_next:x", "jac:x_next:u"],
    )
    return PulseMapJacobian(pulse_map, f)


def _jacobian(
    model: Model, pulse_map: PulseMap | PulseMapJacobian | None, options: PulseMapOptions | None
) -> PulseMapJacobian:
    if isinstance(pulse_map, PulseMapJacobian):
        return pulse_map
    return pulse_map_jacobian(pulse_map or build_pulse_map(model, options))


@functools.cache
def _chart() -> tuple[ca.Function, ca.Function, ca.Function]:
    """(local, ∂retract/∂δ, ∂local/∂x) of the error-state chart, built on first use."""
    retract, local = build_error_state()
    return (
        local,
        retract.factory("retract_jacobian", ["x_op", "dx"], ["jac:x:dx"]),
        local.factory("local_jacobian", ["x_op", "x"], ["jac:dx:x"]),
    )


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
    dx = np.asarray(_chart()[0](x_op, checked_vector("x", x, STATE.size))).ravel()
    return dx[_select(ERROR_STATE, states, "states")]


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
    """

    x: np.ndarray
    u: np.ndarray
    p: np.ndarray
    t: float
    x_next: np.ndarray
    status: PointStatus
    message: str = ""
    iterations: int = 0

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


def climb_point(
    model: Model,
    altitude: float,
    speed: float,
    *,
    offset_L: Sequence[float] = (0.0, 0.0),
    spin: float | None = None,
    energy: float | None = None,
    t: float = 0.0,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
) -> OperatingPoint:
    """A point of a climb in the beam: NOT a fixed point of Φ.

    The craft upright at ``altitude`` [m] above the pad, moving up at ``speed`` [m/s]
    just before the pulse, ``offset_L`` (east, north) [m] from the beam axis (the beam
    on the pad axis), spinning at ``spin`` [rad/s] (default the craft's), under the
    nominal inputs with pulse ``energy`` [J] (default the flight's). Since Φ(x) ≠ x,
    the linearisation here is one step of a time-varying model (status ``TRAJECTORY``).
    """
    x = initial_state(
        model,
        r_L=(*checked_vector("offset_L", offset_L, 2), altitude),
        v_L=(0.0, 0.0, speed),
        spin=spin,
    )
    u = nominal_inputs(model)
    if energy is not None:
        u[_ENERGY] = energy
    p = parameter_values(model)
    if isinstance(pulse_map, PulseMapJacobian):
        pulse_map = pulse_map.pulse_map
    phi = pulse_map or build_pulse_map(model, options)
    x_next = np.asarray(phi.step(x, u, p, t)[0]).ravel()
    return OperatingPoint(x, u, p, t, x_next, PointStatus.TRAJECTORY, "a climb, not a fixed point")


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
    jac = _jacobian(model, pulse_map, options)
    e_max = model.laser.pulse_energy_max if max_energy is None else max_energy
    period = jac.pulse_map.period
    x = initial_state(model, r_L=(0.0, 0.0, altitude), spin=spin)
    u = nominal_inputs(model)
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
            return OperatingPoint(x, u, p, t, x_next, status, msg, k)
        if k == max_iter:
            break
        J = np.array(
            [[A[iz, iv], B[iz, _ENERGY]], [(A[iv, iv] - 1) * period, B[iv, _ENERGY] * period]]
        )
        if abs(B[iv, _ENERGY]) * e_max < 1e-9 * g_guess * period:
            msg = f"the optic catches no energy at {altitude:g} m: no pulse can hold the craft"
            return OperatingPoint(x, u, p, t, x_next, PointStatus.NO_TRIM, msg, k)
        step = np.linalg.solve(J, -r)
        x[iv] += step[0]
        u[_ENERGY] += step[1]
        if u[_ENERGY] > 4 * e_max:
            msg = f"hover needs more than {4 * e_max:.4g} J a pulse (the laser gives {e_max:.4g})"
            return OperatingPoint(x, u, p, t, x_next, PointStatus.NO_TRIM, msg, k + 1)
    msg = f"Newton stopped after {max_iter} iterations, residual {r}"
    return OperatingPoint(x, u, p, t, x_next, PointStatus.NOT_CONVERGED, msg, max_iter)


# --------------------------------------------------------------------------- linear model
def linearize(
    model: Model,
    point: OperatingPoint,
    *,
    coordinates: Coordinates = Coordinates.ERROR_STATE,
    states: Sequence[str] | None = None,
    inputs: Sequence[str] | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
) -> control.StateSpace:
    """Φ linearised about ``point``: ``δ[k+1] = A δ[k] + B δu[k]``, dt = pulse period.

    Parameters
    ----------
    model : the model Φ was (or is to be) built for.
    point : operating point (:func:`trim_hover`, :func:`climb_point`).
    coordinates : ``ERROR_STATE`` (minimal coordinates about the point, module
        docstring) or ``FULL`` (A = ∂Φ/∂x on the 17 raw states).
    states : entries kept, as slot names or ``slot[component]`` (default
        :data:`REDUCED_STATES` for the error state, every state for ``FULL``). A
        truncation: the others are held at zero, and their effect is dropped.
    inputs : map-input entries kept (default all: pointing_L [m], focus [m], energy [J],
        rcs_thrust [N] per thruster, motor_torque [N m] with a carrier).
    pulse_map : Φ, or better its :func:`pulse_map_jacobian` to reuse across points.

    Returns
    -------
    control.StateSpace with A (n, n), B (n, m), C = I, D = 0, ``dt`` the pulse period
    [s]; state and output names ``r_L[east]``, ``theta_B[b2]``, ... (units: those of
    the layouts, SI), input names ``pointing_L[east]``, ``energy``, ...
    """
    jac = _jacobian(model, pulse_map, options)
    craft = model.craft
    ulay = map_input_layout(len(craft.rcs.thrusters) if craft.rcs else 0, craft.has_carrier)
    if ulay.size != point.u.size:
        raise ParameterError("point.u", f"needs {ulay.size} map inputs, got {point.u.size}")
    x_next, A, B = jac(point.x, point.u, point.p, point.t)
    wanted: Sequence[str] | None
    if coordinates is Coordinates.ERROR_STATE:
        _, retract_jac, local_jac = _chart()
        E = np.asarray(retract_jac(point.x, np.zeros(ERROR_STATE.size)))
        L = np.asarray(local_jac(x_next, x_next))
        A, B = L @ A @ E, L @ B
        layout = ERROR_STATE
        wanted = REDUCED_STATES if states is None else states
    elif coordinates is Coordinates.FULL:
        layout, wanted = STATE, states
    else:
        allowed = [c.value for c in Coordinates]
        raise ParameterError("coordinates", f"must be one of {allowed}, got {coordinates!r}")
    keep = _select(layout, wanted, "states")
    ukeep = _select(ulay, inputs, "inputs")
    names = [_names(layout)[i] for i in keep]
    A_k, B_k = A[np.ix_(keep, keep)], B[np.ix_(keep, ukeep)]
    return control.ss(
        A_k,
        B_k,
        np.eye(len(keep)),
        np.zeros((len(keep), len(ukeep))),
        jac.pulse_map.period,
        states=names,
        outputs=names,
        inputs=[_names(ulay)[i] for i in ukeep],
        name=f"{model.name} pulse map ({coordinates.value})",
    )


# --------------------------------------------------------------------------- modes
@dataclass(frozen=True)
class Multipliers:
    """Pulse-to-pulse multipliers (eigenvalues of A) and what each mode loads.

    Attributes
    ----------
    values : (n,) complex multipliers, largest |λ| first.
    participation : (n, n_states) participation factors |l_ki r_ki| of mode i in state
        k, each row summing to 1 (dimensionless, independent of the state units).
    kinds : (n,) the kind of each mode: the state group with the largest share.
    states : names of the states (columns of ``participation``).
    dt : pulse period [s].
    """

    values: np.ndarray
    participation: np.ndarray
    kinds: tuple[ModeKind, ...]
    states: tuple[str, ...]
    dt: float

    @property
    def magnitude(self) -> np.ndarray:
        """(n,) |λ|: growth factor per pulse [-]."""
        return np.abs(self.values)

    @property
    def growth_rate(self) -> np.ndarray:
        """(n,) ln|λ| / T: growth rate [1/s] (negative: decays)."""
        with np.errstate(divide="ignore"):
            return np.log(self.magnitude) / self.dt

    @property
    def angle(self) -> np.ndarray:
        """(n,) arg λ [rad per pulse]: a mode at ω appears at ω T, aliased into (-π, π]."""
        return np.angle(self.values)

    def of_kind(self, *kinds: ModeKind) -> Multipliers:
        """The modes of the given kinds only."""
        sel = [i for i, k in enumerate(self.kinds) if k in kinds]
        return Multipliers(
            self.values[sel],
            self.participation[sel],
            tuple(self.kinds[i] for i in sel),
            self.states,
            self.dt,
        )

    def largest(self) -> float:
        """max |λ| (NaN when there is no mode)."""
        return float(np.max(self.magnitude)) if self.values.size else float("nan")


def _matrices(sys: control.StateSpace) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)


def multipliers(sys: control.StateSpace) -> Multipliers:
    """Eigenvalues of ``sys.A`` with participation factors and a kind per mode.

    ``sys`` is a model from :func:`linearize` (its state names say which kind each state
    is). For a defective A (repeated neutral multipliers, e.g. the consumables of a
    ``FULL`` model), where left eigenvectors are ill-defined, the participation falls
    back to |r_ki|^2 of the unit right eigenvector.
    """
    A, _ = _matrices(sys)
    values, V = np.linalg.eig(A)
    order = np.argsort(-np.abs(values), kind="stable")
    values, V = values[order], V[:, order]
    W = np.linalg.inv(V) if np.linalg.cond(V) < 1e10 else None
    P = np.abs(V * W.T) if W is not None else np.abs(V) ** 2
    P = P / np.maximum(P.sum(axis=0), np.finfo(float).tiny)
    states = tuple(sys.state_labels)
    kinds_of_state = [_kind_of(s) for s in states]
    kinds: list[ModeKind] = []
    for i in range(values.size):
        share = {
            k: P[[j for j, ks in enumerate(kinds_of_state) if ks is k], i].sum() for k in ModeKind
        }
        kinds.append(max(share, key=lambda k: share[k]))
    return Multipliers(values, P.T.copy(), tuple(kinds), states, float(sys.dt))


def beam_riding_modes(sys: control.StateSpace) -> Multipliers:
    """The multipliers of the modes that load lateral offset, lateral velocity and tilt
    (:attr:`ModeKind.BEAM_RIDING`), largest first."""
    return multipliers(sys).of_kind(ModeKind.BEAM_RIDING)


@dataclass(frozen=True)
class Controllability:
    """Which states the inputs of a discrete linear model reach.

    Attributes
    ----------
    rank : numerical rank of the controllability matrix [B, AB, ..., A^(n-1) B].
    singular_values : (n,) of that matrix, block columns scaled to unit norm.
    uncontrollable : (n, n - rank) orthonormal directions the inputs never reach.
    modes : the uncontrollable multipliers: eigenvalues of A on the uncontrollable
        directions (Kalman decomposition, A = [[A_c, *], [0, A_u]] in the basis
        [controllable, uncontrollable]).
    states : state names (rows of ``uncontrollable``).
    """

    rank: int
    singular_values: np.ndarray
    uncontrollable: np.ndarray
    modes: np.ndarray
    states: tuple[str, ...]

    @property
    def controllable(self) -> bool:
        return self.rank == len(self.states)

    @property
    def stabilisable(self) -> bool:
        """Every uncontrollable multiplier lies strictly inside the unit circle."""
        return bool(np.all(np.abs(self.modes) < 1.0))

    def describe(self) -> str:
        """The uncontrollable directions in words: largest state loadings of each."""
        parts = []
        for d in self.uncontrollable.T:
            top = np.argsort(-np.abs(d))[:3]
            parts.append(
                " + ".join(f"{d[j]:.2f} {self.states[j]}" for j in top if abs(d[j]) > 0.05)
            )
        return "; ".join(parts) or "none"


def controllability(sys: control.StateSpace, *, tol: float = 1e-9) -> Controllability:
    """Rank of the controllability matrix and the uncontrollable directions and modes.

    Parameters
    ----------
    tol : relative tolerance: a singular value below ``tol`` times the largest counts as
        zero.

    The numbers depend on the state units (SI here); the block columns A^k B are
    scaled to unit norm so that slowly growing powers do not swamp the rank test.
    Couplings weaker than ``tol`` count as none: e.g. pointing reaches the altitude of a
    hovering craft only through the Coriolis term 2 Ω × v of the lateral velocity it
    makes, ~1e-9 of its lateral reach, so at the default tolerance r_L[up], v_L[up] are
    uncontrollable without the energy input.
    """
    A, B = _matrices(sys)
    n = A.shape[0]
    blocks, Ak_B = [], B
    for _ in range(n):
        norm = np.linalg.norm(Ak_B)
        blocks.append(Ak_B / norm if norm > 0 else Ak_B)
        Ak_B = A @ Ak_B
    U, s, _ = np.linalg.svd(np.hstack(blocks))
    s = np.concatenate([s, np.zeros(max(0, n - s.size))])[:n]
    rank = int(np.sum(s > tol * s[0])) if s[0] > 0 else 0
    Uu = U[:, rank:]
    modes = np.linalg.eigvals(Uu.T @ A @ Uu) if rank < n else np.empty(0, complex)
    return Controllability(rank, s, Uu, modes.astype(complex), tuple(sys.state_labels))


@dataclass(frozen=True)
class LqrResult:
    """Discrete LQR about an operating point: δu = -K δ.

    Attributes
    ----------
    K : (m, n) gain [input units per state unit].
    S : (n, n) solution of the discrete Riccati equation.
    closed_loop : multipliers of A - B K.
    states, inputs : names of the columns and rows of K.
    """

    K: np.ndarray
    S: np.ndarray
    closed_loop: Multipliers
    states: tuple[str, ...]
    inputs: tuple[str, ...]


def _weight(name: str, w: np.ndarray | Sequence[float], n: int, definite: bool) -> np.ndarray:
    """(n, n) symmetric weight from a matrix or its diagonal; positive (semi)definite."""
    W = np.asarray(w, dtype=float)
    if W.ndim == 1:
        W = np.diag(W)
    if W.shape != (n, n) or not np.all(np.isfinite(W)):
        raise ParameterError(name, f"must be a finite ({n}, {n}) matrix or {n} diagonal entries")
    if not np.allclose(W, W.T, rtol=1e-12, atol=0.0):
        raise ParameterError(name, "must be symmetric")
    low = float(np.min(np.linalg.eigvalsh(W)))
    if low < 0.0 or (definite and low <= 0.0):
        kind = "definite" if definite else "semidefinite"
        raise ParameterError(name, f"must be positive {kind}; smallest eigenvalue {low:.3g}")
    return W


def lqr(
    sys: control.StateSpace,
    Q: np.ndarray | Sequence[float],
    R: np.ndarray | Sequence[float],
) -> LqrResult:
    """Discrete LQR (``control.dlqr``): minimise Σ δ'Qδ + δu'Rδu over pulses.

    Parameters
    ----------
    Q : (n, n) state weight, or its n diagonal entries (per squared state unit),
        symmetric positive semidefinite.
    R : (m, m) input weight, or its m diagonal entries (per squared input unit),
        symmetric positive definite.

    Raises
    ------
    ParameterError naming the multipliers and states the inputs cannot reach when
    (A, B) is not stabilisable (e.g. a neutral consumable or the gauge w_B[b1] kept in
    the states), when a weight has the wrong shape or sign, or when control.dlqr fails.
    """
    A, B = _matrices(sys)
    n, m = B.shape
    Qm, Rm = _weight("Q", Q, n, definite=False), _weight("R", R, m, definite=True)
    c = controllability(sys)
    if not c.stabilisable:
        lam = ", ".join(f"{v:.6g}" for v in c.modes if abs(v) >= 1.0)
        raise ParameterError(
            "sys",
            f"(A, B) is not stabilisable: the multipliers {lam} lie on or outside the unit "
            f"circle and no input reaches them (directions: {c.describe()}); keep fewer "
            "states (linearize(states=...)) or add inputs",
        )
    try:
        K, S, _ = control.dlqr(A, B, Qm, Rm)
    except (ValueError, np.linalg.LinAlgError, control.ControlArgument) as err:
        raise ParameterError("Q, R", f"control.dlqr failed: {err}") from err
    closed = control.ss(A - B @ K, B, sys.C, sys.D, sys.dt, states=list(sys.state_labels))
    return LqrResult(
        np.asarray(K),
        np.asarray(S),
        multipliers(closed),
        tuple(sys.state_labels),
        tuple(sys.input_labels),
    )


def lqr_policy(
    model: Model, point: OperatingPoint, gains: LqrResult
) -> Callable[[int, float, np.ndarray], np.ndarray]:
    """The state feedback ``u = u_op - K (x ⊖ x_op)`` as a per-pulse input policy
    ``(k, t, x) -> u`` for :func:`lightcraft_opt.simulate` (the inputs left out of the
    linear model stay at the point's values)."""
    craft = model.craft
    ulay = map_input_layout(len(craft.rcs.thrusters) if craft.rcs else 0, craft.has_carrier)
    iu = _select(ulay, gains.inputs, "gains.inputs")
    states = gains.states

    def policy(k: int, t: float, x: np.ndarray) -> np.ndarray:
        u = point.u.copy()
        u[iu] -= gains.K @ error_state(point, x, states)
        return u

    return policy


# --------------------------------------------------------------------------- stability map
@dataclass(frozen=True)
class StabilityMap:
    """Largest pulse-to-pulse multipliers over a grid of spin rate and beam offset.

    Each cell linearises Φ (reduced error state) about a climb point (:func:`climb_point`:
    ``altitude``, ``speed``, pulse ``energy``) with the craft ``offsets[j]`` east of the
    beam axis, spinning at ``spins[i]``.

    Attributes
    ----------
    spins : (ns,) rotor spin rate relative to B [rad/s].
    offsets : (no,) craft offset from the beam axis, east [m].
    beam_riding : (ns, no) max |λ| of the beam-riding modes [-].
    coning : (ns, no) max |λ| of the coning modes [-] (NaN where no mode is mostly
        transverse rate: slowly spinning, tilt and rate modes merge).
    altitude, speed, energy : of the climb point [m], [m/s], [J].
    model_name : which model.
    """

    spins: np.ndarray
    offsets: np.ndarray
    beam_riding: np.ndarray
    coning: np.ndarray
    altitude: float
    speed: float
    energy: float
    model_name: str

    @property
    def lateral(self) -> np.ndarray:
        """(ns, no) max |λ| over beam-riding and coning modes: > 1 leaves the beam."""
        return np.fmax(self.beam_riding, self.coning)


def stability_map(
    model: Model,
    spins: Sequence[float] | np.ndarray,
    offsets: Sequence[float] | np.ndarray,
    *,
    altitude: float = 2.0,
    speed: float = 5.0,
    energy: float | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> StabilityMap:
    """Beam-riding multipliers over spin rate [rad/s] × beam offset [m] (east).

    One Jacobian of Φ per cell (milliseconds at 8 substeps, ~0.1 s at 32, after the
    Jacobian Function is built once). ``progress(done, total)`` is called after each cell.
    """
    jac = _jacobian(model, pulse_map, options)
    s = np.asarray(spins, dtype=float).ravel()
    d = np.asarray(offsets, dtype=float).ravel()
    e = model.flight.pulse_energy if energy is None else energy
    riding = np.empty((s.size, d.size))
    coning = np.empty((s.size, d.size))
    for i, spin in enumerate(s):
        for j, off in enumerate(d):
            pt = climb_point(
                model, altitude, speed, offset_L=(off, 0.0), spin=spin, energy=e, pulse_map=jac
            )
            modes = multipliers(linearize(model, pt, pulse_map=jac))
            riding[i, j] = modes.of_kind(ModeKind.BEAM_RIDING).largest()
            coning[i, j] = modes.of_kind(ModeKind.CONING).largest()
            if progress is not None:
                progress(i * d.size + j + 1, s.size * d.size)
    return StabilityMap(s, d, riding, coning, altitude, speed, e, model.name)
