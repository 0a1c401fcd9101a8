"""The director's named layouts (layout/controllers.py) against the Functions it builds.

Reference: the dimensions of the casadi Functions themselves. The QP Function
``director_qp(A, B, g, d, lbx, ubx, w0, lam_x0, lam_a0)`` and its constraint assembly take
their sizes from the Hessians the director hands them (control/director_qp.py); Ψ's stage
Function from the reduced map. Each must have the size the director's layouts say, so that
indexing by name reads the entry the QP means.

Model: Flight 5 with RCS under the waist beam model, interpreted Functions.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.options import DirectorOptions
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import (
    DIRECTOR_DISTURBANCE,
    DIRECTOR_INPUT,
    DIRECTOR_OUTPUT,
    DIRECTOR_STAGE,
    DIRECTOR_STATE,
    DIRECTOR_TERMINAL_OUTPUT,
    REDUCED_STATE,
    initial_state,
    map_input_layout,
)
from lightcraft_opt.model import BeamSizeModel


@pytest.fixture(scope="module")
def director() -> DirectorController:
    model = load_model(REPO_ROOT / "models" / "flight5-rcs.toml")
    model = replace(model, laser=replace(model.laser, size_model=BeamSizeModel.WAIST))
    inputs = map_input_layout(model.craft.thruster_count, model.craft.has_carrier)
    options = DirectorOptions(horizon=4, relinearize=3, time_budget=None)
    return DirectorController(model, inputs, options, compiled=False)


def test_the_qp_function_has_the_director_layouts_sizes(director: DirectorController) -> None:
    nz, nu, N = DIRECTOR_STATE.size, DIRECTOR_INPUT.size, director.options.horizon
    qp = director.qp
    assert (qp.nz, qp.nu, qp.horizon) == (nz, nu, N)
    assert nz + nu == DIRECTOR_STAGE.size
    f = qp.function
    n_w = N * DIRECTOR_STAGE.size + nz  # [δz_0, δu_0, ..., δz_N]
    expected = {
        "A": (nz, nz * N),
        "B": (nz, nu * N),
        "g": (n_w, 1),
        "d": (N * nz, 1),
        "lbx": (n_w, 1),
        "ubx": (n_w, 1),
        "w0": (n_w, 1),
        "lam_x0": (n_w, 1),
        "lam_a0": (N * nz, 1),
    }
    assert {name: f.size_in(name) for name in f.name_in()} == expected
    assert f.size_out("w") == (n_w, 1)
    a = qp._assemble  # the dynamics' rows, [A_j B_j -I] by stage
    assert a.size_out("a") == (N * nz, n_w)


def test_the_objective_and_bounds_have_the_director_layouts_sizes(
    director: DirectorController,
) -> None:
    assert director._C.shape == (DIRECTOR_OUTPUT.size, DIRECTOR_STAGE.size)
    assert director._W.shape == (DIRECTOR_OUTPUT.size,)
    assert director._Ct.shape == (DIRECTOR_TERMINAL_OUTPUT.size, DIRECTOR_STATE.size)
    assert director._Wt.shape == (DIRECTOR_TERMINAL_OUTPUT.size,)
    assert director.u_lower.shape == director.u_upper.shape == (DIRECTOR_INPUT.size,)
    assert director.disturbance.shape == (DIRECTOR_DISTURBANCE.size,)
    # the RCS's torque is bounded by the thrusters' reach, not to zero ("tilt", with an RCS)
    assert np.all(DIRECTOR_INPUT.get("torque_B", director.u_upper) > 0)


def test_psi_stage_and_a_step_have_the_layouts_sizes(director: DirectorController) -> None:
    """Ψ's stage Function (z, u, p, t) -> (z_next, engine, A, B) is in REDUCED_STATE, whose
    head the QP's states are; one step plans (N + 1) states and N QP inputs."""
    stage = director._stage
    nz = REDUCED_STATE.size
    assert stage.size_in(0) == (nz, 1)
    assert stage.size_out(0) == (nz, 1)
    assert stage.size_out(2) == (nz, nz)
    assert stage.size_out(3) == (nz, director._psi_inputs.size)
    director.reset()
    u = director.step(initial_state(director.model), 0.0)
    assert u.shape == (director.inputs.size,)
    z, v = director.plan
    N = director.options.horizon
    assert z.shape == (N + 1, nz) and v.shape == (N, DIRECTOR_INPUT.size)
