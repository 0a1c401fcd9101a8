"""The fitted model file ``lightcraft calibrate`` writes: the original text, comments and
all, with only the fitted values' lines replaced and marked as fitted.

Reference: the file reloads with load_model to the fitted parameter vector (to the last
bit but for the slot derived from a value written in the file's units); every line of the
original but the fitted ones is in it unchanged; a value the original did not give is
added to its table. The result is made up (no fit runs): the writer is what is tested.
"""

from __future__ import annotations

import dataclasses as dc
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT
from support.results import made_up_fit

from lightcraft_opt.calibration.result import CalibrationResult
from lightcraft_opt.files.calibration_outputs import write_fitted_model
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import PARAMETERS, parameter_values

NAMES = ("cm", "blast_angle", "wind_speed", "divergence")
UNITS = ("N s/J", "rad", "m/s", "rad")
VALUES = (1.55e-4, 0.45, 2.5, 1.2e-3)
STD = (2e-6, 0.01, np.inf, 1e-4)


def made_up_result(model) -> CalibrationResult:
    p = parameter_values(model).copy()
    slots = ("impulse_per_pulse", "blast_angle", "wind_speed_ref", "beam_divergence")
    file_values = (VALUES[0] * model.flight.pulse_energy, *VALUES[1:])
    for slot, v in zip(slots, file_values, strict=True):
        p[PARAMETERS.slot(slot).start] = v
    p[PARAMETERS.slot("spent_coupling").start] = VALUES[0]  # defaults to the coupling
    return made_up_fit(NAMES, UNITS, VALUES, std=np.array(STD), iterations=3, p=p)


@pytest.fixture
def source(tmp_path: Path) -> Path:
    """models/ copied, Flight 5's wind speed line removed: the default (calm) is fitted."""
    shutil.copytree(REPO_ROOT / "models", tmp_path / "models")
    path = tmp_path / "models" / "flight5.toml"
    lines = path.read_text().splitlines()
    path.write_text("\n".join(x for x in lines if not x.startswith("speed_ref_mps")) + "\n")
    return path


def test_the_fitted_file_keeps_the_comments_and_marks_the_fitted_values(source, tmp_path):
    model = load_model(source)
    result = made_up_result(model)
    out = tmp_path / "fit"
    out.mkdir()
    path = write_fitted_model(result, source, out / "flight5-fitted.toml", track_file="t.csv")

    fitted = load_model(path)
    np.testing.assert_allclose(parameter_values(fitted), result.p, rtol=1e-15, atol=0)
    assert fitted.craft.engine.blast_angle == 0.45 and fitted.laser.divergence == 1.2e-3
    assert fitted.environment.wind.speed_ref == 2.5
    assert dc.replace(fitted, name=model.name) != model  # the fit changed it

    text = path.read_text().splitlines()
    original = source.read_text().splitlines()
    fitted_lines = [x for x in text if "# fitted:" in x]
    assert len(fitted_lines) == 3  # cm, blast angle, wind speed; the divergence: the laser's
    assert (
        "blast_angle_rad = 0.45  # fitted: blast_angle = 25.7831 ± 0.573 deg (calibrate, t.csv); "
        "was blast_angle_deg = 28.6"
    ) in text
    assert (
        "speed_ref_mps = 2.5  # fitted: wind_speed = 2.5 not identifiable m/s (calibrate, "
        "t.csv); was speed_ref_mps = 0.0" not in text  # removed from this copy: added
    )
    assert (
        "speed_ref_mps = 2.5  # fitted: wind_speed = 2.5 not identifiable m/s (calibrate, t.csv)"
        in text
    )
    # every other line of the original, comments included, is kept as it was
    edited = ("blast_angle_deg", "impulse_per_pulse", "site =", "laser =")
    kept = [x for x in original if not x.startswith(edited)]
    assert [x for x in text[3:] if "# fitted:" not in x and not x.startswith(edited)] == kept
    assert text[0].startswith("# Fitted by lightcraft calibrate from flight5.toml, t.csv:")
    data = tomllib.loads(path.read_text())
    assert data["site"] == "../models/white_sands.toml" and data["laser"] == "plvts-fitted.toml"

    laser = (out / "plvts-fitted.toml").read_text()
    # the key in SI (it reloads to the very float), the comment in degrees as calibrate prints
    assert "divergence_rad = 0.0012  # fitted: divergence = 0.0687549 ± 0.00573 deg" in laser
    assert 'size_model = "linear"         # guess: a(z) = side + divergence z' in laser


def test_a_layout_the_line_editor_does_not_know_falls_back_to_the_tables(source, tmp_path):
    """The wind given by dotted keys in [environment]: the edited text would not read
    back, so the file is written from the tables (no comments) and still reloads to the
    fit."""
    text = source.read_text().replace("[environment.wind]\n", "")
    text = text.replace("direction_from_deg", "wind.direction_from_deg")
    source.write_text(text)
    model = load_model(source)
    result = made_up_result(model)
    path = write_fitted_model(result, source, tmp_path / "fitted.toml")
    np.testing.assert_allclose(parameter_values(load_model(path)), result.p, rtol=1e-15, atol=0)
    assert "# fitted:" not in path.read_text()
