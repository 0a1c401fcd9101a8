"""Gravity and the rotating site frame.

References: Newton's inverse-square law; the WGS-84 normal gravity (Somigliana's
closed form, NIMA TR8350.2 Eq. 4-1, docs/references.md#nima-tr8350) which, on the
ellipsoid, is gravity plus centrifugal acceleration and is normal to the ellipsoid; the
Coriolis term -2 W x v.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences
from support.models import table1_flight5
from support.paths import MODELS

from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import PARAMETERS, parameter_values
from lightcraft_opt.model import Environment
from lightcraft_opt.symbolic.terms.gravity import (
    EARTH_GM,
    EARTH_RATE,
    build_gravity,
    dcm_EL,
    site_position_E,
)


def _somigliana(lat: float) -> float:
    s2 = math.sin(lat) ** 2
    return 9.7803253359 * (1 + 0.00193185265241 * s2) / math.sqrt(1 - 0.00669437999013 * s2)


def test_inverse_square_gravity_at_the_pad():
    model = table1_flight5()
    p = parameter_values(model)
    g = np.asarray(
        build_gravity(Environment(gravity_j2=False, earth_rotation=False))([0, 0, 0], [0, 0, 0], p)
    ).ravel()
    lat, lon, h = model.site.latitude, model.site.longitude, model.site.height
    R = np.asarray(site_position_E(lat, lon, h)).ravel()
    assert np.linalg.norm(g) == pytest.approx(EARTH_GM / (R @ R), rel=1e-14)
    # pointing at the Earth's centre
    R_EL = np.asarray(dcm_EL(lat, lon))
    assert (R_EL @ g) / np.linalg.norm(g) == pytest.approx(-R / np.linalg.norm(R), abs=1e-14)


def test_j2_gravity_with_rotation_is_wgs84_normal_gravity_on_the_ellipsoid():
    model = table1_flight5()
    p = parameter_values(model)
    p[PARAMETERS.index("site_height")] = 0.0  # on the ellipsoid, where Somigliana holds
    g = np.asarray(build_gravity(Environment(gravity_j2=True))([0, 0, 0], [0, 0, 0], p)).ravel()
    # magnitude to the size of the neglected J4 and higher terms
    assert np.linalg.norm(g) == pytest.approx(_somigliana(model.site.latitude), rel=2e-5)
    # direction: along -up, deflection of the vertical below 1e-5 rad
    assert math.hypot(g[0], g[1]) / abs(g[2]) < 1e-5


#: The flight models shipped in models/ (site and laser files hold no [craft]).
FLIGHT_MODELS = sorted(f for f in MODELS.glob("*.toml") if "[craft]" in f.read_text())


@pytest.mark.parametrize("path", [None, *FLIGHT_MODELS], ids=lambda f: f.stem if f else "default")
def test_shipped_gravity_is_plumb_along_the_launch_frame_up(path):
    """L's up is the WGS-84 ellipsoid normal. The shipped environments (every model file, and
    Environment()) put gravity plus the centripetal term along it at the pad, to the J2-only
    field's deflection of the vertical (< 1e-5 rad; inverse-square would be 1.5e-3 rad off,
    docs/physics.md#gravity)."""
    model = table1_flight5() if path is None else load_model(path)
    g = np.asarray(
        build_gravity(model.environment)([0, 0, 0], [0, 0, 0], parameter_values(model))
    ).ravel()
    assert math.hypot(g[0], g[1]) / abs(g[2]) < 1e-5


def test_coriolis_acceleration_is_minus_two_omega_cross_v():
    model = table1_flight5()
    p = parameter_values(model)
    f = build_gravity(Environment())
    v = np.array([3.0, -4.0, 20.0])
    dv = np.asarray(f([0, 0, 10], v, p) - f([0, 0, 10], [0, 0, 0], p)).ravel()
    lat = model.site.latitude
    W = EARTH_RATE * np.array([0.0, math.cos(lat), math.sin(lat)])
    # exact up to the round-off of subtracting two ~9.8 m/s^2 accelerations
    assert dv == pytest.approx(-2 * np.cross(W, v), rel=1e-12, abs=1e-14)


def test_gravity_jacobians_match_finite_differences():
    model = table1_flight5()
    f = build_gravity(Environment(gravity_j2=True))
    assert_jacobians_match_finite_differences(
        f,
        [np.array([3.0, -2.0, 40.0]), np.array([1.0, 2.0, 15.0]), parameter_values(model)],
        scale=[1e3, 1.0, 1.0],  # r_L sits on a 6.4e6 m lever: larger steps beat round-off
    )
