"""Options of the numeric runners as frozen dataclasses (STYLE rule 7)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from lightcraft_opt.errors import OptionError

__all__ = [
    "CoastScheme",
    "PulseMapOptions",
    "RcsProfile",
    "SimulationOptions",
    "checked_int",
    "checked_nonnegative",
    "checked_number",
]


class CoastScheme(Enum):
    """How the pulse map integrates the coast between pulses (symbolic/coast.py)."""

    RK4 = "rk4"  # classical Runge-Kutta, fixed steps
    SPLIT = "split"  # Strang splitting, exact spinning-body rotation (2nd order)
    SPLIT4 = "split4"  # Yoshida composition of SPLIT (4th order)


class RcsProfile(Enum):
    """How the RCS thrust varies over one pulse interval (layout.map_input_layout).

    ``HOLD``: one level per thruster, held from pulse to pulse. ``SUBINTERVALS``: one
    level per thruster on each of ``rcs_subintervals`` equal sub-intervals of the
    interval. ``PHASE_LOCKED``: a mean level plus a cosine and a sine at the coning
    (nutation) rate seen in B, so the torque can turn with the ~216 Hz coning mode
    (docs/frames.md, "RCS thrust over a pulse interval").
    """

    HOLD = "hold"
    SUBINTERVALS = "subintervals"
    PHASE_LOCKED = "phase_locked"


@dataclass(frozen=True)
class PulseMapOptions:
    """How Φ integrates one pulse interval.

    Attributes
    ----------
    scheme : coast integration scheme.
    substeps : fixed steps per pulse interval.
    dense : states returned inside each interval by the dense-output Function;
        must divide ``substeps``.
    rcs_profile : how the RCS thrust varies over the interval (:class:`RcsProfile`);
        it sets the map input layout.
    rcs_subintervals : equal sub-intervals of the interval, each with its own RCS
        levels; must divide ``substeps`` (a substep never straddles two levels) and be 1
        unless ``rcs_profile`` is ``SUBINTERVALS``.
    """

    scheme: CoastScheme = CoastScheme.SPLIT4
    substeps: int = 32
    dense: int = 8
    rcs_profile: RcsProfile = RcsProfile.HOLD
    rcs_subintervals: int = 1

    def __post_init__(self) -> None:
        if not isinstance(self.scheme, CoastScheme):
            allowed = [s.value for s in CoastScheme]
            raise OptionError(
                f"PulseMapOptions.scheme must be one of {allowed}, got {self.scheme!r}"
            )
        if not isinstance(self.rcs_profile, RcsProfile):
            allowed = [s.value for s in RcsProfile]
            raise OptionError(
                f"PulseMapOptions.rcs_profile must be one of {allowed} (RcsProfile), "
                f"got {self.rcs_profile!r}"
            )
        for name in ("substeps", "dense", "rcs_subintervals"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise OptionError(f"PulseMapOptions.{name} must be a positive integer, got {v!r}")
        if self.substeps % self.dense:
            raise OptionError(
                f"PulseMapOptions.dense ({self.dense}) must divide substeps ({self.substeps})"
            )
        if self.rcs_subintervals > 1 and self.rcs_profile is not RcsProfile.SUBINTERVALS:
            raise OptionError(
                f"PulseMapOptions.rcs_subintervals ({self.rcs_subintervals}) must be 1 unless "
                f"rcs_profile is 'subintervals' (got {self.rcs_profile.value!r})"
            )
        if self.substeps % self.rcs_subintervals:
            raise OptionError(
                f"PulseMapOptions.rcs_subintervals ({self.rcs_subintervals}) must divide "
                f"substeps ({self.substeps}): a substep may not straddle two RCS levels"
            )


@dataclass(frozen=True)
class SimulationOptions:
    """How :func:`lightcraft_opt.simulate` integrates.

    Attributes
    ----------
    rtol, atol : relative and absolute tolerances of the variable-step coast
        integrator (CVODES, Adams method with functional iteration) [-].
    samples_per_interval : dense-output rows per pulse interval (>= 1).
    stop_on_landing : end the flight when the mass centre returns below the pad.
    """

    rtol: float = 1e-9
    atol: float = 1e-11
    samples_per_interval: int = 8
    stop_on_landing: bool = True

    def __post_init__(self) -> None:
        for name in ("rtol", "atol"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and 0 < v < 1):
                raise OptionError(f"SimulationOptions.{name} must be in (0, 1), got {v!r}")
        if not isinstance(self.samples_per_interval, int) or self.samples_per_interval < 1:
            raise OptionError(
                "SimulationOptions.samples_per_interval must be a positive integer, "
                f"got {self.samples_per_interval!r}"
            )


# --------------------------------------------------------------------------- MPC and closed loop
__all__ += [
    "ClosedLoopOptions",
    "ControlWeights",
    "ControllerFault",
    "Dispersion",
    "MeasurementNoise",
    "MpcOptions",
    "MpcSolver",
]


def checked_int(owner: str, name: str, value: object, low: int) -> None:
    """Raise OptionError unless ``value`` is an integer (not a bool) >= ``low``."""
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise OptionError(f"{owner}.{name} must be an integer >= {low}, got {value!r}")


def checked_number(
    owner: str, name: str, value: object, low: float, high: float = math.inf
) -> None:
    """Raise OptionError unless ``value`` is a finite number in the open interval
    (``low``, ``high``); the message reads "> low" when ``high`` is infinite."""
    if not (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and low < value < high
    ):
        span = f"> {low:g}" if math.isinf(high) else f"in ({low:g}, {high:g})"
        raise OptionError(f"{owner}.{name} must be {span}, got {value!r}")


def checked_nonnegative(owner: str, name: str, value: object) -> None:
    """Raise OptionError unless ``value`` is a finite number >= 0."""
    if not (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and value >= 0
    ):
        raise OptionError(f"{owner}.{name} must be a finite number >= 0, got {value!r}")


class MpcSolver(Enum):
    """QP solver of the nutation MPC (mpc_qp.py), through casadi's ``conic`` interface.

    ``HPIPM``: interior point on the stage structure of the QP (Riccati recursion, cost
    linear in the horizon): the one meant to fly. ``QRQP``: casadi's active set method
    (sparse QR). ``OSQP``: ADMM, first order. ``IPOPT``: the QP posed as an NLP to the
    interior point NLP solver, the reference of the comparisons (bench/mpc.py); it is
    never held to the wall-time budget.
    """

    HPIPM = "hpipm"
    QRQP = "qrqp"
    OSQP = "osqp"
    IPOPT = "ipopt"


class ControllerFault(Enum):
    """A controller failure injected at chosen pulses of a closed loop (closed_loop.py).

    ``RAISE``: the solver call raises. ``NON_FINITE``: the solver answers NaN.
    ``LATE``: the answer comes after the wall-time budget. The MPC flies its shifted
    previous plan for each; controllers without a solver ignore them.
    """

    RAISE = "raise"
    NON_FINITE = "non_finite"
    LATE = "late"


@dataclass(frozen=True)
class ControlWeights:
    """The objective per pulse of the MPC and the LQR (controllers.stage_weights).

    Quadratic weights, Bryson's rule 1 / tolerance^2: the defaults are the tolerances
    0.5 degrees of coning, 2 degrees of tilt, 1 cm of beam offset, 20 cm of drift, 0.2 m/s
    of lateral velocity, 20 cm of beam pointing, 0.5 N of RCS thrust.

    Attributes
    ----------
    coning : on |c|^2, c the coning vector (angle b1 to H) [1/rad^2], >= 0.
    tilt : on the tilt of the axis b1, |h - c|^2 [1/rad^2], >= 0.
    offset : on the beam offset |r - pointing|^2 (the optic at the mass centre) [1/m^2],
        >= 0.
    drift : on the lateral position |r|^2 [1/m^2], >= 0.
    velocity : on the lateral velocity |v|^2 [s^2/m^2], >= 0.
    pointing : on the beam pointing |pointing|^2 off the pad axis [1/m^2], >= 0.
    rcs : on every RCS input (mean thrusts and phase-locked amplitudes) squared
        [1/N^2], > 0 (it keeps the input weight positive definite).
    propellant : linear, on the summed mean thrust [1/N], >= 0 (no LQR counterpart).
    """

    coning: float = 1.0 / math.radians(0.5) ** 2
    tilt: float = 1.0 / math.radians(2.0) ** 2
    offset: float = 1.0 / 0.01**2
    drift: float = 1.0 / 0.2**2
    velocity: float = 1.0 / 0.2**2
    pointing: float = 1.0 / 0.2**2
    rcs: float = 1.0 / 0.5**2
    propellant: float = 1.0

    def __post_init__(self) -> None:
        for name in ("coning", "tilt", "offset", "drift", "velocity", "pointing", "propellant"):
            checked_nonnegative("ControlWeights", name, getattr(self, name))
        checked_number("ControlWeights", "rcs", self.rcs, 0.0)


@dataclass(frozen=True)
class MpcOptions:
    """How the nutation MPC (mpc.py) poses and solves its QP every pulse.

    Attributes
    ----------
    horizon : pulses predicted, >= 1.
    weights : the objective (:class:`ControlWeights`).
    solver : QP solver (:class:`MpcSolver`); HPIPM on the stage-structured QP.
    max_iter : iteration cap of the QP solver, >= 1 (a solve that reaches it falls back).
    tol : solver tolerance on the residuals, in (0, 1).
    time_budget : wall time a solve may take [s], > 0: a later answer is discarded and
        the shifted previous plan flies (not applied to IPOPT, the reference).
    envelope_directions : P >= 2: the thrust envelope, the pointing limit and the beam
        offset limit are regular 2P-gons inscribed in their circles.
    capture_fraction : soft limit of the predicted beam offset, as a fraction of the
        optic's capture radius, in (0, 1]: where the linear engine model holds.
    warm_start : start each solve from the previous plan shifted by a pulse.
    """

    horizon: int = 10
    weights: ControlWeights = ControlWeights()
    solver: MpcSolver = MpcSolver.HPIPM
    max_iter: int = 30
    tol: float = 1e-6
    time_budget: float = 5e-3
    envelope_directions: int = 4
    capture_fraction: float = 0.4
    warm_start: bool = True

    def __post_init__(self) -> None:
        checked_int("MpcOptions", "horizon", self.horizon, 1)
        if not isinstance(self.weights, ControlWeights):
            raise OptionError(f"MpcOptions.weights must be a ControlWeights, got {self.weights!r}")
        if not isinstance(self.solver, MpcSolver):
            allowed = [s.value for s in MpcSolver]
            raise OptionError(f"MpcOptions.solver must be one of {allowed}, got {self.solver!r}")
        checked_int("MpcOptions", "max_iter", self.max_iter, 1)
        checked_number("MpcOptions", "tol", self.tol, 0.0, 1.0)
        checked_number("MpcOptions", "time_budget", self.time_budget, 0.0)
        checked_int("MpcOptions", "envelope_directions", self.envelope_directions, 2)
        c = self.capture_fraction
        if not (
            isinstance(c, int | float)
            and not isinstance(c, bool)
            and math.isfinite(c)
            and 0 < c <= 1
        ):
            raise OptionError(f"MpcOptions.capture_fraction must be in (0, 1], got {c!r}")
        if not isinstance(self.warm_start, bool):
            raise OptionError(
                f"MpcOptions.warm_start must be true or false, got {self.warm_start!r}"
            )


@dataclass(frozen=True)
class MeasurementNoise:
    """White Gaussian noise on the state a controller is told (closed_loop.measured),
    1-sigma; zero (the default) draws nothing.

    Attributes
    ----------
    position : on r_L [m], >= 0.
    velocity : on v_L [m/s], >= 0.
    attitude : a small rotation of B (error-state chart) [rad], >= 0.
    rate : on w_B [rad/s], >= 0.
    spin : on the rotor spin [rad/s], >= 0.
    """

    position: float = 0.0
    velocity: float = 0.0
    attitude: float = 0.0
    rate: float = 0.0
    spin: float = 0.0

    def __post_init__(self) -> None:
        for name in ("position", "velocity", "attitude", "rate", "spin"):
            checked_nonnegative("MeasurementNoise", name, getattr(self, name))


@dataclass(frozen=True)
class Dispersion:
    """The plant's parameters a controller does not know exactly (closed_loop.disperse).

    Attributes
    ----------
    relative : ((parameter name, relative sigma), ...): each named entry of the plant's
        parameter vector (layout.PARAMETERS names, checked when dispersed) is multiplied
        by 1 + sigma n, n ~ N(0, 1) clipped to ±3, one draw per component, in this order;
        sigma [-] >= 0, each name once. Empty (the default): the plant is the model.
    """

    relative: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.relative, tuple):
            raise OptionError(
                "Dispersion.relative must be a tuple of (parameter name, relative sigma) "
                f"pairs, got {self.relative!r}"
            )
        seen: set[str] = set()
        for i, item in enumerate(self.relative):
            ok = isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], str)
            sigma = item[1] if ok else None
            if not (
                ok
                and isinstance(sigma, int | float)
                and not isinstance(sigma, bool)
                and math.isfinite(sigma)
                and sigma >= 0
            ):
                raise OptionError(
                    f"Dispersion.relative[{i}] must be a (parameter name, relative sigma "
                    f">= 0) pair, got {item!r}"
                )
            if item[0] in seen:
                raise OptionError(f"Dispersion.relative[{i}]: {item[0]!r} is given twice")
            seen.add(item[0])


@dataclass(frozen=True)
class ClosedLoopOptions:
    """What goes wrong in a closed-loop flight (closed_loop.py).

    Attributes
    ----------
    noise : on the state the controller is told (:class:`MeasurementNoise`).
    dispersion : of the plant's parameters (:class:`Dispersion`).
    dropout_rate : probability that the laser drops a pulse (no energy), in [0, 1).
    faults : pulse numbers (0 the first, >= 0) at which ``fault`` is injected into the
        controller's step.
    fault : the failure injected (:class:`ControllerFault`).
    seed : of the random generator (drop-outs, dispersion, noise), >= 0.
    """

    noise: MeasurementNoise = MeasurementNoise()
    dispersion: Dispersion = Dispersion()
    dropout_rate: float = 0.0
    faults: tuple[int, ...] = ()
    fault: ControllerFault = ControllerFault.RAISE
    seed: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.noise, MeasurementNoise):
            raise OptionError(
                f"ClosedLoopOptions.noise must be a MeasurementNoise, got {self.noise!r}"
            )
        if not isinstance(self.dispersion, Dispersion):
            raise OptionError(
                f"ClosedLoopOptions.dispersion must be a Dispersion, got {self.dispersion!r}"
            )
        r = self.dropout_rate
        if not (
            isinstance(r, int | float)
            and not isinstance(r, bool)
            and math.isfinite(r)
            and 0 <= r < 1
        ):
            raise OptionError(f"ClosedLoopOptions.dropout_rate must be in [0, 1), got {r!r}")
        if not isinstance(self.faults, tuple) or any(
            isinstance(k, bool) or not isinstance(k, int) or k < 0 for k in self.faults
        ):
            raise OptionError(
                "ClosedLoopOptions.faults must be a tuple of pulse numbers (integers >= 0), "
                f"got {self.faults!r}"
            )
        if not isinstance(self.fault, ControllerFault):
            allowed = [f.value for f in ControllerFault]
            raise OptionError(
                f"ClosedLoopOptions.fault must be one of {allowed}, got {self.fault!r}"
            )
        checked_int("ClosedLoopOptions", "seed", self.seed, 0)
