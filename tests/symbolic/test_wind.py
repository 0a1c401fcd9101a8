"""Wind: power-law profile with veer, 1 - cos gust, height and time tables (params.Wind)."""

from __future__ import annotations

import math
from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences

from lightcraft_opt.layout import PARAMETERS, parameter_values
from lightcraft_opt.model import Environment, Model, Wind
from lightcraft_opt.symbolic.terms.wind import build_wind, wind_velocity_L


def with_wind(model: Model, wind: Wind) -> tuple[ca.Function, np.ndarray]:
    """The wind Function and the parameter vector of ``model`` flying in ``wind``."""
    m = replace(model, environment=Environment(wind=wind))
    return build_wind(wind), parameter_values(m)


def at(f: ca.Function, t: float, z: float, p: np.ndarray, east: float = 3.0) -> np.ndarray:
    return np.asarray(f(t, [east, -2.0, z], p)).ravel()


def blowing_from(w: np.ndarray) -> float:
    """Meteorological direction the wind comes from, clockwise from north [rad], 0..2pi."""
    return math.atan2(-w[0], -w[1]) % (2 * math.pi)


SHEAR = Wind(
    speed_ref=6.0,
    height_ref=10.0,
    roughness_height=0.05,
    shear_exponent=0.2,
    direction_from=math.radians(30.0),
    veer=0.004,
)


def test_calm_air_gives_zero(flight5: Model) -> None:
    f, p = with_wind(flight5, Wind())
    for t, z in [(0.0, 0.0), (3.0, 10.0), (7.5, 120.0)]:
        np.testing.assert_array_equal(at(f, t, z, p), 0.0)


def test_speed_ref_at_height_ref_in_stated_direction(flight5: Model) -> None:
    """From 30 deg (NNE): the air moves toward 210 deg, east = -U sin 30, north = -U cos 30."""
    f, p = with_wind(flight5, replace(SHEAR, veer=0.0))
    w = at(f, 1.0, 10.0, p)
    np.testing.assert_allclose(
        w,
        [-6.0 * math.sin(math.radians(30)), -6.0 * math.cos(math.radians(30)), 0.0],
        rtol=1e-14,
        atol=1e-14,
    )


@pytest.mark.parametrize("z", [0.0, 2.0, 25.0, 71.0])
def test_power_law_profile(z: float, flight5: Model) -> None:
    f, p = with_wind(flight5, replace(SHEAR, veer=0.0))
    expected = 6.0 * ((z + 0.05) / (10.0 + 0.05)) ** 0.2
    w = at(f, 1.0, z, p)
    assert np.linalg.norm(w) == pytest.approx(expected, rel=1e-14)
    assert blowing_from(w) == pytest.approx(math.radians(30.0), rel=1e-13)


def test_veer_rotates_direction_not_speed(flight5: Model) -> None:
    f0, p0 = with_wind(flight5, replace(SHEAR, veer=0.0))
    f, p = with_wind(flight5, SHEAR)
    for z in (0.0, 10.0, 50.0, 100.0):
        w0, w = at(f0, 0.0, z, p0), at(f, 0.0, z, p)
        assert np.linalg.norm(w) == pytest.approx(np.linalg.norm(w0), rel=1e-14)
        assert blowing_from(w) == pytest.approx(math.radians(30.0) + 0.004 * z, rel=1e-13)


def test_below_the_pad_sees_ground_level_wind(flight5: Model) -> None:
    f, p = with_wind(flight5, SHEAR)
    np.testing.assert_array_equal(at(f, 0.0, -0.5, p), at(f, 0.0, 0.0, p))
    assert np.all(np.isfinite(at(f, 0.0, -0.5, p)))


def test_horizontal_position_does_not_matter(flight5: Model) -> None:
    f, p = with_wind(flight5, SHEAR)
    np.testing.assert_array_equal(at(f, 0.0, 20.0, p, east=-40.0), at(f, 0.0, 20.0, p, east=9.0))


def test_gust_one_minus_cosine_shape(flight5: Model) -> None:
    gust = (2.0, -1.0, 0.5)
    f, p = with_wind(flight5, Wind(gust_L=gust, gust_start=2.0, gust_duration=1.5))
    g = np.array(gust)
    for t in (0.0, 1.99, 3.51, 10.0):  # before and after
        np.testing.assert_array_equal(at(f, t, 5.0, p), 0.0)
    np.testing.assert_allclose(at(f, 2.75, 5.0, p), g, rtol=1e-14)  # peak at mid-window
    np.testing.assert_allclose(at(f, 2.375, 5.0, p), 0.5 * g, rtol=1e-14)  # quarter: half
    for t in np.linspace(2.0, 3.5, 13):
        shape = (1 - math.cos(2 * math.pi * (t - 2.0) / 1.5)) / 2
        np.testing.assert_allclose(at(f, t, 5.0, p), shape * g, rtol=1e-13, atol=1e-15)


def test_gust_adds_to_the_mean_wind(flight5: Model) -> None:
    f0, p0 = with_wind(flight5, SHEAR)
    f, p = with_wind(flight5, replace(SHEAR, gust_L=(0.0, 3.0, 0.0), gust_start=1.0))
    np.testing.assert_allclose(
        at(f, 1.5, 30.0, p), at(f0, 1.5, 30.0, p0) + np.array([0, 3.0, 0]), rtol=1e-14
    )


def test_numbers_come_from_p_not_from_the_dataclass(flight5: Model) -> None:
    """Calibration and Monte Carlo change p only; the Function follows."""
    f, p = with_wind(flight5, SHEAR)
    p2 = p.copy()
    p2[PARAMETERS.index("wind_speed_ref")] = 12.0
    np.testing.assert_allclose(at(f, 0.0, 33.0, p2), 2 * at(f, 0.0, 33.0, p), rtol=1e-14)


