"""Stability-constrained spin: the least launch spin that keeps the craft riding the beam.

The beam-riding multipliers (:mod:`.beam_riding`, docs/beam_riding.md) of a climb point
(:func:`~lightcraft_opt.linear.climb_point`: the craft upright, ``speed`` up, an offset east of
the beam axis, spinning at the launch spin) are the largest |λ| of the modes that load the
lateral offset, lateral velocity and tilt (:class:`~.modes.ModeKind`). Along a climb (the
nodes ``altitudes`` × ``offsets`` of :class:`SpinMarginOptions`) the worst of them,

    μ(ω) = max over the nodes of max |λ_beam riding|,

is a function of the launch spin ω [rad/s]. :func:`least_stable_spin` finds the least ω in the
bracket with μ(ω) ≤ ``limit``: μ on a grid of spins first, then bisection between the last
grid spin above the limit and the first one at or below it. Nothing here assumes μ falls
with spin: the grid says where it does not (``SpinScan.rises``), and the resonance bands
above the least spin where μ exceeds the limit again (``SpinScan.bands``: the coning
frequency J ω / A an integer multiple of the pulse rate, near n × 1204 RPM for Flight 5,
docs/linearize.md) are reported, not hidden. A bracket in which no spin meets the limit is
a status (``NOT_REACHED``), with the best spin of the grid.

:func:`~.spin_margin_sweep.spin_margin_sweep` repeats it over the mass centre's position
along b1 (:mod:`.mass_centre`); docs/design.md#stability-constrained-spin gives the method
and Flight 5's table.

Frozen time: each node is one pulse of Φ, the frozen-time multipliers of
docs/beam_riding.md. The spin there is the launch spin decayed by the rotor's air friction
over the reference climb to that node (:mod:`.climb_spin`: Flight 5 keeps 83 % of it at 20
m, 77 % at 30 m of a 10 m/s climb), or the launch spin itself with ``spin_decay=False``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import initial_state, parameter_values
from lightcraft_opt.layout.designed import LAUNCH_SPIN, model_with_parameters
from lightcraft_opt.linear.focus import scheduled_focus
from lightcraft_opt.linear.operating_points import PulseMapJacobian, jacobian_for
from lightcraft_opt.linearize.climb_spin import build_climb_spin
from lightcraft_opt.linearize.stability_grid import climb_multipliers, grid
from lightcraft_opt.model import FocusSchedule, Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties

__all__ = [
    "RPM",
    "SpinMarginOptions",
    "SpinMarginStatus",
    "SpinScan",
    "climb_worst_multiplier",
    "least_stable_spin",
]

#: rad/s per RPM.
RPM = 2 * math.pi / 60


def _number(v: object) -> bool:
    """A real number (numpy's too), not a bool."""
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


class SpinMarginStatus(Enum):
    """Where the least spin that meets the limit lies."""

    FOUND = "found"  # inside the bracket, to the tolerance
    AT_BRACKET_LOW = "at_bracket_low"  # the bracket's lowest spin already meets it
    NOT_REACHED = "not_reached"  # no spin of the grid meets it


@dataclass(frozen=True)
class SpinMarginOptions:
    """How :func:`least_stable_spin` searches.

    Attributes
    ----------
    limit : the largest beam-riding multiplier |λ| allowed along the climb [-].
    spin_range : (lowest, highest) launch spin of the bracket [rad/s] (1000-20000 RPM).
    grid_step : spacing of the spin grid scanned before the bisection [rad/s] (100 RPM:
        finer than Flight 5's resonance bands, docs/design.md#stability-constrained-spin).
    tolerance : the bisection stops when the bracket is this narrow [rad/s] (1 RPM).
    altitudes : heights of the climb nodes above the pad [m] (docs/beam_riding.md's rows
        while the shipped linear beam still holds the craft).
    offsets : craft offsets east of the beam axis at each node [m] (L frame; 1 and 3 cm as
        docs/beam_riding.md).
    speed : climb speed at every node [m/s] (up, L frame; > 0 with ``spin_decay``).
    spin_decay : the spin at a node is the launch spin decayed over the climb to it at
        ``speed`` (:mod:`.climb_spin`); False: the launch spin at every node.
    energy : pulse energy [J] (None: the flight's).
    schedule : the director's focus schedule (:class:`FocusSchedule`; only the ``waist``
        size model feels it).
    reference_spins : spins at which the sweep reports μ [rad/s] (6,000 and 10,000 RPM,
        the historical launch spins).
    pulse_map_options : how Φ is built when no map is passed (8 substeps, as
        docs/beam_riding.md).
    """

    limit: float = 0.98
    spin_range: tuple[float, float] = (1000 * RPM, 20000 * RPM)
    grid_step: float = 100 * RPM
    tolerance: float = 1 * RPM
    altitudes: tuple[float, ...] = (10.0, 20.0, 30.0)
    offsets: tuple[float, ...] = (0.01, 0.03)
    speed: float = 10.0
    spin_decay: bool = True
    energy: float | None = None
    schedule: FocusSchedule = FocusSchedule.FAR
    reference_spins: tuple[float, ...] = (6000 * RPM, 10000 * RPM)
    pulse_map_options: PulseMapOptions = field(
        default_factory=lambda: PulseMapOptions(substeps=8, dense=8)
    )

    def __post_init__(self) -> None:
        name = type(self).__name__
        for key in ("limit", "grid_step", "tolerance"):
            v = getattr(self, key)
            if not (_number(v) and math.isfinite(v) and v > 0):
                raise ParameterError(f"{name}.{key}", f"must be a finite number > 0, got {v!r}")
        lo_hi = np.asarray(self.spin_range, dtype=float).ravel()
        if not (lo_hi.size == 2 and np.all(np.isfinite(lo_hi)) and 0 < lo_hi[0] < lo_hi[1]):
            raise ParameterError(
                f"{name}.spin_range",
                f"needs (lowest, highest) with 0 < lowest < highest [rad/s], got "
                f"{self.spin_range!r}",
            )
        object.__setattr__(self, "spin_range", (float(lo_hi[0]), float(lo_hi[1])))
        for key, positive in (("altitudes", True), ("offsets", False)):
            v = grid(getattr(self, key), f"{name}.{key}", positive=positive)
            object.__setattr__(self, key, tuple(float(a) for a in v))
        spins = grid(self.reference_spins, f"{name}.reference_spins", positive=True)
        object.__setattr__(self, "reference_spins", tuple(float(s) for s in spins))
        if not (_number(self.speed) and math.isfinite(self.speed)):
            raise ParameterError(f"{name}.speed", f"must be finite [m/s], got {self.speed!r}")
        if self.spin_decay and self.speed <= 0:
            raise ParameterError(
                f"{name}.speed",
                f"must be > 0 [m/s] for the spin to decay along a climb (or spin_decay=False); "
                f"got {self.speed!r}",
            )
        if self.energy is not None and not (
            _number(self.energy) and math.isfinite(self.energy) and self.energy > 0
        ):
            raise ParameterError(f"{name}.energy", f"must be > 0 [J] or None, got {self.energy!r}")
        try:
            object.__setattr__(self, "schedule", FocusSchedule(self.schedule))
        except ValueError:
            allowed = [s.value for s in FocusSchedule]
            raise ParameterError(
                f"{name}.schedule", f"must be one of {allowed}, got {self.schedule!r}"
            ) from None
        if not isinstance(self.pulse_map_options, PulseMapOptions):
            raise ParameterError(
                f"{name}.pulse_map_options",
                f"must be a PulseMapOptions, got {type(self.pulse_map_options).__name__}",
            )

    def spin_grid(self) -> np.ndarray:
        """(n,) the scanned spins [rad/s]: ``spin_range`` in steps of at most ``grid_step``,
        both ends included."""
        lo, hi = self.spin_range
        return np.linspace(lo, hi, max(2, math.ceil((hi - lo) / self.grid_step - 1e-9) + 1))


# --------------------------------------------------------------------------- one craft
def climb_worst_multiplier(
    model: Model,
    spin: float,
    options: SpinMarginOptions,
    jacobian: PulseMapJacobian,
) -> np.ndarray:
    """(n_alt, n_off) largest beam-riding |λ| [-] at each climb node of ``options``, the
    craft launched at ``spin`` [rad/s] (decayed to each node unless
    ``options.spin_decay`` is False; module docstring); NaN where no mode is beam riding.
    μ(spin) is its largest entry."""
    energy = model.flight.pulse_energy if options.energy is None else options.energy
    p = parameter_values(model)
    J = float(mass_properties(ca.DM(initial_state(model)), ca.DM(p)).J)
    decay = build_climb_spin(model.craft.spin_decay.model)
    out = np.empty((len(options.altitudes), len(options.offsets)))
    for i, altitude in enumerate(options.altitudes):
        focus = scheduled_focus(options.schedule, altitude, model.laser, p)
        at_node = spin
        if options.spin_decay:
            at_node = float(decay(spin, altitude / options.speed, options.speed, J, p))
        for j, offset in enumerate(options.offsets):
            out[i, j], _ = climb_multipliers(
                model,
                jacobian,
                altitude,
                options.speed,
                offset,
                energy=energy,
                spin=at_node,
                focus=focus,
            )
    return out


@dataclass(frozen=True)
class SpinScan:
    """The least launch spin that keeps μ (module docstring) at or below the limit.

    Attributes
    ----------
    status : where the least spin lies (:class:`SpinMarginStatus`).
    least_spin : the least spin meeting the limit [rad/s], to ``tolerance`` (NaN when
        ``NOT_REACHED``; the bracket's lowest spin when ``AT_BRACKET_LOW``).
    multiplier_at_least : μ there [-] (≤ limit; NaN when not reached).
    below_spin, multiplier_below : the bisection's upper failing spin [rad/s] (within
        ``tolerance`` below ``least_spin``) and μ there [-] (> limit); NaN unless FOUND.
    limiting_node : (altitude [m], offset [m]) of the node that sets μ at ``least_spin``
        (NaNs when not reached).
    spins, multipliers : (n,) the grid [rad/s] and μ on it [-].
    bands : ((lowest, highest) grid spins [rad/s], ...) runs of the grid above
        ``least_spin`` where μ exceeds the limit again (resonance bands).
    rises : how many grid steps μ rises by more than 1e-6 (0: it fell with spin all along).
    best_spin, best_multiplier : the grid's smallest μ and its spin [rad/s].
    limit, tolerance : as asked [-], [rad/s].
    evaluations : spins at which μ was computed.
    """

    status: SpinMarginStatus
    least_spin: float
    multiplier_at_least: float
    below_spin: float
    multiplier_below: float
    limiting_node: tuple[float, float]
    spins: np.ndarray
    multipliers: np.ndarray
    bands: tuple[tuple[float, float], ...]
    rises: int
    best_spin: float
    best_multiplier: float
    limit: float
    tolerance: float
    evaluations: int

    @property
    def held_fraction(self) -> float:
        """The share of the grid's spins at or above ``least_spin`` that meet the limit [-]
        (1: it holds to the bracket's top; small: ``least_spin`` opens a narrow window
        between resonance bands); NaN when not reached."""
        if not math.isfinite(self.least_spin):
            return math.nan
        above = self.spins >= self.least_spin
        return float(np.mean(self.multipliers[above] <= self.limit)) if above.any() else 1.0

    @property
    def monotone(self) -> bool:
        """μ fell (or held) with spin at every step of the grid."""
        return self.rises == 0


def _runs(mask: np.ndarray, values: np.ndarray) -> tuple[tuple[float, float], ...]:
    """(first, last) of ``values`` over each run of True in ``mask``."""
    runs, start = [], None
    for i, m in enumerate(mask):
        if m and start is None:
            start = i
        if start is not None and (not m or i == mask.size - 1):
            end = i if m else i - 1
            runs.append((float(values[start]), float(values[end])))
            start = None
    return tuple(runs)


def _pulse_map_jacobian(
    model: Model, pulse_map: PulseMap | PulseMapJacobian | None, options: SpinMarginOptions
) -> PulseMapJacobian:
    return jacobian_for(model, pulse_map, options.pulse_map_options)


def _check_spin_range(model: Model, options: SpinMarginOptions) -> None:
    """The model's own checks (the rim's speed) at the bracket's top spin."""
    try:
        model_with_parameters(model, {LAUNCH_SPIN: options.spin_range[1]})
    except ParameterError as err:
        raise ParameterError(
            "SpinMarginOptions.spin_range", f"its highest spin is refused: {err}"
        ) from None


def least_stable_spin(
    model: Model,
    options: SpinMarginOptions | None = None,
    *,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SpinScan:
    """The least launch spin [rad/s] in ``options.spin_range`` whose beam-riding
    multipliers stay at or below ``options.limit`` at every climb node (module docstring).

    μ on the grid (:meth:`SpinMarginOptions.spin_grid`), then bisection to
    ``options.tolerance`` between the last grid spin above the limit before the first one
    at or below it. ``pulse_map``: Φ or its :func:`~lightcraft_opt.linear.pulse_map_jacobian`
    built for a model of the same structure (reused across calls; default built here with
    ``options.pulse_map_options``). ``progress(done, total)`` after each grid spin.
    """
    options = SpinMarginOptions() if options is None else options
    _check_spin_range(model, options)
    jac = _pulse_map_jacobian(model, pulse_map, options)
    evaluations = 0

    def mu(spin: float) -> tuple[float, np.ndarray]:
        nonlocal evaluations
        evaluations += 1
        nodes = climb_worst_multiplier(model, spin, options, jac)
        return (float(np.max(nodes)) if np.all(np.isfinite(nodes)) else math.nan), nodes

    spins = options.spin_grid()
    values = np.empty(spins.size)
    node_values = []
    for k, s in enumerate(spins):
        values[k], nodes = mu(float(s))
        node_values.append(nodes)
        if progress is not None:
            progress(k + 1, spins.size)
    ok = values <= options.limit  # NaN: not ok
    rises = int(np.sum(np.diff(values) > 1e-6))
    finite = np.isfinite(values)
    best = int(np.nanargmin(np.where(finite, values, np.inf))) if finite.any() else 0
    nan2 = (math.nan, math.nan)
    common = {
        "spins": spins,
        "multipliers": values,
        "rises": rises,
        "best_spin": float(spins[best]),
        "best_multiplier": float(values[best]),
        "limit": float(options.limit),
        "tolerance": float(options.tolerance),
    }
    if not ok.any():
        return SpinScan(
            SpinMarginStatus.NOT_REACHED,
            math.nan,
            math.nan,
            math.nan,
            math.nan,
            nan2,
            bands=(),
            evaluations=evaluations,
            **common,  # type: ignore[arg-type]
        )
    first = int(np.argmax(ok))

    def node_of(nodes: np.ndarray) -> tuple[float, float]:
        i, j = np.unravel_index(int(np.nanargmax(nodes)), nodes.shape)
        return options.altitudes[i], options.offsets[j]

    bands = _runs(~ok[first:], spins[first:])
    if first == 0:
        return SpinScan(
            SpinMarginStatus.AT_BRACKET_LOW,
            float(spins[0]),
            float(values[0]),
            math.nan,
            math.nan,
            node_of(node_values[0]),
            bands=bands,
            evaluations=evaluations,
            **common,  # type: ignore[arg-type]
        )
    lo, hi = float(spins[first - 1]), float(spins[first])  # μ(lo) > limit >= μ(hi)
    mu_lo, mu_hi, nodes_hi = float(values[first - 1]), float(values[first]), node_values[first]
    while hi - lo > options.tolerance:
        mid = 0.5 * (lo + hi)
        m, nodes = mu(mid)
        if m <= options.limit:
            hi, mu_hi, nodes_hi = mid, m, nodes
        else:
            lo, mu_lo = mid, m
    return SpinScan(
        SpinMarginStatus.FOUND,
        hi,
        mu_hi,
        lo,
        mu_lo,
        node_of(nodes_hi),
        bands=bands,
        evaluations=evaluations,
        **common,  # type: ignore[arg-type]
    )
