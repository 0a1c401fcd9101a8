"""The OCP predicting with the coning-aware reduced map Ψ (OcpOptions.prediction = "reduced").

Reference: Φ at full accuracy (Yoshida splitting, 32 substeps: the simulator's default). The
crosswind launch (problems/crosswind_launch.toml, 3 m/s, the beam steered to keep the craft
within half the capture radius) solved over its first 20 pulses with Ψ as the prediction,
then the optimal pointing flown by Φ: Ψ's predicted positions stay within 3 mm of Φ's across
the beam and 2.5 cm along it (measured 1.3, 0.5 and 14.6 mm east, north, up), where the map the
file plans with (Φ's Strang splitting, 2 substeps) predicts the same pointing 6-20 times worse
(12.5, 11.8 and 83 mm); and the flown craft keeps the constraint to within that error (capture
fraction <= 0.55 flown, 0.5 planned).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.errors import OptionError
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.layout import ENGINE, STATE, RcsProfile
from lightcraft_opt.ocp.options import OcpOptions, PredictionMap
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp, rollout
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

PULSES = 20


@pytest.fixture(scope="module")
def planned():
    loaded = load_problem(REPO_ROOT / "problems" / "crosswind_launch.toml")
    problem = dataclasses.replace(loaded.problem, horizon=PULSES)
    options = dataclasses.replace(loaded.options, prediction=PredictionMap.REDUCED)
    compiled = CompiledOcp(problem, options)
    return problem, loaded.options, compiled, compiled.solve()


def test_reduced_prediction_is_what_phi_flies(planned):
    problem, file_options, compiled, result = planned
    assert result.status is OcpStatus.SOLVED, result.message
    assert compiled.pulse_map.step.name() == "reduced_pulse_map"
    p, t0 = problem.p, problem.t0
    r = slice(STATE.slot("r_L").start, STATE.slot("r_L").stop)
    phi = build_pulse_map(problem.model, PulseMapOptions())
    flown = rollout(problem, phi, result.u)[0]
    strang_map = build_pulse_map(problem.model, problem.pulse_map_options(file_options.pulse_map))
    strang = rollout(problem, strang_map, result.u)[0]
    reduced_error = np.max(np.abs(result.x[:, r] - flown[:, r]), axis=0)  # east, north, up
    strang_error = np.max(np.abs(strang[:, r] - flown[:, r]), axis=0)
    assert np.all(reduced_error[:2] < 0.003) and reduced_error[2] < 0.025
    assert np.all(strang_error > 4 * reduced_error)
    capture = problem.model.craft.engine.capture_radius
    offset = slice(ENGINE.slot("offset_L").start, ENGINE.slot("offset_L").stop)
    fractions = [
        np.hypot(*np.asarray(phi.step(flown[k], result.u[k], p, t0 + k * phi.period)[1])[offset])
        / capture
        for k in range(PULSES)
    ]
    assert max(fractions) < 0.55


def test_reduced_prediction_needs_held_rcs_levels():
    loaded = load_problem(REPO_ROOT / "problems" / "rcs_gust_tilt.toml")
    problem = dataclasses.replace(
        loaded.problem, rcs_profile=RcsProfile.PHASE_LOCKED, horizon=4, constraints=()
    )
    options = dataclasses.replace(loaded.options, prediction=PredictionMap.REDUCED)
    with pytest.raises(OptionError, match="prediction 'reduced' takes held RCS levels"):
        CompiledOcp(problem, options)
    with pytest.raises(OptionError, match=r"OcpOptions\.prediction must be one of"):
        OcpOptions(prediction="reduced")  # type: ignore[arg-type]
