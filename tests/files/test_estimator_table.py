"""The ``[estimator]`` table of closed-loop and campaign files, and what a flight with an
estimator writes (steps.csv's estimate columns, summary.json's entries, the exact archive).

References: the table's values read back in SI are the file's numbers times the units'
factors (docs/files.md#units); each bad value is refused naming its key as written; the
steps.csv columns are the EstimationLog's arrays in the columns' units, to the file's 9
significant digits, and appear only with an estimator; result.npz gives the log back bit
for bit.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.control.closed_loop import closed_loop
from lightcraft_opt.control.controllers import OpenLoopController
from lightcraft_opt.control.estimation import (
    PSI_CURVES,
    CameraOptions,
    GyroOptions,
    SensorOptions,
)
from lightcraft_opt.control.options import EstimatorKind, EstimatorSpec, MeasurementNoise
from lightcraft_opt.control.result import ClosedLoopResult, EstimationLog
from lightcraft_opt.errors import ProblemFileError
from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.closed_loop_outputs import (
    ESTIMATE_COLUMNS,
    STEP_COLUMNS,
    write_closed_loop_summary,
    write_steps_csv,
)
from lightcraft_opt.files.model import load_model
from lightcraft_opt.files.result_archive import read_archive, write_archive
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

#: A closed-loop file with sensors and without [plant.noise] (an estimator refuses it).
BASE = f'''title = "estimator table"
model = "{REPO_ROOT / "models" / "flight5.toml"}"
duration_s = 0.5
controller = "none"

[plant]
dropout_rate = 0.1

[sensors.camera]
noise_mm = 5.0
'''


def _load(tmp_path: Path, text: str) -> EstimatorSpec:
    path = tmp_path / "loop.toml"
    path.write_text(BASE + text, encoding="utf-8")
    return load_closed_loop(path).estimator


def test_without_the_table_the_controller_is_told_the_truth(tmp_path):
    assert _load(tmp_path, "") == EstimatorSpec(EstimatorKind.TRUTH, {})
    assert _load(tmp_path, '[estimator]\nkind = "truth"\n') == EstimatorSpec()


def test_the_table_reads_into_si(tmp_path):
    spec = _load(
        tmp_path,
        """[estimator]
