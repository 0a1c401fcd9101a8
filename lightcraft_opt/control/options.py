"""Options of the controllers and the closed loop: the MPC, its weights, what goes wrong."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from lightcraft_opt.errors import OptionError
from lightcraft_opt.options import checked_int, checked_nonnegative, checked_number

__all__ = [
    "ClosedLoopOptions",
    "ControlWeights",
    "ControllerFault",
    "MeasurementNoise",
    "MpcOptions",
    "MpcSolver",
    "PlantDispersion",
]


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
class PlantDispersion:
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
                "PlantDispersion.relative must be a tuple of (parameter name, relative sigma) "
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
                    f"PlantDispersion.relative[{i}] must be a (parameter name, relative sigma "
                    f">= 0) pair, got {item!r}"
                )
            if item[0] in seen:
                raise OptionError(f"PlantDispersion.relative[{i}]: {item[0]!r} is given twice")
            seen.add(item[0])


@dataclass(frozen=True)
class ClosedLoopOptions:
    """What goes wrong in a closed-loop flight (closed_loop.py).

    Attributes
    ----------
    noise : on the state the controller is told (:class:`MeasurementNoise`).
    dispersion : of the plant's parameters (:class:`PlantDispersion`).
    dropout_rate : probability that the laser drops a pulse (no energy), in [0, 1).
    faults : pulse numbers (0 the first, >= 0) at which ``fault`` is injected into the
        controller's step.
    fault : the failure injected (:class:`ControllerFault`).
    seed : of the random generator (drop-outs, dispersion, noise), >= 0.
    """

    noise: MeasurementNoise = MeasurementNoise()
    dispersion: PlantDispersion = PlantDispersion()
    dropout_rate: float = 0.0
    faults: tuple[int, ...] = ()
    fault: ControllerFault = ControllerFault.RAISE
    seed: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.noise, MeasurementNoise):
            raise OptionError(
                f"ClosedLoopOptions.noise must be a MeasurementNoise, got {self.noise!r}"
            )
        if not isinstance(self.dispersion, PlantDispersion):
            raise OptionError(
                f"ClosedLoopOptions.dispersion must be a PlantDispersion, got {self.dispersion!r}"
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
