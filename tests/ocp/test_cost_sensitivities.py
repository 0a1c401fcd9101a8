"""The optimum's sensitivities (ocp/sensitivity.py, CompiledOcp.sensitivities,
OcpOptions.sensitivities, summary.json's ``sensitivities``) against references.

References:

- central finite differences of the optimal cost: the problem re-solved, warm started,
  to a KKT tolerance of 1e-10 at θ ± h, h = 1e-4 |θ|; agreement 1e-4 relative (the
  issue's demand). The difference quotient's own error: its truncation, ~h² J''' / J'
  ~ 1e-8 relative, and the re-solves' KKT error over 2h, ~1e-10 / (2e-4 |θ| |J'|);
  measured agreement 4e-8 on the lateral problem;
- the closed form of a drag-free vertical pulse train (tests/ocp/test_ocp.py's
  ``_vertical_flow``): the least sum (E_k / E_max)² that puts the craft at H after N
  pulses is J* = (H - z_free - v0 S)² / (|a|² E_max²), a = c s with c = I0 / (m E0), S =
  sinh(kNT) / k the launch climb rate's share; so θ dJ*/dθ = -2 J* for the impulse per
  pulse I0 and +2 J* for the dry mass m and the reference pulse energy E0, and
  dJ*/dv0 = -2 (H - z_free) S / (|a|² E_max²);
- the same NLP solved with Φ's chain derivatives and with casadi's AD: the same
  multipliers, hence the same sensitivities.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from support.models import table1_flight5
from test_ocp import (
    CHEAP_MAP,
    QUADRATURE,
    TOL,
    _energy_only,
    _vertical_flow,
    drag_free_vertical,
    lateral_problem,
)

from lightcraft_opt.cli import main
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.ocp_outputs import write_ocp_summary
from lightcraft_opt.files.problem import ProblemFile, load_problem
from lightcraft_opt.files.result_archive import read_archive
from lightcraft_opt.layout import PARAMETERS, STATE
from lightcraft_opt.model import Engine
from lightcraft_opt.ocp.options import OcpOptions, OcpSolver
from lightcraft_opt.ocp.problem import (
    ControlEffort,
    DesignVariable,
    OcpProblem,
    TerminalAltitude,
)
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.terms.gravity import EARTH_GM, WGS84_A, WGS84_F

REPO = Path(__file__).resolve().parents[2]
TIGHT = 1e-10  # KKT tolerance of the solves differenced
STEP = 1e-4  # finite-difference step, relative to the parameter


@pytest.fixture(scope="module")
def lateral():
    """The lateral beam-tracking problem of tests/ocp/test_ocp.py (wind, full
    aerodynamics, slew limit and capture constraint active), solved tight with casadi's
    AD through Φ, sensitivities attached."""
    base = table1_flight5()
    model = replace(base, craft=replace(base.craft, engine=Engine(**QUADRATURE)))  # type: ignore[arg-type]
    problem = lateral_problem(model)
    phi = build_pulse_map(model, CHEAP_MAP)
    options = OcpOptions(tol=TIGHT, chain_derivatives=False, replay=False, sensitivities=True)
    compiled = CompiledOcp(problem, options, pulse_map=phi)
    result = compiled.solve()
    assert result.status is OcpStatus.SOLVED, result.message
    return problem, phi, compiled, result


def _perturbed(problem: OcpProblem, name: str, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """(x0, p) of ``problem`` with the parameter ``name`` (an entry of p, or ``launch_``
    and a state entry of x0, e.g. ``launch_v_L[up]``) moved by ``delta`` [SI]."""
    x0, p = np.array(problem.x0, dtype=float), np.array(problem.p, dtype=float)
    labels = [label.split(" [")[0] for label in PARAMETERS.labels()]
    if name.startswith("launch_"):
        states = [label.split(" [")[0] for label in STATE.labels()]
        x0[states.index(name.removeprefix("launch_"))] += delta
    else:
        p[labels.index(name)] += delta
    return x0, p


@pytest.mark.parametrize(
    "name",
    ["wind_speed_ref", "rotor_mass_dry", "cd_scale", "impulse_per_pulse", "launch_v_L[up]"],
)
def test_sensitivities_are_central_differences_of_re_solves(lateral, name):
    """dJ*/dθ against (J*(θ + h) - J*(θ - h)) / 2h on a problem whose slew limit (first
    step) and capture constraint (pulses 1-5) are active: the envelope theorem through
    active inequalities, a wind speed, an aerodynamic coefficient, the craft's mass and
    impulse, and a launch state entry."""
    problem, _, compiled, result = lateral
    rows = compiled.transcription.constraint_rows
    active = {
        row.kind
        for row, lam, lo, hi in zip(
            rows, result.lam_g, compiled.transcription.lbg, compiled.transcription.ubg, strict=True
        )
        if lo < hi and abs(lam) > 1e-6
    }
    assert {"slew_limit", "offset_limit"} <= active
    sens = result.sensitivities
    assert sens is not None and sens.computed, sens
    item = sens.of(name)
    h = STEP * abs(item.value)
    costs = []
    for sign in (1.0, -1.0):
        x0, p = _perturbed(problem, name, sign * h)
        moved = compiled.solve(x0=x0, p=p, warm_start=result)
        assert moved.status is OcpStatus.SOLVED, moved.message
        costs.append(moved.cost)
    difference = (costs[0] - costs[1]) / (2 * h)
    assert abs(difference) > 1e-3 * abs(result.cost) / abs(item.value)  # a real change
    assert item.derivative == pytest.approx(difference, rel=1e-4)
    # the same figure by the method, from the result alone
    again = compiled.sensitivities(result)
    assert again.of(name).derivative == item.derivative


def test_the_lagrangian_gradient_is_its_finite_differences(lateral):
    """MultipleShooting.lagrangian_gradient against central differences of
    f + lam_gᵀ g in P at the optimum, for the entries of P that Φ, the constraints and
    the cost read (docs/architecture.md#rule-3); parameters_read marks every entry with
    a nonzero gradient. Step 1e-6 relative, agreement 1e-6 relative to the largest term
    (measured: 1e-9); an entry nothing reads (the RCS's specific impulse) is not read."""
    problem, _, compiled, result = lateral
    tr = compiled.transcription
    P = tr.parameter_vector(
        problem.x0, problem.p, problem.t0, None, compiled._u_fixed, problem.reference()
    )
    grad = np.asarray(tr.lagrangian_gradient()(result.w, P, result.lam_g)).ravel()
    read = tr.parameters_read()
    assert np.all(read[grad != 0.0])
    p0 = tr.parameters.slot("p").start
    assert not read[p0 + PARAMETERS.slot("rcs_isp").start]

    def lagrangian(P: np.ndarray) -> float:
        f = float(np.sum(np.asarray(tr.cost_terms(result.w, P))))
        return f + float(np.dot(result.lam_g, np.asarray(tr.constraints(result.w, P)).ravel()))

    for name in ("wind_speed_ref", "cd_scale", "capture_radius", "beam_side"):
        i = p0 + PARAMETERS.slot(name).start
        h = 1e-6 * abs(P[i])
        up, down = P.copy(), P.copy()
        up[i] += h
        down[i] -= h
        difference = (lagrangian(up) - lagrangian(down)) / (2 * h)
        assert grad[i] == pytest.approx(difference, rel=1e-6), name


def test_chain_and_ad_nlps_give_the_same_sensitivities(lateral):
    """The NLP solved with Φ's chain derivatives reaches the same point and multipliers
    as with casadi's AD (both to 1e-10): every sensitivity within 1e-6 of the largest
    (measured: 1e-13 relative)."""
    problem, phi, _, reference = lateral
    options = OcpOptions(tol=TIGHT, chain_derivatives=True, replay=False, sensitivities=True)
    compiled = CompiledOcp(problem, options, pulse_map=phi)
    assert compiled.chain is not None
    result = compiled.solve()
    assert result.status is OcpStatus.SOLVED, result.message
    ours, theirs = result.sensitivities, reference.sensitivities
    assert ours is not None and theirs is not None
    assert ours.names == theirs.names
    scale = np.max(np.abs(theirs.derivatives * theirs.values))
    assert np.max(np.abs(ours.elasticities - theirs.elasticities)) < 1e-6 * scale


@pytest.fixture(scope="module")
def vertical():
    model = drag_free_vertical()
    return model, build_pulse_map(model, CHEAP_MAP)


def _least_squared_energies(model, n, height, **design) -> OcpProblem:
    e_max = model.laser.pulse_energy_max
    return replace(
        _energy_only(
            model,
            n,
            (ControlEffort("energy", weight=e_max**-2),),
            (TerminalAltitude(minimum=height, maximum=height),),
        ),
        **design,
    )


@pytest.mark.parametrize("solver", [OcpSolver.IPOPT, OcpSolver.SQP_QRQP, OcpSolver.FATROP])
def test_sensitivities_of_a_vertical_pulse_train_are_the_closed_form(vertical, solver):
    """6 pulses, 0.7 m exactly, least sum (E_k / E_max)²: the elasticities to I0, m and
    E0 are -2 J*, +2 J*, +2 J*, and the launch climb rate's derivative is
    -2 (H - z_free) S / (|a|² E_max²) (module docstring). Tolerance 1e-6 relative: the
    solvers' KKT tolerance 1e-8, the multiplier of the height constraint to as much. The
    multipliers of an interior point method (IPOPT, fatrop) and of an active-set SQP
    (qrqp) in casadi's one sign convention."""
    model, phi = vertical
    n, height, e_max = 6, 0.7, model.laser.pulse_energy_max
    problem = _least_squared_energies(model, n, height)
    options = OcpOptions(
        solver=solver, tol=TOL, replay=False, sensitivities=True, chain_derivatives=False
    )
    result = CompiledOcp(problem, options, pulse_map=phi).solve()
    assert result.status is OcpStatus.SOLVED, result.message
    sens = result.sensitivities
    assert sens is not None and sens.computed, sens
    cost = result.cost
    assert sens.of("impulse_per_pulse").elasticity == pytest.approx(-2 * cost, rel=1e-6)
    assert sens.of("rotor_mass_dry").elasticity == pytest.approx(2 * cost, rel=1e-6)
    assert sens.of("reference_pulse_energy").elasticity == pytest.approx(2 * cost, rel=1e-6)
    z_free, a = _vertical_flow(model, n, phi.period)
    radius = WGS84_A * (1 - WGS84_F) + model.site.height  # as _vertical_flow's
    k = math.sqrt(2 * EARTH_GM / radius**3)
    climb = math.sinh(k * n * phi.period) / k  # S
    expected = -2 * (height - z_free) * climb / (a @ a) / e_max**2
    assert sens.of("launch_v_L[up]").derivative == pytest.approx(expected, rel=1e-6)
    # the three move J* together: the ranking puts them first, E0 and m tied
    assert {s.name for s in sens.ranked(3)} == {
        "impulse_per_pulse",
        "rotor_mass_dry",
        "reference_pulse_energy",
    }


def test_a_designed_parameter_is_chosen_not_held(vertical):
    """The same train with I0 designed in [I0 / 2, I0]: a larger impulse costs less, so
    the optimum takes the upper bound, the model's I0, and is the undesigned optimum. I0
    has no sensitivity then (it is chosen; its bound's multiplier is not a derivative in a
    held parameter), the mass keeps the closed form +2 J*."""
    model, phi = vertical
    impulse = model.flight.impulse_per_pulse
    design = (DesignVariable("impulse_per_pulse", 0.5 * impulse, impulse),)
    problem = _least_squared_energies(model, 6, 0.7, design=design)
    options = OcpOptions(tol=TOL, replay=False, sensitivities=True)
    result = CompiledOcp(problem, options, pulse_map=phi).solve()
    assert result.status is OcpStatus.SOLVED, result.message
    assert result.design["impulse_per_pulse"] == pytest.approx(impulse, rel=1e-7)
    sens = result.sensitivities
    assert sens is not None and "impulse_per_pulse" not in sens.names
    assert sens.of("rotor_mass_dry").elasticity == pytest.approx(2 * result.cost, rel=1e-6)


def test_an_unsolved_result_has_no_sensitivities_and_says_why(vertical):
    """The envelope theorem needs an optimum: a solve stopped at its iteration limit gets
    an empty Sensitivities with the reason, shown in its summary; without
    OcpOptions.sensitivities a result has none at all."""
    model, phi = vertical
    problem = _least_squared_energies(model, 6, 0.7)
    options = OcpOptions(tol=TOL, replay=False, max_iter=1, chain_derivatives=False)
    compiled = CompiledOcp(problem, options, pulse_map=phi)
    result = compiled.solve()
    assert result.status is OcpStatus.MAX_ITER
    assert result.sensitivities is None
    with pytest.raises(ParameterError, match="result"):
        compiled.sensitivities(replace(result, w=result.w[:-1]))
    sens = compiled.sensitivities(result)
    assert not sens.computed and len(sens) == 0
    assert "max_iter" in sens.reason
    assert f"none: {sens.reason}" in replace(result, sensitivities=sens).summary()


def test_summary_json_and_the_archive_carry_the_sensitivities(lateral, tmp_path):
    """summary.json: every held parameter under its name and SI unit, largest
    |elasticity| first, with value, derivative and elasticity; result.npz keeps them to
    the bit; the summary shows the five largest."""
    problem, _, compiled, result = lateral
    pf = ProblemFile(problem, compiled.options, "lateral", tmp_path / "lateral.toml")
    summary = write_ocp_summary(result, pf, tmp_path / "summary.json")
    written = json.loads((tmp_path / "summary.json").read_text())["sensitivities"]
    assert written == json.loads(json.dumps(summary["sensitivities"]))
    sens = result.sensitivities
    assert sens is not None
    entry = written["parameters"]["rotor_mass_dry_kg"]
    assert entry["derivative"] == sens.of("rotor_mass_dry").derivative
    assert entry["value"] * entry["derivative"] == pytest.approx(entry["elasticity"])
    assert "wind_speed_ref_mps" in written["parameters"]
    assert "launch_v_L_up_mps" in written["parameters"]
    assert len(written["parameters"]) == len(sens)
    elasticities = [abs(e["elasticity"]) for e in written["parameters"].values()]
    assert elasticities == sorted(elasticities, reverse=True)
    assert written["ranked"] == list(written["parameters"])[:5]
    assert written["reason"] is None
    back = read_archive(tmp_path)
    assert back.sensitivities.names == sens.names
    assert np.array_equal(back.sensitivities.derivatives, sens.derivatives)
    lines = result.summary().splitlines()
    top = [s.name for s in sens.ranked(5)]
    shown = [
        line.split()[0]
        for line in lines[
            lines.index(next(line for line in lines if line.strip().startswith("sensitivities")))
            + 1 :
        ]
    ]
    assert shown == top


def test_a_problem_file_asks_for_them(tmp_path):
    """``[solver] sensitivities = true`` sets OcpOptions.sensitivities; false by default."""
    source = REPO / "problems" / "crosswind_launch.toml"
    assert load_problem(source).options.sensitivities is False
    text = source.read_text().replace('"../models/', f'"{REPO / "models"}/')
    path = tmp_path / "asks.toml"
    path.write_text(text.replace("[solver]\n", "[solver]\nsensitivities = true\n", 1))
    assert load_problem(path).options.sensitivities is True


STEER = """\
title = "steer the beam under Flight 5 in a crosswind, sensitivities asked"
model = "{models}/flight5.toml"
horizon_pulses = 3

[model_overrides.environment.wind]
speed_ref_mps = 3.0
direction_from_deg = 90.0
[model_overrides.craft.engine]
quadrature_radial = 4
quadrature_azimuthal = 16

[initial]
position_L_m = [0.01, 0.0, 2.0]
velocity_L_mps = [0.0, 0.0, 4.0]

[[objective]]
term = "lateral_offset"
weight = 1e4
[[objective]]
term = "control_effort"
input = "pointing_L"
weight = 1e3

[[control]]
input = "pointing_L"
lower_cm = -5
upper_cm = 5
[[control]]
input = "energy"
lower_j = 420.0
upper_j = 420.0

[solver]
sensitivities = true

[pulse_map]
scheme = "split"
substeps = 1
dense = 1
"""


@pytest.mark.slow  # the replay's simulator Φ and the figures: ~16 s
def test_optimize_prints_the_largest_and_writes_them_all(tmp_path, capsys):
    """``lightcraft optimize`` on a file that asks for them: the five largest printed in
    the order of summary.json's ``ranked``, every one in summary.json."""
    path = tmp_path / "steer.toml"
    path.write_text(STEER.format(models=REPO / "models"))
    out = tmp_path / "out"
    assert main(["optimize", str(path), "--out", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    summary = json.loads((out / "summary.json").read_text())["sensitivities"]
    assert summary["reason"] is None and len(summary["ranked"]) == 5
    first = next(i for i, line in enumerate(printed) if line.startswith("sensitivities:"))
    shown = [line.split()[0] for line in printed[first + 1 : first + 6]]
    keys = [name.replace("[", "_").rstrip("]") for name in shown]  # + the unit
    assert all(k.startswith(n) for k, n in zip(summary["ranked"], keys, strict=True))