kind = "mhe"
horizon_pulses = 12
max_iter = 5
relinearize = 12
prior_position_mm = 5.0
prior_velocity_cm_per_s = 2.0
prior_coning_deg = 1.0
prior_wind_kmh = 3.6
""",
    )
    assert spec.kind is EstimatorKind.MHE
    assert spec.options == pytest.approx(
        {
            "horizon": 12,
            "max_iter": 5,
            "relinearize": 12,
            "prior_position": 5e-3,
            "prior_velocity": 2e-2,
            "prior_coning": math.radians(1.0),
            "prior_wind": 1.0,
        },
        rel=1e-15,
    )
    assert isinstance(spec.options["horizon"], int)
    ekf = _load(tmp_path, '[estimator]\nkind = "ekf"\nnoise_scale = 2.0\n')
    assert ekf == EstimatorSpec(EstimatorKind.EKF, {"noise_scale": 2.0})
    ukf = _load(tmp_path, '[estimator]\nkind = "ukf"\nnoise_scale = 2.0\n')
    assert ukf == EstimatorSpec(EstimatorKind.UKF, {"noise_scale": 2.0})
    curved = _load(tmp_path, '[estimator]\nkind = "ekf"\nsecond_order = true\n')
    assert curved == EstimatorSpec(EstimatorKind.EKF, {"second_order": True})
    listed = '["r_L[east]", "r_L[north]", "H_L", "coning", "wind_L", "coupling"]'
    named = _load(tmp_path, f'[estimator]\nkind = "mhe"\nsecond_order = {listed}\n')
    assert named == EstimatorSpec(EstimatorKind.MHE, {"second_order": PSI_CURVES})


@pytest.mark.parametrize(
    ("table", "key", "reason"),
    [
        ('kind = "kalman"', "estimator.kind", r"'truth', 'ekf', 'ukf', 'mhe'"),
        ('kind = "ekf"\nprior_position_mm = -1.0', "estimator.prior_position_mm", r"> 0"),
        ('kind = "ekf"\nhorizon_pulses = 10', "estimator.horizon_pulses", r"kind 'mhe', not"),
        ('kind = "mhe"\nhorizon_pulses = 0', "estimator.horizon_pulses", r">= 1"),
        ('kind = "ekf"\nrelinearize = 2', "estimator.relinearize", r"kind 'mhe', not"),
        ('kind = "mhe"\nrelinearize = 0', "estimator.relinearize", r">= 1"),
        ('kind = "mhe"\nnoise_scale = 0.5', "estimator.noise_scale", r"kind 'ekf' or 'ukf', not"),
        ('kind = "ekf"\nnoise_scale = 0.0', "estimator.noise_scale", r"> 0"),
        ('kind = "ukf"\nsecond_order = true', "estimator.second_order", r"'ekf' or 'mhe', not"),
        ('kind = "ekf"\nsecond_order = 1', "estimator.second_order", r"true, false or a list"),
        ('kind = "ekf"\nsecond_order = []', "estimator.second_order", r"true, false or a list"),
        ('kind = "ekf"\nsecond_order = ["H_L", 2]', "estimator.second_order", r"list of names"),
        (
            'kind = "ekf"\nsecond_order = ["r_L", "spin"]',
            "estimator.second_order",
            r"'spin' names no entry of the estimated state; its entries are \['r_L\[east\]'",
        ),
        ("prior_wind_mps = 1.0", "estimator.prior_wind_mps", r"not 'truth'"),
        ('kind = "ekf"\ngain = 1.0', "estimator.gain", r"kind|unknown|not"),
        ('kind = "ekf"\nprior_position_kg = 1.0', "estimator.prior_position_kg", r"unit|mm"),
    ],
)
def test_a_bad_value_is_refused_naming_its_key(tmp_path, table, key, reason):
    with pytest.raises(ProblemFileError) as err:
        _load(tmp_path, f"[estimator]\n{table}\n")
    assert err.value.field == key
    assert re.search(reason, err.value.reason), err.value.reason


def test_an_estimator_beside_plant_noise_is_refused_naming_it(tmp_path):
    with pytest.raises(ProblemFileError) as err:
        _load(tmp_path, '[plant.noise]\nposition_mm = 1.0\n\n[estimator]\nkind = "ekf"\n')
    assert err.value.field == "plant.noise" and "remove [plant.noise]" in err.value.reason


def test_an_estimator_without_sensors_is_refused_naming_them(tmp_path):
    path = tmp_path / "bare.toml"
    path.write_text(BASE.split("[sensors.camera]")[0] + '[estimator]\nkind = "mhe"\n')
    with pytest.raises(ProblemFileError) as err:
        load_closed_loop(path)
    assert err.value.field == "sensors" and "an empty [sensors]" in err.value.reason
    path.write_text(BASE.split("[sensors.camera]")[0] + '[sensors]\n[estimator]\nkind = "mhe"\n')
    loaded = load_closed_loop(path)
    assert loaded.sensors == SensorOptions() and loaded.estimator.kind is EstimatorKind.MHE


def test_a_campaign_carries_the_estimator_and_the_truth_keeps_its_fingerprint(tmp_path):
    """A campaign file's [estimator] reaches its Campaign; naming the truth changes
    nothing a run depends on (the same fingerprint: a resumed campaign stays valid), an
    EKF does."""
    dispersion = '\n[dispersions.mass]\ndistribution = "normal"\nrelative_sigma = 0.01\n'
    dispersion += "truncate_sigmas = 3.0\n"
    specs = {}
    for name, table in (("plain", ""), ("truth", 'kind = "truth"'), ("ekf", 'kind = "ekf"')):
        path = tmp_path / f"{name}.toml"
        path.write_text(BASE + f"\n[estimator]\n{table}\n" + dispersion, encoding="utf-8")
        specs[name] = load_campaign(path)
    assert specs["ekf"].estimator == EstimatorSpec(EstimatorKind.EKF)
    assert specs["plain"].fingerprint == specs["truth"].fingerprint != specs["ekf"].fingerprint


# --------------------------------------------------------------------------- what is written
@pytest.fixture(scope="module")
def flown() -> ClosedLoopResult:
    """The open loop's 13 pulses with a made-up estimation log (seeded numbers)."""
    model = load_model(REPO_ROOT / "models" / "flight5.toml")
    phi = build_pulse_map(model)
    result = closed_loop(model, OpenLoopController(model, phi.inputs), 0.5, pulse_map=phi)  # type: ignore[arg-type]
    n = result.pulses_commanded
    rng = np.random.default_rng(5)
    log = EstimationLog(
        estimator="ekf",
        error_r_L=1e-3 * rng.standard_normal((n, 3)),
        error_v_L=1e-2 * rng.standard_normal((n, 3)),
        error_tilt=1e-3 * rng.standard_normal(n),
        error_coning=1e-3 * rng.standard_normal(n),
        error_spin=rng.standard_normal(n),
        sigma_r_L=1e-3 * (1 + rng.random((n, 3))),
        seconds=1e-4 * (1 + rng.random(n)),
        readings=rng.integers(0, 3, n),
    )
    return dataclasses.replace(result, estimation=log)


