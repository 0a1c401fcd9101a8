"""Results as objects: ``summary()``, a short ``repr``, ``plot()``, ``save()`` and
:func:`lightcraft_opt.load_result`, and the figures summary.json gains.

References: the trajectory and pulse record themselves (apogee time is the time of the
highest state, energy captured the sum of the pulse record's column, the capture margin
the beam gap recomputed from pulses.csv by flight_log.beam_gap), the problem's own
numbers for each constraint's margin, and exact equality for the archive's round trip.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from support.paths import REPO_ROOT
from support.results import made_up_solve

import lightcraft_opt as lc
from lightcraft_opt.calibration.result import CalibrationStatus, FitFlag, FlagKind
from lightcraft_opt.campaign.runner import CampaignResult
from lightcraft_opt.files.model import load_model
from lightcraft_opt.files.ocp_outputs import constraint_margins
from lightcraft_opt.files.result_archive import read_archive, write_archive
from lightcraft_opt.files.simulation_outputs import PULSE_COLUMNS
from lightcraft_opt.layout import (
    ENGINE,
    PARAMETERS,
    STATE,
    RcsProfile,
    initial_state,
    parameter_values,
)
from lightcraft_opt.ocp.problem import (
    EnergyBudget,
    LaserEnergy,
    NoGroundContact,
    OffsetLimit,
    RcsEnvelope,
    TiltLimit,
)
from lightcraft_opt.simulation.coast_reference import simulate_coast
from lightcraft_opt.simulation.flight_log import beam_gap
from lightcraft_opt.symbolic.terms.beam import beam_side


@pytest.fixture(scope="module")
def saved(flight: lc.SimulationResult, model: lc.Model, tmp_path_factory) -> Path:
    """Saved without figures (seconds each): test_plot_returns_the_cli_figures draws them."""
    return flight.save(tmp_path_factory.mktemp("flight") / "run", model=model, figures=False)


def test_summary_names_the_figures_with_units_and_repr_is_one_line(flight):
    text = flight.summary()
    assert str(flight) == text
    for line in ("apogee", "top speed", "energy captured", "capture margin", "max coning"):
        assert line in text
    assert f"{flight.apogee:.3f} m at {flight.apogee_time:.3f} s" in text
    assert f"{flight.energy_captured:.2f} J" in text and "m/s" in text and " deg" in text
    said = repr(flight)
    assert "\n" not in said and len(said) < 120 and "array" not in said
    assert said.startswith("<SimulationResult flight5: duration_reached, apogee")


def test_save_writes_the_cli_files_and_load_result_reads_them_back_exactly(flight, saved):
    names = {p.name for p in saved.iterdir()}
    assert {"trajectory.csv", "pulses.csv", "summary.json", "result.json"} <= names
    assert not any(n.endswith(".png") for n in names)  # figures=False
    back = lc.load_result(saved)
    assert isinstance(back, lc.SimulationResult) and back.status is flight.status
    for name in ("t", "x", "tilt", "coning", "H_L", "kinetic_energy", "mass"):
        assert np.array_equal(getattr(back, name), getattr(flight, name)), name
    for name in ("t", "u", "engine", "beam_gap"):
        a, b = getattr(back.pulses, name), getattr(flight.pulses, name)
        assert np.array_equal(a, b, equal_nan=True), name


def test_a_cli_folder_without_the_archive_reads_from_its_csv(flight, saved, tmp_path):
    """trajectory.csv and pulses.csv keep 12 significant digits."""
    for name in ("trajectory.csv", "pulses.csv", "summary.json"):
        (tmp_path / name).write_bytes((saved / name).read_bytes())
    back = lc.load_result(tmp_path)
    assert back.model_name == "flight5" and back.status is flight.status
    np.testing.assert_allclose(back.x, flight.x, rtol=1e-11, atol=1e-14)
    np.testing.assert_allclose(back.tilt, flight.tilt, rtol=1e-11, atol=1e-16)
    np.testing.assert_allclose(back.pulses.engine, flight.pulses.engine, rtol=1e-11, atol=1e-14)
    assert back.energy_captured == pytest.approx(flight.energy_captured, rel=1e-11)
    assert back.capture_margin == pytest.approx(flight.capture_margin, rel=1e-11)


def test_summary_json_figures_agree_with_the_trajectory_and_the_pulses(flight, saved, model):
    s = json.loads((saved / "summary.json").read_text())
    z = flight.state("r_L")[:, 2]
    assert s["apogee_time_s"] == flight.t[np.argmax(z)]
    assert s["top_speed_mps"] == np.max(np.linalg.norm(flight.state("v_L"), axis=1))
    assert s["max_coning_deg"] == pytest.approx(math.degrees(np.max(flight.coning)), rel=1e-15)
    assert s["landing_speed_mps"] is None  # it did not land
    rows = np.loadtxt(saved / "pulses.csv", delimiter=",", skiprows=1)
    col = {c: i for i, c in enumerate(PULSE_COLUMNS)}
    captured = rows[:, col["energy_captured_j"]]
    assert s["energy_captured_j"] == pytest.approx(np.sum(captured), rel=1e-11)
    assert s["energy_captured_j"] == np.sum(flight.pulses.energy_captured)
    # the capture margin from scratch: beam size at the craft at each fired pulse
    p = parameter_values(model)
    radius = model.craft.engine.capture_radius
    fired = rows[:, col["energy_j"]] > 0
    assert np.sum(~fired) == 1 and s["pulses_fired"] == len(rows) - 1
    gaps = []
    for row in rows[fired]:
        z_at = np.interp(row[col["t_s"]], flight.t, z)
        side = float(beam_side(z_at, row[col["focus_m"]], p, model.laser))
        offset = row[[col["offset_x_m"], col["offset_y_m"]]]
        gaps.append(beam_gap(offset, side, radius, model.laser.profile, signed=True))
    assert s["capture_margin_m"] == pytest.approx(-max(gaps), rel=1e-9)
    # near the axis: the capture radius plus about half the beam
    assert radius < s["capture_margin_m"] < radius + 0.5 * side


def test_plot_returns_the_cli_figures_by_name(flight, model):
    figures = flight.plot(model=model)
    assert set(figures) == {
        "flight.png",
        "altitude.png",
        "track.png",
        "attitude.png",
        "flight3d.png",
    }
    assert all(type(f).__name__ == "Figure" for f in figures.values())


def test_a_landed_coast_reports_its_landing_speed(model):
    """Thrown up at 4 m/s with the laser off, it lands at about the same speed (drag)."""
    x0 = initial_state(model, v_L=(0.0, 0.0, 4.0))
    coast = simulate_coast(model, 2.0, x0=x0)
    assert coast.status is lc.SimulationStatus.LANDED
    v = np.linalg.norm(coast.state("v_L")[-1])
    assert coast.landing_speed == v and 3.5 < v <= 4.0
    assert coast.capture_margin is None and coast.energy_captured == 0.0
    assert "landing speed    3." in coast.summary()


def _ocp(model: lc.Model) -> tuple[lc.OcpProblem, lc.OcpResult]:
    """A three-pulse problem and a made-up result: the craft rising 0.1 m a pulse, the
    optic 1, 2 and 3 mm off the beam, 400 J a pulse."""
    problem = lc.OcpProblem(
        model,
        horizon=3,
        objective=(LaserEnergy(),),
        constraints=(
            TiltLimit(math.radians(10)),
            OffsetLimit(0.5),
            NoGroundContact(0.05),
            EnergyBudget(1500.0),
        ),
    )
    x = np.tile(initial_state(model), (4, 1))
    x[:, STATE.slot("r_L").start + 2] = [0.0, 0.1, 0.2, 0.3]
    u = np.tile(problem.nominal_input(), (3, 1))
    u[:, problem.inputs.index("energy")] = 400.0
    engine = np.zeros((3, ENGINE.size))
    engine[:, ENGINE.slot("offset_L").start] = [1e-3, 2e-3, 3e-3]
    result = made_up_solve(
        x, u, problem.inputs, engine=engine, cost=1.5, iterations=7, solve_time=0.25,
        cost_terms=np.array([1.5]), w=np.arange(5.0),
    )  # fmt: skip
    return problem, result


def test_ocp_constraint_margins_are_each_constraints_smallest_slack(model):
    problem, result = _ocp(model)
    radius = float(PARAMETERS.get("capture_radius", problem.p))
    margins = {
        m["constraint"]: (m["margin"], m["unit"]) for m in constraint_margins(result, problem)
    }
    assert margins["tilt_limit"] == (pytest.approx(10.0), "deg")  # upright throughout
    assert margins["offset_limit"] == (pytest.approx(0.5 - 3e-3 / radius), "-")
    assert margins["no_ground_contact"] == (pytest.approx(0.1 - 0.05), "m")
    assert margins["energy_budget"] == (pytest.approx(1500.0 - 1200.0), "J")


def test_ocp_save_and_load_round_trip_and_summary(model, tmp_path):
    problem, result = _ocp(model)
    assert "laser energy    1200.00 J" in result.summary()
    assert repr(result).startswith("<OcpResult solved: cost 1.5, 7 iterations, 3 pulses")
    result.save(tmp_path, problem=problem, figures=False)
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["max_tilt_deg"] == pytest.approx(0.0, abs=1e-9)
    assert s["propellant_used_kg"] == 0.0 and len(s["constraint_margins"]) == 4
    back = lc.load_result(tmp_path)
    assert isinstance(back, lc.OcpResult) and back.status is lc.OcpStatus.SOLVED
    for name in ("t", "x", "u", "engine", "cost_terms", "w", "lam_g"):
        assert np.array_equal(getattr(back, name), getattr(result, name)), name
    assert back.inputs.names == result.inputs.names and back.iterations == 7
    with pytest.raises(lc.LightcraftError, match="problem"):
        result.save(tmp_path / "again", figures=False)


def test_calibration_and_campaign_round_trip_through_the_archive(tmp_path):
    fit = lc.CalibrationResult(
        CalibrationStatus.CONVERGED, "made up", ("cm", "launch_offset_x"), ("N/W", "m"),
        np.array([1.5e-4, 2e-3]), np.array([1e-4, 0.0]), np.zeros(2), np.ones(2),
        np.array([1e-6, np.inf]), np.eye(2), np.eye(2), np.array([3.0, 0.0]), np.inf,
        (FitFlag("launch_offset_x", FlagKind.NOT_IDENTIFIABLE, "null direction"),), 4, 1e-6,
        1e-3, 1e-3, np.full(3, 1e-3), np.zeros((2, 3)), np.arange(2.0), np.zeros((2, 3)),
        np.arange(2.0), np.zeros((2, STATE.size)), np.zeros(PARAMETERS.size),
        np.zeros(STATE.size), 0.5,
    )  # fmt: skip
    assert "launch_offset_x  0.002 not identifiable m  [not_identifiable]" in fit.summary()
    assert repr(fit) == (
        "<CalibrationResult converged: cm=0.00015, launch_offset_x=0.002; sigma 1.000 mm, "
        "4 iterations>"
    )
    write_archive(fit, tmp_path)
    back = read_archive(tmp_path)
    assert back.flags == fit.flags and back.names == fit.names
    assert np.array_equal(back.std, fit.std) and back.condition == math.inf

    stats = {"title": "t", "runs": 2, "status_counts": {"landed": 2}, "apogee_m": {"n": 0}}
    stats["left_beam"] = {"count": 0, "probability": 0.0, "wilson_95": [0.0, 0.84]}
    campaign = CampaignResult(
        tmp_path, 2, 2, 0, True, {"run": np.arange(2), "status": np.array(["landed"] * 2)},
        stats, "serial", 1.5, dispersed=("mass_kg", "tilt_deg"), capture_radius=0.055,
    )  # fmt: skip
    assert campaign.summary["status_counts"] == {"landed": 2}  # still the dict
    assert "status           2 landed" in campaign.summary()
    assert repr(campaign).startswith("<CampaignResult 2 runs (complete): 2 landed")
    (tmp_path / "result.json").unlink()
    write_archive(campaign, tmp_path)
    again = lc.load_result(tmp_path)
    assert dict(again.summary) == stats and again.engine == "serial"
    assert again.dispersed == ("mass_kg", "tilt_deg") and again.capture_radius == 0.055
    assert np.array_equal(again.table["status"], campaign.table["status"])


@pytest.mark.parametrize("profile", [RcsProfile.HOLD, RcsProfile.PHASE_LOCKED])
def test_the_rcs_envelope_margin_is_the_thrusts_least_room_over_every_phase(profile):
    """The margin against a sweep of 3600 phases of each pulse's thrust profile
    mean + cos cos(φ) + sin sin(φ) (held levels: the level itself), made-up inputs."""
    model = load_model(REPO_ROOT / "models" / "flight5-rcs.toml")
    problem = lc.OcpProblem(
        model, horizon=3, objective=(LaserEnergy(),), constraints=(RcsEnvelope(),),
        rcs_profile=profile,
    )  # fmt: skip
    top = np.array([t.max_thrust for t in model.craft.rcs.thrusters])
    rng = np.random.default_rng(3)
    u = np.tile(problem.nominal_input(), (3, 1))
    mean = rng.uniform(0.2, 0.8, (3, top.size)) * top
    cols = {
        n: slice(problem.inputs.slot(n).start, problem.inputs.slot(n).stop)
        for n in ("rcs_thrust", "rcs_cos", "rcs_sin")
        if n in problem.inputs.names
    }
    u[:, cols["rcs_thrust"]] = mean
    thrust = mean[:, :, None] * np.ones(3600)
    if profile is RcsProfile.PHASE_LOCKED:
        cos, sin = (rng.uniform(-0.3, 0.3, (3, top.size)) * top for _ in range(2))
        u[:, cols["rcs_cos"]], u[:, cols["rcs_sin"]] = cos, sin
        phase = np.linspace(0.0, 2 * np.pi, 3600, endpoint=False)
        thrust = thrust + cos[:, :, None] * np.cos(phase) + sin[:, :, None] * np.sin(phase)
    x = np.tile(initial_state(model), (4, 1))
    result = made_up_solve(x, u, problem.inputs)
    swept = min(thrust.min(), (top[None, :, None] - thrust).min())
    (margin,) = [
        m for m in constraint_margins(result, problem) if m["constraint"] == "rcs_envelope"
    ]
    assert margin["unit"] == "N"
    assert margin["margin"] == pytest.approx(swept, abs=1e-6 * top.max())
