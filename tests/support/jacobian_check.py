"""Compare a casadi.Function's Jacobians with central finite differences."""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np


def assert_jacobians_match_finite_differences(
    f: ca.Function,
    args: Sequence[np.ndarray | float],
    *,
    rtol: float = 1e-6,
    scale: Sequence[float | np.ndarray] | None = None,
) -> None:
    """For every input i and output j: d out_j / d in_i (AD) equals central differences.

    The step for entry k of input i is 1e-5 * (|value_k| + scale_i) (scale_i a number
    or an array per entry; default 1e-4: a relative step near the cube root of machine
    precision, with a small floor for zero entries); the error of each block
    d out_j / d in_i is its largest entry-wise difference over its largest entry.
    """
    vals = [np.atleast_1d(np.asarray(a, dtype=float)).ravel() for a in args]
    jac = f.jacobian()  # inputs: ins, outs; outputs: jac_out_in for all pairs
    res = jac(*vals, *[np.zeros(f.numel_out(j)) for j in range(f.n_out())])
    for i in range(f.n_in()):
        if f.numel_in(i) == 0:
            continue
        for j in range(f.n_out()):
            J_ad = np.asarray(res[j * f.n_in() + i]).reshape(f.numel_out(j), f.numel_in(i))
            J_fd = np.zeros_like(J_ad)
            base = vals[i]
            s = np.broadcast_to(1e-4 if scale is None else scale[i], base.shape)
            for k in range(base.size):
                h = 1e-5 * (abs(base[k]) + s[k])
                plus = [v.copy() for v in vals]
                minus = [v.copy() for v in vals]
                plus[i][k] += h
                minus[i][k] -= h
                fp = np.asarray(f(*plus)[j] if f.n_out() > 1 else f(*plus)).ravel()
                fm = np.asarray(f(*minus)[j] if f.n_out() > 1 else f(*minus)).ravel()
                J_fd[:, k] = (fp - fm) / (2 * h)
            assert np.all(np.isfinite(J_ad)), (
                f"{f.name()}: non-finite d{f.name_out(j)}/d{f.name_in(i)}"
            )
            if J_ad.size == 0:
                continue
            biggest = float(np.max(np.abs(J_ad)))
            worst = (
                float(np.max(np.abs(J_ad - J_fd))) / biggest
                if biggest > 0
                else float(np.max(np.abs(J_fd)))
            )
            assert worst < rtol, (
                f"{f.name()}: d{f.name_out(j)}/d{f.name_in(i)} differs from finite "
                f"differences by {worst:.3g} (relative)"
            )


def state_step_scale(craft_mass: float) -> np.ndarray:
    """(STATE.size,) finite-difference step scale per state entry, a small size of each slot:
    1 cm, 0.1 m/s, 0.01 of the quaternion, 1 rad/s, 1 rad/s of spin, the craft mass for the
    propellant masses, one pulse for the counter."""
    from lightcraft_opt.layout import STATE

    natural = {
        "r_L": 1e-2,
        "v_L": 0.1,
        "q_LB": 1e-2,
        "w_B": 1.0,
        "spin": 1.0,
        "liner_mass": craft_mass,
        "rcs_mass": craft_mass,
        "engine_load": 1.0,
    }
    return STATE.pack({k: np.full(STATE.slot(k).size, v) for k, v in natural.items()})
