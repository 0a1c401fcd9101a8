"""What the hardware can do: the range of each map input the laser and the thrusters allow.

The beam axis within +-``laser.pointing_limit`` of the pad's vertical (per component), the
focus within ``laser.focus_range``, the pulse energy in [0, ``laser.pulse_energy_max``], each
RCS level in [0, its thruster's ``max_thrust``] and each phase-locked amplitude within
+-``max_thrust`` / 2; the motor torque unlimited (the model gives it no limit). An
:class:`~lightcraft_opt.ocp.problem.OcpProblem` refuses a ControlBound beyond them with a
:class:`~lightcraft_opt.errors.HardwareLimitError` naming the limit (issue 29: ``lower =
-10.0`` meant as cm was read as 10 m, a hundred times the laser's reach, and solved).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from lightcraft_opt.errors import HardwareLimitError
from lightcraft_opt.layout import VectorLayout
from lightcraft_opt.model import Model

__all__ = ["HardwareLimits", "hardware_limits"]


@dataclass(frozen=True, eq=False)
class HardwareLimits:
    """Per map-input entry: ``lower``, ``upper`` [the slot's unit] and ``limit``, whose
    limit it is in words with the model field ("the laser's pointing reach
    (laser.pointing_limit)"; "none" where unlimited)."""

    lower: np.ndarray
    upper: np.ndarray
    limit: tuple[str, ...]

    def check(self, field: str, idx: slice, values: np.ndarray, unit: str) -> None:
        """Raise HardwareLimitError (``field``) at the first of ``values`` (the entries
        ``idx``) outside the hardware's range; a round-off of 1e-12 is let through."""
        low, high = self.lower[idx], self.upper[idx]
        slack = 1e-12 * np.maximum(np.abs(values), 1.0)
        outside = np.flatnonzero((values < low - slack) | (values > high + slack))
        if outside.size:
            j = int(outside[0])
            entry = range(self.lower.size)[idx][j]
            raise HardwareLimitError(
                field, float(values[j]), float(low[j]), float(high[j]), unit, self.limit[entry]
            )


def hardware_limits(model: Model, inputs: VectorLayout) -> HardwareLimits:
    """The range of each entry of the map input ``inputs`` on ``model``'s hardware."""
    laser, rcs = model.laser, model.craft.rcs
    lower, upper = np.full(inputs.size, -math.inf), np.full(inputs.size, math.inf)
    limit = ["none"] * inputs.size

    def put(slot: str, low: Any, high: Any, words: list[str]) -> None:
        idx = inputs.index(slot)
        lower[idx], upper[idx] = low, high
        for j, i in enumerate(range(inputs.size)[idx]):
            limit[i] = words[j % len(words)]

    reach = laser.pointing_limit
    put("pointing_L", -reach, reach, ["the laser's pointing reach (laser.pointing_limit)"])
    put("focus", *laser.focus_range, ["the laser's focus range (laser.focus_range)"])
    put("energy", 0.0, laser.pulse_energy_max,
        ["the laser's pulse energy (laser.pulse_energy_max)"])  # fmt: skip
    if rcs is not None:
        top = np.array([t.max_thrust for t in rcs.thrusters], dtype=float)
        field = [f"craft.rcs.thrusters[{i}].max_thrust" for i in range(top.size)]
        # thruster i (numbered from 1, docs/frames.md) is Python's thrusters[i - 1]
        said = [f"thruster {i + 1}'s force ({f}" for i, f in enumerate(field)]
        levels = inputs.slot("rcs_thrust").size // top.size
        put("rcs_thrust", 0.0, np.tile(top, levels),
            [f"{t})" for t in said])  # fmt: skip
        for name in ("rcs_cos", "rcs_sin"):
            if name in inputs:
                put(name, -top / 2, top / 2,
                    [f"{t} / 2)" for t in said])  # fmt: skip
    return HardwareLimits(lower, upper, tuple(limit))
