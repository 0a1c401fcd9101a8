"""MUMPS's pivot tolerance in IPOPT (OcpOptions.mumps_pivtol, ``mumps_pivtol`` under
``[solver]``).

References: the optimum does not depend on how the KKT systems on the way were pivoted,
so the lateral problem (tests/ocp/test_ocp.py) solved with a pivot tolerance of 1e-3
reaches the optimum of IPOPT's default to the solve's tolerance; the option's range and
the solvers it belongs to, refused by name otherwise.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from ocp.test_chain_derivatives import _lateral
from ocp.test_ocp import TOL
from support.capped_energy import capped_flight16

from lightcraft_opt.errors import OptionError, ProblemFileError
from lightcraft_opt.files.problem import load_problem
from lightcraft_opt.ocp.options import LinearSolver, OcpOptions, OcpSolver
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

POINTING = 0.05  # the lateral problem's pointing range [m], each side


def test_the_pivot_tolerance_leaves_the_optimum_where_it_is():
    problem, options = _lateral()
    phi = build_pulse_map(problem.model, problem.pulse_map_options(options))
    results = {
        pivtol: CompiledOcp(
            problem,
            OcpOptions(pulse_map=options, tol=TOL, replay=False, mumps_pivtol=pivtol),
            pulse_map=phi,
        ).solve()
        for pivtol in (None, 1e-3)
    }
    default, pivoted = results[None], results[1e-3]
    assert default.status is pivoted.status is OcpStatus.SOLVED, pivoted.message
    assert pivoted.cost == pytest.approx(default.cost, rel=1e-7)
    assert np.max(np.abs(pivoted.u - default.u)) < 1e-5 * POINTING


@pytest.mark.parametrize("bad", [0.0, 1.0, -1e-3, 2, math.nan, True, "1e-3"])
def test_a_pivot_tolerance_outside_0_1_is_refused(bad):
    with pytest.raises(OptionError, match=r"OcpOptions\.mumps_pivtol"):
        OcpOptions(mumps_pivtol=bad)  # type: ignore[arg-type]


def test_the_pivot_tolerance_is_mumps_in_ipopt():
    with pytest.raises(OptionError, match="linear_solver 'mumps', got 'ipopt' and 'spral'"):
        OcpOptions(mumps_pivtol=1e-3, linear_solver=LinearSolver.SPRAL)
    with pytest.raises(OptionError, match="needs solver 'ipopt'"):
        OcpOptions(mumps_pivtol=1e-3, solver=OcpSolver.SQP_HPIPM)
    assert OcpOptions().mumps_pivtol is None  # IPOPT's own default


def test_the_pivot_tolerance_is_read_from_the_solver_table(tmp_path):
    path = capped_flight16(tmp_path / "capped.toml", energy_cap_J=20.0, minimum_m=5.0)
    text = path.read_text()
    assert load_problem(path).options.mumps_pivtol is None
    path.write_text(text.replace("[solver]", "[solver]\nmumps_pivtol = 1e-3"))
    assert load_problem(path).options.mumps_pivtol == 1e-3
    path.write_text(text.replace("[solver]", "[solver]\nmumps_pivtol = 1.5"))
    with pytest.raises(ProblemFileError) as err:
        load_problem(path)
    assert err.value.field == "solver.mumps_pivtol" and "(0, 1)" in str(err.value)
