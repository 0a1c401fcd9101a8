"""Ψ's estimation model: F and H against central finite differences (tests/support style)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from support.models import table1_flight5

from lightcraft_opt.control.estimation import EstimationModel
from lightcraft_opt.control.estimation.psi_model import (
    ProcessNoise,
    PsiEstimationModel,
    estimation_model,
)
from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, nominal_inputs

G = 9.80665  # m/s², the camera's fall over dt (a test's own model of the sensor)


def camera() -> ca.Function:
    """A position camera: r_L at the reading's time, dt before the node (ballistic back)."""
    x, p, dt = ca.SX.sym("x", STATE.size), ca.SX.sym("p", PARAMETERS.size), ca.SX.sym("dt")
    r, v = STATE.get("r_L", x), STATE.get("v_L", x)
    y = r - v * dt - 0.5 * G * dt**2 * ca.DM([0, 0, 1])
    return ca.Function("camera", [x, p, dt], [y], ["x", "p", "dt"], ["y"])


def gyro() -> ca.Function:
    """A gyro: the transverse body rates w_B[b2, b3] [rad/s]."""
    x, p, dt = ca.SX.sym("x", STATE.size), ca.SX.sym("p", PARAMETERS.size), ca.SX.sym("dt")
    return ca.Function("gyro", [x, p, dt], [STATE.get("w_B", x)[1:]], ["x", "p", "dt"], ["y"])


@pytest.fixture(scope="module")
def model() -> PsiEstimationModel:
    sensors = {"camera": (camera(), 0.005**2 * np.eye(3)), "gyro": (gyro(), 0.01**2 * np.eye(2))}
    return PsiEstimationModel(estimation_model(table1_flight5()), sensors, compiled=False)


def _state(model: PsiEstimationModel, wind: tuple[float, float]) -> np.ndarray:
    x0 = initial_state(model.model, r_L=(0.01, 0.0, 2.0), v_L=(0.0, 0.0, 4.0), w_B=(0, 0.3, -0.2))
    s = model.start(x0)
    s[model.names.index("wind_L[east]") :][:2] = wind
    return s


