"""Calibration: a synthetic track from known parameters is recovered within 3 σ; what the
data cannot see is flagged; bad input gets clear errors.

References: the "truth" is flown by :func:`simulate` (the numeric path, not the CasADi
residual graph), sampled at irregular video times with a gap and Gaussian noise of 7 mm per
axis (a 10 cm craft tracked on video); the recovered values must lie within 3 standard
deviations of the truth, and the standard deviations must be small in physical terms.
Flight 5's model uses the sector impulse model, in which ``tipping_gain`` does not enter
at all (symbolic/terms/engine.py): a parameter the data cannot identify by construction.
"""

from __future__ import annotations

import dataclasses as dc
from types import SimpleNamespace

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.calibration.fit import CalibrationOptions, calibrate
from lightcraft_opt.calibration.parameters import fit_components
from lightcraft_opt.calibration.problem import Track, build_calibration_problem, initial_values
from lightcraft_opt.calibration.result import CalibrationStatus, FlagKind
from lightcraft_opt.errors import OptionError, ParameterError, ProblemFileError
from lightcraft_opt.files.calibration_outputs import write_fitted_model
from lightcraft_opt.files.model import load_model
from lightcraft_opt.files.track import read_track
from lightcraft_opt.layout import initial_state, parameter_values
from lightcraft_opt.model import Model
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_sensitivities import build_dense_sensitivity

MODEL_FILE = REPO_ROOT / "models" / "flight5.toml"
NOISE = 0.007  # m, per axis
# 16 substeps instead of 32: within 2e-4 m of a 64-substep reference over these flights
# (test_residual_at_the_truth_is_the_interpolation_error), 1/35 of the noise, at half the cost.
FIT_MAP = PulseMapOptions(substeps=16, dense=8)
OPTIONS = CalibrationOptions(pulse_map=FIT_MAP)


@pytest.fixture(scope="module")
def model() -> Model:
    return load_model(MODEL_FILE)


@pytest.fixture(scope="module")
def fit_map(model: Model):
    return build_pulse_map(model, FIT_MAP)


def truth_model(model: Model, cm_factor: float, blast_angle: float) -> Model:
    engine = dc.replace(model.craft.engine, blast_angle=blast_angle)
    return dc.replace(
        model,
        flight=dc.replace(
            model.flight, impulse_per_pulse=model.flight.impulse_per_pulse * cm_factor
        ),
        craft=dc.replace(model.craft, engine=engine),
    )


def video_track(true: Model, x0: np.ndarray, duration: float, seed: int, noise: float) -> Track:
    """Positions of ``true``'s flight at 60 frames/s with ±3 ms jitter, a 0.2 s gap lost
    by the tracker, and Gaussian noise; linear interpolation of a 1.2 ms dense output
    (its error, a h²/8 ~ 2e-6 m, is far below the noise)."""
    sim = simulate(true, duration + 0.05, x0=x0, options=PulseMapOptions(substeps=64, dense=32))
    rng = np.random.default_rng(seed)
    frames = np.arange(0.01, duration, 1 / 60)
    t = frames + rng.uniform(-0.003, 0.003, frames.size)
    t = t[(t < 0.5 * duration) | (t > 0.5 * duration + 0.2)]
    r = np.column_stack([np.interp(t, sim.t, sim.x[:, i]) for i in range(3)])
    return Track(t, r + rng.normal(0.0, noise, r.shape), gaps=12, source="synthetic")


TRUE_OFFSET = (0.008, -0.005)  # m
TRUE_TILT, TRUE_AZIMUTH = 0.015, 0.7  # rad


@pytest.fixture(scope="module")
def recovery(model: Model, fit_map):
    true = truth_model(model, 1.03, 0.47)
    x0 = initial_state(true, r_L=(*TRUE_OFFSET, 0.0), tilt=TRUE_TILT, tilt_azimuth=TRUE_AZIMUTH)
    track = video_track(true, x0, 1.5, seed=1, noise=NOISE)
    result = calibrate(
        model, track, ["cm", "offset", "tilt", "blast_angle"], options=OPTIONS, pulse_map=fit_map
    )
    truth = {
        "cm": true.flight.impulse_per_pulse / true.flight.pulse_energy,
        "launch_offset_x": TRUE_OFFSET[0],
        "launch_offset_y": TRUE_OFFSET[1],
        # small-angle components of the lean (quaternion_from_tilt vs the two rotations
        # of the fit differ by O(tilt^2) ~ 2e-4 rad, far below their std)
        "launch_tilt_x": TRUE_TILT * np.sin(TRUE_AZIMUTH),
        "launch_tilt_y": TRUE_TILT * np.cos(TRUE_AZIMUTH),
        "blast_angle": 0.47,
    }
    return result, truth


