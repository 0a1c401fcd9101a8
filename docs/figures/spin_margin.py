"""The figure and the table of docs/design.md#stability-constrained-spin: Flight 5's least
launch spin for beam riding against its mass centre's position along b1.

Run from the repository root: ``python docs/figures/spin_margin.py`` (about fifteen minutes on
2 shared cores); it writes ``docs/figures/spin_margin.png`` and prints the tables of the page.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from lightcraft_opt.files.model import load_model
from lightcraft_opt.linear.operating_points import jacobian_for
from lightcraft_opt.linearize import SpinMarginOptions, model_with_mass_centre, spin_margin_sweep
from lightcraft_opt.linearize.spin_margin import RPM, climb_worst_multiplier
from lightcraft_opt.plots import spin_margin_figure

ROOT = Path(__file__).resolve().parents[2]
POSITIONS = np.arange(-0.06, 0.0401, 0.02)  # mass centre from the ring plane [m]
#: the issue's limit, and 2 % a pulse, a limit spin can meet on this craft
LIMITS = (0.98, 1.02)


def high_spin(model, options: SpinMarginOptions, jac) -> None:
    """|λ| toward 1 from above: spin frozen, midway between the coning resonances."""
    frozen = replace(options, spin_decay=False)
    resonance = 2 * np.pi * model.flight.pulse_rate * model.craft.inertia_transverse
    resonance /= model.craft.inertia_axial  # rad/s: the coning rate at a pulse-rate multiple
    for x in (0.0, -0.06):
        moved = model_with_mass_centre(model, x)
        for n in (17, 25, 33, 46):
            spin = (n + 0.5) * resonance
            mu = climb_worst_multiplier(moved, spin, frozen, jac).max()
            print(f"  {100 * x:+.0f} cm, frozen {spin / RPM:,.0f} RPM: |λ| {mu:.4f}")


def main() -> None:
    model = load_model(ROOT / "models" / "flight5.toml")
    options = SpinMarginOptions()
    jac = jacobian_for(model, None, options.pulse_map_options)
    sweeps = []
    for limit in LIMITS:
        sweep = spin_margin_sweep(model, POSITIONS, replace(options, limit=limit), pulse_map=jac)
        sweeps.append(sweep)
        print(sweep.summary())
        for x, scan in zip(sweep.positions, sweep.scans, strict=True):
            bands = ", ".join(f"{lo / RPM:.0f}-{hi / RPM:.0f}" for lo, hi in scan.bands)
            print(
                f"  {100 * x:+.0f} cm: {scan.status.value}, node {scan.limiting_node}, "
                f"grid rises {scan.rises}, bands above [RPM] {bands or 'none'}"
            )
    frozen = replace(options, limit=LIMITS[-1], spin_decay=False)  # --frozen-spin
    print(spin_margin_sweep(model, POSITIONS, frozen, pulse_map=jac).summary())
    high_spin(model, options, jac)
    out = ROOT / "docs" / "figures" / "spin_margin.png"
    spin_margin_figure(sweeps).savefig(out, dpi=90)
    print(f"\nwrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
