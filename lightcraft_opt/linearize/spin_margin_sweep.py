"""The least stable launch spin against the mass centre's position along b1.

:func:`spin_margin_sweep` runs :func:`~.spin_margin.least_stable_spin` at each position of
the mass centre (:mod:`.mass_centre`: from the optic's ring plane, moved by the carrier or
the ring) and reports μ at the historical launch spins; :class:`SpinMarginSweep` is the
table (``rows()``, ``summary()``) that docs/design.md#stability-constrained-spin shows.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from lightcraft_opt.linear.operating_points import PulseMapJacobian, jacobian_for
from lightcraft_opt.linearize.mass_centre import (
    MassCentreHandle,
    handle_for,
    mass_centre_from_ring,
    model_with_mass_centre,
)
from lightcraft_opt.linearize.spin_margin import (
    RPM,
    SpinMarginOptions,
    SpinMarginStatus,
    SpinScan,
    climb_worst_multiplier,
    least_stable_spin,
)
from lightcraft_opt.linearize.stability_grid import grid
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["SpinMarginSweep", "spin_margin_sweep"]


@dataclass(frozen=True)
class SpinMarginSweep:
    """The least stable launch spin against the mass centre's position along b1.

    Attributes
    ----------
    positions : (np,) launch mass centre along b1 from the ring plane [m] (B frame).
    handle : what moved it (:class:`MassCentreHandle`).
    scans : (np,) :class:`SpinScan` of each position.
    reference_spins : (nr,) [rad/s] (6,000 and 10,000 RPM by default).
    reference_multipliers : (np, nr) μ at each reference spin [-].
    nominal_position : the model's own position [m].
    spin_range : (lowest, highest) spin of the bracket [rad/s].
    limit : the multiplier limit [-].
    altitudes, offsets, speed, energy : the climb nodes [m], [m] east, [m/s], [J].
    model_name : which model.
    """

    positions: np.ndarray
    handle: MassCentreHandle
    scans: tuple[SpinScan, ...]
    reference_spins: np.ndarray
    reference_multipliers: np.ndarray
    nominal_position: float
    spin_range: tuple[float, float]
    limit: float
    altitudes: tuple[float, ...]
    offsets: tuple[float, ...]
    speed: float
    energy: float
    model_name: str

    @property
    def least_spins(self) -> np.ndarray:
        """(np,) least stable launch spin [rad/s] (NaN: none in the bracket)."""
        return np.array([s.least_spin for s in self.scans])

    @property
    def statuses(self) -> tuple[SpinMarginStatus, ...]:
        return tuple(s.status for s in self.scans)

    @property
    def best_multipliers(self) -> np.ndarray:
        """(np,) the smallest μ of each spin grid [-]."""
        return np.array([s.best_multiplier for s in self.scans])

    def rows(self) -> list[dict[str, float | str]]:
        """The table, one dict a position, units in the keys (SI, and RPM for reading)."""
        out: list[dict[str, float | str]] = []
        for k, scan in enumerate(self.scans):
            row: dict[str, float | str] = {
                "mass_centre_b1_m": float(self.positions[k]),
                "status": scan.status.value,
                "least_spin_rad_per_s": scan.least_spin,
                "least_spin_rpm": scan.least_spin / RPM,
                "multiplier_at_least": scan.multiplier_at_least,
            }
            for s, m in zip(self.reference_spins, self.reference_multipliers[k], strict=True):
                row[f"multiplier_at_{s / RPM:.0f}_rpm"] = float(m)
            row["best_multiplier"] = scan.best_multiplier
            row["best_spin_rpm"] = scan.best_spin / RPM
            row["held_fraction_above_least"] = scan.held_fraction
            row["bands_above_least"] = len(scan.bands)
            row["grid_rises"] = scan.rises
            out.append(row)
        return out

    def summary(self, length_unit_factor: float = 100.0, length_unit: str = "cm") -> str:
        """The table as text (positions in ``length_unit``, spins in RPM)."""
        refs = [f"μ@{s / RPM:.0f}" for s in self.reference_spins]
        head = f"{'b1 ' + length_unit:>8}  {'least RPM':>10}  {'μ there':>8}  " + "  ".join(
            f"{r:>9}" for r in refs
        )
        lines = [
            f"{self.model_name}: least launch spin with beam-riding |λ| <= {self.limit:g} "
            f"along the climb ({self.handle.value} moved)",
            head + f"  {'held':>5}  {'best μ':>8}  {'at RPM':>7}",
        ]
        for k, scan in enumerate(self.scans):
            least = (
                f"{scan.least_spin / RPM:>10.0f}"
                if scan.status is not SpinMarginStatus.NOT_REACHED
                else f"{'none':>10}"
            )
            if scan.status is SpinMarginStatus.AT_BRACKET_LOW:
                least = f"{'<=' + format(scan.least_spin / RPM, '.0f'):>10}"
            ref = "  ".join(f"{m:>9.4f}" for m in self.reference_multipliers[k])
            lines.append(
                f"{self.positions[k] * length_unit_factor:>8.2f}  {least}  "
                f"{scan.multiplier_at_least:>8.4f}  {ref}  {scan.held_fraction:>5.2f}  "
                f"{scan.best_multiplier:>8.4f}  "
                f"{scan.best_spin / RPM:>7.0f}"
            )
        return "\n".join(lines)


def spin_margin_sweep(
    model: Model,
    positions: Sequence[float] | np.ndarray,
    options: SpinMarginOptions | None = None,
    *,
    handle: MassCentreHandle | str | None = None,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SpinMarginSweep:
    """:func:`least_stable_spin` at each launch mass-centre ``positions`` [m] along b1
    from the ring plane (:func:`model_with_mass_centre`, moved by ``handle``), with μ at
    ``options.reference_spins``. One Φ Jacobian serves every position (the position is
    an entry of p). ``progress(done, total)`` after each position."""
    options = SpinMarginOptions() if options is None else options
    x = grid(positions, "positions")
    kind = handle_for(model, handle)
    jac = jacobian_for(model, pulse_map, options.pulse_map_options)
    scans, refs = [], np.empty((x.size, len(options.reference_spins)))
    for k, position in enumerate(x):
        moved = model_with_mass_centre(model, float(position), kind)
        scans.append(least_stable_spin(moved, options, pulse_map=jac))
        for r, spin in enumerate(options.reference_spins):
            refs[k, r] = float(np.max(climb_worst_multiplier(moved, spin, options, jac)))
        if progress is not None:
            progress(k + 1, x.size)
    energy = model.flight.pulse_energy if options.energy is None else options.energy
    return SpinMarginSweep(
        x,
        kind,
        tuple(scans),
        np.asarray(options.reference_spins, dtype=float),
        refs,
        mass_centre_from_ring(model),
        options.spin_range,
        float(options.limit),
        options.altitudes,
        options.offsets,
        float(options.speed),
        float(energy),
        model.name,
    )
