"""Beam-riding and coning multipliers over a grid of spin rate and beam offset.

Each cell is a climb point (:mod:`lightcraft_opt.linear.operating_points`), its linear model
(:mod:`.state_space`) and its multipliers (:mod:`.modes`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.linear.operating_points import PulseMapJacobian, climb_point, jacobian_for
from lightcraft_opt.linearize.modes import ModeKind, multipliers
from lightcraft_opt.linearize.state_space import linearize
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap


@dataclass(frozen=True)
class StabilityMap:
    """Largest pulse-to-pulse multipliers over a grid of spin rate and beam offset.

    Each cell linearises Φ (reduced error state) about a climb point (:func:`climb_point`:
    ``altitude``, ``speed``, pulse ``energy``) with the craft ``offsets[j]`` east of the
    beam axis, spinning at ``spins[i]``.

    Attributes
    ----------
    spins : (ns,) rotor spin rate relative to B [rad/s].
    offsets : (no,) craft offset from the beam axis, east [m].
    beam_riding : (ns, no) max |λ| of the beam-riding modes [-].
    coning : (ns, no) max |λ| of the coning modes [-] (NaN where no mode is mostly
        transverse rate: slowly spinning, tilt and rate modes merge).
    altitude, speed, energy : of the climb point [m], [m/s], [J].
    model_name : which model.
    """

    spins: np.ndarray
    offsets: np.ndarray
    beam_riding: np.ndarray
    coning: np.ndarray
    altitude: float
    speed: float
    energy: float
    model_name: str

    @property
    def lateral(self) -> np.ndarray:
        """(ns, no) max |λ| over beam-riding and coning modes: > 1 leaves the beam."""
        return np.fmax(self.beam_riding, self.coning)


def climb_multipliers(
    model: Model,
    jacobian: PulseMapJacobian,
    altitude: float,
    speed: float,
    offset: float,
    *,
    energy: float,
    spin: float | None = None,
    focus: float | None = None,
) -> tuple[float, float]:
    """(beam-riding, coning) largest |λ| at a climb point (:func:`climb_point`: ``altitude``
    [m], ``speed`` [m/s] up, ``offset`` [m] east of the beam axis, ``spin`` [rad/s],
    ``energy`` [J], ``focus`` [m]), linearised with ``jacobian``; coning NaN where no mode
    is mostly transverse rate."""
    point = climb_point(
        model,
        altitude,
        speed,
        offset_L=(offset, 0.0),
        spin=spin,
        energy=energy,
        focus=focus,
        pulse_map=jacobian,
    )
    modes = multipliers(linearize(model, point, pulse_map=jacobian))
    return modes.of_kind(ModeKind.BEAM_RIDING).largest(), modes.of_kind(ModeKind.CONING).largest()


def grid(values: Sequence[float] | np.ndarray, name: str, positive: bool = False) -> np.ndarray:
    """``values`` as a 1-D float array; ParameterError naming ``name`` when empty, not finite
    or (``positive``) not all > 0."""
    v = np.asarray(values, dtype=float).ravel()
    if not (v.size and np.all(np.isfinite(v)) and (not positive or np.all(v > 0))):
        need = "finite values > 0" if positive else "finite values"
        raise ParameterError(name, f"needs at least one value, all {need}; got {v.tolist()}")
    return v


def stability_map(
    model: Model,
    spins: Sequence[float] | np.ndarray,
    offsets: Sequence[float] | np.ndarray,
    *,
    altitude: float = 2.0,
    speed: float = 5.0,
    energy: float | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> StabilityMap:
    """Beam-riding multipliers over spin rate [rad/s] × beam offset [m] (east).

    One Jacobian of Φ per cell (its cost grows with the substeps, figures:
    bench/README.md#compile-cost-and-compiler-flags; after the Jacobian Function is built
    once). ``progress(done, total)`` is called after each cell.
    """
    jac = jacobian_for(model, pulse_map, options)
    s = np.asarray(spins, dtype=float).ravel()
    d = np.asarray(offsets, dtype=float).ravel()
    e = model.flight.pulse_energy if energy is None else energy
    riding = np.empty((s.size, d.size))
    coning = np.empty((s.size, d.size))
    for i, spin in enumerate(s):
        for j, off in enumerate(d):
            riding[i, j], coning[i, j] = climb_multipliers(
                model, jac, altitude, speed, off, energy=e, spin=spin
            )
            if progress is not None:
                progress(i * d.size + j + 1, s.size * d.size)
    return StabilityMap(s, d, riding, coning, altitude, speed, e, model.name)
