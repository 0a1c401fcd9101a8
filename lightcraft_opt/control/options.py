"""Options of the controllers and the closed loop: which controller, the MPC, the director,
their weights, what goes wrong, and which estimator tells the controller the state."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from lightcraft_opt.errors import OptionError
from lightcraft_opt.model import FocusSchedule
from lightcraft_opt.model.checks import (
    checked_choice,
    checked_int,
    checked_nonnegative,
    checked_number,
)

__all__ = [
    "ESTIMATOR_OPTIONS",
    "MAX_CONTROL_HORIZON",
    "PRIOR_SLOTS",
    "ClosedLoopOptions",
    "ControlWeights",
    "ControllerFault",
    "ControllerKind",
    "DirectorOptions",
    "DirectorRcs",
    "DirectorWeights",
    "EstimatorKind",
    "EstimatorSpec",
    "FocusSchedule",
    "MeasurementNoise",
    "MpcOptions",
    "MpcSolver",
    "PlantDispersion",
]

#: Longest horizon of the pulse-by-pulse controllers [pulses]: 10 s ahead at 26 Hz.
MAX_CONTROL_HORIZON = 260
_WHY_HORIZON = "10 s ahead; the QP grows with the horizon and a pulse leaves 38 ms to solve it"


class ControllerKind(Enum):
    """Which controller flies a closed loop (control/factory.py builds each one).

    ``MPC``: the nutation MPC (mpc.py). ``LQR``: a discrete LQR on the MPC's prediction
    model and weights (controllers.py). ``DIRECTOR``: beam tracking by a real-time
    iteration on the reduced map Ψ (director.py). ``NONE``: the open loop, the nominal
    input every pulse.
    """

    MPC = "mpc"
    LQR = "lqr"
    DIRECTOR = "director"
    NONE = "none"


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
    time_budget : None (default): no wall-clock check, the deterministic mode (max_iter
        still bounds the work): the flight depends only on its inputs, not on the machine's
        load. A number [s], > 0, makes a real-time study: a solve that takes longer is
        discarded and the shifted previous plan flies (not applied to IPOPT, the
        reference).
    envelope_directions : P >= 2: the thrust envelope, the pointing limit and the beam
        offset limit are regular 2P-gons inscribed in their circles.
    max_offset_over_capture_radius : soft limit of the predicted beam offset over the
        optic's capture radius R_c, |offset| / R_c, in (0, 1]: where the linear engine
        model holds.
    warm_start : start each solve from the previous plan shifted by a pulse.
    """

    horizon: int = 10
    weights: ControlWeights = ControlWeights()
    solver: MpcSolver = MpcSolver.HPIPM
    max_iter: int = 30
    tol: float = 1e-6
    time_budget: float | None = None
    envelope_directions: int = 4
    max_offset_over_capture_radius: float = 0.4
    warm_start: bool = True

    def __post_init__(self) -> None:
        checked_int("MpcOptions", "horizon", self.horizon, 1, MAX_CONTROL_HORIZON, _WHY_HORIZON)
        _checked_qp_options("MpcOptions", self, ControlWeights)
        checked_int("MpcOptions", "envelope_directions", self.envelope_directions, 2)
        c = self.max_offset_over_capture_radius
        if not (
            isinstance(c, int | float)
            and not isinstance(c, bool)
            and math.isfinite(c)
            and 0 < c <= 1
        ):
            raise OptionError(
                f"MpcOptions.max_offset_over_capture_radius must be in (0, 1], got {c!r}"
            )
        if not isinstance(self.warm_start, bool):
            raise OptionError(
                f"MpcOptions.warm_start must be true or false, got {self.warm_start!r}"
            )


class DirectorRcs(Enum):
    """Who fires the RCS of a craft that has one while the director flies.

    ``TILT``: the director itself, held torques against the tilt of H
    (control/rcs_allocation.py). ``NUTATION``: the nutation MPC alongside (mpc.py), its
    beam pointing replaced by the director's. ``OFF``: nobody.
    """

    TILT = "tilt"
    NUTATION = "nutation"
    OFF = "off"


