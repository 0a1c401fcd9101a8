"""Spin decay: paper Eq. 6 exponential law, rotating-disk friction (docs/physics.md#spin-decay).

The paper is the seed paper (docs/references.md#paper-eq-6); the disk laws are von Karman's
(docs/references.md#von-karman-1921) and Schlichting's (docs/references.md#schlichting).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from support.jacobian_check import assert_jacobians_match_finite_differences

from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import PARAMETERS, parameter_values
from lightcraft_opt.model import Model, SpinDecayModel
from lightcraft_opt.symbolic.terms.spin_decay import (
    SMOOTH_MAX_ORDER,
    build_spin_decay,
    spin_decay_torque,
)

RPM = 2 * math.pi / 60
W0 = 10_000 * RPM  # rad/s
J = 6.027e-5  # kg m^2, Flight 5 (Table 1: 602.7 g cm^2)
RHO = 1.0906  # kg/m^3 at 1194 m
MU = 1.79e-5  # Pa s, air near 1194 m on a warm day (approximate)


def params(model: Model, **changes: float) -> np.ndarray:
    p = parameter_values(model)
    for name, value in changes.items():
        p[PARAMETERS.index(name)] = value
    return p


def torque(model: SpinDecayModel, w: float, p: np.ndarray, rho: float = RHO) -> float:
    return float(build_spin_decay(model)(w, J, rho, MU, p))


def disk_by_hand(w: float, radius: float, rho: float = RHO) -> tuple[float, float]:
    """Laminar and turbulent torque of a free disk, docs/physics.md#spin-decay (both faces)."""
    nu = MU / rho
    laminar = 0.616 * math.pi * rho * radius**4 * math.sqrt(nu * abs(w) ** 3)
    turbulent = 0.073 * rho * w**2 * radius**5 * (nu / (radius**2 * abs(w))) ** 0.2
    return laminar, turbulent


def test_none_is_zero(flight5: Model) -> None:
    p = params(flight5)
    for w in (-W0, 0.0, 3.0, W0):
        assert torque(SpinDecayModel.NONE, w, p) == 0.0


def test_exponential_decay_paper_eq6(flight5: Model) -> None:
    """J dw/dt = T integrated with scipy gives w0 exp(-t / tau)."""
    tau = 12.5
    p = params(flight5, spin_time_constant=tau)
    f = build_spin_decay(SpinDecayModel.EXPONENTIAL)
    sol = solve_ivp(
        lambda t, w: [float(f(w[0], J, RHO, MU, p)) / J],
        (0.0, 12.0),
        [W0],
        method="DOP853",
        rtol=1e-11,
        atol=1e-9,
        dense_output=True,
    )
    assert sol.success
    t = np.linspace(0.0, 12.0, 25)
    np.testing.assert_allclose(sol.sol(t)[0], W0 * np.exp(-t / tau), rtol=1e-9)


def test_rotating_disk_time_constant_flight5(flight5: Model) -> None:
    """Flight 5 at 10,000 RPM: J w / |T| between 10 and 16 s (docs/physics.md#spin-decay,
    derived)."""
    p = params(flight5, disk_faces=1.0)
    T = torque(SpinDecayModel.ROTATING_DISK, W0, p)
    assert T < 0
    tau = J * W0 / abs(T)
    assert 10.0 < tau < 16.0
    laminar, turbulent = disk_by_hand(W0, 0.1222 / 2)
    assert J * W0 / laminar == pytest.approx(15.6, abs=0.1)  # laminar bound of the range
    assert J * W0 / turbulent == pytest.approx(10.1, abs=0.1)  # turbulent bound


@pytest.mark.parametrize("w", [0.5, 30.0, 300.0, W0, 5 * W0])
def test_rotating_disk_is_a_smooth_max_of_the_two_laws(w: float, flight5: Model) -> None:
    """max <= |T| <= 2^(1/k) max; tight (0.4 %) for Flight 5."""
    p = params(flight5, disk_faces=1.0)
    T = abs(torque(SpinDecayModel.ROTATING_DISK, w, p))
    laminar, turbulent = disk_by_hand(w, 0.1222 / 2)
    hard = max(laminar, turbulent)
    assert hard * (1 - 1e-12) <= T <= hard * 2 ** (1 / SMOOTH_MAX_ORDER)
    x = turbulent / laminar
    assert T == pytest.approx(
        laminar * (1 + x**SMOOTH_MAX_ORDER) ** (1 / SMOOTH_MAX_ORDER), rel=1e-12
    )
    if w == W0:
        assert T == pytest.approx(hard, rel=0.005)


