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
from lightcraft_opt.model import Craft, Site
from lightcraft_opt.simulation.coast_reference import SimulationOptions, simulate_coast
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions


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


# ---------------------------------------------------------------- physical ranges (issue 18)
def _flight5_file(tmp_path: Path, old: str, new: str) -> Path:
    """models/flight5.toml with one line changed, beside its site and laser files."""
    models = Path(__file__).resolve().parents[1] / "models"
    for name in ("white_sands.toml", "plvts.toml"):
        shutil.copy(models / name, tmp_path / name)
    text = (models / "flight5.toml").read_text()
    assert old in text
    path = tmp_path / "edited.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "key", "reason"),
    [
        ("spin_rpm = 10000.0", "spin_rpm = 1e300", "craft.spin_rpm", "rim would move"),
        ("speed_ref_mps = 0.0", "speed_ref_mps = 1e300", "wind.speed_ref_mps", "surface wind"),
        ("pulse_rate_hz = 26.0", "pulse_rate_hz = 1e300", "flight.pulse_rate_hz", "refilled"),
        ("mass_g = 32.5", "mass_g = 1e300", "craft.mass_g", "fitted to craft of 10-100 g"),
        ("mass_g = 32.5", "mass_g = 3.25", "inertia_axial_g_cm2", "all the mass on the rim"),
        ("quadrature_radial = 8", "quadrature_radial = 1000000000", "quadrature_radial", "finer"),
    ],
)
def test_finite_but_absurd_model_values_are_refused_with_a_reason(
    tmp_path, capsys, old, new, key, reason
):
    """Values that loaded and then crashed simulate (or flew nonsense) are refused at load,
    naming the key as written and the physical reason."""
    path = _flight5_file(tmp_path, old, new)
    assert main(["simulate", str(path), "--duration", "0.1", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert key in err and reason in err and "Traceback" not in err


def test_the_rim_speed_bound_is_the_hoop_stress_figure():
    """500 m/s of rim speed: Flight 5's 122.2 mm rotor may spin to 78,100 RPM, not faster."""
    rpm_at_limit = 500.0 / (0.1222 / 2) * 60 / (2 * np.pi)
    table1_flight5(spin=0.99 * rpm_at_limit * 2 * np.pi / 60)
    with pytest.raises(ParameterError, match=r"craft\.spin.*rim would move at 50[0-9.]+ m/s"):
        table1_flight5(spin=1.01 * rpm_at_limit * 2 * np.pi / 60)


@pytest.mark.parametrize("tilt", [float("inf"), float("nan"), np.pi / 2, -0.1])
def test_launch_tilt_outside_a_quarter_turn_is_refused(tilt):
    with pytest.raises(ParameterError, match="tilt"):
        initial_state(table1_flight5(), tilt=tilt)


@pytest.mark.parametrize("coning", ["200", "90", "-5"])
def test_initial_coning_must_be_below_a_quarter_turn(tmp_path, coning):
    """A coning of 200 degrees used to fly as 20 (the angle wrapped), 90 flew too."""
    from lightcraft_opt.errors import ProblemFileError
    from lightcraft_opt.files.closed_loop import load_closed_loop

    models = Path(__file__).resolve().parents[1] / "models"
    path = tmp_path / "loop.toml"
    path.write_text(
        f'title = "t"\nmodel = "{(models / "flight5.toml").as_posix()}"\nduration_s = 0.1\n'
        f"[initial]\nconing_deg = {coning}\n"
    )
    with pytest.raises(ProblemFileError, match=r"initial\.coning_deg: must lie in \[0, 90\)"):
        load_closed_loop(path)


def test_a_huge_horizon_is_refused_before_anything_is_built(tmp_path):
    """horizon_pulses = 1e9 spent minutes inside load_problem before any check."""
    from lightcraft_opt.errors import ProblemFileError
    from lightcraft_opt.files.problem import load_problem

    problems = Path(__file__).resolve().parents[1] / "problems"
    with pytest.raises(ProblemFileError, match=r"horizon_pulses: 1000000000 pulses is above"):
        load_problem(problems / "least_energy_flight16.toml", horizon=1_000_000_000)


@pytest.mark.parametrize("duration", [1e300, 3600.5, True])
def test_a_duration_beyond_an_hour_is_refused_by_every_runner(duration):
    """simulate(model, 1e300) used to size its pulse arrays first: 'maximum dimension'."""
    from lightcraft_opt.simulation.simulate import simulate

    for run in (simulate, simulate_coast):
        with pytest.raises(ParameterError, match=r"duration: must (lie in \(0, 3600\] s|be a)"):
            run(table1_flight5(), duration)


def test_a_controller_horizon_beyond_ten_seconds_is_refused():
    """horizon_pulses = 1e9 in a closed-loop file would build a QP of a billion stages."""
    from lightcraft_opt.control.options import MAX_CONTROL_HORIZON, DirectorOptions, MpcOptions

    MpcOptions(horizon=MAX_CONTROL_HORIZON)
    for options in (MpcOptions, DirectorOptions):
        with pytest.raises(OptionError, match=r"horizon must be <= 260 \(10 s ahead"):
            options(horizon=10**9)