@dataclass(frozen=True)
class DirectorWeights:
    """The director's objective per pulse (control/director.py), Bryson's rule: each weight
    is 1 / tolerance^2; the defaults are the tolerances below.

    Attributes
    ----------
    offset : beam offset |r - pointing| (the optic at the mass centre), 1 cm [1/m^2].
    drift : lateral position |r| off the pad axis, 5 cm [1/m^2]: the beam reaches 10 cm.
    velocity : lateral velocity |v|, 5 cm/s [s^2/m^2]: the damping that keeps a dropped
        pulse or a gust from setting the craft drifting.
    coning : |c|, the sine of the coning angle, 2 degrees [1/rad^2].
    tilt : of the angular momentum from the vertical, 10 degrees [1/rad^2]: loose, since in a
        crosswind the craft must lean into the wind (its thrust then balances the drag: 7-12
        degrees in 3 m/s); at 2 degrees the director fought that lean and lost the craft
        after dropped pulses (docs/director.md).
    pointing : beam axis off the pad axis, 10 cm [1/m^2].
    vergence : the focus's vergence 1/f off the schedule's, 0.002 1/m [m^2] (at 50 m the
        beam's side moves by ~10 % for it).
    energy : pulse energy off the flight's, 100 J [1/J^2].
    torque : the RCS's held transverse torque, 10 mN m [1/(N m)^2] (with ``rcs = "tilt"``).
    move : the pointing's step from the plan it linearises about, 2 cm [1/m^2]: a proximal
        term that keeps each real-time iteration where its linearisation holds (the
        engine's push is far from linear across the beam's edge).
    move_vergence : likewise on the vergence's step, 0.001 1/m [m^2].
    terminal : factor on the state terms at the end of the horizon, >= 1.

    All >= 0; vergence, energy and torque > 0 (they keep the QP's input weight positive
    definite).
    """

    offset: float = 1.0 / 0.01**2
    drift: float = 1.0 / 0.05**2
    velocity: float = 1.0 / 0.05**2
    coning: float = 1.0 / math.radians(2.0) ** 2
    tilt: float = 1.0 / math.radians(10.0) ** 2
    pointing: float = 1.0 / 0.1**2
    vergence: float = 1.0 / 0.002**2
    energy: float = 1.0 / 100.0**2
    torque: float = 1.0 / 0.01**2
    move: float = 1.0 / 0.02**2
    move_vergence: float = 1.0 / 0.001**2
    terminal: float = 5.0

    def __post_init__(self) -> None:
        for name in (
            "offset",
            "drift",
            "velocity",
            "coning",
            "tilt",
            "pointing",
            "move",
            "move_vergence",
        ):
            checked_nonnegative("DirectorWeights", name, getattr(self, name))
        for name in ("vergence", "energy", "torque"):
            checked_number("DirectorWeights", name, getattr(self, name), 0.0)
        checked_nonnegative("DirectorWeights", "terminal", self.terminal)
        if self.terminal < 1:
            raise OptionError(f"DirectorWeights.terminal must be >= 1, got {self.terminal!r}")


