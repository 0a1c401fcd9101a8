"""The gyrostat equations against an independent Kane's-method derivation
(docs/references.md#kane-levinson).

sympy.physics.mechanics (test-only dependency) derives the equations of a carrier B
(full inertia matrix I_B about the system mass centre) and a symmetric rotor R
(J, I) spinning about b1 at u4 relative to B, with an external torque on B, a motor
torque between B and R and an external axial torque on R. The corrected mass
matrix of docs/physics.md#gyrostat follows; the seed paper's printed Eq. 1 (I11 for I11 + J,
docs/references.md#paper-eq-1) does not.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

from lightcraft_opt.symbolic.terms.gyrostat import gyrostat_accelerations


@pytest.fixture(scope="module")
def kane():
    q = me.dynamicsymbols("q1:5")
    u = me.dynamicsymbols("u1:5")
    I11, I22, I33, I12, I13, I23, J, I = sp.symbols("I11 I22 I33 I12 I13 I23 J I")
    Mx, My, Mz, Tm, Ta = sp.symbols("Mx My Mz Tm Ta")
    N = me.ReferenceFrame("N")
    B = me.ReferenceFrame("B")
    R = me.ReferenceFrame("R")
    B.set_ang_vel(N, u[0] * B.x + u[1] * B.y + u[2] * B.z)
    R.set_ang_vel(B, u[3] * B.x)
    O = me.Point("O")
    O.set_vel(N, 0)
    carrier = me.RigidBody(
        "carrier",
        O,
        B,
        sp.Integer(1),
        (me.inertia(B, I11, I22, I33, I12, I23, I13), O),
    )
    rotor = me.RigidBody("rotor", O, R, sp.Integer(1), (me.inertia(B, J, I, I), O))
    loads = [
        (B, Mx * B.x + My * B.y + Mz * B.z),  # external torque on the carrier
        (R, (Tm + Ta) * B.x),  # motor torque and external axial torque on the rotor
        (B, -Tm * B.x),  # the motor's reaction on the carrier
    ]
    km = me.KanesMethod(
        N, q_ind=q, u_ind=u, kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u, strict=True)]
    )
    km.kanes_equations([carrier, rotor], loads)
    syms = (I11, I22, I33, I12, I13, I23, J, I, Mx, My, Mz, Tm, Ta)
    mass = sp.lambdify((*syms, *u), km.mass_matrix)
    forcing = sp.lambdify((*syms, *u), km.forcing)
    return mass, forcing


def _ours(massless: bool):
    w = ca.SX.sym("w", 3)
    spin = ca.SX.sym("spin")
    M = ca.SX.sym("M", 3)
    T_R = ca.SX.sym("T_R")
    I_B = ca.SX.sym("I_B", 3, 3)
    J = ca.SX.sym("J")
    I = ca.SX.sym("I")
    w_dot, spin_dot = gyrostat_accelerations(w, spin, M, T_R, I_B, J, I, massless_carrier=massless)
    return ca.Function("ours", [w, spin, M, T_R, I_B, J, I], [ca.vertcat(w_dot, spin_dot)])


def _random_case(rng):
    # a physical carrier inertia: random rotation times principal moments obeying the
    # triangle inequality
    a, b = rng.uniform(1e-5, 8e-5, 2)
    c = rng.uniform(abs(a - b) + 1e-6, a + b)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    I_B = Q @ np.diag([a, b, c]) @ Q.T
    J = rng.uniform(2e-5, 1e-4)
    I = rng.uniform(J / 2 + 1e-6, 1.5 * J)
    w = rng.uniform(-50, 50, 3)
    spin = rng.uniform(-1200, 1200)
    M_ext = rng.uniform(-1e-2, 1e-2, 3)
    T_m, T_a = rng.uniform(-1e-3, 1e-3, 2)
    return I_B, J, I, w, spin, M_ext, T_m, T_a


def _kane_solution(kane, I_B, J, I, w, spin, M_ext, T_m, T_a):
    mass, forcing = kane
    args = (
        I_B[0, 0],
        I_B[1, 1],
        I_B[2, 2],
        I_B[0, 1],
        I_B[0, 2],
        I_B[1, 2],
        J,
        I,
        *M_ext,
        T_m,
        T_a,
        *w,
        spin,
    )
    MM = np.asarray(mass(*args), dtype=float)
    F = np.asarray(forcing(*args), dtype=float).ravel()
    return MM, np.linalg.solve(MM, F)


def test_rotational_equations_match_kane_sympy_mechanics(kane):
    rng = np.random.default_rng(20261123)
    ours = _ours(massless=False)
    worst = 0.0
    for _ in range(25):
        I_B, J, I, w, spin, M_ext, T_m, T_a = _random_case(rng)
        _, ref = _kane_solution(kane, I_B, J, I, w, spin, M_ext, T_m, T_a)
        M_B = M_ext + np.array([T_a, 0.0, 0.0])  # total external moment
        got = np.asarray(ours(w, spin, M_B, T_m + T_a, I_B, J, I)).ravel()
        err = np.linalg.norm(got - ref) / np.linalg.norm(ref)
        worst = max(worst, err)
    assert worst < 1e-10


def test_kane_mass_matrix_is_the_corrected_eq1_not_the_printed_one(kane):
    rng = np.random.default_rng(7)
    I_B, J, I, w, spin, M_ext, T_m, T_a = _random_case(rng)
    MM, _ = _kane_solution(kane, I_B, J, I, w, spin, M_ext, T_m, T_a)
    corrected = np.array(
        [
            [I_B[0, 0] + J, I_B[0, 1], I_B[0, 2], J],
            [I_B[0, 1], I_B[1, 1] + I, I_B[1, 2], 0.0],
            [I_B[0, 2], I_B[1, 2], I_B[2, 2] + I, 0.0],
            [J, 0.0, 0.0, J],
        ]
    )
    assert MM == pytest.approx(corrected, rel=1e-14, abs=1e-20)
    printed = corrected.copy()
    printed[0, 0] = I_B[0, 0]  # the paper's Eq. 1
    assert np.max(np.abs(printed - MM)) == pytest.approx(J, rel=1e-14)  # off by J


def test_massless_carrier_is_paper_eq7_with_spin_decay_term():
    rng = np.random.default_rng(11)
    ours = _ours(massless=True)
    for _ in range(10):
        _, J, I, w, spin, M, _, _ = _random_case(rng)
        got = np.asarray(ours(w, spin, M, 0.0, np.zeros((3, 3)), J, I)).ravel()
        w1d, w2d, w3d, spin_dd = got
        assert w1d == 0.0  # the despun-frame gauge
        assert J * (w1d + spin_dd) == pytest.approx(M[0], rel=1e-12)
        assert I * w2d + (J - I) * w[2] * w[0] + J * w[2] * spin == pytest.approx(
            M[1], rel=1e-9, abs=1e-12
        )
        assert I * w3d - (J - I) * w[0] * w[1] - J * w[1] * spin == pytest.approx(
            M[2], rel=1e-9, abs=1e-12
        )


def test_massless_carrier_is_the_limit_of_a_vanishing_carrier():
    """I_B = eps * 1 with no motor: the full gyrostat tends to the degenerate case, O(eps)."""
    rng = np.random.default_rng(3)
    full, degenerate = _ours(massless=False), _ours(massless=True)
    _, J, I, w, spin, M, _, _ = _random_case(rng)
    ref = np.asarray(degenerate(w, spin, M, 0.0, np.zeros((3, 3)), J, I)).ravel()
    errors = []
    for eps in (1e-6, 1e-8, 1e-10):
        got = np.asarray(full(w, spin, M, M[0], eps * I * np.eye(3), J, I)).ravel()
        errors.append(np.linalg.norm(got - ref) / np.linalg.norm(ref))
    assert errors[0] < 10 * 1e-6
    assert errors[1] == pytest.approx(errors[0] / 100, rel=0.05)
    assert errors[2] == pytest.approx(errors[0] / 1e4, rel=0.05)