def test_synthetic_track_is_recovered_within_3_sigma(recovery):
    result, truth = recovery
    assert result.status is CalibrationStatus.CONVERGED, result.message
    # physical tolerances the standard deviations must meet: 0.5 % of Cm, 3 mm, 5 mrad,
    # 0.03 rad of blast angle: otherwise "within 3 sigma" would say little
    tolerance = {
        "cm": 0.005 * truth["cm"],
        "launch_offset_x": 0.003,
        "launch_offset_y": 0.003,
        "launch_tilt_x": 0.005,
        "launch_tilt_y": 0.005,
        "blast_angle": 0.03,
    }
    for name, value in truth.items():
        std = result.std_of(name)
        assert 0 < std < tolerance[name], (name, std)
        assert abs(result.value(name) - value) < 3 * std, (name, result.value(name), value, std)
    assert result.unidentified == ()
    assert not [f for f in result.flags if f.kind is not FlagKind.CORRELATED]
    # the residuals are the noise: σ within 15 % of it on every axis
    assert result.sigma == pytest.approx(NOISE, rel=0.15)
    assert np.all(np.abs(result.rms / NOISE - 1) < 0.15)
    assert result.cost < 0.5 * result.initial_cost
    assert result.residuals.shape == (result.t.size, 3)
    assert result.gaps == 12


def test_statistics_are_consistent(recovery):
    result, _ = recovery
    n = len(result.names)
    assert result.covariance.shape == (n, n)
    np.testing.assert_allclose(result.covariance, result.covariance.T, rtol=1e-12, atol=0)
    np.testing.assert_allclose(np.sqrt(np.diag(result.covariance)), result.std, rtol=1e-12)
    np.testing.assert_allclose(np.diag(result.correlation), 1.0)
    assert np.all(np.abs(result.correlation) <= 1 + 1e-12)
    assert np.all(np.diff(result.singular_values) <= 0)
    assert result.condition == pytest.approx(result.singular_values[0] / result.singular_values[-1])


def test_fitted_model_file_reloads_to_the_fitted_parameters(recovery, tmp_path, model):
    result, _ = recovery
    path = write_fitted_model(result, MODEL_FILE, tmp_path / "fitted.toml")
    reloaded = load_model(path)
    # equal to rounding: derived slots (spent_coupling from the coupling written in the
    # file's units) may differ in the last bit
    np.testing.assert_allclose(parameter_values(reloaded), result.p, rtol=1e-15, atol=0)
    assert reloaded.craft.engine.blast_angle == result.value("blast_angle")
    assert reloaded.flight.impulse_per_pulse == pytest.approx(
        result.value("cm") * model.flight.pulse_energy, rel=1e-15
    )


def test_unidentifiable_parameters_are_flagged(model, fit_map):
    """A centred, upright flight of 1 s (26 pulses): tipping_gain does not enter the sector
    model, the overheating step sits near pulse 100; only Cm is seen."""
    true = truth_model(model, 0.98, 0.5)
    track = video_track(true, initial_state(true), 1.0, seed=2, noise=NOISE)
    result = calibrate(
        model, track, "cm,tipping_gain,overheating", options=OPTIONS, pulse_map=fit_map
    )
    assert result.status is CalibrationStatus.CONVERGED, result.message
    for name in ("tipping_gain", "health_pulse", "health_floor"):
        assert name in result.unidentified
        kinds = {f.kind for f in result.flags_of(name)}
        assert kinds & {FlagKind.NOT_IDENTIFIABLE, FlagKind.POORLY_DETERMINED}, name
        assert any(f"cannot identify {name}" in f.reason for f in result.flags_of(name))
    (tip,) = [f for f in result.flags_of("tipping_gain")]
    assert tip.kind is FlagKind.NOT_IDENTIFIABLE
    assert np.isinf(result.std_of("tipping_gain"))
    assert result.value("tipping_gain") == model.craft.engine.tipping_gain  # never moved
    assert result.flags_of("cm") == ()
    cm_true = true.flight.impulse_per_pulse / true.flight.pulse_energy
    assert abs(result.value("cm") - cm_true) < 3 * result.std_of("cm")
    assert result.singular_values[-1] <= 1e-8 * result.singular_values[0]


