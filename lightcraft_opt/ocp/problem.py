"""What an optimal control problem of a lightcraft flight asks for (docs/architecture.md#rule-2).

A problem states the model, the horizon in pulses, the per-pulse controls with their bounds
and slew-rate limits, the path and terminal constraints and a weighted sum of objective
terms; how it is transcribed and solved (:mod:`lightcraft_opt.ocp.transcription`,
:mod:`lightcraft_opt.ocp.solve`, :class:`~lightcraft_opt.ocp.options.OcpOptions`) is chosen
separately. Everything is plain numpy and validated on creation: a bad value raises
:class:`~lightcraft_opt.errors.ParameterError` naming the field.

Nodes and pulses (docs/frames.md for frames and the state): node k is the state x_k just
before pulse k at t_k = t0 + k T (T the pulse period), k = 0..N; pulse k (k = 0..N-1)
fires the map input u_k (layout :func:`~lightcraft_opt.layout.map_input_layout`:
``pointing_L`` (2) [m, L east/north], ``focus`` [m], ``energy`` [J], then the RCS thrust
[N] over the interval and ``motor_torque`` [N m] with a carrier), and the map Φ carries
x_k to x_{k+1}. x_0 is given; node terms and constraints apply at k = 1..N, pulse terms
and constraints at k = 0..N-1.

How the RCS thrust varies over a pulse interval is part of what the problem asks
(``rcs_profile``, ``rcs_subintervals``; :class:`~lightcraft_opt.layout.RcsProfile`): it
fixes the decision variables. ``HOLD``: one level per thruster; ``SUBINTERVALS``: one per
thruster and sub-interval; ``PHASE_LOCKED``: mean levels ``rcs_thrust`` with cosine and
sine amplitudes ``rcs_cos``, ``rcs_sin`` at the coning rate. Φ does not clip the thrust:
levels are bounded to [0, max_thrust] and, for PHASE_LOCKED, :class:`RcsEnvelope` keeps
the thrust in [0, max_thrust] at every phase.

Model parameters and wind are inputs: ``parameters`` overrides entries of the parameter
vector p (:data:`~lightcraft_opt.layout.PARAMETERS`) by name, e.g.
``{"wind_speed_ref": 4.0, "wind_direction_from": math.pi / 2}`` for a 4 m/s wind from the
east at the reference height.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from enum import Enum
from typing import Any

import numpy as np

from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.layout import (
    STATE,
    RcsProfile,
    VectorLayout,
    initial_state,
    map_input_layout,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import BeamSizeModel, Model
from lightcraft_opt.model.checks import checked_vector, number, numbers, set_frozen
from lightcraft_opt.ocp.design import DesignLayout, DesignVariable
from lightcraft_opt.ocp.hardware import HardwareLimits, hardware_limits
from lightcraft_opt.ocp.horizon import MAX_HORIZON, check_horizon
from lightcraft_opt.ocp.scenarios import Scenarios, check_scenarios
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

__all__ = [
    "MAX_HORIZON",
    "Constraint",
    "ControlBound",
    "ControlEffort",
    "ControlRate",
    "DesignVariable",
    "EnergyBudget",
    "FinalAltitude",
    "LaserEnergy",
    "LateralOffset",
    "NoGroundContact",
    "ObjectiveTerm",
    "OcpProblem",
    "OffsetFrom",
    "OffsetLimit",
    "RcsEnvelope",
    "TerminalAltitude",
    "TerminalState",
    "TiltLimit",
    "TrackReference",
    "check_horizon",
]

Values = float | Sequence[float]


# --------------------------------------------------------------------------- objective terms
class OffsetFrom(Enum):
    """What a lateral offset is measured from."""

    PAD = "pad"  # the craft's mass centre from the pad's vertical: r_L east/north at nodes
    BEAM = "beam"  # the optic centre from the beam axis at each pulse (engine offset_L)


@dataclass(frozen=True)
class LaserEnergy:
    """Laser energy fired: ``weight * sum_k E_k`` (E_k the pulse energies [J]).

    weight : [1/J], >= 0.
    """

    weight: float = 1.0

    def __post_init__(self) -> None:
        set_frozen(self, "weight", number("LaserEnergy.weight", self.weight, low=0.0))


@dataclass(frozen=True)
class FinalAltitude:
    """Altitude reached, rewarded: ``-weight * r_L[up](t_N)`` [m] (maximise it).

    weight : [1/m], >= 0.
    """

    weight: float = 1.0

    def __post_init__(self) -> None:
        set_frozen(self, "weight", number("FinalAltitude.weight", self.weight, low=0.0))


@dataclass(frozen=True, eq=False)
class TrackReference:
    """Follow a reference: ``sum_{k=1..N} sum_i weights_i (slot(x_k)_i - path[k, i])^2``.

    path : (N + 1, slot size) reference at the nodes, in the slot's unit and frame (for the
        default ``r_L``: positions [m], L frame); row 0 (the given x_0) is not used.
    weights : one per component or one for all, >= 0 [1/unit^2].
    slot : a state slot (:data:`~lightcraft_opt.layout.STATE`), default ``r_L``.

    The path is a run-time input of a compiled solver: a new reference needs no rebuild.
    """

    path: np.ndarray
    weights: Values = 1.0
    slot: str = "r_L"

    def __post_init__(self) -> None:
        size = STATE.slot(self.slot).size
        try:
            path = np.array(self.path, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError("TrackReference.path", "must be an array of numbers") from None
        if path.ndim == 1 and size == 1:
            path = path[:, None]
        if path.ndim != 2 or path.shape[1] != size:
            raise ParameterError(
                "TrackReference.path", f"must have shape (N + 1, {size}), got {path.shape}"
            )
        if not np.all(np.isfinite(path)):
            raise ParameterError("TrackReference.path", "must be finite (got NaN or inf)")
        path.setflags(write=False)
        set_frozen(self, "path", path)
        w = numbers("TrackReference.weights", self.weights, size)
        if np.any(w < 0):
            raise ParameterError("TrackReference.weights", "must not be negative")
        set_frozen(self, "weights", tuple(float(v) for v in w))


@dataclass(frozen=True)
class LateralOffset:
    """Stay near the vertical: ``weight * sum |d_k|^2`` [m^2], d the east/north offset.

    weight : [1/m^2], >= 0.
    relative_to : ``PAD`` (the mass centre's drift from the pad's vertical, nodes 1..N; a
        crosswind pushes it) or ``BEAM`` (the optic centre from the beam axis at each pulse).
    """

    weight: float = 1.0
    relative_to: OffsetFrom = OffsetFrom.PAD

    def __post_init__(self) -> None:
        set_frozen(self, "weight", number("LateralOffset.weight", self.weight, low=0.0))
        if not isinstance(self.relative_to, OffsetFrom):
            raise ParameterError(
                "LateralOffset.relative_to",
                f"must be one of {[o.value for o in OffsetFrom]}, got {self.relative_to!r}",
            )


@dataclass(frozen=True)
class ControlEffort:
    """Control effort: ``weight * sum_k |u_k[slot] - reference|^2`` (slot units squared).

    slot : a map-input slot (``pointing_L``, ``focus``, ``energy``, ``rcs_thrust``,
        ``motor_torque``); reference : one value or one per component, in the slot's unit.
    """

    slot: str
    weight: float = 1.0
    reference: Values = 0.0

    def __post_init__(self) -> None:
        set_frozen(self, "weight", number("ControlEffort.weight", self.weight, low=0.0))
        ref = np.atleast_1d(np.asarray(self.reference, dtype=float)).reshape(-1)
        if not np.all(np.isfinite(ref)):
            raise ParameterError("ControlEffort.reference", "must be finite")
        set_frozen(self, "reference", tuple(ref.tolist()))


@dataclass(frozen=True)
class ControlRate:
    """Smooth controls: ``weight * sum_k |(u_k[slot] - u_{k-1}[slot]) / T|^2``, rates in the
    slot's unit per second (from ``u_previous`` at k = 0 when the problem gives it)."""

    slot: str
    weight: float = 1.0

    def __post_init__(self) -> None:
        set_frozen(self, "weight", number("ControlRate.weight", self.weight, low=0.0))


