"""Statistics of a campaign's run table (numpy only).

:func:`campaign_summary` reads the columns of runs.csv (and of timings.csv) and gives the
apogee's mean, standard deviation and percentiles, the mean and covariance of the landing
points and of the final horizontal positions with their 1σ and 95 % confidence ellipses,
the probability of leaving the beam with its Wilson 95 % interval, the status counts, the
controller's statistics and, where the controller was told an estimate, the estimator's
position error and NEES. Runs with status ``error`` or ``never_fired`` (no pulse fired:
the craft never left the pad) count in the status counts only.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = [
    "CHI2_2DOF_95",
    "Z_95",
    "campaign_summary",
    "chi2_mean_band",
    "ellipse",
    "wilson_interval",
]

#: Two-sided 95 % quantile of the standard normal.
Z_95 = 1.959963984540054
#: 95 % quantile of χ² with 2 degrees of freedom: -2 ln 0.05.
CHI2_2DOF_95 = -2.0 * math.log(0.05)


def wilson_interval(successes: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (Wilson 1927,
    docs/references.md#wilson-1927); (nan, nan) for n = 0."""
    if n <= 0:
        return (math.nan, math.nan)
    p = successes / n
    denom = 1.0 + z**2 / n
    centre = (p + z**2 / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / denom
    low = 0.0 if successes == 0 else max(0.0, centre - half)  # exact at the ends
    high = 1.0 if successes == n else min(1.0, centre + half)
    return (low, high)


def ellipse(cov: np.ndarray, scale: float = 1.0) -> dict[str, float]:
    """Semi-axes [m] and orientation of the ellipse x^T C^-1 x = scale of a 2×2
    covariance C [m^2]: ``major``, ``minor`` and ``angle_deg`` of the major axis, from east
    toward north (counter-clockwise, L frame). scale = 1: the 1σ ellipse; scale =
    :data:`CHI2_2DOF_95`: the ellipse holding 95 % of a normal distribution."""
    values, vectors = np.linalg.eigh(np.asarray(cov, dtype=float))
    values = np.clip(values, 0.0, None)
    major = vectors[:, 1]
    angle = math.degrees(math.atan2(major[1], major[0]))
    angle = (angle + 90.0) % 180.0 - 90.0  # an axis, not a direction: (-90, 90]
    return {
        "major_m": math.sqrt(scale * values[1]),
        "minor_m": math.sqrt(scale * values[0]),
        "angle_deg": angle,
    }


def _stats(v: np.ndarray) -> dict[str, Any]:
    v = v[np.isfinite(v)]
    if not v.size:
        return {"n": 0}
    p = np.percentile(v, [5, 50, 95])
    return {
        "n": int(v.size),
        "mean": float(np.mean(v)),
        "std": float(np.std(v, ddof=1)) if v.size > 1 else 0.0,
        "min": float(np.min(v)),
        "p5": float(p[0]),
        "median": float(p[1]),
        "p95": float(p[2]),
        "max": float(np.max(v)),
    }


def chi2_mean_band(k: int, z: float = Z_95) -> tuple[float, float]:
    """The two-sided band holding 95 % (``z``) of χ²(k) / k, by Wilson and Hilferty's cube
    root (docs/references.md#wilson-hilferty: within 0.1 % of the exact quantiles for
    k >= 30); (nan, nan) for k < 1."""
    if k < 1:
        return (math.nan, math.nan)
    a = 2.0 / (9.0 * k)
    return ((1 - a - z * math.sqrt(a)) ** 3, (1 - a + z * math.sqrt(a)) ** 3)


def _estimation(rms: np.ndarray, nees: np.ndarray) -> dict[str, Any]:
    """The estimator's figures over the runs told an estimate: its position error's RMS
    [m], and its position NEES per axis (1 when consistent) with the band of its mean
    over n runs, χ²(3 n) / (3 n): the band of each run's pulses fully correlated, the
    widest a consistent estimator can need (docs/estimation.md#the-unscented-filter)."""
    n = int(np.sum(np.isfinite(nees)))
    return {
        "position_rms_m": _stats(rms),
        "position_nees": _stats(nees),
        "position_nees_band_95": list(chi2_mean_band(3 * n)),
    }


def _points(x: np.ndarray, y: np.ndarray) -> dict[str, Any]:
    """Mean and covariance of the finite points (x, y) [m, L: east, north]."""
    ok = np.isfinite(x) & np.isfinite(y)
    xy = np.column_stack([x[ok], y[ok]])
    out: dict[str, Any] = {"n": len(xy)}
    if len(xy) < 3:
        return out
    cov = np.cov(xy.T)
    out.update(
        mean_m=xy.mean(axis=0).tolist(),
        covariance_m2=cov.tolist(),
        ellipse_1sigma=ellipse(cov),
        ellipse_95=ellipse(cov, CHI2_2DOF_95),
    )
    return out


def _points_by_status(status: np.ndarray, x: np.ndarray, y: np.ndarray) -> dict[str, Any]:
    """:func:`_points` of the runs of each status apart (``status``, x, y: one per run)."""
    return {str(name): _points(x[status == name], y[status == name]) for name in np.unique(status)}


def campaign_summary(
    table: Mapping[str, np.ndarray], timings: Mapping[str, np.ndarray] | None = None
) -> dict[str, Any]:
    """The campaign's statistics (module docstring) as a JSON-ready dict.

    Parameters
    ----------
    table : {column: (n,) array} of runs.csv (run_table.read_table).
    timings : the same of timings.csv, for wall and solve times.
    """
    status = np.asarray(table["status"]).astype(str)
    flown = (status != "error") & (status != "never_fired")
    n = int(flown.sum())
    names, counts = np.unique(status, return_counts=True)
    left = int(np.sum(np.asarray(table["left_beam"])[flown] == 1))

    def col(name: str) -> np.ndarray:
        return np.asarray(table[name], dtype=float)[flown]

    out: dict[str, Any] = {
        "runs": int(status.size),
        "status_counts": {str(k): int(c) for k, c in zip(names, counts, strict=True)},
        "apogee_m": _stats(col("apogee_m")),
        "apogee_time_s": _stats(col("apogee_time_s")),
        "landing": _points(col("landing_x_m"), col("landing_y_m")),
        "final_position": _points(col("final_x_m"), col("final_y_m")),
        # each outcome apart: those that stay in the beam and those that leave it are two
        # clouds, not one Gaussian (end_points.png draws these ellipses)
        "final_position_by_status": _points_by_status(
            status[flown], col("final_x_m"), col("final_y_m")
        ),
        "left_beam": {
            "count": left,
            "probability": left / n if n else math.nan,
            "wilson_95": list(wilson_interval(left, n)),
        },
        "max_tilt_deg": _stats(col("max_tilt_deg")),
        "max_coning_deg": _stats(col("max_coning_deg")),
        "final_coning_deg": _stats(col("final_coning_deg")),
        "max_offset_m": _stats(col("max_offset_m")),
        "rcs_used_kg": _stats(col("rcs_used_kg")),
    }
    fallbacks = col("fallbacks")
    iterations = col("iterations_total")
    pulses = col("pulses_commanded")
    counted = (iterations >= 0) & (pulses >= 0)
    out["controller"] = {
        "fallbacks_total": int(np.sum(fallbacks)) if n else 0,
        "runs_with_fallback": int(np.sum(fallbacks > 0)),
        "fallbacks_per_run": _stats(fallbacks),
        # over the runs that counted them (iterations_total -1: an errored run, or a
        # controller that does not say, a compiled step); NaN without one
        "iterations_per_pulse_mean": float(np.sum(iterations[counted]) / np.sum(pulses[counted]))
        if np.any(counted) and np.sum(pulses[counted]) > 0
        else math.nan,
        "iterations_max": int(np.max(col("iterations_max"))) if n else 0,
    }
    if "estimate_position_nees" in table and np.any(np.isfinite(col("estimate_position_nees"))):
        out["estimation"] = _estimation(
            col("estimate_position_rms_m"), col("estimate_position_nees")
        )
    if timings is not None and len(timings.get("run", ())):
        ms = {k: 1000.0 * np.asarray(timings[k], dtype=float) for k in timings if k != "run"}
        out["timing"] = {
            "run_wall_s": _stats(ms["wall_s"] / 1000.0),
            "solve_time_median_ms": _stats(ms["solve_time_median_s"]),
            "solve_time_p99_ms": _stats(ms["solve_time_p99_s"]),
            "solve_time_max_ms": float(np.nanmax(ms["solve_time_max_s"]))
            if np.any(np.isfinite(ms["solve_time_max_s"]))
            else math.nan,
        }
    return out