def test_residual_jacobian_matches_ad_and_finite_differences(model, fit_map):
    """The Jacobian of r(θ) over every fit component, on a 0.3 s track (8 pulses): chained
    over Φ's pieces in forward mode (what :func:`calibrate` uses) equal to casadi's AD
    through Φ's graph to rounding (1e-9 relative; ~1e-15 measured), and against central
    differences (steps 1e-3 of each scale); the wind speed starts away from 0, where its
    direction enters."""
    t = np.linspace(0.01, 0.3, 12)
    track = Track(t, np.zeros((t.size, 3)))
    comps = fit_components(
        ["cm", "overheating", "divergence", "blast_angle", "offset", "tilt", "wind", "cd"]
    )
    by_ad = build_calibration_problem(model, track, comps, fit_map)
    sensitivity = build_dense_sensitivity(fit_map, len(comps))
    problem = build_calibration_problem(model, track, comps, fit_map, None, sensitivity)
    theta = initial_values(comps, model, problem.x0)
    names = [c.name for c in comps]
    theta[names.index("wind_speed")] = 2.0
    theta[names.index("launch_offset_x")] = 0.01
    theta[names.index("launch_tilt_y")] = 0.02
    r, J = (np.asarray(a) for a in problem.jacobian(theta))
    r_ad, J_ad = (np.asarray(a) for a in by_ad.jacobian(theta))
    np.testing.assert_allclose(r, r_ad, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.ravel(), np.asarray(problem.residual(theta)).ravel(), atol=1e-12)
    for k in range(len(comps)):
        assert np.max(np.abs(J[:, k] - J_ad[:, k])) <= 1e-9 * np.max(np.abs(J_ad[:, k]))

    for k, c in enumerate(comps):
        # steps 1e-3 of each scale: at 1e-4 the residual's rounding over h alone reaches
        # 1e-9 on the weakest column (health_floor, |J| 3e-6: 1.0e-9 at 1e-4, 1.2e-10 at 1e-3)
        h = 1e-3 * c.scale
        plus, minus = theta.copy(), theta.copy()
        plus[k] += h
        minus[k] -= h
        fd = (np.asarray(problem.residual(plus)) - np.asarray(problem.residual(minus))).ravel()
        fd /= 2 * h
        err = np.max(np.abs(J[:, k] - fd))
        assert err <= 1e-5 * np.max(np.abs(J[:, k])) + 1e-9, (c.name, err)
    with pytest.raises(ParameterError, match="sensitivity: has 2 directions for 12 fitted"):
        build_calibration_problem(
            model, track, comps, fit_map, None, build_dense_sensitivity(fit_map, 2)
        )


def test_residual_at_the_truth_is_the_interpolation_error(model, fit_map):
    """Noise-free track of the model itself: r(θ_model) is only the Hermite interpolation
    and the 16-substep map's error against a 64-substep flight, far below the noise."""
    x0 = initial_state(model, r_L=(0.01, 0.0, 0.0), tilt=0.02)
    track = video_track(model, x0, 1.5, seed=3, noise=0.0)
    comps = fit_components(["cm", "offset"])
    problem = build_calibration_problem(model, track, comps, fit_map, x0)
    r = np.asarray(problem.residual(initial_values(comps, model, x0))).ravel()
    assert np.max(np.abs(r)) < 3e-4  # m, 1/20 of the noise (measured 1.9e-4, in z)
    default = build_pulse_map(model, PulseMapOptions())  # 32 substeps: 1.3e-5 measured
    on_default = build_calibration_problem(model, track, comps, default, x0)
    assert np.max(np.abs(np.asarray(on_default.residual(initial_values(comps, model, x0))))) < 3e-5
    # at dense nodes the Hermite weights pick the node itself
    flight = np.asarray(problem.flight(initial_values(comps, model, x0)))
    t_nodes = problem.flight_t[[3, 17, 40]]
    node_track = Track(t_nodes, flight[0:3, [3, 17, 40]].T)
    on_nodes = build_calibration_problem(model, node_track, comps, fit_map, x0)
    assert np.max(np.abs(np.asarray(on_nodes.residual(initial_values(comps, model, x0))))) < 1e-12