ObjectiveTerm = (
    LaserEnergy | FinalAltitude | TrackReference | LateralOffset | ControlEffort | ControlRate
)
OBJECTIVE_KINDS = (
    LaserEnergy,
    FinalAltitude,
    TrackReference,
    LateralOffset,
    ControlEffort,
    ControlRate,
)


# --------------------------------------------------------------------------- constraints
@dataclass(frozen=True)
class ControlBound:
    """Bounds of one map-input slot, one value or one per component, in the slot's unit.

    lower, upper : lower <= u_k[slot] <= upper at every pulse (equal: held at that value,
        not a decision variable); +-inf for no bound of its own (the hardware's); None (the
        default) keeps the model's limit below, so a ControlBound that sets only a slew
        rate stays within the laser. A bound beyond what the hardware can do
        (:meth:`OcpProblem.hardware_limits`) is refused with a
        :class:`~lightcraft_opt.errors.HardwareLimitError` naming the limit.
    slew_rate : |u_k - u_{k-1}| / T <= slew_rate [unit/s], > 0; inf for none (from
        ``u_previous`` at k = 0 when the problem gives it).

    A slot without a ControlBound keeps the model's limits: pointing within
    +-``laser.pointing_limit``, focus within ``laser.focus_range`` (held at its far end for
    a LINEAR beam, where it has no effect), energy within [0, ``laser.pulse_energy_max``],
    each RCS level (``rcs_thrust``: held, per sub-interval, or the phase-locked mean)
    within [0, its thruster's ``max_thrust``], the phase-locked amplitudes ``rcs_cos`` and
    ``rcs_sin`` within +-``max_thrust`` / 2, the motor torque held at 0 (the model gives it
    no limit, so bounds of any size are taken).
    """

    slot: str
    lower: Values | None = None
    upper: Values | None = None
    slew_rate: Values = math.inf