@dataclass(frozen=True)
class DirectorOptions:
    """How the director (control/director.py) plans every pulse.

    Attributes
    ----------
    horizon : pulses predicted on the reduced map Ψ, >= 2.
    weights : the objective (:class:`DirectorWeights`).
    solver : QP solver (:class:`MpcSolver`); HPIPM on the stage structure.
    max_iter : QP iteration cap, >= 1.
    tol : QP tolerance on the residuals, in (0, 1).
    time_budget : None (default): no wall-clock check, the deterministic mode; a number
        [s], > 0: a real-time study, a QP that takes longer is discarded and the shifted
        plan flies (as :class:`MpcOptions`).
    relinearize : stages whose Jacobians are computed afresh each pulse, in [1, horizon]:
        the first (at the measured state), the new last one and the others in turn; the
        rest are the previous pulses' Jacobians, shifted (a multi-level real-time
        iteration). ``horizon``: all, the plain real-time iteration.
    focus_schedule : the focus reference (:class:`~lightcraft_opt.model.FocusSchedule`).
    matched_side : the beam's side the "matched" schedule puts at the craft [m], > 0; None
        (default) the launch side a0 (docs/beam_riding.md: 8.5 cm for the record craft).
    energy_range : (lowest, highest) pulse energy as fractions of the flight's, 0 <= low
        <= high; the highest is capped at the laser's maximum (a closed-loop file whose
        highest lies beyond it is refused).
    quadrature : (radial, azimuthal) points of the optic quadrature of the director's
        model of the engine, each >= 2 (coarser than the plant's: the planner's belief).
    disturbance_gain : in [0, 1): how fast the lateral velocity and the lateral angular
        momentum the prediction misses each pulse (gusts, model error) are learnt and added
        to the prediction; 0 never.
    rcs : on a craft with RCS, who fires it (:class:`DirectorRcs`): ``TILT`` (default) the
        director, held torques in its QP against the tilt of H; ``NUTATION`` the nutation
        MPC alongside (its beam pointing replaced by the director's); ``OFF``.
    warm_start : start each QP from the previous one shifted by a pulse.
    """

    horizon: int = 10
    weights: DirectorWeights = DirectorWeights()
    solver: MpcSolver = MpcSolver.HPIPM
    max_iter: int = 30
    tol: float = 1e-6
    time_budget: float | None = None
    relinearize: int = 3
    focus_schedule: FocusSchedule = FocusSchedule.MATCHED
    matched_side: float | None = None
    energy_range: tuple[float, float] = (0.5, 1.0)
    quadrature: tuple[int, int] = (4, 16)
    disturbance_gain: float = 0.05
    rcs: DirectorRcs = DirectorRcs.TILT
    warm_start: bool = True

    def __post_init__(self) -> None:
        checked_int(
            "DirectorOptions", "horizon", self.horizon, 2, MAX_CONTROL_HORIZON, _WHY_HORIZON
        )
        _checked_qp_options("DirectorOptions", self, DirectorWeights)
        checked_int("DirectorOptions", "relinearize", self.relinearize, 1)
        if self.relinearize > self.horizon:
            raise OptionError(
                f"DirectorOptions.relinearize must be <= horizon ({self.horizon}), "
                f"got {self.relinearize}"
            )
        checked_choice("DirectorOptions", "focus_schedule", self.focus_schedule, FocusSchedule)
        if self.matched_side is not None:
            checked_number("DirectorOptions", "matched_side", self.matched_side, 0.0)
        e = self.energy_range
        if not (
            isinstance(e, tuple)
            and len(e) == 2
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in e)
            and all(math.isfinite(v) for v in e)
            and 0 <= e[0] <= e[1]
        ):
            raise OptionError(
                f"DirectorOptions.energy_range must be (low, high) with 0 <= low <= high, got {e!r}"
            )
        q = self.quadrature
        if not (
            isinstance(q, tuple)
            and len(q) == 2
            and all(isinstance(v, int) and not isinstance(v, bool) and v >= 2 for v in q)
        ):
            raise OptionError(
                f"DirectorOptions.quadrature must be (radial, azimuthal) integers >= 2, got {q!r}"
            )
        checked_nonnegative("DirectorOptions", "disturbance_gain", self.disturbance_gain)
        if self.disturbance_gain >= 1:
            raise OptionError(
                f"DirectorOptions.disturbance_gain must be in [0, 1), got {self.disturbance_gain!r}"
            )
        checked_choice("DirectorOptions", "rcs", self.rcs, DirectorRcs)
        if not isinstance(self.warm_start, bool):
            raise OptionError(
                f"DirectorOptions.warm_start must be true or false, got {self.warm_start!r}"
            )