# --------------------------------------------------------------------------- tables
def sampled_profile_table(wind: Wind, heights: np.ndarray) -> Wind:
    speed = (
        wind.speed_ref
        * ((heights + wind.roughness_height) / (wind.height_ref + wind.roughness_height))
        ** wind.shear_exponent
    )
    direction = wind.direction_from + wind.veer * heights
    return Wind(
        table_height=tuple(heights), table_speed=tuple(speed), table_direction_from=tuple(direction)
    )


def test_height_table_agrees_with_power_law(flight5: Model) -> None:
    """Exact at the nodes; between them within the linear-interpolation error h^2/8 |f''|."""
    heights = np.arange(0.0, 201.0, 5.0)
    f_law, p_law = with_wind(flight5, SHEAR)
    f_tab, p_tab = with_wind(flight5, sampled_profile_table(SHEAR, heights))
    for z in heights:
        np.testing.assert_allclose(
            at(f_tab, 0.0, z, p_tab), at(f_law, 0.0, z, p_law), rtol=1e-13, atol=1e-13
        )
    for z in np.linspace(5.0, 200.0, 97):
        w_tab, w_law = at(f_tab, 0.0, z, p_tab), at(f_law, 0.0, z, p_law)
        # speed curvature |U''| = U n (1 - n) / (z + z0)^2, largest at the lower node
        z_lo = 5.0 * math.floor(z / 5.0)
        u_pp = np.linalg.norm(w_law) * 0.2 * 0.8 / (z_lo + 0.05) ** 2
        assert abs(np.linalg.norm(w_tab) - np.linalg.norm(w_law)) <= 25 / 8 * u_pp + 1e-12
        assert blowing_from(w_tab) == pytest.approx(blowing_from(w_law), abs=1e-12)


def test_height_table_takes_the_short_way_round(flight5: Model) -> None:
    table = Wind(
        table_height=(0.0, 100.0),
        table_speed=(4.0, 4.0),
        table_direction_from=(math.radians(350.0), math.radians(10.0)),
    )
    f, p = with_wind(flight5, table)
    w = at(f, 0.0, 50.0, p)
    assert abs(math.remainder(blowing_from(w), 2 * math.pi)) < 1e-12  # from north, not south
    assert np.linalg.norm(w) == pytest.approx(4.0, rel=1e-14)
    # held constant above the top of the table
    np.testing.assert_allclose(at(f, 0.0, 500.0, p), at(f, 0.0, 100.0, p), rtol=1e-14)


def test_gust_table_agrees_with_one_minus_cosine(flight5: Model) -> None:
    gust, t0, T = np.array([1.5, 0.0, -0.5]), 1.0, 2.0
    times = np.linspace(t0, t0 + T, 81)
    shape = (1 - np.cos(2 * math.pi * (times - t0) / T)) / 2
    table = Wind(
        gust_table_time=tuple(times), gust_table_L=tuple(map(tuple, np.outer(shape, gust)))
    )
    f_par, p_par = with_wind(flight5, Wind(gust_L=tuple(gust), gust_start=t0, gust_duration=T))
    f_tab, p_tab = with_wind(flight5, table)
    h = T / 80
    curvature = (2 * math.pi / T) ** 2 / 2 * np.abs(gust)  # max |g''|
    for t in np.linspace(0.0, 4.0, 161):
        err = np.abs(at(f_tab, t, 3.0, p_tab) - at(f_par, t, 3.0, p_par))
        assert np.all(err <= h**2 / 8 * curvature + 1e-14), (t, err)


# --------------------------------------------------------------------------- Function
def test_function_signature() -> None:
    f = build_wind(Wind())
    assert f.name() == "wind"
    assert f.name_in() == ["t", "r_L", "p"]
    assert f.name_out() == ["wind_L"]
    assert f.numel_in(2) == PARAMETERS.size


def test_expressions_work_on_mx() -> None:
    table = sampled_profile_table(SHEAR, np.arange(0.0, 50.0, 10.0))
    w = wind_velocity_L(ca.MX.sym("t"), ca.MX.sym("r", 3), ca.MX.sym("p", PARAMETERS.size), table)
    assert isinstance(w, ca.MX)


@pytest.mark.parametrize("kind", ["parametric", "tables"])
def test_jacobian_matches_finite_differences(kind: str, flight5: Model) -> None:
    gusty = replace(SHEAR, gust_L=(1.0, 2.0, -0.3), gust_start=0.5, gust_duration=3.0)
    if kind == "tables":
        heights = np.arange(0.0, 201.0, 10.0)
        times = np.linspace(0.0, 4.0, 9)
        rows = np.outer(np.sin(times), [1.0, 2.0, -0.3])
        wind = replace(
            sampled_profile_table(gusty, heights),
            gust_table_time=tuple(times),
            gust_table_L=tuple(map(tuple, rows)),
        )
    else:
        wind = gusty
    f, p = with_wind(flight5, wind)
    rng = np.random.default_rng(7)
    for _ in range(4):
        # ordinary points: inside the gust window, away from table nodes and the ground
        t = 0.75 + rng.uniform(0.0, 0.2) + 0.5 * rng.integers(0, 5)
        z = 12.0 + rng.uniform(0.0, 6.0) + 10.0 * rng.integers(0, 15)
        r = np.array([rng.uniform(-20, 20), rng.uniform(-20, 20), z])
        assert_jacobians_match_finite_differences(f, [t, r, p], rtol=1e-6, scale=[1.0, 10.0, 1.0])
