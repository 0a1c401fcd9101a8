"""Rotational dynamics of the assembled coast model against closed forms and invariants.

References: torque-free symmetric top (Goldstein, Classical Mechanics, 3rd ed., 5.6,
docs/references.md#goldstein:
body-frame nutation rate (J - I)/I Omega, coning rate |H|/I = J Omega/(I cos theta));
conservation of H and kinetic energy without torques; gyroscopic stability factor
S_g = H^2 / (4 I M_alpha) (docs/physics.md#gyroscopic-stability).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from support.models import table1_flight5, torque_free

from lightcraft_opt.layout import STATE, initial_state, parameter_values, quaternion_from_tilt
from lightcraft_opt.model import Carrier
from lightcraft_opt.simulation.coast_reference import SimulationOptions, simulate_coast
from lightcraft_opt.symbolic.maps.coast_rhs import build_coast_rhs, coast_terms
from lightcraft_opt.symbolic.terms.invariants import build_invariants

TIGHT = SimulationOptions(rtol=1e-12, atol=1e-14, samples_per_interval=40, stop_on_landing=False)


def _coasting_state(model, *, w_B, tilt=0.0):
    """High above the pad (no landing), at rest, in free fall."""
    return initial_state(model, r_L=(0.0, 0.0, 1000.0), w_B=w_B, tilt=tilt)


def _phase_rate(t: np.ndarray, z: np.ndarray) -> float:
    """Mean rotation rate of the complex signal z(t) [rad/s]."""
    phase = np.unwrap(np.angle(z))
    return float((phase[-1] - phase[0]) / (t[-1] - t[0]))


def test_flight5_nutation_and_coning_rates_match_torque_free_symmetric_top():
    model = torque_free(table1_flight5())
    J, I, spin = model.craft.inertia_axial, model.craft.inertia_transverse, model.craft.spin
    res = simulate_coast(model, 0.5, x0=_coasting_state(model, w_B=(0.0, 1e-3, 0.0)), options=TIGHT)
    w = res.state("w_B")
    # w_t turns in B at J/I spin (gauge w1 = 0); relative to the rotor (turning at spin in B):
    rate_B = _phase_rate(res.t, w[:, 1] + 1j * w[:, 2])
    relative_to_rotor = rate_B - spin
    assert relative_to_rotor == pytest.approx((J - I) / I * spin, rel=1e-6)
    # docs/physics.md#coning-rates, 2 decimals
    assert relative_to_rotor == pytest.approx(309.23, abs=0.005)

    # b1 cones about the fixed H_L at |H|/I = J spin / (I cos theta)
    coning = _coning_rate(res)
    theta = res.coning[0]
    assert coning == pytest.approx(J * spin / (I * math.cos(theta)), rel=1e-6)
    assert coning == pytest.approx(1356.43, abs=0.005)  # docs/physics.md#coning-rates: 216 Hz


def test_coning_rate_at_large_cone_angle_is_H_over_I():
    model = torque_free(table1_flight5())
    J, I, spin = model.craft.inertia_axial, model.craft.inertia_transverse, model.craft.spin
    w_t = math.tan(math.radians(5.0)) * J * spin / I  # 5 degree coning
    res = simulate_coast(model, 0.2, x0=_coasting_state(model, w_B=(0.0, w_t, 0.0)), options=TIGHT)
    assert math.degrees(res.coning[0]) == pytest.approx(5.0, rel=1e-12)
    H = res.H_L[0]
    rate = _coning_rate(res)
    assert rate == pytest.approx(np.linalg.norm(H) / I, rel=1e-6)
    assert rate == pytest.approx(J * spin / (I * math.cos(res.coning[0])), rel=1e-6)
    # the cone angle itself stays constant, to the integrator's accuracy
    # (rtol 1e-12 accumulated over ~270 rad of coning)
    assert np.ptp(res.coning) / res.coning[0] < 1e-7


def _coning_rate(res) -> float:
    """Rate at which b1 turns about the (fixed) angular momentum H_L [rad/s]."""
    h = res.H_L[0] / np.linalg.norm(res.H_L[0])
    e1 = np.cross(h, [0.0, 1.0, 0.0])  # any axis not along H (H is near up here)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(h, e1)
    b1_L = np.array([_b1_L(q) for q in res.state("q_LB")])
    return _phase_rate(res.t, b1_L @ e1 + 1j * (b1_L @ e2))


def _b1_L(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)])


GYROSTAT_CARRIER = Carrier(
    mass=0.010,
    inertia=(2.0e-5, 3.1e-5, 2.6e-5, 0.3e-5, -0.2e-5, 0.4e-5),
    position_B=(0.004, 0.002, -0.003),
)


@pytest.mark.parametrize("carrier", [None, GYROSTAT_CARRIER], ids=["spinning_body", "gyrostat"])
def test_torque_free_motion_conserves_angular_momentum_and_energy(carrier):
    model = torque_free(table1_flight5(), carrier=carrier)
    x0 = _coasting_state(model, w_B=(0.3, 40.0, -25.0), tilt=0.2)
    res = simulate_coast(model, 10.0, x0=x0, options=TIGHT)
    assert res.status.value == "duration_reached"
    H = res.H_L
    dH = np.max(np.linalg.norm(H - H[0], axis=1)) / np.linalg.norm(H[0])
    assert dH < 1e-9
    p = parameter_values(model)
    inv = build_invariants()
    # rotational energy only (the translational part grows in free fall)
    rot = np.array(
        [float(inv(x, p)[1]) - 0.5 * float(inv(x, p)[4]) * x[3:6] @ x[3:6] for x in res.x]
    )
    assert np.max(np.abs(rot - rot[0])) / rot[0] < 1e-9


def test_coast_agrees_with_independent_dop853_integrator():
    """CVODES (inside simulate) and scipy's DOP853 on the same right-hand side."""
    model = table1_flight5()  # full model: aerodynamics, spin decay, rotating Earth
    x0 = initial_state(
        model, r_L=(0.0, 0.0, 50.0), v_L=(1.0, -0.5, 15.0), tilt=0.1, w_B=(0.0, 20.0, 5.0)
    )
    res = simulate_coast(model, 1.0, x0=x0, options=TIGHT)
    rhs = build_coast_rhs(model)
    p = parameter_values(model)

    def f(t, x):
        return np.asarray(rhs(t, x, [], p)).ravel()

    ref = solve_ivp(
        f, (0.0, 1.0), x0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=res.t, dense_output=False
    )
    assert ref.success
    scale = np.maximum(np.abs(ref.y.T), 1.0)
    err = np.max(np.abs(res.x - ref.y.T) / scale)
    assert err < 1e-7


