"""Calibration: fit engine, beam, aerodynamic and launch parameters to a tracked flight.

Least squares over the pulse map Φ (docs/architecture.md#rule-1): minimise ½ |r(θ)|² with r the
predicted minus the tracked positions (:mod:`lightcraft_opt.calibration.problem`), by
Gauss-Newton with Levenberg-Marquardt damping (Nielsen's update of the damping; Madsen,
Nielsen & Tingleff, *Methods for non-linear least squares problems*, 2004, Sec. 3.2;
docs/references.md#madsen-nielsen-tingleff)
and box bounds (an active set: a component on a bound whose gradient pushes outward is
held there; a step is clipped into the box). The fit works in scaled variables θ / scale
(each component's typical size), where the damping is λ I.

Statistics at the optimum (Seber & Wild, *Nonlinear Regression*, 1989, Sec. 2.1;
docs/references.md#seber-wild):
σ² = RSS / (3 m - n), covariance σ² (JᵀJ)⁺ from the SVD of the scaled Jacobian
(pseudo-inverse: never a singular-matrix exception), standard deviations, correlations.
Identifiability flags (:class:`~lightcraft_opt.calibration.result.FlagKind`), each with
its reason: a null direction of J that loads on the parameter (the data do not depend on
it, or only on a combination), a standard deviation above ``rel_std_max`` times
max(|value|, scale), a correlation above ``correlation_max``, a value on its bound.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from lightcraft_opt.calibration.parameters import FORMER_NAMES, FitComponent, fit_components
from lightcraft_opt.calibration.problem import (
    CalibrationProblem,
    Track,
    build_calibration_problem,
    initial_values,
)
from lightcraft_opt.calibration.result import CalibrationResult, CalibrationStatus
from lightcraft_opt.calibration.statistics import fit_statistics, identifiability_flags
from lightcraft_opt.compiled import dense_sensitivity_for, pulse_map_for
from lightcraft_opt.errors import OptionError, ParameterError, renamed
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap
from lightcraft_opt.symbolic.maps.pulse_map_sensitivities import build_dense_sensitivity

__all__ = ["CalibrationOptions", "calibrate"]


@dataclass(frozen=True)
class CalibrationOptions:
    """How :func:`calibrate` solves and judges a fit.

    Attributes
    ----------
    max_iter : Gauss-Newton iterations at most (>= 1).
    ftol : converged when an accepted step lowers the cost by less than ftol times it.
    xtol : converged when the scaled step is below xtol (|z| + xtol), z = θ / scale.
    gtol : converged when the projected scaled gradient is below gtol [m²].
    damping : initial λ relative to the largest diagonal entry of JᵀJ (scaled).
    null_tolerance : singular values below it times the largest span null directions.
    rel_std_max : POORLY_DETERMINED when std > rel_std_max max(|value|, scale).
    correlation_max : CORRELATED when |correlation| exceeds it (in (0, 1)).
    pulse_map : options of Φ (dense must be >= 2: the Hermite nodes).
    verbose : print one line per iteration.
    time_limit : wall-clock limit of the fit [s], > 0, or None for none (max_iter still
        bounds it); checked before every evaluation of a trial step. A fit that reaches it
        stops at its last accepted step with status ``TIME_LIMIT``. Default 30 minutes, as
        an optimal control solve's (ocp/options.py: OCP_TIME_LIMIT).
    """

    max_iter: int = 50
    ftol: float = 1e-8
    xtol: float = 1e-8
    gtol: float = 1e-14
    damping: float = 1e-3
    null_tolerance: float = 1e-8
    rel_std_max: float = 0.5
    correlation_max: float = 0.95
    pulse_map: PulseMapOptions = field(default_factory=PulseMapOptions)
    verbose: bool = False
    time_limit: float | None = 1800.0

    def __post_init__(self) -> None:
        t = self.time_limit
        if t is not None and not (
            isinstance(t, int | float) and not isinstance(t, bool) and np.isfinite(t) and t > 0
        ):
            raise OptionError(
                "CalibrationOptions.time_limit must be a positive number of seconds or None, "
                f"got {t!r}"
            )
        if isinstance(self.max_iter, bool) or not isinstance(self.max_iter, int):
            raise OptionError(
                f"CalibrationOptions.max_iter must be an integer, got {self.max_iter!r}"
            )
        if self.max_iter < 1:
            raise OptionError(f"CalibrationOptions.max_iter must be >= 1, got {self.max_iter}")
        for name in ("ftol", "xtol", "gtol", "damping", "null_tolerance", "rel_std_max"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise OptionError(f"CalibrationOptions.{name} must be a positive number, got {v!r}")
        if not 0 < self.correlation_max < 1:
            raise OptionError(
                "CalibrationOptions.correlation_max must lie in (0, 1), got "
                f"{self.correlation_max!r}"
            )
        if not isinstance(self.pulse_map, PulseMapOptions):
            raise OptionError("CalibrationOptions.pulse_map must be a PulseMapOptions")
        if self.pulse_map.dense < 2:
            raise OptionError(
                f"CalibrationOptions.pulse_map.dense must be >= 2 (Hermite nodes), got "
                f"{self.pulse_map.dense}"
            )


def calibrate(
    model: Model,
    track: Track,
    fit: Sequence[str] | str,
    *,
    x0: Sequence[float] | np.ndarray | None = None,
    initial: Mapping[str, float] | None = None,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    options: CalibrationOptions | None = None,
    pulse_map: PulseMap | None = None,
    compiled: bool | None = None,
) -> CalibrationResult:
    """Fit the components named by ``fit`` to ``track`` (module docstring).

    Parameters
    ----------
    model : the model to calibrate; its values are the starting point.
    track : tracked positions, L frame [m], times from the first pulse [s].
    fit : ``--fit`` names (``cm``, ``overheating``, ``divergence``, ``blast_angle``,
        ``lateral_gain``, ``tipping_gain``, ``offset``, ``tilt``, ``wind``, ``cd``), a
        list or one comma-separated string.
    x0 : (STATE.size,) initial state at the first pulse (default: on the pad, upright).
    initial : starting values by component name [SI], instead of the model's.
    bounds : (lower, upper) by component name [SI], instead of the catalogue's.
    options : solver and flag thresholds.
    pulse_map : a prebuilt Φ of ``model`` (its dense output must have >= 2 states); its
        Jacobian is then chained over its own pieces, interpreted (AD through its graph for
        a Φ without pieces).
    compiled : without ``pulse_map``, whether Φ and the pieces its Jacobian is chained over
        are compiled (:func:`~lightcraft_opt.compiled.pulse_map_for`,
        :func:`~lightcraft_opt.compiled.dense_sensitivity_for`); None: compiled unless
        ``LIGHTCRAFT_COMPILE=0``.

    Returns
    -------
    CalibrationResult with a status; a fit that fails is a result, not an exception.

    Raises
    ------
    ParameterError
        An unknown fit name (the allowed ones listed), a start outside its bounds, or a
        track with no more residuals (3 per point) than fitted components.
    """
    opts = options or CalibrationOptions()
    comps = fit_components(fit)
    n = len(comps)
    if 3 * track.t.size <= n:
        raise ParameterError(
            "track",
            f"{track.t.size} points give {3 * track.t.size} residuals: too few "
            f"for {n} fitted components",
        )
    if pulse_map is None:
        phi = pulse_map_for(model, opts.pulse_map, compiled=compiled)
        sensitivity = dense_sensitivity_for(model, opts.pulse_map, n, compiled=compiled)
    else:
        phi = pulse_map
        sensitivity = build_dense_sensitivity(phi, n) if phi.pieces is not None else None
    if phi.dense.size_out(0)[1] < 2:
        raise OptionError("pulse_map: its dense output needs >= 2 states per pulse")
    problem = build_calibration_problem(model, track, comps, phi, x0, sensitivity)
    lower, upper = _bounds(comps, bounds)
    start = _start(comps, initial_values(comps, model, problem.x0), initial, lower, upper)
    t0 = time.perf_counter()
    stopped = _solve(problem, start, lower, upper, opts)
    solve_time = time.perf_counter() - t0
    return _result(problem, stopped, start, lower, upper, solve_time, opts)


def _bounds(
    comps: Sequence[FitComponent], given: Mapping[str, tuple[float, float]] | None
) -> tuple[np.ndarray, np.ndarray]:
    names = [c.name for c in comps]
    lower = np.array([c.lower for c in comps])
    upper = np.array([c.upper for c in comps])
    for name, pair in (given or {}).items():
        if name not in names:
            raise ParameterError(f"bounds.{name}", f"is not fitted; fitted: {names}")
        try:
            lo, hi = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise ParameterError(f"bounds.{name}", f"needs (lower, upper), got {pair!r}") from None
        if not lo < hi:
            raise ParameterError(f"bounds.{name}", f"needs lower < upper, got ({lo}, {hi})")
        i = names.index(name)
        lower[i], upper[i] = lo, hi
    return lower, upper


def _start(
    comps: Sequence[FitComponent],
    model_values: np.ndarray,
    given: Mapping[str, float] | None,
    lower: np.ndarray,
    upper: np.ndarray,
) -> np.ndarray:
    names = [c.name for c in comps]
    start = model_values.copy()
    for name, value in (given or {}).items():
        if name in FORMER_NAMES:
            raise ParameterError(f"initial.{name}", renamed(name, FORMER_NAMES[name]))
        if name not in names:
            raise ParameterError(f"initial.{name}", f"is not fitted; fitted: {names}")
        v = float(value)
        if not np.isfinite(v):
            raise ParameterError(f"initial.{name}", f"must be finite, got {value!r}")
        start[names.index(name)] = v
    for i, c in enumerate(comps):
        if not lower[i] <= start[i] <= upper[i]:
            raise ParameterError(
                f"initial.{c.name}",
                f"start {start[i]:.6g} {c.unit} lies outside its bounds "
                f"[{lower[i]:.6g}, {upper[i]:.6g}]",
            )
    return start


def _evaluate(problem: CalibrationProblem, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r, J = problem.jacobian(theta)
    return np.asarray(r).ravel(), np.asarray(J)


@dataclass(frozen=True)
class _Stop:
    """Where the solver stopped: θ [SI], its residual r [m] and Jacobian J, the costs."""

    status: CalibrationStatus
    message: str
    theta: np.ndarray
    iterations: int
    initial_cost: float
    cost: float
    r: np.ndarray
    J: np.ndarray


def _solve(
    problem: CalibrationProblem,
    start: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    opts: CalibrationOptions,
) -> _Stop:
    """Projected Levenberg-Marquardt in z = θ / scale, stopped at ``opts.time_limit``
    seconds from the call."""
    until = np.inf if opts.time_limit is None else time.perf_counter() + opts.time_limit
    scale = np.array([c.scale for c in problem.components])
    lo, hi = lower / scale, upper / scale
    z = start / scale
    r, J = _evaluate(problem, z * scale)
    if not (np.all(np.isfinite(r)) and np.all(np.isfinite(J))):
        return _Stop(
            CalibrationStatus.FAILED,
            "non-finite residual at the start",
            start,
            0,
            np.nan,
            np.nan,
            r,
            J,
        )
    cost0 = cost = 0.5 * float(r @ r)

    def stop(status: CalibrationStatus, message: str, iterations: int) -> _Stop:
        return _Stop(status, message, z * scale, iterations, cost0, cost, r, J)

    def out_of_time(iterations: int) -> _Stop:
        message = f"wall-clock limit {opts.time_limit:g} s reached after {iterations} iterations"
        return stop(CalibrationStatus.TIME_LIMIT, message, iterations)

    Js = J * scale
    H = Js.T @ Js
    lam = opts.damping * max(float(np.max(np.diag(H))), 1e-30)
    nu = 2.0
    tiny = 1e-12 * (hi - lo)
    for it in range(1, opts.max_iter + 1):
        g = Js.T @ r
        held = ((z <= lo + tiny) & (g > 0)) | ((z >= hi - tiny) & (g < 0))
        free = ~held
        if not np.any(free) or np.max(np.abs(g[free])) <= opts.gtol:
            return stop(CalibrationStatus.CONVERGED, "projected gradient vanished", it - 1)
        while True:
            step = np.zeros_like(z)
            Hf = H[np.ix_(free, free)]
            step[free] = np.linalg.solve(Hf + lam * np.eye(int(free.sum())), -g[free])
            z_new = np.clip(z + step, lo, hi)
            d = z_new - z
            predicted = -(g @ d + 0.5 * d @ H @ d)
            if time.perf_counter() > until:
                return out_of_time(it - 1)
            r_new, J_new = _evaluate(problem, z_new * scale)
            finite = bool(np.all(np.isfinite(r_new)) and np.all(np.isfinite(J_new)))
            cost_new = 0.5 * float(r_new @ r_new) if finite else np.inf
            rho = (cost - cost_new) / predicted if predicted > 0 else -1.0
            small = np.linalg.norm(d) <= opts.xtol * (np.linalg.norm(z) + opts.xtol)
            if rho > 0:
                break
            if small:
                return stop(CalibrationStatus.CONVERGED, "step below xtol", it)
            lam *= nu
            nu *= 2.0
            if lam > 1e20 * max(float(np.max(np.diag(H))), 1e-30):
                return stop(CalibrationStatus.FAILED, "no descent step found", it)
        decrease = cost - cost_new
        z, r, J, cost = z_new, r_new, J_new, cost_new
        Js = J * scale
        H = Js.T @ Js
        lam *= max(1 / 3, 1 - (2 * rho - 1) ** 3)
        nu = 2.0
        if opts.verbose:
            print(
                f"  iteration {it:3d}: cost {cost:.6e} m^2, step {np.linalg.norm(d):.3e}, "
                f"damping {lam:.2e}",
                flush=True,
            )
        if decrease <= opts.ftol * cost:
            return stop(CalibrationStatus.CONVERGED, "cost decrease below ftol", it)
        if small:
            return stop(CalibrationStatus.CONVERGED, "step below xtol", it)
    return stop(
        CalibrationStatus.MAX_ITER,
        f"stopped after max_iter = {opts.max_iter} iterations",
        opts.max_iter,
    )


def _result(
    problem: CalibrationProblem,
    fit: _Stop,
    start: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    solve_time: float,
    opts: CalibrationOptions,
) -> CalibrationResult:
    """The result at the solver's stop, from the residual and Jacobian it evaluated there."""
    comps = problem.components
    n = len(comps)
    track = problem.track
    theta, r, J = fit.theta, fit.r, fit.J
    scale = np.array([c.scale for c in comps])
    m_obs = r.size
    rss = float(r @ r)
    sigma2 = rss / (m_obs - n)
    if np.all(np.isfinite(r)) and np.all(np.isfinite(J)):
        cov, std, corr, sv, null_load = fit_statistics(
            J * scale, scale, sigma2, opts.null_tolerance
        )
        flags = identifiability_flags(
            comps,
            theta,
            std,
            corr,
            sv,
            null_load,
            lower,
            upper,
            null_tolerance=opts.null_tolerance,
            rel_std_max=opts.rel_std_max,
            correlation_max=opts.correlation_max,
        )
    else:  # a failed fit: no statistics (NaN), never a LinAlgError
        cov, corr = np.full((n, n), np.nan), np.full((n, n), np.nan)
        std, sv = np.full(n, np.nan), np.full(n, np.nan)
        flags = ()
    p, x0 = (np.asarray(v).ravel() for v in problem.setup(theta))
    p_start, x0_start = (np.asarray(v).ravel() for v in problem.setup(start))
    X = np.asarray(problem.flight(theta)).T
    residuals = r.reshape(-1, 3)
    return CalibrationResult(
        status=fit.status,
        message=fit.message,
        names=tuple(c.name for c in comps),
        units=tuple(c.unit for c in comps),
        values=theta,
        initial=start,
        lower=lower,
        upper=upper,
        std=std,
        covariance=cov,
        correlation=corr,
        singular_values=sv,
        condition=float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf"),
        flags=flags,
        iterations=fit.iterations,
        cost=0.5 * rss,
        initial_cost=fit.initial_cost,
        sigma=float(np.sqrt(sigma2)),
        rms=np.sqrt(np.mean(residuals**2, axis=0)),
        residuals=residuals,
        t=track.t,
        r_measured=track.r_L,
        flight_t=np.concatenate([[0.0], problem.flight_t]),
        flight_x=np.vstack([x0, X]),
        p=p,
        x0=x0,
        solve_time=solve_time,
        gaps=track.gaps,
        initial_p=p_start,
        initial_x0=x0_start,
    )