def test_rotating_disk_limits(flight5: Model) -> None:
    """Slow spin: laminar von Karman law; fast spin: turbulent law."""
    p = params(flight5, disk_faces=1.0)
    slow, fast = 1e-3, 1e6
    assert abs(torque(SpinDecayModel.ROTATING_DISK, slow, p)) == pytest.approx(
        disk_by_hand(slow, 0.0611)[0], rel=1e-9
    )
    assert abs(torque(SpinDecayModel.ROTATING_DISK, fast, p)) == pytest.approx(
        disk_by_hand(fast, 0.0611)[1], rel=1e-6
    )


def test_rotating_disk_scales_with_faces_and_density(flight5: Model) -> None:
    p1 = params(flight5, disk_faces=1.0)
    p2 = params(flight5, disk_faces=2.0)
    T1 = torque(SpinDecayModel.ROTATING_DISK, W0, p1)
    assert torque(SpinDecayModel.ROTATING_DISK, W0, p2) == pytest.approx(2 * T1, rel=1e-14)
    # at fixed nu (mu scaled with rho) the torque is proportional to rho
    f = build_spin_decay(SpinDecayModel.ROTATING_DISK)
    assert float(f(W0, J, 2 * RHO, 2 * MU, p1)) == pytest.approx(2 * T1, rel=1e-13)


@pytest.mark.parametrize("model", list(SpinDecayModel))
def test_torque_is_odd_and_opposes_spin(model: SpinDecayModel, flight5: Model) -> None:
    p = params(flight5, disk_faces=1.0)
    for w in (1e-6, 0.3, 50.0, W0):
        T_plus, T_minus = torque(model, w, p), torque(model, -w, p)
        assert T_minus == -T_plus
        if model is not SpinDecayModel.NONE:
            assert T_plus < 0
    assert torque(model, 0.0, p) == 0.0


@pytest.mark.parametrize("model", list(SpinDecayModel))
def test_finite_derivative_at_zero_spin(model: SpinDecayModel, flight5: Model) -> None:
    f = build_spin_decay(model)
    p = params(flight5, disk_faces=1.0)
    jac = f.jacobian()(0.0, J, RHO, MU, p, 0.0)
    for block in jac:
        assert np.all(np.isfinite(np.asarray(block)))


def test_unknown_model_lists_the_choices() -> None:
    w, one = ca.SX.sym("w"), ca.SX(1.0)
    with pytest.raises(OptionError, match="rotating_disk"):
        spin_decay_torque(w, one, one, one, ca.SX.sym("p", PARAMETERS.size), "fast")  # type: ignore[arg-type]


def test_function_signature() -> None:
    f = build_spin_decay(SpinDecayModel.ROTATING_DISK)
    assert f.name() == "spin_decay"
    assert f.name_in() == ["w_rotor", "J", "rho", "mu", "p"]
    assert f.name_out() == ["T"]
    assert f.numel_in(4) == PARAMETERS.size


@pytest.mark.parametrize("model", [SpinDecayModel.EXPONENTIAL, SpinDecayModel.ROTATING_DISK])
def test_jacobian_matches_finite_differences(model: SpinDecayModel, flight5: Model) -> None:
    f = build_spin_decay(model)
    rng = np.random.default_rng(3)
    p = params(flight5, disk_faces=1.0, spin_time_constant=13.0)
    for _ in range(4):
        w = rng.choice([-1.0, 1.0]) * rng.uniform(10.0, 1500.0)
        args = [w, J * rng.uniform(0.8, 1.2), rng.uniform(0.9, 1.2), MU * rng.uniform(0.9, 1.1), p]
        assert_jacobians_match_finite_differences(
            f, args, rtol=1e-6, scale=[100.0, J, 1.0, MU, 1.0]
        )
