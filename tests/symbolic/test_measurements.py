"""The sensors' measurement Functions (symbolic/maps/measurements.py): the camera's coast
backwards against the plant's own dense coast along a Flight 5 climb, bearings that
triangulate back to the position, and every Function's derivatives against finite
differences."""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences, state_step_scale

import lightcraft_opt as lc
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import STATE, initial_state, nominal_inputs, parameter_values
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.measurements import (
    bearings_from,
    build_camera_position,
    build_gyro,
    build_spin_sensor,
    build_stereo_bearings,
)
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.terms.gravity import build_gravity

#: Two tracking mounts, 30 m east and 40 m south of the pad, 1 m up.
SITES = ((30.0, 0.0, 1.0), (0.0, -40.0, 1.0))
DENSE = 32  # plant states a coast: every substep of Φ's default 32


@functools.cache
def _flight5() -> Model:
    return lc.load_model("models/flight5.toml")


@functools.cache
def _climb(coning_deg: float) -> tuple[np.ndarray, list[np.ndarray], float]:
    """Flight 5 from 2 m at 4 m/s, 1 cm off the beam and coning by ``coning_deg``, 40
    pulses under the nominal inputs: the nodes (41, STATE.size) and each coast's dense
    states (STATE.size, DENSE), the last the next node; the pulse period [s]."""
    model = _flight5()
    phi = lc.build_pulse_map(model, PulseMapOptions(substeps=DENSE, dense=DENSE))
    x = initial_state(
        model, r_L=(0.01, 0.0, 2.0), v_L=(0.0, 0.0, 4.0), coning=np.radians(coning_deg)
    )
    u, p = nominal_inputs(model, phi.inputs), parameter_values(model)
    nodes, coasts = [x], []
    for k in range(40):
        X = np.asarray(phi.dense(nodes[-1], u, p, k * phi.period)[0])
        coasts.append(X)
        nodes.append(X[:, -1])
    return np.array(nodes), coasts, phi.period


@pytest.mark.parametrize(("coning_deg", "bound"), [(0.5, 6e-5), (3.0, 4e-4)])
def test_the_camera_coast_backwards_is_the_plants_within_its_stated_bound(
    coning_deg: float, bound: float
) -> None:
    """Every dense state of every coast (and the position the coast started from, at dt =
    one period) against camera_position(node, p, dt): within the bound the module
    docstring states (measured 0.048 mm at 0.5 degrees of coning, 0.36 mm at 3), while
    gravity and the frame terms alone leave more than 20 mm (the drag reaches 40 m/s²)."""
    model, p = _flight5(), parameter_values(_flight5())
    nodes, coasts, T = _climb(coning_deg)
    camera = build_camera_position(model).map(DENSE)
    gravity = build_gravity(model.environment)
    r, v = STATE.index("r_L"), STATE.index("v_L")
    assert nodes[-1][v][2] > 10.0  # a real climb, past 10 m/s: the drag above 15 m/s²
    dt = T * (1.0 - np.arange(1, DENSE + 1) / DENSE)
    dt[-1] = T  # the last column is the node itself: compare the coast's start instead
    worst = worst_gravity = 0.0
    for k, X in enumerate(coasts):
        node = X[:, -1]
        truth = np.c_[X[r, :-1], nodes[k][r]]  # position is continuous through the pulse
        seen = np.asarray(camera(np.tile(node[:, None], DENSE), p, dt[None, :]))
        worst = max(worst, float(np.abs(seen - truth).max()))
        a = np.asarray(gravity(node[r], node[v], p)).ravel()
        ballistic = node[r][:, None] - np.outer(node[v], dt) + 0.5 * np.outer(a, dt**2)
        worst_gravity = max(worst_gravity, float(np.abs(ballistic - truth).max()))
    assert worst < bound, f"{worst * 1e3:.4f} mm"
    assert worst_gravity > 2e-2, f"{worst_gravity * 1e3:.1f} mm"


def test_the_camera_sees_the_node_itself_at_dt_zero() -> None:
    nodes, _, _ = _climb(0.5)
    model = _flight5()
    y = build_camera_position(model)(nodes[20], parameter_values(model), 0.0)
    assert np.array_equal(np.asarray(y).ravel(), nodes[20][STATE.index("r_L")])