def _checked_qp_options(owner: str, options: MpcOptions | DirectorOptions, weights: type) -> None:
    """Raise OptionError naming the field unless ``options`` (an MpcOptions or
    DirectorOptions) has weights of class ``weights``, an MpcSolver, an iteration cap >= 1,
    a tolerance in (0, 1) and a positive time budget or None."""
    if not isinstance(options.weights, weights):
        raise OptionError(f"{owner}.weights must be a {weights.__name__}, got {options.weights!r}")
    checked_choice(owner, "solver", options.solver, MpcSolver)
    checked_int(owner, "max_iter", options.max_iter, 1)
    checked_number(owner, "tol", options.tol, 0.0, 1.0)
    if options.time_budget is not None:
        checked_number(owner, "time_budget", options.time_budget, 0.0)


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
    dropout_rate : probability that the laser drops a pulse (no energy), in [0, 1].
    faults : pulse numbers (0 the first, >= 0) at which ``fault`` is injected into the
        controller's step.
    fault : the failure injected (:class:`ControllerFault`).
    seed : of the random generator (drop-outs, dispersion, noise), >= 0.
    chunked : fly a controller whose pulse is a casadi Function (the director, the MPC)
        together with the plant a second of pulses per call (control/loop_chunks.py) when
        nothing needs Python between pulses (no estimator, no time budget, no fault in the
        chunk): the same flight to the last bit, its steps' iterations unknown (-1) and
        their times the chunk's shared. False (the default): pulse by pulse, which measured
        as fast (docs/mpc.md#the-closed-loop-in-chunks).
    """

    noise: MeasurementNoise = MeasurementNoise()
    dispersion: PlantDispersion = PlantDispersion()
    dropout_rate: float = 0.0
    faults: tuple[int, ...] = ()
    fault: ControllerFault = ControllerFault.RAISE
    seed: int = 0
    chunked: bool = False

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
            and 0 <= r <= 1
        ):
            raise OptionError(f"ClosedLoopOptions.dropout_rate must be in [0, 1], got {r!r}")
        if not isinstance(self.faults, tuple) or any(
            isinstance(k, bool) or not isinstance(k, int) or k < 0 for k in self.faults
        ):
            raise OptionError(
                "ClosedLoopOptions.faults must be a tuple of pulse numbers (integers >= 0), "
                f"got {self.faults!r}"
            )
        checked_choice("ClosedLoopOptions", "fault", self.fault, ControllerFault)
        checked_int("ClosedLoopOptions", "seed", self.seed, 0)
        if not isinstance(self.chunked, bool):
            raise OptionError(
                f"ClosedLoopOptions.chunked must be True or False, got {self.chunked!r}"
            )


class EstimatorKind(Enum):
    """What tells a closed loop's controller the state (control/factory.py builds each).

    ``TRUTH``: no estimator; the controller is told the plant's true state with the
    closed loop's :class:`MeasurementNoise` on it (the loop before issue 30). ``EKF``: the
    extended Kalman filter on Ψ, fed the sensors' readings. ``UKF``: the unscented Kalman
    filter (the EKF with its prediction by sigma points), likewise. ``MHE``: the
    moving-horizon estimator, likewise.
    """

    TRUTH = "truth"
    EKF = "ekf"
    UKF = "ukf"
    MHE = "mhe"


_FILTERS = (EstimatorKind.EKF, EstimatorKind.UKF)
_ALL = (*_FILTERS, EstimatorKind.MHE)
#: The options an :class:`EstimatorSpec` may carry: their SI unit and the kinds that take
#: each (docs/files/closed_loop.md#keys-estimator).
ESTIMATOR_OPTIONS: Mapping[str, tuple[str, tuple[EstimatorKind, ...]]] = {
    "prior_position": ("m", _ALL),
    "prior_velocity": ("m/s", _ALL),
    "prior_coning": ("rad", _ALL),
    "prior_wind": ("m/s", _ALL),
    "noise_scale": ("-", _FILTERS),
    "horizon": ("pulses", (EstimatorKind.MHE,)),
    "max_iter": ("-", (EstimatorKind.MHE,)),
    "relinearize": ("stages", (EstimatorKind.MHE,)),
    "second_order": ("switch", (EstimatorKind.EKF, EstimatorKind.MHE)),
}
#: The prior options and the entries of the estimated state s (Ψ's z and the slow states:
#: docs/estimation.md) whose prior standard deviation each sets, every axis of the slot.
PRIOR_SLOTS: Mapping[str, str] = {
    "prior_position": "r_L",
    "prior_velocity": "v_L",
    "prior_coning": "coning",
    "prior_wind": "wind_L",
}
#: The options that count (pulses, iterations): integers in [low, high].
_COUNTS = {
    "horizon": (1, MAX_CONTROL_HORIZON),
    "max_iter": (1, None),
    "relinearize": (1, MAX_CONTROL_HORIZON),
}


@dataclass(frozen=True)
class EstimatorSpec:
    """Which estimator a closed loop flies and the options it is built with (SI), as a
    closed-loop file's ``[estimator]`` gives them; :func:`~.factory.build_estimator`
    makes the estimator.

    Attributes
    ----------
    kind : :class:`EstimatorKind` (default ``TRUTH``: no estimator).
    options : {name: value} of :data:`ESTIMATOR_OPTIONS`, SI, each left out taking the
        estimator's own default (``TRUTH`` takes none): the prior standard deviation at the
        start of a flight of each axis of r_L, ``prior_position`` [m], of v_L,
        ``prior_velocity`` [m/s], of Ψ's coning offset, ``prior_coning`` [rad], and of the
        wind, ``prior_wind`` [m/s], each > 0 (:meth:`prior_sigmas`); the EKF's and the
        UKF's ``noise_scale`` (its process noise times this, > 0); the moving-horizon
        estimator's window ``horizon`` [pulses] (an integer in [1, 260]), its solver's
        ``max_iter`` (>= 1) and ``relinearize`` (stages evaluated afresh a pulse, in [1,
        the horizon]; the horizon: every stage; :class:`MheOptions`); the EKF's and the
        moving-horizon estimator's ``second_order`` (default False; True: the prediction
        keeps Ψ's curvature across the offset in the beam, control/estimation/curvature.py's
        ``BEAM_OFFSET``; a tuple of entry or slot names of the estimated state: across
        those, e.g. ``PSI_CURVES``, the consistent filter).
    """

    kind: EstimatorKind = EstimatorKind.TRUTH
    options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        checked_choice("EstimatorSpec", "kind", self.kind, EstimatorKind)
        if not isinstance(self.options, Mapping):
            raise OptionError(
                f"EstimatorSpec.options must be a mapping of option name to value, got "
                f"{self.options!r}"
            )
        for name, value in self.options.items():
            where = f"options[{name}]"
            if name not in ESTIMATOR_OPTIONS:
                raise OptionError(
                    f"EstimatorSpec.{where}: no such option; allowed: {list(ESTIMATOR_OPTIONS)}"
                )
            kinds = ESTIMATOR_OPTIONS[name][1]
            if self.kind not in kinds:
                takers = " or ".join(repr(k.value) for k in kinds)
                raise OptionError(
                    f"EstimatorSpec.{where} is an option of kind {takers}, not {self.kind.value!r}"
                )
            if name == "second_order":
                named = isinstance(value, tuple) and all(isinstance(v, str) for v in value)
                if not isinstance(value, bool) and not (named and value):
                    raise OptionError(
                        f"EstimatorSpec.{where} must be true, false or a tuple of entry names, "
                        f"got {value!r}"
                    )
            elif name in _COUNTS:
                low, high = _COUNTS[name]
                why = "10 s of pulses; the QP grows with the window and a pulse leaves 38 ms"
                checked_int("EstimatorSpec", where, value, low, high, why)
            else:
                checked_number("EstimatorSpec", where, value, 0.0)

    def prior_sigmas(self) -> tuple[tuple[str, float], ...]:
        """((slot of s, prior standard deviation [SI]), ...) of the prior options given, in
        :data:`PRIOR_SLOTS`' order: what the estimators' options take
        (``EkfOptions.prior``, ``MheOptions.prior_sigmas``)."""
        return tuple(
            (slot, float(self.options[name]))
            for name, slot in PRIOR_SLOTS.items()
            if name in self.options
        )