def test_bad_fit_names_and_options_get_clear_errors(model, fit_map):
    t = np.linspace(0.01, 0.2, 6)
    track = Track(t, np.zeros((t.size, 3)))
    with pytest.raises(ParameterError, match=r"unknown fit parameter.*'beam'.*cm, overheating"):
        calibrate(model, track, ["cm", "beam"], pulse_map=fit_map)
    with pytest.raises(ParameterError, match="fit: name at least one"):
        calibrate(model, track, [], pulse_map=fit_map)
    with pytest.raises(ParameterError, match="twice"):
        calibrate(model, track, "cm,cm", pulse_map=fit_map)
    few = Track(t[:2], np.zeros((2, 3)))
    with pytest.raises(ParameterError, match="too few"):
        calibrate(model, few, "cm,overheating,offset,tilt", pulse_map=fit_map)
    with pytest.raises(ParameterError, match=r"initial\.cm.*outside its bounds"):
        calibrate(model, track, "cm", initial={"cm": 1.0}, pulse_map=fit_map)
    with pytest.raises(ParameterError, match=r"bounds\.divergence.*not fitted"):
        calibrate(model, track, "cm", bounds={"divergence": (0, 1)}, pulse_map=fit_map)
    # issue 19: the launch offset and tilt are x/y components (docs/outputs.md)
    with pytest.raises(
        ParameterError, match=r"initial\.tilt_north: 'tilt_north' was renamed 'launch_tilt_y'"
    ):
        calibrate(model, track, "tilt", initial={"tilt_north": 0.01}, pulse_map=fit_map)
    with pytest.raises(OptionError, match="max_iter"):
        CalibrationOptions(max_iter=0)
    with pytest.raises(OptionError, match="correlation_max"):
        CalibrationOptions(correlation_max=1.5)
    with pytest.raises(OptionError, match="dense"):
        CalibrationOptions(pulse_map=PulseMapOptions(substeps=8, dense=1))
    for bad in (0.0, -2.0, float("nan"), False):
        with pytest.raises(OptionError, match=r"CalibrationOptions\.time_limit"):
            CalibrationOptions(time_limit=bad)


def test_max_iter_is_a_status_not_an_exception(model, fit_map):
    t = np.linspace(0.01, 0.3, 12)
    sim = simulate(truth_model(model, 1.1, 0.5), 0.35)
    r = np.column_stack([np.interp(t, sim.t, sim.x[:, i]) for i in range(3)])
    result = calibrate(
        model,
        Track(t, r),
        "cm",
        options=CalibrationOptions(max_iter=1, pulse_map=FIT_MAP),
        pulse_map=fit_map,
    )
    assert result.status is CalibrationStatus.MAX_ITER
    assert result.iterations == 1
    assert "max_iter" in result.message


def test_a_wall_clock_limit_stops_the_fit_at_its_last_accepted_step(model, fit_map, monkeypatch):
    """Each residual and Jacobian made to take 0.25 s of the fit's clock: the start's is ready at
    0.25 s, the first step's at 0.5 s, past the 0.3 s limit, so the fit stops before its
    second trial step with status TIME_LIMIT after 1 iteration (Cm is 10 % off: one step
    cannot converge), at that step's values, within the limit plus one evaluation."""
    import lightcraft_opt.calibration.fit as fit_module

    t = np.linspace(0.01, 0.3, 12)
    sim = simulate(truth_model(model, 1.1, 0.5), 0.35)
    r = np.column_stack([np.interp(t, sim.t, sim.x[:, i]) for i in range(3)])
    evaluate = fit_module._evaluate
    clock = [0.0]  # the fit's clock: advanced by the evaluations alone, whatever the load

    def slow(problem, theta):
        clock[0] += 0.25
        return evaluate(problem, theta)

    monkeypatch.setattr(fit_module, "_evaluate", slow)
    monkeypatch.setattr(fit_module, "time", SimpleNamespace(perf_counter=lambda: clock[0]))
    options = CalibrationOptions(max_iter=50, time_limit=0.3, pulse_map=FIT_MAP)
    result = calibrate(model, Track(t, r), "cm", options=options, pulse_map=fit_map)
    assert result.status is CalibrationStatus.TIME_LIMIT
    assert not result.success
    assert result.iterations == 1
    assert result.message == "wall-clock limit 0.3 s reached after 1 iterations"
    assert result.value("cm") != result.initial[0]  # the accepted step's value
    assert result.cost < result.initial_cost
    assert result.solve_time == pytest.approx(0.5)  # the start's evaluation and one step's


