"""A closed-loop file's ``[sensors]`` (files/closed_loop.py, docs/files/closed_loop.md
#keys-sensors-camera): read into SensorOptions in SI, and every bad value refused with the
key as written."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.control.estimation import (
    CameraKind,
    CameraOptions,
    SensorOptions,
)
from lightcraft_opt.errors import ProblemFileError
from lightcraft_opt.files.closed_loop import load_closed_loop

HEAD = f'model = "{REPO_ROOT / "models" / "flight5.toml"}"\nduration_s = 1.0\n'


def _load(tmp_path: Path, tables: str) -> SensorOptions | None:
    path = tmp_path / "loop.toml"
    path.write_text(HEAD + tables, encoding="utf-8")
    return load_closed_loop(path).sensors


def test_without_sensors_the_reader_gives_none(tmp_path: Path) -> None:
    assert _load(tmp_path, "") is None


def test_an_empty_sensors_table_is_the_default_camera(tmp_path: Path) -> None:
    assert _load(tmp_path, "[sensors]\n") == SensorOptions()
    assert SensorOptions().camera == CameraOptions(CameraKind.POSITION, noise=0.005)


def test_the_target_scenario_reads_in_si(tmp_path: Path) -> None:
    """Cameras only, 5 mm, one pulse late, 5 % of the frames lost, 30 frames a second."""
    got = _load(
        tmp_path,
        "[sensors.camera]\nnoise_mm = 5.0\nlatency_pulses = 1\nlost_percent = 5.0\n"
        "frame_rate_hz = 30.0\n",
    )
    assert got == SensorOptions(
        CameraOptions(noise=0.005, latency_pulses=1, lost_rate=0.05, frame_rate=30.0)
    )


def test_stereo_gyro_and_spin_read_in_si(tmp_path: Path) -> None:
    got = _load(
        tmp_path,
        '[sensors.camera]\nkind = "stereo"\nnoise_mrad = 0.2\n'
        "sites_m = [[30.0, 0.0, 1.0], [0.0, -40.0, 1.0]]\n"
        "[sensors.gyro]\nnoise_deg_per_s = 0.5\nlatency_pulses = 2\n"
        "[sensors.spin]\nnoise_rpm = 6.0\n",
    )
    assert got is not None
    camera = CameraOptions(CameraKind.STEREO, 2e-4, ((30.0, 0.0, 1.0), (0.0, -40.0, 1.0)))
    assert got.camera == camera
    assert got.gyro is not None and got.spin is not None
    assert got.gyro.noise == pytest.approx(math.radians(0.5)) and got.gyro.latency_pulses == 2
    assert got.spin.noise == pytest.approx(6.0 * 2 * math.pi / 60) and got.spin.latency_pulses == 0


@pytest.mark.parametrize(
    ("tables", "key", "says"),
    [
        ("[sensors.camera]\nnoise_mm = 0.0\n", "sensors.camera.noise_mm", "must be > 0"),
        ("[sensors.camera]\nnoise_mrad = 1.0\n", "sensors.camera.noise_mrad", "not known for"),
        (
            '[sensors.camera]\nkind = "stereo"\nnoise_mm = 1.0\n',
            "sensors.camera.noise_mm",
            "not known for angle",
        ),
        (
            '[sensors.camera]\nkind = "stereo"\nsites_m = [[30.0, 0.0, 1.0], [0.0, -40.0, 1.0]]\n',
            "sensors.camera.noise",
            "noise_mrad",
        ),
        ('[sensors.camera]\nkind = "mono"\n', "sensors.camera.kind", "position"),
        ("[sensors.camera]\nlost_percent = 100.0\n", "sensors.camera.lost_percent", "[0, 1)"),
        ("[sensors.camera]\nlatency_pulses = -1\n", "sensors.camera.latency_pulses", ">= 0"),
        ("[sensors.camera]\nlatency_pulses = 1.5\n", "sensors.camera.latency_pulses", "whole"),
        ("[sensors.camera]\nframe_rate_hz = 0.0\n", "sensors.camera.frame_rate_hz", "> 0"),
        (
            "[sensors.camera]\nsites_m = [[30.0, 0.0, 1.0], [0.0, -40.0, 1.0]]\n",
            "sensors.camera.sites_m",
            "position camera takes none",
        ),
        (
            '[sensors.camera]\nkind = "stereo"\nnoise_mrad = 0.2\n'
            "sites_m = [[30.0, 0.0, 1.0], [0.3, 0.0, 9.0]]\n",
            "sensors.camera.sites_m[1]",
            "at least 1 m off",
        ),
        (
            '[sensors.camera]\nkind = "stereo"\nnoise_mrad = 0.2\nsites_m = [[30.0, 0.0]]\n',
            "sensors.camera.sites_m[0]",
            "3 values",
        ),
        ("[sensors.gyro]\nnoise_rad_per_s = -0.1\n", "sensors.gyro.noise_rad_per_s", "> 0"),
        ("[sensors.spin]\nlatency_pulses = -3\n", "sensors.spin.latency_pulses", ">= 0"),
        ("[sensors.lidar]\nnoise_mm = 1.0\n", "sensors.lidar", "unknown"),
        ("[sensors]\ncamera = 3\n", "sensors.camera", "must be a table"),
    ],
)
def test_bad_values_name_their_key(tmp_path: Path, tables: str, key: str, says: str) -> None:
    with pytest.raises(ProblemFileError) as err:
        _load(tmp_path, tables)
    assert err.value.field == key, err.value
    assert says in err.value.reason, err.value
