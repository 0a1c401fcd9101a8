"""U.S. Standard Atmosphere 1976 (NOAA-S/T 76-1562, docs/references.md#us1976), geometric-altitude
table values; the pad density is the one of docs/physics.md#atmosphere."""

from __future__ import annotations

import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences

from lightcraft_opt.symbolic.terms.atmosphere import LAYERS, R0, build_atmosphere

# geometric altitude [m]: density [kg/m^3], temperature [K], pressure [Pa] (table, 5 digits)
TABLE = {
    0.0: (1.2250, 288.15, 101325.0),
    1000.0: (1.1117, 281.65, 89876.0),
    5000.0: (0.73643, 255.68, 54048.0),
    10000.0: (0.41351, 223.25, 26500.0),
    20000.0: (0.088910, 216.65, 5529.3),
    86000.0: (6.958e-6, 186.87, 0.37338),
}


@pytest.mark.parametrize("h", sorted(TABLE))
def test_us1976_table_values(h):
    rho, T, p, _mu = (float(v) for v in build_atmosphere()(h))
    rho_ref, T_ref, p_ref = TABLE[h]
    assert rho == pytest.approx(rho_ref, rel=1e-4)
    # the table gives T to 0.01 K; at 86 km it lists the kinetic T, 0.08 K from molecular T_M
    assert T == pytest.approx(T_ref, abs=0.1 if h == 86000.0 else 0.005)
    assert p == pytest.approx(p_ref, rel=1e-4)


def test_white_sands_density_from_physics_md():
    assert float(build_atmosphere()(1194.0)[0]) == pytest.approx(1.0906, abs=5e-5)


def test_sutherland_viscosity_at_sea_level():
    assert float(build_atmosphere()(0.0)[3]) == pytest.approx(1.7894e-5, rel=1e-4)


def test_layers_join_continuously():
    f = build_atmosphere()
    for H_b, *_ in LAYERS[1:]:
        h_b = R0 * H_b / (R0 - H_b)  # geometric altitude of the geopotential base
        below = np.array([float(v) for v in f(h_b * (1 - 1e-12))])
        above = np.array([float(v) for v in f(h_b * (1 + 1e-12))])
        assert above == pytest.approx(below, rel=1e-9)


def test_closed_forms_solve_the_hydrostatic_equation():
    """dp/dH = -g0 M p / (R T(H)), integrated numerically from sea level."""
    from scipy.integrate import solve_ivp

    f = build_atmosphere()

    def T_of_H(H):
        return float(f(R0 * H / (R0 - H))[1])

    gmr = 9.80665 * 0.0289644 / 8.31432
    sol = solve_ivp(
        lambda H, lnp: [-gmr / T_of_H(H)],
        (0.0, 84000.0),
        [np.log(101325.0)],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        dense_output=True,
        t_eval=[5000.0, 15000.0, 30000.0, 50000.0, 60000.0, 80000.0],
    )
    for H, lnp in zip(sol.t, sol.y[0], strict=True):
        assert float(f(R0 * H / (R0 - H))[2]) == pytest.approx(np.exp(lnp), rel=1e-7)


@pytest.mark.parametrize("h", [500.0, 1194.0, 15000.0, 40000.0, 60000.0])
def test_atmosphere_jacobian_matches_finite_differences(h):
    assert_jacobians_match_finite_differences(build_atmosphere(), [h])


def test_each_layer_is_its_own_closed_form_to_the_last_bit():
    """Inside each layer, us1976's T and p are that layer's textbook formulas (power law or
    exponential) written out here, bit for bit: the other layers' branches add nothing."""
    import math

    from lightcraft_opt.symbolic.terms.atmosphere import _PB

    gmr = 9.80665 * 0.0289644 / 8.31432
    f = build_atmosphere()
    rng = np.random.default_rng(3)
    tops = [layer[0] for layer in LAYERS[1:]] + [84852.0]
    for (H_b, T_b, lapse), p_b, H_top in zip(LAYERS, _PB, tops, strict=True):
        for H in rng.uniform(H_b, H_top, 20):
            h = R0 * H / (R0 - H)
            H_exact = R0 * h / (R0 + h)  # what us1976 computes from h
            T = T_b + lapse * (H_exact - H_b)
            if lapse == 0.0:
                p = p_b * math.exp(-gmr * (H_exact - H_b) / T_b)
            else:
                p = p_b * (T / T_b) ** (-gmr / lapse)
            _rho, T_got, p_got, _mu = (float(v) for v in f(h))
            assert (T_got, p_got) == (T, p)


@pytest.mark.parametrize("h", [500.0, 15000.0, 50000.0])
def test_density_curvature_matches_finite_differences(h):
    """d²rho/dh² by casadi's AD (what the OCP's Hessian uses) against central differences
    of the exact first derivative."""
    import casadi as ca

    x = ca.SX.sym("h")
    rho = build_atmosphere()(x)[0]
    d1 = ca.Function("d1", [x], [ca.jacobian(rho, x)])
    d2 = ca.Function("d2", [x], [ca.hessian(rho, x)[0]])
    step = 1.0
    fd = (float(d1(h + step)) - float(d1(h - step))) / (2 * step)
    assert float(d2(h)) == pytest.approx(fd, rel=1e-6)
