"""Bad input gets a clear error naming the field, never a raw casadi traceback."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from support.models import table1_flight5

from lightcraft_opt.cli import main
from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.layout import STATE, initial_state
from lightcraft_opt.options import CoastScheme, PulseMapOptions, SimulationOptions
from lightcraft_opt.params import Craft, Site
from lightcraft_opt.simulation.coast_reference import simulate_coast


def test_nan_initial_state_names_the_field():
    model = table1_flight5()
    x0 = initial_state(model)
    x0[STATE.index("w_B")][1] = np.nan
    with pytest.raises(ParameterError, match=r"x0.*finite"):
        simulate_coast(model, 1.0, x0=x0)


@pytest.mark.parametrize("duration", [0.0, -1.0, float("nan")])
def test_non_positive_duration_is_refused(duration):
    with pytest.raises(ParameterError, match="duration"):
        simulate_coast(table1_flight5(), duration)


def test_wrong_state_size_is_refused():
    with pytest.raises(ParameterError, match=r"x0.*needs 17"):
        simulate_coast(table1_flight5(), 1.0, x0=np.zeros(5))


def test_negative_mass_and_triangle_inequality_are_refused():
    with pytest.raises(ParameterError, match=r"craft\.mass.*positive"):
        table1_flight5(mass=-0.03)
    with pytest.raises(ParameterError, match="triangle inequality"):
        Craft("bad", 0.1, 0.03, inertia_axial=1e-4, inertia_transverse=4e-5, spin=100.0)
    with pytest.raises(ParameterError, match=r"site\.latitude"):
        Site("nowhere", 2.0, 0.0, 0.0)


def test_numbers_in_messages_print_plainly():
    """A numpy scalar reads as its number, never as np.float64(...)."""
    with pytest.raises(ParameterError, match=r"craft\.mass: must be positive, got -0\.03$"):
        table1_flight5(mass=np.float64(-0.03))
    with pytest.raises(ParameterError, match=r"site\.latitude: must lie in .*, got 2\.0$"):
        Site("nowhere", np.float64(2.0), 0.0, 0.0)
    with pytest.raises(ParameterError, match=r"must be finite, got inf$"):
        table1_flight5(mass=np.float64("inf"))


def test_unknown_option_values_list_the_allowed_ones():
    with pytest.raises(OptionError, match="rk4"):
        PulseMapOptions(scheme="euler")  # type: ignore[arg-type]
    with pytest.raises(OptionError, match="divide"):
        PulseMapOptions(scheme=CoastScheme.RK4, substeps=10, dense=4)
    with pytest.raises(OptionError, match="rtol"):
        SimulationOptions(rtol=float("nan"))


def test_cli_reports_a_bad_model_file_without_a_traceback(tmp_path, capsys):
    models = Path(__file__).resolve().parents[1] / "models"
    for name in ("white_sands.toml", "plvts.toml"):
        shutil.copy(models / name, tmp_path / name)
    bad = tmp_path / "bad.toml"
    bad.write_text((models / "flight5.toml").read_text().replace("mass_g = ", "mass_lb = "))
    assert main(["simulate", str(bad), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err and "mass_lb" in err
    assert "Traceback" not in err
