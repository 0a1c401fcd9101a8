"""A flight's dense samples gathered pulse by pulse, for plots that must not alias.

The pulse map's dense output samples each pulse interval a few times (e.g. every 1/208 s
at 26 Hz). A craft coning at 216 Hz sampled so draws beats that are not there. What can be
drawn honestly from those samples:

- the tilt of the angular momentum H from L up: it moves only by the pulses' angular
  impulses and the slow aerodynamic torque, so it is smooth between pulses;
- an envelope of the body axis b1's tilt: b1 lies on the cone of half-angle ``coning``
  about H, so its tilt from up lies in ``[|tilt_H - coning|, tilt_H + coning]`` (the
  spherical triangle inequality), taken over each pulse interval;
- the vertical speed just before and just after each pulse (a sawtooth: the coast between
  pulses is smooth).

Angles in rad, speeds in m/s, L frame (docs/frames.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lightcraft_opt.simulation.result import SimulationResult

__all__ = ["PulseSpeeds", "TiltEnvelope", "h_tilt", "pulse_speeds", "tilt_envelope"]


def h_tilt(result: SimulationResult) -> np.ndarray:
    """(n,) angle between the angular momentum H_L and L up at each dense sample [rad];
    0 where H is zero."""
    H = np.asarray(result.H_L, dtype=float)
    norm = np.linalg.norm(H, axis=1)
    cos = np.divide(H[:, 2], norm, out=np.ones_like(norm), where=norm > 0.0)
    return np.arccos(np.clip(cos, -1.0, 1.0))


def _intervals(result: SimulationResult) -> tuple[np.ndarray, list[np.ndarray]]:
    """Pulse times (k,) [s] and, per pulse, the indices of the dense samples after it and
    up to the next pulse (empty for a pulse the flight ended at)."""
    rec = result.pulses
    t = result.t
    if rec is None or len(rec.t) == 0:
        return np.empty(0), []
    eps = 1e-9 * max(1.0, float(abs(t[-1])))
    starts = np.searchsorted(t, rec.t + eps, side="left")
    stops = np.append(np.searchsorted(t, rec.t[1:] + eps, side="left"), len(t))
    return np.asarray(rec.t), [np.arange(a, b) for a, b in zip(starts, stops, strict=True)]


@dataclass(frozen=True)
class TiltEnvelope:
    """Per pulse interval [t[k], t_end[k]]: the smallest and largest tilt of b1 from L up
    the cone about H allows [rad]."""

    t: np.ndarray
    t_end: np.ndarray
    low: np.ndarray
    high: np.ndarray


def tilt_envelope(result: SimulationResult) -> TiltEnvelope:
    """The envelope of b1's tilt over each pulse interval (module docstring).

    A flight without pulses has one interval, the whole flight.
    """
    theta_H = h_tilt(result)
    coning = np.asarray(result.coning, dtype=float)
    low_all = np.abs(theta_H - coning)
    high_all = theta_H + coning
    t_pulse, groups = _intervals(result)
    if not groups:
        t, groups = np.array([result.t[0]]), [np.arange(len(result.t))]
    else:
        t = t_pulse
    keep = [i for i, g in enumerate(groups) if g.size]
    return TiltEnvelope(
        t=t[keep],
        t_end=np.array([result.t[groups[i][-1]] for i in keep]),
        low=np.array([low_all[groups[i]].min() for i in keep]),
        high=np.array([high_all[groups[i]].max() for i in keep]),
    )


@dataclass(frozen=True)
class PulseSpeeds:
    """Vertical speed v_L[up] just before and just after each pulse at times t [s, m/s]."""

    t: np.ndarray
    before: np.ndarray
    after: np.ndarray


def pulse_speeds(result: SimulationResult) -> PulseSpeeds:
    """v_L[up] just before each pulse (the dense sample at the pulse time) and just after
    it (the first two samples after the pulse extrapolated back to its time: the coast's
    acceleration varies little over a sample, so the error is second order in the sample
    step). Pulses without a sample at their time or after them are left out."""
    t = result.t
    v = result.state("v_L")[:, 2]
    t_pulse, groups = _intervals(result)
    eps = 1e-9 * max(1.0, float(abs(t[-1]))) if len(t) else 0.0
    out_t, before, after = [], [], []
    for tk, g in zip(t_pulse, groups, strict=True):
        i = int(np.searchsorted(t, tk - eps, side="left"))
        if g.size == 0 or i >= len(t) or abs(t[i] - tk) > eps:
            continue
        a = g[0]
        v_after = v[a]
        if g.size > 1:
            b = g[1]
            v_after = v[a] + (v[a] - v[b]) * (t[a] - tk) / (t[b] - t[a])
        out_t.append(tk)
        before.append(v[i])
        after.append(v_after)
    return PulseSpeeds(np.array(out_t), np.array(before), np.array(after))
