"""Calibration: fit a model's uncertain parameters to tracked flights.

- :mod:`.parameters`: what can be fitted (:data:`FIT_GROUPS`, :func:`fit_components`);
- :mod:`.problem`: the least-squares problem on Φ (:class:`Track`,
  :func:`build_calibration_problem`);
- :mod:`.fit`: :func:`calibrate` (Levenberg-Marquardt with bounds, :class:`CalibrationOptions`);
- :mod:`.flights`: :func:`fit_flights`, the fitted flight and the one before the fit, whole;
- :mod:`.statistics`: covariance, correlations and identifiability flags of a fit;
- :mod:`.result`: :class:`CalibrationResult` with its :class:`CalibrationStatus`.
"""

from lightcraft_opt.calibration.fit import CalibrationOptions, calibrate
from lightcraft_opt.calibration.flights import fit_flights
from lightcraft_opt.calibration.parameters import FIT_GROUPS, FitComponent, fit_components
from lightcraft_opt.calibration.problem import (
    CalibrationProblem,
    Track,
    apply_fit,
    build_calibration_problem,
    initial_values,
)
from lightcraft_opt.calibration.result import (
    CalibrationResult,
    CalibrationStatus,
    FitFlag,
    FlagKind,
)
from lightcraft_opt.calibration.statistics import fit_statistics, identifiability_flags

__all__ = [
    "FIT_GROUPS",
    "CalibrationOptions",
    "CalibrationProblem",
    "CalibrationResult",
    "CalibrationStatus",
    "FitComponent",
    "FitFlag",
    "FlagKind",
    "Track",
    "apply_fit",
    "build_calibration_problem",
    "calibrate",
    "fit_components",
    "fit_flights",
    "fit_statistics",
    "identifiability_flags",
    "initial_values",
]