def test_paper_aero_moment_spinning_craft_holds_angle_of_attack_nonspinning_diverges():
    base = table1_flight5()
    p = parameter_values(base)
    alpha0 = math.radians(5.0)
    x_kw = {"r_L": (0.0, 0.0, 20.0), "v_L": (0.0, 0.0, 20.0), "tilt": alpha0}

    def alpha_history(model, spin):
        x0 = initial_state(model, spin=spin, **x_kw)
        res = simulate_coast(model, 0.3, x0=x0, options=SimulationOptions(samples_per_interval=20))
        t_s, x_s = ca.SX.sym("t"), ca.SX.sym("x", STATE.size)
        terms = coast_terms(t_s, x_s, ca.SX(0, 1), ca.SX(p), model)
        alpha = ca.Function("alpha", [t_s, x_s], [terms["alpha"]])
        return np.array([float(alpha(t, x)) for t, x in zip(res.t, res.x, strict=True)])

    spinning = alpha_history(base, base.craft.spin)
    still = alpha_history(base, 0.0)
    assert spinning[0] == pytest.approx(alpha0, rel=1e-9)
    assert np.max(spinning) < 1.1 * alpha0  # S_g ~ 860: holds its angle of attack
    assert np.max(still) > 4 * alpha0  # destabilising C_M: diverges within 0.3 s


def test_gyrostat_spin_rate_follows_motor_torque():
    """J (w1_dot + psi_ddot) = T_motor: the rotor row of the corrected Eq. 1
    (docs/references.md#paper-eq-1)."""
    model = torque_free(table1_flight5(), carrier=GYROSTAT_CARRIER)
    rhs = build_coast_rhs(model)
    p = parameter_values(model)
    x = _coasting_state(model, w_B=(0.0, 0.0, 0.0))
    torque = 1e-4
    xdot = np.asarray(rhs(0.0, x, [torque], p)).ravel()
    w1_dot = xdot[STATE.index("w_B")][0]
    spin_dot = xdot[STATE.index("spin")]
    J = model.craft.inertia_axial
    assert J * (w1_dot + spin_dot) == pytest.approx(torque, rel=1e-12)
    # and the carrier turns the other way: total axial momentum is unchanged
    H_dot_axial = np.asarray(_system_inertia(model))[0] @ xdot[STATE.index("w_B")] + J * spin_dot
    assert abs(H_dot_axial) < 1e-12 * torque / J


def _system_inertia(model):
    from lightcraft_opt.symbolic.terms.mass_properties import mass_properties

    x = initial_state(model)
    mp = mass_properties(ca.DM(x), ca.DM(parameter_values(model)))
    return mp.I_B + ca.diag(ca.vertcat(mp.J, mp.I, mp.I))


def test_upright_attitude_points_b1_up():
    assert _b1_L(quaternion_from_tilt()) == pytest.approx([0.0, 0.0, 1.0], abs=1e-15)
    lean = _b1_L(quaternion_from_tilt(0.3, math.radians(90.0)))  # lean toward east
    assert lean == pytest.approx([math.sin(0.3), 0.0, math.cos(0.3)], abs=1e-15)