@dataclass(frozen=True)
class OffsetLimit:
    """Keep the beam on the optic: at every pulse the optic centre's offset from the beam
    axis, over the capture radius, stays within a bound: |offset_L| / R_c <=
    ``max_offset_over_capture_radius`` (the ``offset_over_capture_radius`` column of
    solution.csv; not the captured energy fraction, docs/outputs.md).

    max_offset_over_capture_radius : (0, 1].
    """

    max_offset_over_capture_radius: float

    def __post_init__(self) -> None:
        name = "OffsetLimit.max_offset_over_capture_radius"
        v = number(name, self.max_offset_over_capture_radius)
        if not 0 < v <= 1:
            raise ParameterError(name, f"must lie in (0, 1], got {v!r}")
        set_frozen(self, "max_offset_over_capture_radius", v)


@dataclass(frozen=True)
class TiltLimit:
    """Angle between the craft axis b1 and L up at nodes 1..N at most ``max_tilt`` [rad],
    in (0, pi)."""

    max_tilt: float

    def __post_init__(self) -> None:
        v = number("TiltLimit.max_tilt", self.max_tilt)
        if not 0 < v < math.pi:
            raise ParameterError("TiltLimit.max_tilt", f"must lie in (0, pi) rad, got {v!r}")
        set_frozen(self, "max_tilt", v)


@dataclass(frozen=True)
class NoGroundContact:
    """Mass centre at least ``clearance`` [m] above the pad (r_L[up]) at nodes 1..N (not
    checked between pulses)."""

    clearance: float = 0.0

    def __post_init__(self) -> None:
        set_frozen(self, "clearance", number("NoGroundContact.clearance", self.clearance))


@dataclass(frozen=True)
class TerminalAltitude:
    """``minimum <= r_L[up](t_N) <= maximum`` [m]; equal values pin it."""

    minimum: float = -math.inf
    maximum: float = math.inf

    def __post_init__(self) -> None:
        lo = number("TerminalAltitude.minimum", self.minimum, allow_inf=True)
        hi = number("TerminalAltitude.maximum", self.maximum, allow_inf=True)
        if lo > hi:
            raise ParameterError("TerminalAltitude.minimum", f"{lo} exceeds maximum {hi}")
        set_frozen(self, "minimum", lo)
        set_frozen(self, "maximum", hi)


@dataclass(frozen=True)
class TerminalState:
    """``lower <= x_N[slot] <= upper`` for a state slot, in its unit and frame."""

    slot: str
    lower: Values = -math.inf
    upper: Values = math.inf

    def __post_init__(self) -> None:
        if self.slot not in STATE:
            raise ParameterError(
                "TerminalState.slot", f"no such state {self.slot!r}; states: {list(STATE.names)}"
            )
        size = STATE.slot(self.slot).size
        lo = numbers("TerminalState.lower", self.lower, size, allow_inf=True)
        hi = numbers("TerminalState.upper", self.upper, size, allow_inf=True)
        if np.any(lo > hi):
            raise ParameterError("TerminalState.lower", f"{lo} exceeds upper {hi}")
        set_frozen(self, "lower", tuple(lo.tolist()))
        set_frozen(self, "upper", tuple(hi.tolist()))


