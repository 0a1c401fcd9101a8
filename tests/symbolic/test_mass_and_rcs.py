"""Mass properties under propellant use, and the RCS forces, moments and flow.

References: parallel-axis theorem; rocket mass flow mdot = T / (Isp g0); the moment of
a force about the mass centre; Table 1 launch values (the seed paper,
docs/references.md#paper-table-1) reproduced at launch.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from support.models import table1_flight5

from lightcraft_opt.layout import STATE, initial_state, parameter_values
from lightcraft_opt.model import Liner, Rcs, Thruster
from lightcraft_opt.symbolic.maps.coast_rhs import coast_terms
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.rcs import STANDARD_GRAVITY

LINER = Liner(mass=0.003, radius=0.045, axial_offset=0.01)
RCS = Rcs(
    thrusters=(
        Thruster((0.02, 0.0, 0.05), (0.0, -1.0, 0.0), 0.05),
        Thruster((0.02, 0.05, 0.0), (0.0, 0.0, 1.0), 0.05),
        Thruster((-0.03, 0.0, 0.0), (1.0, 0.0, 0.0), 0.05),
    ),
    isp=60.0,
    propellant_mass=0.002,
    tank_position_B=(-0.01, 0.0, 0.0),
)


def _props(model, x):
    mp = mass_properties(ca.DM(x), ca.DM(parameter_values(model)))
    return (
        float(mp.mass),
        np.asarray(mp.cm_B).ravel(),
        np.asarray(mp.I_B),
        float(mp.J),
        float(mp.I),
    )


def test_launch_mass_properties_reproduce_table1_with_a_liner():
    model = table1_flight5(liner=LINER)
    m, cm, I_B, J, I = _props(model, initial_state(model))
    assert m == pytest.approx(0.0325, rel=1e-15)
    assert J == pytest.approx(602.7e-7, rel=1e-12)
    assert I == pytest.approx(465.3e-7, rel=1e-12)
    # launch mass centre: the liner's share of its offset
    assert cm == pytest.approx([0.003 * 0.01 / 0.0325, 0, 0], rel=1e-12, abs=1e-18)
    # no carrier: nothing but the rotor itself, which sits on the mass centre
    assert np.max(np.abs(I_B)) < 1e-20


def test_spent_liner_leaves_the_dry_rotor():
    model = table1_flight5(liner=LINER)
    x = initial_state(model)
    x[STATE.index("liner_mass")] = 0.0
    m, cm, _I_B, J, I = _props(model, x)
    assert m == pytest.approx(0.0295, rel=1e-14)
    assert cm == pytest.approx([0, 0, 0], abs=1e-18)
    j_dry, i_dry = model.craft.dry_rotor_inertia()
    assert (J, I) == pytest.approx((j_dry, i_dry), rel=1e-14)
    assert J == pytest.approx(602.7e-7 - 0.003 * 0.045**2, rel=1e-12)


def test_propellant_point_mass_obeys_parallel_axis_theorem():
    model = table1_flight5(rcs=RCS)
    m, cm, I_B, _J, _I = _props(model, initial_state(model))
    m_p, d = 0.002, np.array([-0.01, 0.0, 0.0])
    assert m == pytest.approx(0.0345, rel=1e-14)
    assert cm == pytest.approx(m_p * d / m, rel=1e-12)
    # rotor (mass 0.0325 at 0) and tank (0.002 at d) about their common centre
    mu = 0.0325 * m_p / m
    expected = mu * (d @ d * np.eye(3) - np.outer(d, d))
    assert expected[0] == pytest.approx([0, 0, 0], abs=1e-20)  # on-axis: b1 row zero
    assert I_B == pytest.approx(expected, rel=1e-12, abs=1e-22)


def test_rcs_force_moment_and_mass_flow():
    model = table1_flight5(rcs=RCS)
    p = parameter_values(model)
    x = initial_state(model, r_L=(0.0, 0.0, 100.0))
    t = ca.SX.sym("t")
    xs = ca.SX.sym("x", STATE.size)
    us = ca.SX.sym("u", 3)
    terms = coast_terms(t, xs, us, ca.SX(p), model)
    f = ca.Function("f", [xs, us], [terms["F_rcs_B"], terms["M_rcs_B"], terms["xdot"]])
    thrust = np.array([0.01, 0.02, 0.03])
    F, M, xdot = (np.asarray(v).ravel() for v in f(x, thrust))
    dirs = np.array([t.direction_B for t in RCS.thrusters])
    pos = np.array([t.position_B for t in RCS.thrusters])
    assert F == pytest.approx(thrust @ dirs, rel=1e-14)
    _m, cm, *_ = _props(model, x)
    M_ref = sum(np.cross(pos[k] - cm, thrust[k] * dirs[k]) for k in range(3))
    assert M == pytest.approx(M_ref, rel=1e-12)
    assert xdot[STATE.index("rcs_mass")] == pytest.approx(
        -thrust.sum() / (60.0 * STANDARD_GRAVITY), rel=1e-14
    )
    # an empty tank gives no thrust
    x[STATE.index("rcs_mass")] = 0.0
    F0, M0, xdot0 = (np.asarray(v).ravel() for v in f(x, thrust))
    assert np.all(F0 == 0) and np.all(M0 == 0) and xdot0[STATE.index("rcs_mass")] == 0