def test_steps_csv_has_the_estimate_columns_only_with_an_estimator(flown, tmp_path):
    write_steps_csv(flown, tmp_path / "with.csv")
    write_steps_csv(dataclasses.replace(flown, estimation=None), tmp_path / "without.csv")
    header = (tmp_path / "without.csv").read_text().splitlines()[0]
    assert header.split(",") == list(STEP_COLUMNS)
    table = np.genfromtxt(tmp_path / "with.csv", delimiter=",", names=True, dtype=None)
    assert list(table.dtype.names) == [*STEP_COLUMNS, *ESTIMATE_COLUMNS]
    log = flown.estimation
    expected = {
        "error_x_m": log.error_r_L[:, 0],
        "error_z_m": log.error_r_L[:, 2],
        "error_vy_mps": log.error_v_L[:, 1],
        "error_tilt_deg": np.degrees(log.error_tilt),
        "error_coning_deg": np.degrees(log.error_coning),
        "error_spin_rad_per_s": log.error_spin,
        "sigma_y_m": log.sigma_r_L[:, 1],
    }
    for column, values in expected.items():
        np.testing.assert_allclose(table[column], values, rtol=1e-8, err_msg=column)
    np.testing.assert_allclose(table["estimator_time_ms"], 1e3 * log.seconds, rtol=1e-5)
    np.testing.assert_array_equal(table["readings"], log.readings)


def test_summary_and_archive_keep_the_log(flown, tmp_path):
    """summary.json names the estimator and its RMS position error only with one; the
    archive gives the log back bit for bit, and None as None."""
    summary = write_closed_loop_summary(flown, None, tmp_path / "summary.json")
    log = flown.estimation
    rms = math.sqrt(np.mean(np.sum(log.error_r_L**2, axis=1)))
    assert summary["estimator"] == "ekf"
    assert summary["position_error_rms_m"] == pytest.approx(rms, rel=1e-12)
    back = read_archive(tmp_path)
    for field in dataclasses.fields(EstimationLog):
        a, b = getattr(back.estimation, field.name), getattr(log, field.name)
        assert np.array_equal(a, b) if isinstance(b, np.ndarray) else a == b
    plain = tmp_path / "plain"
    plain.mkdir()
    bare = dataclasses.replace(flown, estimation=None)
    assert "estimator" not in write_closed_loop_summary(bare, None, plain / "summary.json")
    write_archive(bare, plain)
    assert read_archive(plain).estimation is None
    assert "estimator" not in json.loads((plain / "summary.json").read_text())


def test_docs_outputs_names_every_estimate_column():
    page = (REPO_ROOT / "docs" / "outputs.md").read_text(encoding="utf-8")
    ranged = {"error_y_m", "error_vy_mps", "sigma_y_m"}  # written as x ... z
    assert [c for c in ESTIMATE_COLUMNS if f"`{c}`" not in page and c not in ranged] == []


# --------------------------------------------------------------------------- shipped files
#: The shipped files with a tracker, and the files they copy but for it.
TRACKED = {
    "director_tracked.toml": "director_crosswind.toml",
    "montecarlo_director_tracked.toml": "montecarlo_director.toml",
    "director_tracked_gyro.toml": "director_crosswind.toml",
    "montecarlo_director_tracked_gyro.toml": "montecarlo_director.toml",
}


@pytest.mark.parametrize("name", TRACKED)
def test_the_tracked_problems_fly_the_ekf_on_a_camera(name):
    """problems/director_tracked.toml and its campaign: the director told the EKF's
    estimate from a 5 mm position camera, one pulse late, 5 % of frames lost (the _gyro
    files: and a 0.01 rad/s gyro), and no [plant.noise]; otherwise director_crosswind's
    (and montecarlo_director's) plant, director and wind."""
    load = load_campaign if name.startswith("montecarlo") else load_closed_loop
    tracked = load(REPO_ROOT / "problems" / name)
    reference = load(REPO_ROOT / "problems" / TRACKED[name])
    assert tracked.estimator == EstimatorSpec(EstimatorKind.EKF)
    camera = CameraOptions(noise=5e-3, latency_pulses=1, lost_rate=0.05)
    gyro = GyroOptions(noise=0.01) if "gyro" in name else None
    assert tracked.sensors == SensorOptions(camera, gyro=gyro)
    assert reference.sensors is None and reference.estimator == EstimatorSpec()
    assert tracked.loop.noise == MeasurementNoise() != reference.loop.noise
    assert dataclasses.replace(tracked.loop, noise=reference.loop.noise) == reference.loop
    assert (tracked.director, tracked.plant_parameters) == (
        reference.director,
        reference.plant_parameters,
    )