def test_track_validation():
    with pytest.raises(ParameterError, match=r"track\.t: must increase strictly"):
        Track([0.1, 0.2, 0.2], np.zeros((3, 3)))
    with pytest.raises(ParameterError, match="finite"):
        Track([0.1, 0.2, 0.3], [[0, 0, 0], [0, np.nan, 0], [0, 0, 0]])
    with pytest.raises(ParameterError, match=r"track\.r_L: needs shape \(3, 3\)"):
        Track([0.1, 0.2, 0.3], np.zeros((3, 2)))
    with pytest.raises(ParameterError, match="t >= 0"):
        Track([-0.1, 0.2], np.zeros((2, 3)))


def test_track_file_gaps_units_and_errors(tmp_path):
    good = tmp_path / "track.csv"
    good.write_text(
        "# tracked at 60 fps\n"
        "frame,t_ms,x_mm,y_m,z_m\n"
        "1,16.7,1.5,0.002,0.05\n"
        "2,33.3,,0.002,0.09\n"
        "3,50.0,2.0,nan,0.14\n"
        "4,66.7,2.5,0.003,0.20\n"
    )
    track = read_track(good)
    assert track.gaps == 2
    np.testing.assert_array_equal(track.t, [0.0167, 0.0667])
    np.testing.assert_array_equal(track.r_L, [[0.0015, 0.002, 0.05], [0.0025, 0.003, 0.2]])

    def error(text: str) -> str:
        bad = tmp_path / "bad.csv"
        bad.write_text(text)
        with pytest.raises(ProblemFileError) as err:
            read_track(bad)
        return str(err.value)

    assert "line 1, column z: missing" in error("t_s,x_m,y_m\n0.1,0,0\n0.2,0,0\n")
    assert "line 3, column t_s: times must increase strictly: 0.1 s follows 0.2 s (line 2)" in (
        error("t_s,x_m,y_m,z_m\n0.2,0,0,0\n0.1,0,0,0\n")
    )
    assert "must be >= 0, got -0.1 s" in error("t_s,x_m,y_m,z_m\n-0.1,0,0,0\n0.1,0,0,0\n")
    assert "line 2, column y_m: must be a number, got 'abc'" in error(
        "t_s,x_m,y_m,z_m\n0.1,0,abc,0\n0.2,0,0,0\n"
    )
    assert "line 2, column x_m: must be finite" in error("t_s,x_m,y_m,z_m\n0.1,inf,0,0\n")
    assert "line 3: has 3 fields" in error("t_s,x_m,y_m,z_m\n0.1,0,0,0\n0.2,0,0\n")
    assert "at least 2 tracked rows" in error("t_s,x_m,y_m,z_m\n0.1,0,0,0\n")
    with pytest.raises(ProblemFileError, match="no such file"):
        read_track(tmp_path / "no.csv")


def test_track_file_with_a_byte_order_mark_reads_as_without(tmp_path):
    """A spreadsheet's "CSV UTF-8" starts with the byte-order mark U+FEFF: the same track."""
    text = "t_s,x_m,y_m,z_m\n0.1,0.001,0,0.1\n0.2,0.002,0,0.3\n"
    plain, marked = tmp_path / "plain.csv", tmp_path / "marked.csv"
    plain.write_text(text, encoding="utf-8")
    marked.write_text(text, encoding="utf-8-sig")
    assert marked.read_bytes()[:3] == b"\xef\xbb\xbf"
    a, b = read_track(plain), read_track(marked)
    np.testing.assert_array_equal(b.t, [0.1, 0.2])
    np.testing.assert_array_equal(b.t, a.t)
    np.testing.assert_array_equal(b.r_L, a.r_L)