def _fd(f, s: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Central differences of f at s, steps 1e-5 of each entry's scale."""
    cols = []
    for j in range(s.size):
        e = np.zeros(s.size)
        e[j] = 1e-5 * scale[j]
        cols.append((f(s + e) - f(s - e)) / (2 * e[j]))
    return np.array(cols).T


def _scale(model: PsiEstimationModel, s: np.ndarray) -> np.ndarray:
    """A step scale per entry: its size, at least a typical error (1e-3 of SI, 1 m/s wind)."""
    scale = np.maximum(np.abs(s), 1e-3)
    scale[model.names.index("wind_L[east]") :][:2] = 1.0
    return scale


def test_meets_the_protocol(model: PsiEstimationModel) -> None:
    assert isinstance(model, EstimationModel)
    assert model.names[-3:] == ("wind_L[east]", "wind_L[north]", "coupling")


@pytest.mark.parametrize("wind", [(3.0, 0.5), (0.0, 0.0)], ids=["crosswind", "calm"])
def test_F_is_psi_jacobian(model: PsiEstimationModel, wind: tuple[float, float]) -> None:
    """F (the compiled chain, the wind columns through p's speed and direction, the
    coupling's through the energy column) against central differences of f, each row
    relative to its largest entry: 1e-6 (the differences' truncation error is ~1e-10)."""
    s = _state(model, wind)
    u = nominal_inputs(model.model, model.psi.inputs)
    _, F = model.predict(s, u, 0.0)
    F_fd = _fd(lambda v: model.predict(v, u, 0.0)[0], s, _scale(model, s))
    row = np.abs(F_fd).max(axis=1, keepdims=True)
    assert np.all(np.abs(F - F_fd) <= 1e-6 * row + 1e-12)
    # the slow states are held (random walks)
    assert np.array_equal(F[14:], np.eye(model.n)[14:])
    assert np.abs(F[3:6, 14:16]).max() > 1e-4  # the wind does push the craft


@pytest.mark.parametrize("sensor", ["camera", "gyro"])
def test_H_is_the_lifted_sensor_jacobian(model: PsiEstimationModel, sensor: str) -> None:
    s = _state(model, (3.0, 0.5))
    dt = 0.4 * model.period
    y, H = model.measure(sensor, s, dt)
    H_fd = _fd(lambda v: model.measure(sensor, v, dt)[0], s, _scale(model, s))
    row = np.abs(H_fd).max(axis=1, keepdims=True)
    assert np.all(np.abs(H - H_fd) <= 1e-6 * row + 1e-12)
    if sensor == "camera":  # the position dt before the node, falling ballistically
        r, v = s[0:3], s[3:6]
        np.testing.assert_allclose(y, r - v * dt - 0.5 * G * dt**2 * np.array([0, 0, 1]))


def test_slow_states_round_trip(model: PsiEstimationModel) -> None:
    """p built from the slow states holds them: the wind from the west at 3 m/s blows east;
    the coupling is Flight 5's C = 0.0637 / 420 N s/J."""
    s = _state(model, (3.0, 0.0))
    p = model.parameters(s)
    assert p[PARAMETERS.slot("wind_speed_ref").start] == pytest.approx(3.0)
    assert p[PARAMETERS.slot("wind_direction_from").start] == pytest.approx(-np.pi / 2)
    assert model.slow_values()[-1] == pytest.approx(0.0637 / 420.0)
    np.testing.assert_allclose(
        PsiEstimationModel(model.model, {}, slow=("wind",), compiled=False).slow_values(p),
        s[14:16],
        atol=1e-12,
    )


def test_bad_slow_states_are_named(model: PsiEstimationModel) -> None:
    with pytest.raises(OptionError, match="slow"):
        PsiEstimationModel(model.model, {}, slow=("gusts",), compiled=False)


@pytest.mark.parametrize("kind", ["position", "stereo"])
def test_the_sensor_suites_functions_plug_in(kind: str) -> None:
    """The SensorSuite's own h (the camera's coast backwards, or two stations' bearings;
    the gyro's w_B; the spin counter) composed with Ψ's lift: H against central
    differences, to 1e-6 of each row."""
    from lightcraft_opt.control.estimation import (
        CameraKind,
        CameraOptions,
        GyroOptions,
        SensorOptions,
        SensorSuite,
        SpinSensorOptions,
    )

    plant = table1_flight5()
    camera_options = (
        CameraOptions()
        if kind == "position"
        else CameraOptions(
            kind=CameraKind.STEREO, sites=((-30.0, 0.0, 0.0), (0.0, -30.0, 0.0)), noise=1e-4
        )
    )
    suite = SensorSuite(
        plant, SensorOptions(camera_options, gyro=GyroOptions(), spin=SpinSensorOptions())
    )
    sensors = {n: (suite.measurement(n), suite.covariance(n)) for n in suite.names}
    model = PsiEstimationModel(estimation_model(plant), sensors, slow=("coupling",), compiled=False)
    s, dt = _state_of(model), 0.3 * model.period
    for name in suite.names:
        _, H = model.measure(name, s, dt)
        H_fd = _fd(lambda v, n=name: model.measure(n, v, dt)[0], s, np.maximum(np.abs(s), 1e-3))
        row = np.abs(H_fd).max(axis=1, keepdims=True)
        assert np.all(np.abs(H - H_fd) <= 1e-6 * row + 1e-12), name


def _state_of(model: PsiEstimationModel) -> np.ndarray:
    x0 = initial_state(model.model, r_L=(0.01, 0.0, 2.0), v_L=(0.0, 0.0, 4.0), w_B=(0, 0.3, -0.2))
    return model.start(x0)


def test_the_moments_columns_are_psis_derivative() -> None:
    """With the rotor's moments as slow states (the estimators the factory builds), F's
    columns in them (the pieces' Jacobians in p's moments, chained) against central
    differences of f (step 1e-5): rows to 1e-6 of their largest entry; the
    transverse moment turns the cone (its column's coning rows are not zero; the axial
    moment enters Ψ's step only through the lift, the spin that |H| means)."""
    sensors = {"camera": (camera(), 0.005**2 * np.eye(3))}
    model = PsiEstimationModel(
        estimation_model(table1_flight5()),
        sensors,
        slow=("wind", "coupling", "inertia"),
        compiled=False,
    )
    assert model.names[-2:] == ("inertia[transverse]", "inertia[axial]")
    s = _state(model, (3.0, 0.5))
    np.testing.assert_array_equal(s[-2:], [1.0, 1.0])  # the model's moments
    u = nominal_inputs(model.model, model.psi.inputs)
    _, F = model.predict(s, u, 0.0)
    F_fd = _fd(lambda v: model.predict(v, u, 0.0)[0], s, _scale(model, s))
    row = np.abs(F_fd).max(axis=1, keepdims=True)
    assert np.all(np.abs(F - F_fd) <= 1e-6 * row + 1e-12)
    cone = [model.names.index("coning[e1]"), model.names.index("coning[e2]")]
    assert np.abs(F[cone, -2]).min() > 0.01


def test_the_moments_columns_are_exact() -> None:
    """The transverse moment's column of F is Ψ's derivative itself, not a difference:
    central differences of f in it approach it at second order (a tenth of the step, a
    hundredth of the error: 1.9e-6 at 1e-4, 1.9e-8 at 1e-5, of a column of 0.41), where
    the forward differences it replaced (step 1e-7) were 1e-6 of the column off."""
    model = PsiEstimationModel(
        estimation_model(table1_flight5()),
        {"camera": (camera(), 0.005**2 * np.eye(3))},
        slow=("wind", "coupling", "inertia"),
        compiled=False,
    )
    s = _state(model, (3.0, 0.5))
    u = nominal_inputs(model.model, model.psi.inputs)
    _, F = model.predict(s, u, 0.0)
    j = model.names.index("inertia[transverse]")
    column = F[:, j]

    def error(step: float) -> float:
        e = np.zeros(s.size)
        e[j] = step
        central = (model.predict(s + e, u, 0.0)[0] - model.predict(s - e, u, 0.0)[0]) / (2 * step)
        return float(np.abs(central - column).max())

    big, small = error(1e-4), error(1e-5)
    assert small <= 1e-7 * np.abs(column).max()
    assert 50.0 <= big / small <= 200.0


def test_the_estimator_chain_is_the_directors_in_its_columns(model: PsiEstimationModel) -> None:
    """The estimator's chain (psi_chain.py: its pieces differentiate in z, the energy and
    the wind's entries of p only) against Ψ's full chain (reduced_map_derivatives.py, the
    director's): the same z_next, ∂z_next/∂z and energy column, to 1e-12 of each one's
    largest entry (the same derivatives, summed in another order)."""
    from lightcraft_opt.layout import PULSE_INPUT
    from lightcraft_opt.symbolic.maps.reduced_map_derivatives import (
        build_reduced_map_derivatives,
    )

    s = _state(model, (3.0, 0.5))
    u = nominal_inputs(model.model, model.psi.inputs)
    p, z = model.parameters(s), s[:14]
    ours = model._stage(z, u, p, 0.1)
    z_next, _, A, B = build_reduced_map_derivatives(model.psi).stage(z, u, p, 0.1)
    energy = PULSE_INPUT.slot("energy").start
    for got, want in ((ours[:, 0], z_next), (ours[:, 1:15], A), (ours[:, 15], B[:, energy])):
        want = np.asarray(want).reshape(np.shape(got))
        assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()


@pytest.mark.parametrize("sensor", ["camera", "gyro"])
def test_measure_many_is_measure_row_by_row(model: PsiEstimationModel, sensor: str) -> None:
    """measure_many (the sensor's Function mapped over the rows, what the MHE reads its
    window with) gives each row's measure bit for bit, a row in calm air included."""
    rng = np.random.default_rng(5)
    s = _state(model, (3.0, 0.5))
    S = s + 1e-3 * np.abs(s).max() * rng.normal(size=(4, model.n)) * (s != 0)
    S[2, model.names.index("wind_L[east]") :][:2] = 0.0  # calm
    dts = np.array([0.0, 0.01, 0.02, 0.03])
    Y, H = model.measure_many(sensor, S, dts)
    for i in range(4):
        y, h = model.measure(sensor, S[i], dts[i])
        np.testing.assert_array_equal(Y[i], y)
        np.testing.assert_array_equal(H[i], h)


def test_many_points_are_each_points_prediction(model: PsiEstimationModel) -> None:
    """predict_many (Ψ's value chain mapped over rows, for the unscented filter) gives each
    row's predict value to the last bit, calm rows included; parameters_many each row's
    parameters to 1e-15 (numpy's hypot against math's)."""
    rng = np.random.default_rng(2)
    S = (
        _state(model, (3.0, 0.5))
        + rng.normal(size=(5, model.n)) * _scale(model, _state(model, (3.0, 0.5))) * 1e-2
    )
    S[0, model.names.index("wind_L[east]") :][:2] = 0.0  # calm air
    u = nominal_inputs(model.model, model.psi.inputs)
    want = np.array([model.predict(s, u, 0.1)[0] for s in S])
    np.testing.assert_array_equal(model.predict_many(S, u, 0.1), want)
    P = np.array([model.parameters(s) for s in S])
    np.testing.assert_allclose(model.parameters_many(S), P, rtol=1e-15, atol=0)


def test_a_sampled_turn_keeps_the_cone(model: PsiEstimationModel) -> None:
    """sample_next with every noise negligible but the cone's phase (ProcessNoise.inertia):
    Ψ's prediction with its coning offset turned, |c| kept to 1e-14; the turns' standard
    deviation over 400 draws |H| T / A · 0.01 to 10 % (its sampling error is 3.5 %)."""
    negligible = ("position", "velocity", "angular_momentum", "coning", "mass", "load", "wind")
    noise = ProcessNoise(**{name: 1e-18 for name in (*negligible, "coupling")})
    quiet = PsiEstimationModel(model.model, {}, noise=noise, compiled=False)
    s = quiet.start(initial_state(quiet.model, r_L=(0.01, 0.0, 2.0), v_L=(0.0, 0.0, 4.0)))
    cone = [quiet.names.index("coning[e1]"), quiet.names.index("coning[e2]")]
    s[cone] = (0.02, -0.01)
    u = nominal_inputs(quiet.model, quiet.psi.inputs)
    mean = quiet.predict(s, u, 0.0)[0]
    rng = np.random.default_rng(4)
    turns = []
    for _ in range(400):
        drawn = quiet.sample_next(s, u, 0.0, rng)
        np.testing.assert_allclose(np.delete(drawn, cone), np.delete(mean, cone), rtol=0, atol=1e-9)
        c, c0 = drawn[cone], mean[cone]
        assert np.hypot(*c) == pytest.approx(np.hypot(*c0), rel=1e-14)
        turns.append(np.arctan2(c0[0] * c[1] - c0[1] * c[0], c0 @ c))
    H = s[[quiet.names.index(f"H_L[{a}]") for a in ("east", "north", "up")]]
    sigma = np.linalg.norm(H) * quiet.period / quiet.model.craft.inertia_transverse * 0.01
    assert np.std(turns) == pytest.approx(sigma, rel=0.1)
