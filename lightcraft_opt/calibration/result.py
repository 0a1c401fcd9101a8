"""Typed, numpy-only result of a calibration (docs/architecture.md#rule-9): status, fitted
values with their covariance, and the identifiability flags that say what the data cannot
tell."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from lightcraft_opt.presenters import Presentable

__all__ = ["SHOWN_UNITS", "CalibrationResult", "CalibrationStatus", "FitFlag", "FlagKind"]

#: The unit a fitted component is printed and written in, and its factor from SI, where it
#: is not SI: angles in degrees, as in every file (docs/outputs.md).
SHOWN_UNITS: dict[str, tuple[str, float]] = {"rad": ("deg", 180.0 / np.pi)}


class CalibrationStatus(Enum):
    """How the least-squares fit ended."""

    CONVERGED = "converged"  # cost or step stopped changing
    MAX_ITER = "max_iter"  # the iteration limit came first
    TIME_LIMIT = "time_limit"  # the wall-clock limit (CalibrationOptions.time_limit) came first
    FAILED = "failed"  # a non-finite residual or Jacobian, or no descent possible


class FlagKind(Enum):
    """Why a fitted parameter is not trustworthy."""

    NOT_IDENTIFIABLE = "not_identifiable"  # loads on a null direction of the Jacobian
    POORLY_DETERMINED = "poorly_determined"  # standard deviation too large for its size
    CORRELATED = "correlated"  # |correlation| with another parameter above the limit
    AT_BOUND = "at_bound"  # ended on a bound: its statistics do not hold

    @property
    def unidentified(self) -> bool:
        """True when the data cannot determine the parameter (not merely a warning)."""
        return self in (FlagKind.NOT_IDENTIFIABLE, FlagKind.POORLY_DETERMINED)


@dataclass(frozen=True)
class FitFlag:
    """One identifiability flag: the parameter, the kind and the reason in words."""

    parameter: str
    kind: FlagKind
    reason: str


@dataclass(frozen=True)
class CalibrationResult(Presentable):
    """A fitted model: values, statistics and the fitted flight.

    Attributes
    ----------
    status, message : how the fit ended, in words.
    names, units : (n,) fitted components
        (:data:`~lightcraft_opt.calibration.parameters.FIT_GROUPS`) and their SI units.
    values, initial : (n,) fitted and starting values [SI, per ``units``].
    lower, upper : (n,) bounds used [SI].
    std : (n,) standard deviations [SI]; inf for a parameter on a null direction.
    covariance : (n, n) σ² (JᵀJ)⁺ at the optimum [SI products].
    correlation : (n, n) [-] (0 off the diagonal where a std is inf).
    singular_values : of the scaled Jacobian J diag(scale), largest first [m].
    condition : their largest over smallest (inf when one is zero) [-].
    flags : the identifiability flags, each with its reason.
    iterations : Gauss-Newton iterations taken.
    cost : ½ Σ r² at the optimum [m²]; ``initial_cost`` at the start.
    sigma : residual standard deviation sqrt(RSS / (3 m - n)) [m].
    rms : (3,) root-mean-square residual per L axis (x east, y north, z up) [m].
    residuals : (m, 3) predicted minus measured positions, L frame [m].
    t : (m,) track times [s]; ``r_measured`` (m, 3) the tracked positions, L [m].
    flight_t : (k,) times of the fitted flight's dense states [s].
    flight_x : (k, STATE.size) fitted flight's states (docs/frames.md).
    p : (PARAMETERS.size,) fitted parameter vector; ``x0`` (STATE.size,) fitted initial
        state; ``initial_p``, ``initial_x0`` those of the starting values (the flight
        before the fit; empty when not recorded).
    solve_time : wall time of the fit [s]; ``gaps`` track rows dropped as gaps.
    """

    status: CalibrationStatus
    message: str
    names: tuple[str, ...]
    units: tuple[str, ...]
    values: np.ndarray
    initial: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    singular_values: np.ndarray
    condition: float
    flags: tuple[FitFlag, ...]
    iterations: int
    cost: float
    initial_cost: float
    sigma: float
    rms: np.ndarray
    residuals: np.ndarray
    t: np.ndarray
    r_measured: np.ndarray
    flight_t: np.ndarray
    flight_x: np.ndarray
    p: np.ndarray
    x0: np.ndarray
    solve_time: float
    gaps: int = 0
    initial_p: np.ndarray = field(default_factory=lambda: np.empty(0))
    initial_x0: np.ndarray = field(default_factory=lambda: np.empty(0))

    @property
    def success(self) -> bool:
        return self.status is CalibrationStatus.CONVERGED

    def value(self, name: str) -> float:
        """Fitted value of component ``name`` [SI]."""
        return float(self.values[self.names.index(name)])

    def std_of(self, name: str) -> float:
        """Standard deviation of component ``name`` [SI]."""
        return float(self.std[self.names.index(name)])

    def shown(self, name: str) -> tuple[str, float]:
        """The unit component ``name`` is printed and written in (summary(), the CLI,
        fit_report.json: degrees for an angle, else its SI unit), and the factor that
        takes its SI values there."""
        unit = self.units[self.names.index(name)]
        return SHOWN_UNITS.get(unit, (unit, 1.0))

    def flags_of(self, name: str) -> tuple[FitFlag, ...]:
        """The flags raised on component ``name``."""
        return tuple(f for f in self.flags if f.parameter == name)

    @property
    def unidentified(self) -> tuple[str, ...]:
        """Components the data cannot determine (a NOT_IDENTIFIABLE or
        POORLY_DETERMINED flag), in fit order."""
        bad = {f.parameter for f in self.flags if f.kind.unidentified}
        return tuple(n for n in self.names if n in bad)

    def summary(self) -> str:
        """The fit on one screen: how it ended, each value with its standard deviation and
        unit, the residuals."""
        lines = [
            f"CalibrationResult: {self.status.value} ({self.message})",
            f"  {self.iterations} iterations, {self.solve_time:.2f} s, {self.t.size} tracked "
            f"points ({self.gaps} gaps dropped)",
            f"  residual sigma {1e3 * self.sigma:.3f} mm; rms x/y/z "
            + " / ".join(f"{1e3 * v:.3f}" for v in self.rms)
            + " mm",
            f"  cost {self.initial_cost:.4g} -> {self.cost:.4g} m^2, "
            f"condition {self.condition:.3g}",
        ]
        width = max(len(n) for n in self.names) if self.names else 0
        for i, name in enumerate(self.names):
            unit, factor = self.shown(name)
            sd = factor * self.std[i]
            std = "not identifiable" if not np.isfinite(sd) else f"± {sd:.3g}"
            flags = ", ".join(f.kind.value for f in self.flags_of(name))
            lines.append(
                f"  {name:<{width}}  {factor * self.values[i]:.6g} {std} {unit}"
                + (f"  [{flags}]" if flags else "")
            )
        return "\n".join(lines)

    def __repr__(self) -> str:
        fitted = ", ".join(
            f"{n}={self.shown(n)[1] * v:.4g}"
            + (f" {self.shown(n)[0]}" if self.shown(n)[0] != u else "")
            for n, v, u in zip(self.names, self.values, self.units, strict=True)
        )
        return (
            f"<CalibrationResult {self.status.value}: {fitted}; sigma "
            f"{1e3 * self.sigma:.3f} mm, {self.iterations} iterations>"
        )