def _triangulated(y: np.ndarray, sites: tuple[tuple[float, ...], ...]) -> np.ndarray:
    """The point nearest every mount's ray (least squares), from (azimuth, elevation)
    pairs: the rays rebuilt independently of the Function from the stated convention."""
    A, b = np.zeros((3, 3)), np.zeros(3)
    for i, site in enumerate(np.asarray(sites)):
        az, el = y[2 * i], y[2 * i + 1]
        f = np.r_[-site[:2] / np.hypot(*site[:2]), 0.0]
        e = np.array([f[1], -f[0], 0.0])
        d = np.cos(el) * (np.cos(az) * f + np.sin(az) * e) + np.sin(el) * np.array([0, 0, 1.0])
        P = np.eye(3) - np.outer(d, d)  # projector across the ray
        A += P
        b += P @ site
    return np.linalg.solve(A, b)


@pytest.mark.parametrize("dt", [0.0, 0.013])
def test_two_mounts_bearings_triangulate_back_to_the_position(dt: float) -> None:
    """Noise-free, the two rays meet at the camera's position to 1e-9 m."""
    model = _flight5()
    nodes, _, _ = _climb(0.5)
    p = parameter_values(model)
    stereo = build_stereo_bearings(model, SITES)
    camera = build_camera_position(model)
    for x in nodes[::8]:
        y = np.asarray(stereo(x, p, dt)).ravel()
        r = np.asarray(camera(x, p, dt)).ravel()
        assert np.linalg.norm(_triangulated(y, SITES) - r) < 1e-9


def test_bearing_conventions_on_a_known_point() -> None:
    """A point 10 m above the pad from a mount 10 m south on the ground: azimuth 0 (on the
    line to the pad), elevation 45 degrees; 10 m east of the pad at the same height the
    mount sees it 45 degrees to its right (east) at atan(10 / sqrt(200))."""
    r = ca.SX.sym("r", 3)
    f = ca.Function("b", [r], [bearings_from(r, [(0.0, -10.0, 0.0)])])
    np.testing.assert_allclose(np.asarray(f([0, 0, 10.0])).ravel(), [0, np.pi / 4], atol=1e-15)
    np.testing.assert_allclose(
        np.asarray(f([10.0, 0, 10.0])).ravel(), [np.pi / 4, np.arctan(10 / np.sqrt(200))]
    )


def test_a_mount_on_the_pads_vertical_is_refused() -> None:
    with pytest.raises(ParameterError, match=r"sites_L\[1\].*off the pad's vertical"):
        build_stereo_bearings(_flight5(), [(30.0, 0.0, 0.0), (0.0, 0.0, 5.0)])


def test_gyro_and_spin_read_their_slots() -> None:
    x = initial_state(_flight5(), w_B=(0.1, -0.2, 0.3))
    p = parameter_values(_flight5())
    assert np.array_equal(np.asarray(build_gyro()(x, p, 0.0)).ravel(), [0.1, -0.2, 0.3])
    spin = float(STATE.get("spin", x))
    assert spin > 1000.0 and float(build_spin_sensor()(x, p, 0.0)) == spin  # 10,000 RPM


@pytest.mark.parametrize("sensor", ["camera_position", "stereo_bearings", "gyro", "spin_sensor"])
def test_derivatives_match_finite_differences(sensor: str) -> None:
    """∂y/∂x, ∂y/∂p, ∂y/∂dt at a climbing, coning node, 20 ms before it."""
    model = _flight5()
    nodes, _, _ = _climb(3.0)
    built = {
        "camera_position": lambda: build_camera_position(model),
        "stereo_bearings": lambda: build_stereo_bearings(model, SITES),
        "gyro": build_gyro,
        "spin_sensor": build_spin_sensor,
    }[sensor]()
    assert built.name() == sensor and built.name_in() == ["x", "p", "dt"]
    assert built.name_out() == ["y"]
    p = parameter_values(model)
    x = nodes[25]
    scale = [state_step_scale(model.craft.mass), np.abs(p) + 1e-3, 1e-2]
    assert_jacobians_match_finite_differences(built, [x, p, 0.02], scale=scale)