@dataclass(frozen=True)
class EnergyBudget:
    """The laser fires at most ``total`` [J] over the horizon (>= 0)."""

    total: float

    def __post_init__(self) -> None:
        set_frozen(self, "total", number("EnergyBudget.total", self.total, low=0.0))


@dataclass(frozen=True)
class RcsEnvelope:
    """Every RCS thruster within [0, its ``max_thrust``] at every instant of every pulse
    interval, not only its levels.

    For ``PHASE_LOCKED`` (thrust_i(τ) = mean_i + cos_i cos(ω τ) + sin_i sin(ω τ)) this is
    sqrt(cos_i^2 + sin_i^2) <= min(mean_i, max_i - mean_i), posed per pulse and thruster
    in the smooth form (cos_i^2 + sin_i^2) / max_i^2 <= (mean_i / max_i)^2 and
    <= ((max_i - mean_i) / max_i)^2, with the mean within [0, max_i] by its bounds. For
    ``HOLD`` and ``SUBINTERVALS`` the bounds of the levels already say it. In every case
    the problem checks that the ``rcs_thrust`` bounds lie within [0, max_thrust].
    """


Constraint = (
    OffsetLimit
    | TiltLimit
    | NoGroundContact
    | TerminalAltitude
    | TerminalState
    | EnergyBudget
    | RcsEnvelope
)
CONSTRAINT_KINDS = (
    OffsetLimit,
    TiltLimit,
    NoGroundContact,
    TerminalAltitude,
    TerminalState,
    EnergyBudget,
    RcsEnvelope,
)


