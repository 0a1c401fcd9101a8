"""Aerodynamic loads: paper Eqs. 2-5 (corrected), geometry, smoothness, Magnus, units.

The paper is the seed paper (docs/references.md#paper-eq-2); the corrections are listed in
docs/physics.md#departures.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, parameter_values
from lightcraft_opt.model import Aerodynamics, AeroModel, Model
from lightcraft_opt.symbolic.terms.aero import aero_coefficients, aero_loads, build_aero_loads

RHO = 1.0906  # kg/m^3 at 1194 m (docs/physics.md#atmosphere)
SPIN = 10_000 * 2 * math.pi / 60  # rad/s


# --------------------------------------------------------------------------- helpers
def paper_eq5(a: float) -> tuple[float, float, float]:
    """Eq. 5 exactly as printed (descending powers), with 8794 read as 0.8794."""
    cd = 0.3928 * a**3 - 0.8463 * a**2 + 0.0398 * a + 0.731
    cl = 0.1993 * a**5 - 0.3317 * a**4 - 0.2724 * a**3 + 0.5531 * a**2 + 0.5531 * a
    cm = 0.1598 * a**6 - 0.6619 * a**5 + 0.8794 * a**4 - 0.3585 * a**3 - 0.0583 * a**2 + 0.080 * a
    return cd, cl, cm


def coefficients(alpha: float, aero: Aerodynamics) -> np.ndarray:
    return np.array([float(c) for c in aero_coefficients(ca.DM(alpha), aero)])


def params(model: Model, **changes: float) -> np.ndarray:
    p = parameter_values(model)
    for name, value in changes.items():
        p[PARAMETERS.index(name)] = value
    return p


def loads(f: ca.Function, v: np.ndarray, w: float, rho: float, p: np.ndarray):
    F, M, alpha = f(v, w, rho, p)
    return np.asarray(F).ravel(), np.asarray(M).ravel(), float(alpha)


def reference_loads(v: np.ndarray, p: np.ndarray, w: float, rho: float) -> tuple:
    """Independent, unregularised numpy derivation with unit vectors (paper Eqs. 2-5)."""
    get = PARAMETERS.unpack(p)
    b1 = np.array([1.0, 0.0, 0.0])
    speed = np.linalg.norm(v)
    v_hat = v / speed
    alpha = math.acos(np.clip(v_hat @ b1, -1, 1))
    cd, cl, cm = paper_eq5(min(alpha, math.pi - alpha))
    S = math.pi * get["diameter"] ** 2 / 4
    qS = 0.5 * rho * speed**2 * S
    e_perp = (b1 - math.cos(alpha) * v_hat) / math.sin(alpha)
    axis = np.cross(v_hat, b1) / np.linalg.norm(np.cross(v_hat, b1))
    F = -qS * get["cd_scale"] * cd * v_hat + qS * get["cl_scale"] * cl * e_perp
    M = qS * get["reference_length"] * get["cm_scale"] * cm * axis
    ratio = w * get["diameter"] / (2 * speed)  # spin ratio
    F = F + qS * get["magnus_force_coefficient"] * ratio * np.cross(b1, v_hat)
    M = M + qS * get["diameter"] * get["magnus_moment_coefficient"] * ratio * np.cross(
        b1, np.cross(b1, v_hat)
    )
    return F, M, alpha


ORDINARY = [
    np.array([12.0, -5.0, 7.0]),
    np.array([20.0, 1.0, 0.0]),
    np.array([3.0, 0.2, -0.4]),
    np.array([-4.0, 6.0, 2.5]),  # beyond 90 degrees
    np.array([0.5, -8.0, -3.0]),
]


# --------------------------------------------------------------------------- paper Eq. 5
@pytest.mark.parametrize("alpha", [0.0, 0.1, 0.3, math.pi / 4, 1.0, 1.3, math.pi / 2])
def test_paper_eq5_polynomials_by_hand(alpha: float) -> None:
    np.testing.assert_allclose(
        coefficients(alpha, Aerodynamics()), paper_eq5(alpha), rtol=1e-13, atol=1e-14
    )


def test_paper_eq5_hand_values() -> None:
    """Numbers worked out on paper from the printed polynomials."""
    cd, cl, cm = coefficients(0.0, Aerodynamics())
    assert (cd, cl, cm) == (0.731, 0.0, 0.0)
    # alpha = 0.5: C_D = 0.3928/8 - 0.8463/4 + 0.0398/2 + 0.731 = 0.588425
    # C_L = 0.1993/32 - 0.3317/16 - 0.2724/8 + 0.5531/4 + 0.5531/2 = 0.36649...
    cd, cl, cm = coefficients(0.5, Aerodynamics())
    assert cd == pytest.approx(0.588425, abs=1e-12)
    assert cl == pytest.approx(0.1993 / 32 - 0.3317 / 16 - 0.2724 / 8 + 0.5531 * 0.75, abs=1e-12)
    assert cm == pytest.approx(
        0.1598 / 64 - 0.6619 / 32 + 0.8794 / 16 - 0.3585 / 8 - 0.0583 / 4 + 0.04, abs=1e-12
    )


def test_paper_eq5_cm_typo_correction_matters() -> None:
    """C_M(90 deg) with 0.8794 is 0.0168 (worked by hand below); the printed 8794 gives 5.35e4.

    By hand at a = pi/2: 0.1598 a^6 = 2.40047, -0.6619 a^5 = -6.32983, 0.8794 a^4 = 5.35389,
    -0.3585 a^3 = -1.38948, -0.0583 a^2 = -0.14385, 0.080 a = 0.12566; sum 0.01684.
    (A peak of "about 0.063" is not what the corrected curve gives: it peaks at 0.0463 near
    68 deg and never reaches 0.063 on 0..pi/2.)
    """
    a = math.pi / 2
    cm = coefficients(a, Aerodynamics())[2]
    assert cm == pytest.approx(0.01684, abs=5e-5)
    printed = Aerodynamics(cm=(0.0, 0.080, -0.0583, -0.3585, 8794.0, -0.6619, 0.1598))
    cm_printed = coefficients(a, printed)[2]
    assert cm_printed == pytest.approx(8794 * a**4, rel=1e-3)  # 5.35e4
    assert cm_printed == pytest.approx(5.35e4, rel=0.01)
    assert cm_printed / cm > 1e6


def test_mirror_beyond_90_degrees() -> None:
    aero = Aerodynamics()
    for a in (0.0, 0.2, 0.9, 1.5):
        np.testing.assert_allclose(
            coefficients(math.pi - a, aero), coefficients(a, aero), rtol=1e-12, atol=1e-14
        )


def test_nonzero_lift_at_zero_alpha_is_refused() -> None:
    with pytest.raises(ParameterError, match=r"aero\.cl"):
        aero_coefficients(ca.DM(0.1), Aerodynamics(cl=(0.01, 0.5)))
    with pytest.raises(ParameterError, match=r"aero\.cm"):
        build_aero_loads(Aerodynamics(cm=(0.002, 0.08)))


# --------------------------------------------------------------------------- geometry
@pytest.mark.parametrize("v", ORDINARY)
def test_loads_match_unregularised_reference(v: np.ndarray, flight5: Model) -> None:
    """Independent derivation with unit vectors; also bounds the eps regularisation."""
    p = params(
        flight5,
        cd_scale=1.3,
        cl_scale=0.7,
        cm_scale=1.1,
        magnus_force_coefficient=0.2,
        magnus_moment_coefficient=-0.05,
    )
    F, M, alpha = loads(build_aero_loads(Aerodynamics()), v, SPIN, RHO, p)
    F_ref, M_ref, alpha_ref = reference_loads(v, p, SPIN, RHO)
    np.testing.assert_allclose(F, F_ref, rtol=1e-9, atol=1e-9 * float(np.linalg.norm(F_ref)))
    np.testing.assert_allclose(M, M_ref, rtol=1e-9, atol=1e-9 * float(np.linalg.norm(M_ref)))
    assert alpha == pytest.approx(alpha_ref, rel=1e-9)


@pytest.mark.parametrize("v", ORDINARY)
def test_drag_lift_moment_directions_and_sizes(v: np.ndarray, flight5: Model) -> None:
    p = params(flight5, cd_scale=1.3, cl_scale=0.7, cm_scale=1.1)
    F, M, alpha = loads(build_aero_loads(Aerodynamics()), v, SPIN, RHO, p)
    b1 = np.array([1.0, 0.0, 0.0])
    speed = np.linalg.norm(v)
    v_hat = v / speed
    assert alpha == pytest.approx(math.acos(v_hat[0]), rel=1e-12)
    cd, cl, cm = paper_eq5(min(alpha, math.pi - alpha))
    D = 0.1222
    qS = 0.5 * RHO * speed**2 * math.pi * D**2 / 4
    drag = -(F @ v_hat)
    lift = F + drag * v_hat
    # drag antiparallel to v_air, of size q S C_D
    assert drag == pytest.approx(qS * 1.3 * cd, rel=1e-12)
    # lift perpendicular to v_air, in the plane of b1 and v_air, toward b1, size q S C_L
    assert abs(lift @ v_hat) < 1e-12 * np.linalg.norm(F)
    assert abs(lift @ np.cross(b1, v_hat)) < 1e-12 * np.linalg.norm(F)
    assert lift @ b1 > 0
    assert np.linalg.norm(lift) == pytest.approx(qS * 0.7 * cl, rel=1e-12)
    # moment perpendicular to b1 and v_air, size q S c C_M
    assert abs(M @ b1) < 1e-14 * np.linalg.norm(M)
    assert abs(M @ v_hat) < 1e-12 * np.linalg.norm(M)
    assert np.linalg.norm(M) == pytest.approx(qS * D * 1.1 * cm, rel=1e-12)


def test_moment_is_destabilising(flight5: Model) -> None:
    """Turning b1 a little about M (C_M > 0) increases the angle of attack."""
    p = params(flight5)
    f = build_aero_loads(Aerodynamics())
    for v in ORDINARY:
        _, M, alpha = loads(f, v, 0.0, RHO, p)
        assert paper_eq5(min(alpha, math.pi - alpha))[2] > 0
        m_hat = M / np.linalg.norm(M)
        b1 = np.array([1.0, 0.0, 0.0])
        b1_turned = b1 + 1e-4 * np.cross(m_hat, b1)
        b1_turned /= np.linalg.norm(b1_turned)
        new_alpha = math.acos(b1_turned @ v / np.linalg.norm(v))
        assert new_alpha > alpha + 0.5e-4


def test_loads_continuous_through_90_degrees(flight5: Model) -> None:
    p = params(flight5)
    f = build_aero_loads(Aerodynamics())
    speed, delta = 15.0, 1e-7
    below = speed * np.array([math.cos(math.pi / 2 - delta), math.sin(math.pi / 2 - delta), 0])
    above = speed * np.array([math.cos(math.pi / 2 + delta), math.sin(math.pi / 2 + delta), 0])
    F1, M1, a1 = loads(f, below, SPIN, RHO, p)
    F2, M2, a2 = loads(f, above, SPIN, RHO, p)
    assert a1 < math.pi / 2 < a2
    # the loads change by O(delta), not O(1)
    assert np.linalg.norm(F1 - F2) < 10 * delta * np.linalg.norm(F1)
    assert np.linalg.norm(M1 - M2) < 10 * delta * np.linalg.norm(M1)


# --------------------------------------------------------------------------- smoothness
@pytest.mark.parametrize(
    "v",
    [
        np.array([10.0, 0.0, 0.0]),
        np.array([-10.0, 0.0, 0.0]),
        np.zeros(3),
        np.array([0.0, 10.0, 0.0]),
    ],
    ids=["alpha=0", "alpha=pi", "v=0", "alpha=pi/2"],
)
def test_finite_values_and_jacobians_at_singular_states(v: np.ndarray, flight5: Model) -> None:
    p = params(flight5, magnus_force_coefficient=0.1, magnus_moment_coefficient=0.02)
    for aero in (Aerodynamics(), table_from_polynomials(91)):
        f = build_aero_loads(aero)
        outs = f(v, SPIN, RHO, p)
        jac = f.jacobian()(v, SPIN, RHO, p, *outs)
        for x in [*outs, *jac]:
            assert np.all(np.isfinite(np.asarray(x)))


def test_axial_flight_is_pure_drag_and_limits_agree(flight5: Model) -> None:
    """At alpha = 0 and pi only drag acts; tiny alpha gives the same (continuity)."""
    p = params(flight5)
    f = build_aero_loads(Aerodynamics())
    qS = 0.5 * RHO * 100.0 * math.pi * 0.1222**2 / 4
    for sign in (1.0, -1.0):
        F, M, alpha = loads(f, np.array([10.0 * sign, 0.0, 0.0]), SPIN, RHO, p)
        # regularised alpha = eps / |v| = 1e-10 rad shifts C_D by 0.0398e-10: 5e-12 relative
        np.testing.assert_allclose(F, [-sign * qS * 0.731, 0, 0], rtol=1e-10, atol=1e-15)
        np.testing.assert_allclose(M, 0, atol=1e-15)
        assert alpha == pytest.approx(0.0 if sign > 0 else math.pi, abs=1e-9)
        F_near, M_near, _ = loads(f, np.array([10.0 * sign, 1e-6, 0.0]), SPIN, RHO, p)
        np.testing.assert_allclose(F_near, F, atol=1e-6 * abs(F[0]))
        assert np.linalg.norm(M_near) < 1e-6


def test_craft_at_rest_feels_nothing(flight5: Model) -> None:
    F, M, _ = loads(build_aero_loads(Aerodynamics()), np.zeros(3), SPIN, RHO, params(flight5))
    np.testing.assert_array_equal(np.abs(F), 0)
    np.testing.assert_array_equal(np.abs(M), 0)


# --------------------------------------------------------------------------- tables
def table_from_polynomials(n: int) -> Aerodynamics:
    grid = np.linspace(0.0, math.pi / 2, n)
    cols = np.array([paper_eq5(a) for a in grid])
    return Aerodynamics(
        model=AeroModel.TABLE,
        table_alpha=tuple(grid),
        cd=tuple(cols[:, 0]),
        cl=tuple(cols[:, 1]),
        cm=tuple(cols[:, 2]),
    )


def fourth_derivative_bounds() -> np.ndarray:
    """Bounds on the fourth derivatives of the Eq. 5 C_D, C_L, C_M on [0, pi/2]."""
    a = np.linspace(0, math.pi / 2, 2001)
    return np.array(
        [
            0.0,
            np.max(np.abs(120 * 0.1993 * a - 24 * 0.3317)),
            np.max(np.abs(360 * 0.1598 * a**2 - 120 * 0.6619 * a + 24 * 0.8794)),
        ]
    )


def spline_error_bound(folded_alpha: float, n: int) -> np.ndarray:
    """Cubic-spline error on a grid of step h: values O(h^4 C4), slopes O(h^3 C4).

    The table is exact at alpha = 0, so near 0 the error is also below alpha times the
    slope error. The constant 1 is generous for the not-a-knot ends.
    """
    h = (math.pi / 2) / (n - 1)
    d4 = fourth_derivative_bounds()
    return np.minimum(h**4 * d4, folded_alpha * h**3 * d4) + 1e-14


def test_table_sampled_from_polynomials_agrees_to_interpolation_error() -> None:
    n = 91
    table = table_from_polynomials(n)
    for alpha in np.linspace(0.0, math.pi, 157):
        err = np.abs(coefficients(alpha, table) - coefficients(alpha, Aerodynamics()))
        bound = spline_error_bound(min(alpha, math.pi - alpha), n)
        assert np.all(err <= bound), (alpha, err, bound)


def test_table_loads_agree_with_polynomial_loads(flight5: Model) -> None:
    """Loads differ by q S (times c) the coefficient interpolation error, no more."""
    n = 91
    p = params(flight5)
    f_poly = build_aero_loads(Aerodynamics())
    f_table = build_aero_loads(table_from_polynomials(n))
    D = 0.1222
    for v in [*ORDINARY, np.array([10.0, 0.0, 0.0]), np.array([-10.0, 0.0, 1e-3])]:
        F1, M1, alpha = loads(f_poly, v, SPIN, RHO, p)
        F2, M2, _ = loads(f_table, v, SPIN, RHO, p)
        qS = 0.5 * RHO * (v @ v) * math.pi * D**2 / 4
        e_d, e_l, e_m = spline_error_bound(min(alpha, math.pi - alpha), n)
        assert np.linalg.norm(F2 - F1) <= qS * (e_d + e_l)
        assert np.linalg.norm(M2 - M1) <= qS * D * e_m


def test_short_table_falls_back_to_linear() -> None:
    grid = (0.0, 0.8, math.pi / 2)
    table = Aerodynamics(
        model=AeroModel.TABLE,
        table_alpha=grid,
        cd=(0.7, 0.6, 0.9),
        cl=(0.0, 0.5, 0.4),
        cm=(0.0, 0.05, 0.06),
    )
    np.testing.assert_allclose(coefficients(0.4, table), [0.65, 0.25, 0.025], rtol=1e-12)
    np.testing.assert_allclose(coefficients(math.pi - 0.8, table), [0.6, 0.5, 0.05], rtol=1e-12)


# --------------------------------------------------------------------------- Magnus
def test_magnus_off_by_default(flight5: Model) -> None:
    f = build_aero_loads(Aerodynamics())
    p = params(flight5)
    for v in ORDINARY:
        F0, M0, _ = loads(f, v, 0.0, RHO, p)
        F1, M1, _ = loads(f, v, SPIN, RHO, p)
        np.testing.assert_array_equal(F1, F0)
        np.testing.assert_array_equal(M1, M0)


def test_magnus_along_b1_cross_v_when_on(flight5: Model) -> None:
    cf, cm = 0.15, 0.03
    f = build_aero_loads(Aerodynamics())
    p = params(flight5, magnus_force_coefficient=cf, magnus_moment_coefficient=cm)
    b1 = np.array([1.0, 0.0, 0.0])
    D = 0.1222
    S = math.pi * D**2 / 4
    for v in ORDINARY:
        F0, M0, _ = loads(f, v, 0.0, RHO, p)
        F1, M1, _ = loads(f, v, SPIN, RHO, p)
        dF, dM = F1 - F0, M1 - M0
        expected_dir = np.cross(b1, v) / np.linalg.norm(np.cross(b1, v))
        assert dF @ expected_dir == pytest.approx(np.linalg.norm(dF), rel=1e-12)
        # q S C (w D / 2V) |b1 x v_hat| = C rho S (w D / 4) |b1 x v|
        assert np.linalg.norm(dF) == pytest.approx(
            cf * RHO * S * SPIN * D / 4 * np.linalg.norm(np.cross(b1, v)), rel=1e-12
        )
        # moment of that force applied (cm / cf) D ahead of the mass centre
        np.testing.assert_allclose(dM, np.cross((cm / cf) * D * b1, dF), rtol=1e-12, atol=1e-18)


# --------------------------------------------------------------------------- units
def test_units_density_and_diameter_scaling(flight5: Model) -> None:
    """Dimensional check: F, M ~ rho; F ~ D^2 at fixed reference length (Magnus off)."""
    f = build_aero_loads(Aerodynamics())
    p = params(flight5)
    p2 = params(flight5, diameter=2 * 0.1222)
    for v in ORDINARY:
        F, M, _ = loads(f, v, SPIN, RHO, p)
        F_rho, M_rho, _ = loads(f, v, SPIN, 2 * RHO, p)
        F_d, M_d, _ = loads(f, v, SPIN, RHO, p2)
        np.testing.assert_allclose(F_rho, 2 * F, rtol=1e-13, atol=1e-300)
        np.testing.assert_allclose(M_rho, 2 * M, rtol=1e-13, atol=1e-300)
        np.testing.assert_allclose(F_d, 4 * F, rtol=1e-13, atol=1e-300)
        np.testing.assert_allclose(M_d, 4 * M, rtol=1e-13, atol=1e-300)


# --------------------------------------------------------------------------- Function
def test_function_signature() -> None:
    f = build_aero_loads(Aerodynamics())
    assert f.name() == "aero_loads"
    assert f.name_in() == ["v_air_B", "w_rotor", "rho", "p"]
    assert f.name_out() == ["F_B", "M_B", "alpha"]
    assert f.numel_in(3) == PARAMETERS.size


def test_expressions_work_on_mx() -> None:
    v = ca.MX.sym("v", 3)
    p = ca.MX.sym("p", PARAMETERS.size)
    F, M, alpha = aero_loads(v, ca.MX.sym("w"), ca.MX.sym("rho"), p, table_from_polynomials(20))
    assert isinstance(F, ca.MX) and isinstance(M, ca.MX) and isinstance(alpha, ca.MX)


@pytest.mark.parametrize("kind", ["polynomial", "table"])
def test_jacobian_matches_finite_differences(kind: str, flight5: Model) -> None:
    aero = Aerodynamics() if kind == "polynomial" else table_from_polynomials(91)
    f = build_aero_loads(aero)
    rng = np.random.default_rng(5)
    p = params(
        flight5,
        cd_scale=1.2,
        cl_scale=0.9,
        cm_scale=1.1,
        magnus_force_coefficient=0.1,
        magnus_moment_coefficient=0.02,
    )
    for _ in range(4):
        v = rng.uniform(-20, 20, 3)
        w = rng.uniform(500, 1100)
        rho = rng.uniform(0.9, 1.2)
        assert_jacobians_match_finite_differences(
            f, [v, w, rho, p], rtol=1e-6, scale=[10.0, 1000.0, 1.0, 1.0]
        )


def test_gyroscopic_stability_factor_flight5(flight5: Model) -> None:
    """docs/physics.md#gyroscopic-stability (derived): S_g = H^2 / (4 I M_alpha) ~ 860 at 20 m/s."""
    f = build_aero_loads(Aerodynamics())
    alpha = 1e-4
    v = 20.0 * np.array([math.cos(alpha), math.sin(alpha), 0.0])
    _, M, _ = loads(f, v, SPIN, RHO, params(flight5))
    m_alpha = np.linalg.norm(M) / alpha  # N m / rad
    H = flight5.craft.inertia_axial * SPIN
    s_g = H**2 / (4 * flight5.craft.inertia_transverse * m_alpha)
    assert s_g == pytest.approx(860, rel=0.01)
