"""``print(multipliers(sys))`` (the README's line) prints a table by mode, not a matrix:
one row per mode with |λ|, its angle, its growth rate, its kind and the state it loads."""

from __future__ import annotations

import math

import numpy as np

from lightcraft_opt.linearize.modes import ModeKind, Multipliers


def test_one_row_per_mode_with_its_numbers_and_its_main_state() -> None:
    dt = 1 / 26
    values = np.array([1.02 * np.exp(1j * 0.3), 1.02 * np.exp(-1j * 0.3), 0.5])
    participation = np.array([[0.7, 0.3, 0.0], [0.7, 0.3, 0.0], [0.0, 0.1, 0.9]])
    kinds = (ModeKind.CONING, ModeKind.CONING, ModeKind.VERTICAL)
    states = ("w_B[b2]", "w_B[b3]", "v_L[up]")
    table = str(Multipliers(values, participation, kinds, states, dt)).splitlines()
    rows = table[2:]
    assert len(rows) == 3 and "[[" not in "\n".join(table)
    for row, lam, kind, main in zip(
        rows, values, kinds, ("w_B[b2]", "w_B[b2]", "v_L[up]"), strict=True
    ):
        cells = row.split()
        assert float(cells[1]) == round(abs(lam), 5)
        assert float(cells[2]) == round(math.degrees(np.angle(lam)), 2)
        assert float(cells[3]) == float(f"{math.log(abs(lam)) / dt:.3g}")
        assert cells[4] == kind.value and cells[5] == main