# --------------------------------------------------------------------------- the problem
@dataclass(frozen=True, eq=False)
class OcpProblem:
    """An optimal control problem over ``horizon`` pulses of ``model`` (module docstring).

    Attributes
    ----------
    model : craft, laser, site, flight, environment (structure of Φ).
    horizon : N, pulses, >= 1.
    objective : terms summed into the cost (at least one).
    constraints : path and terminal constraints.
    controls : one :class:`ControlBound` per slot to change the model's limits.
    x0 : (STATE.size,) state at t0 (default: on the pad, upright, spinning); validated
        into a read-only array on construction.
    parameters : {PARAMETERS slot: value} overriding the model's p (wind, aerodynamics ...).
    t0 : time of the first pulse [s] (gusts depend on time).
    u_previous : (map-input size,) input of the pulse before t0 (a read-only array once
        validated), for slew limits and
        control rates at k = 0 (default: none, pulse 0 is free of them).
    rcs_profile : how the RCS thrust varies over a pulse interval (module docstring); a
        profile other than HOLD needs a craft with an RCS.
    rcs_subintervals : sub-intervals of ``SUBINTERVALS`` (1 for the other profiles); the
        pulse map's substeps must be a multiple (checked when Φ is built).
    design : entries of p (and the launch spin) the optimiser chooses with the inputs
        (:class:`~lightcraft_opt.ocp.design.DesignVariable`, docs/design.md); their values
        in ``parameters``/``x0`` are where the design starts.
    scenarios : S cases of the flight sharing the design, each with its own inputs (or
        the first ``shared_pulses`` shared), and an expected or worst-case objective
        (:class:`~lightcraft_opt.ocp.scenarios.Scenarios`, docs/design.md#robust-design);
        None: the problem's own case alone.

    Derived (read-only): ``p`` (PARAMETERS.size,) parameter vector; ``inputs`` the
    map-input layout; ``lower``, ``upper``, ``slew`` (size of the map input,) bounds [unit]
    and slew limits per pulse [unit] (slew_rate T); ``free`` entries that are decision
    variables; ``period`` T [s]; ``design_layout`` where the design sits in p and x0.
    Default bounds of the RCS slots: each level
    (``rcs_thrust``, the mean for PHASE_LOCKED) in [0, max_thrust], ``rcs_cos`` and
    ``rcs_sin`` in [-max_thrust / 2, max_thrust / 2].
    """

    model: Model
    horizon: int
    objective: tuple[ObjectiveTerm, ...]
    constraints: tuple[Constraint, ...] = ()
    controls: tuple[ControlBound, ...] = ()
    x0: np.ndarray | Sequence[float] | None = None
    parameters: Mapping[str, Values] | None = None
    t0: float = 0.0
    u_previous: np.ndarray | Sequence[float] | None = None
    rcs_profile: RcsProfile = RcsProfile.HOLD
    rcs_subintervals: int = 1
    design: tuple[DesignVariable, ...] = ()
    scenarios: Scenarios | None = None
    p: np.ndarray = field(init=False, repr=False)
    inputs: VectorLayout = field(init=False, repr=False)
    lower: np.ndarray = field(init=False, repr=False)
    upper: np.ndarray = field(init=False, repr=False)
    slew: np.ndarray = field(init=False, repr=False)
    design_layout: DesignLayout = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.model, Model):
            raise ParameterError("model", f"must be a Model, got {type(self.model).__name__}")
        n = self.horizon
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ParameterError("horizon", f"must be an integer >= 1 (pulses), got {n!r}")
        check_horizon("horizon", int(n))
        set_frozen(self, "horizon", int(n))
        set_frozen(self, "inputs", self._input_layout())
        set_frozen(self, "objective", self._kinds("objective", self.objective, OBJECTIVE_KINDS))
        if not self.objective:
            raise ParameterError("objective", "needs at least one term")
        set_frozen(
            self, "constraints", self._kinds("constraints", self.constraints, CONSTRAINT_KINDS)
        )
        set_frozen(self, "controls", self._kinds("controls", self.controls, (ControlBound,)))
        set_frozen(self, "parameters", dict(self.parameters or {}))
        self._check_terms()
        x0 = initial_state(self.model) if self.x0 is None else self.x0
        set_frozen(self, "x0", checked_vector("x0", x0, STATE.size))
        set_frozen(self, "t0", number("t0", self.t0))
        if self.u_previous is not None:
            u_prev = checked_vector("u_previous", self.u_previous, self.inputs.size)
            set_frozen(self, "u_previous", u_prev)
        set_frozen(self, "p", self._parameter_vector())
        set_frozen(self, "design", self._kinds("design", self.design, (DesignVariable,)))
        set_frozen(self, "design_layout", DesignLayout(self.model, self.design))
        self._set_bounds()
        self._check_envelope()
        if self.scenarios is not None:
            energy_free = bool(np.any(self.free[self.inputs.index("energy")]))
            check_scenarios(self.scenarios, self.horizon, self.design_layout.p_index, energy_free)
        for name in ("x0", "p", "lower", "upper", "slew"):
            getattr(self, name).setflags(write=False)

    # ----------------------------------------------------------------- derived
    @property
    def period(self) -> float:
        """Pulse period T [s]."""
        return 1.0 / self.model.flight.pulse_rate

    @property
    def n_thrusters(self) -> int:
        """RCS thrusters of the craft (0 without an RCS)."""
        return self.model.craft.thruster_count

    def max_thrust(self) -> np.ndarray:
        """(n_thrusters,) each thruster's max_thrust [N]."""
        rcs = self.model.craft.rcs
        return np.array([t.max_thrust for t in rcs.thrusters] if rcs else [], dtype=float)

    def term_names(self) -> tuple[str, ...]:
        """A name per objective term, in order: the term's kind as a problem file names it
        (``lateral_offset``), its slot or reference in brackets (``control_effort[pointing_L]``,
        ``lateral_offset[beam]``), then ``#2`` ... for repeats. The names of
        ``OcpResult.cost_terms``."""
        names: list[str] = []
        for term in self.objective:
            name = re.sub(r"(?<!^)(?=[A-Z])", "_", type(term).__name__).lower()
            if isinstance(term, ControlEffort | ControlRate | TrackReference):
                name += f"[{term.slot}]"
            elif isinstance(term, LateralOffset):
                name += f"[{term.relative_to.value}]"
            repeat = sum(n == name or n.startswith(name + "#") for n in names)
            names.append(f"{name}#{repeat + 1}" if repeat else name)
        return tuple(names)

    def pulse_map_options(self, base: PulseMapOptions) -> PulseMapOptions:
        """``base`` (scheme, substeps, dense) with this problem's RCS profile: the options
        of the Φ this problem needs. Raises OptionError when ``base`` asks for another
        RCS profile, or when ``rcs_subintervals`` does not divide its substeps."""
        if (base.rcs_profile, base.rcs_subintervals) not in (
            (RcsProfile.HOLD, 1),
            (self.rcs_profile, self.rcs_subintervals),
        ):
            raise OptionError(
                f"PulseMapOptions.rcs_profile {base.rcs_profile.value!r} "
                f"(rcs_subintervals {base.rcs_subintervals}) differs from the problem's "
                f"{self.rcs_profile.value!r} ({self.rcs_subintervals}): the problem's "
                "rcs_profile decides (leave the pulse map's at 'hold')"
            )
        return replace(base, rcs_profile=self.rcs_profile, rcs_subintervals=self.rcs_subintervals)

    @property
    def free(self) -> np.ndarray:
        """(map-input size,) bool: entries that are decision variables (lower < upper)."""
        return self.lower < self.upper

    def nominal_input(self) -> np.ndarray:
        """The flight's own map input (beam on the pad axis, focus at the far end, the
        flight's pulse energy, RCS and motor off) clipped to the bounds."""
        return np.clip(nominal_inputs(self.model, self.inputs), self.lower, self.upper)

    def reference(self) -> np.ndarray:
        """(N + 1, size) path of the TrackReference terms side by side (size 0 if none)."""
        paths = [t.path for t in self.objective if isinstance(t, TrackReference)]
        return np.hstack(paths) if paths else np.zeros((self.horizon + 1, 0))

    # ----------------------------------------------------------------- checks
    def _input_layout(self) -> VectorLayout:
        """The map-input layout of the model and the RCS profile (checked here)."""
        craft = self.model.craft
        if not isinstance(self.rcs_profile, RcsProfile):
            raise ParameterError(
                "rcs_profile",
                f"must be one of {[r.value for r in RcsProfile]} (RcsProfile), "
                f"got {self.rcs_profile!r}",
            )
        m = self.rcs_subintervals
        if isinstance(m, bool) or not isinstance(m, int | np.integer) or m < 1:
            raise ParameterError("rcs_subintervals", f"must be a positive integer, got {m!r}")
        set_frozen(self, "rcs_subintervals", int(m))
        if m > 1 and self.rcs_profile is not RcsProfile.SUBINTERVALS:
            raise ParameterError(
                "rcs_subintervals",
                f"must be 1 unless rcs_profile is 'subintervals' (got {m} with "
                f"{self.rcs_profile.value!r})",
            )
        if self.rcs_profile is not RcsProfile.HOLD and not self.n_thrusters:
            raise ParameterError(
                "rcs_profile",
                f"{self.rcs_profile.value!r} needs a craft with an RCS; "
                f"{self.model.name!r} has none",
            )
        return map_input_layout(
            self.n_thrusters, craft.has_carrier, self.rcs_profile, self.rcs_subintervals
        )

    @staticmethod
    def _kinds(name: str, items: Any, kinds: tuple[type, ...]) -> tuple[Any, ...]:
        if isinstance(items, kinds):
            items = (items,)
        try:
            out = tuple(items)
        except TypeError:
            raise ParameterError(name, f"must be a sequence of terms, got {items!r}") from None
        allowed = [k.__name__ for k in kinds]
        for i, item in enumerate(out):
            if not isinstance(item, kinds):
                raise ParameterError(
                    f"{name}[{i}]", f"unknown kind {type(item).__name__}; allowed: {allowed}"
                )
        return out

    def _control_slot(self, name: str, slot: str) -> int:
        if slot not in self.inputs:
            raise ParameterError(name, f"no such input {slot!r}; inputs: {list(self.inputs.names)}")
        return self.inputs.slot(slot).size

    def _check_terms(self) -> None:
        n = self.horizon
        for i, term in enumerate(self.objective):
            where = f"objective[{i}]"
            if isinstance(term, ControlEffort):
                size = self._control_slot(f"{where}.slot", term.slot)
                if np.size(term.reference) not in (1, size):
                    raise ParameterError(
                        f"{where}.reference", f"needs 1 or {size} values, got {term.reference}"
                    )
            elif isinstance(term, ControlRate):
                self._control_slot(f"{where}.slot", term.slot)
            elif isinstance(term, TrackReference) and term.path.shape[0] != n + 1:
                raise ParameterError(
                    f"{where}.path", f"needs N + 1 = {n + 1} rows, got {term.path.shape[0]}"
                )

    def _parameter_vector(self) -> np.ndarray:
        return parameter_values(self.model, self.parameters)

    def hardware_limits(self) -> HardwareLimits:
        """What the laser and the thrusters can do, per map-input entry
        (:mod:`~lightcraft_opt.ocp.hardware`); a ControlBound beyond it is refused."""
        return hardware_limits(self.model, self.inputs)

    def _set_bounds(self) -> None:
        lay, laser = self.inputs, self.model.laser
        hardware = self.hardware_limits()
        lower, upper = hardware.lower.copy(), hardware.upper.copy()
        if laser.size_model is not BeamSizeModel.WAIST:  # the focus has no effect: held
            lower[lay.index("focus")] = upper[lay.index("focus")]
        if "motor_torque" in lay:  # no limit in the model: held at 0 unless bounded
            lower[lay.index("motor_torque")] = upper[lay.index("motor_torque")] = 0.0
        slew = np.full(lay.size, math.inf)
        seen: set[str] = set()
        for i, bound in enumerate(self.controls):
            where = f"controls[{i}]"
            size = self._control_slot(f"{where}.slot", bound.slot)
            if bound.slot in seen:
                raise ParameterError(f"{where}.slot", f"{bound.slot!r} is bounded twice")
            seen.add(bound.slot)
            idx = lay.index(bound.slot)
            lo = (
                lower[idx]
                if bound.lower is None
                else numbers(f"{where}.lower", bound.lower, size, allow_inf=True)
            )
            hi = (
                upper[idx]
                if bound.upper is None
                else numbers(f"{where}.upper", bound.upper, size, allow_inf=True)
            )
            rate = numbers(f"{where}.slew_rate", bound.slew_rate, size, allow_inf=True)
            if np.any(lo > hi):
                raise ParameterError(f"{where}.lower", f"{lo} exceeds upper {hi}")
            if np.any(rate <= 0):
                raise ParameterError(f"{where}.slew_rate", f"must be positive, got {rate}")
            if np.any(np.isinf(lo) & (lo == hi)):
                raise ParameterError(f"{where}.lower", "an input cannot be held at infinity")
            # inf: no bound of its own, the hardware's; beyond the hardware: refused
            lo = np.where(np.isinf(lo), hardware.lower[idx], lo)
            hi = np.where(np.isinf(hi), hardware.upper[idx], hi)
            unit = lay.slot(bound.slot).unit
            hardware.check(f"{where}.lower", idx, lo, unit)
            hardware.check(f"{where}.upper", idx, hi, unit)
            lower[idx], upper[idx], slew[idx] = lo, hi, rate * self.period
        set_frozen(self, "lower", lower)
        set_frozen(self, "upper", upper)
        set_frozen(self, "slew", slew)

    def _check_envelope(self) -> None:
        """RcsEnvelope: an RCS, and thrusters whose phase-locked inputs are all held must
        hold them inside the envelope."""
        where = [i for i, c in enumerate(self.constraints) if isinstance(c, RcsEnvelope)]
        if not where:
            return
        name = f"constraints[{where[0]}]"
        if not self.n_thrusters:
            raise ParameterError(
                name, f"RcsEnvelope needs a craft with an RCS; {self.model.name!r} has none"
            )
        # the levels lie within [0, max_thrust]: _set_bounds refuses bounds beyond them
        lay, top = self.inputs, np.tile(self.max_thrust(), self.rcs_subintervals)
        if self.rcs_profile is not RcsProfile.PHASE_LOCKED:
            return
        held = ~self.free
        mean, c, s = (
            lay.slot(n).start + np.arange(self.n_thrusters)
            for n in ("rcs_thrust", "rcs_cos", "rcs_sin")
        )
        for i in range(self.n_thrusters):
            if held[mean[i]] and held[c[i]] and held[s[i]]:
                amp = math.hypot(self.lower[c[i]], self.lower[s[i]])
                m, mx = self.lower[mean[i]], top[i]
                if amp > min(m, mx - m):
                    raise ParameterError(
                        name,
                        f"thruster {i + 1}'s held inputs (mean {m}, amplitude {amp:.6g} N) leave "
                        f"[0, {mx}] N over a coning period",
                    )
