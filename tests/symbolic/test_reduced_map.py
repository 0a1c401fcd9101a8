"""The coning-aware reduced map Ψ (symbolic/maps/reduced_map.py) against Φ.

References: Φ itself at full accuracy (Yoshida splitting, 32 substeps, the model's optic),
flown along coning flights (a beam 3-4 cm off the pad axis pumps the coning up, from an
initial transverse rate): each full state x_k read as z_k = project(x_k), then

- one pulse: Ψ(z_k) against project(x_{k+1}), in velocity;
- ten pulses: Ψ iterated from z_k against project(x_{k+10}), in position;
- the same pulse by the OCP's map (Strang splitting, 2 substeps) from x_k, the map Ψ is
  meant to replace in planning.

Bounds (measured, 2026-12-01): Flight 5, coning up to 5°: 0.87 cm/s at most a pulse, 0.27
median, where the OCP map is off by 6.3 and 4.1; 10 pulses 0.52 cm at most. The record
craft, coning up to 8.4°: 0.92 and 0.41 cm/s (the OCP map 12.8, 6.8); 10 pulses 2.6 cm.
The pulse itself is Φ's jump at the lifted state (tested equal), and lift and project
invert each other on the reduced manifold.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from support.models import COARSE_OPTIC, table1_flight5
from support.paths import REPO_ROOT

from lightcraft_opt.errors import OptionError
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import (
    ENGINE,
    PULSE_INPUT,
    STATE,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import build_pulse_map_derivatives
from lightcraft_opt.symbolic.maps.reduced_map import (
    REDUCED_STATE,
    ReducedMapOptions,
    build_reduced_map,
    reduced_pulse_map,
)

#: (model, transverse rate at launch [rad/s], beam offset east [m], bounds: 1-pulse velocity
#: max and median [m/s], 10-pulse position max [m])
CASES = {
    "flight5": ("flight5", 12.0, 0.04, (0.012, 0.004, 0.008)),
    "record": ("record-2000-10-02", 8.0, 0.03, (0.013, 0.006, 0.035)),
}


@pytest.fixture(scope="module", params=list(CASES))
def flight(request):
    name, transverse, offset, bounds = CASES[request.param]
    model = load_model(REPO_ROOT / "models" / f"{name}.toml")
    phi = build_pulse_map(model)
    psi = build_reduced_map(model)
    p = parameter_values(model)
    u = nominal_inputs(model, phi.inputs)
    u[PULSE_INPUT.slot("pointing_L").start] = offset
    x = initial_state(model, w_B=(0.0, transverse, 0.0))
    xs = [x]
    for k in range(40):
        x = np.asarray(phi.step(x, u, p, k * phi.period)[0]).ravel()
        xs.append(x)
    zs = [np.asarray(psi.project(x, p)).ravel() for x in xs]
    return model, phi, psi, p, u, xs, zs, bounds


def _coning_deg(z):
    return np.degrees(np.arcsin(np.linalg.norm(REDUCED_STATE.get("coning", z))))


def test_one_pulse_velocity_error_is_bounded_and_beats_the_ocp_map(flight):
    model, phi, psi, p, u, xs, zs, (v_max, v_median, _) = flight
    assert max(_coning_deg(z) for z in zs) > 4.5  # the flight cones
    ocp = build_pulse_map(model, PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=2, dense=2))
    v = slice(STATE.slot("v_L").start, STATE.slot("v_L").stop)
    reduced, coarse = [], []
    for k in range(30):
        t = k * phi.period
        z_next = np.asarray(psi.step(zs[k], u, p, t)[0]).ravel()
        reduced.append(np.linalg.norm(REDUCED_STATE.get("v_L", z_next - zs[k + 1])))
        x_next = np.asarray(ocp.step(xs[k], u, p, t)[0]).ravel()
        coarse.append(np.linalg.norm(x_next[v] - xs[k + 1][v]))
    assert max(reduced) < v_max and np.median(reduced) < v_median
    assert np.median(coarse) > 5 * np.median(reduced)


def test_ten_pulse_position_error_is_bounded(flight):
    _, phi, psi, p, u, _, zs, (_, _, r_max) = flight
    errors = []
    for k0 in range(0, 30, 5):
        z = zs[k0]
        for k in range(k0, k0 + 10):
            z = np.asarray(psi.step(z, u, p, k * phi.period)[0]).ravel()
        errors.append(np.linalg.norm(REDUCED_STATE.get("r_L", z - zs[k0 + 10])))
    assert max(errors) < r_max


def test_lift_and_project_invert_each_other_and_the_jump_is_phis(flight):
    _, phi, psi, p, u, _, zs, _ = flight
    rng = np.random.default_rng(7)
    for z in zs[5::10]:
        z = z.copy()
        cone, spin = REDUCED_STATE.slot("coning"), REDUCED_STATE.slot("H_L")
        z[cone.start : cone.stop] += rng.normal(0, 0.05, 2)
        z[spin.start : spin.stop] += rng.normal(0, 0.05, 3) * np.linalg.norm(
            REDUCED_STATE.get("H_L", z)
        )
        x = np.asarray(psi.lift(z, p)).ravel()
        np.testing.assert_allclose(np.asarray(psi.project(x, p)).ravel(), z, rtol=0, atol=1e-12)
        assert STATE.get("w_B", x)[0] == 0.0  # the gauge of docs/frames.md
        pulse = u[: PULSE_INPUT.size]
        z_plus, engine = psi.jump(z, pulse, p)
        assert phi.pieces is not None
        x_plus, full_engine = phi.pieces.jump(x, pulse, p)
        np.testing.assert_array_equal(np.asarray(engine), np.asarray(full_engine))
        np.testing.assert_allclose(
            np.asarray(z_plus).ravel(),
            np.asarray(psi.project(x_plus, p)).ravel(),
            rtol=0,
            atol=1e-15 * np.max(np.abs(z)),
        )
        assert np.asarray(engine).size == ENGINE.size


def test_options_are_checked():
    with pytest.raises(OptionError, match="substeps must be >= 1"):
        ReducedMapOptions(substeps=0)
    with pytest.raises(OptionError, match="substeps must be an integer"):
        ReducedMapOptions(substeps=2.0)  # type: ignore[arg-type]
    with pytest.raises(OptionError, match=r"dense \(3\) must divide substeps \(2\)"):
        ReducedMapOptions(substeps=2, dense=3)


def test_full_state_form_is_psi_and_phis_chain_differentiates_it():
    """reduced_pulse_map composes Ψ like Φ (pieces on full states): its step is
    lift(Ψ(project(x))) to rounding, and Φ's explicit chain over those pieces gives casadi's
    AD Jacobian and Lagrangian Hessian to rounding (1e-9 relative; ~1e-15 measured). A 2 x 8
    optic keeps the symbolic Hessians quick."""
    model = table1_flight5(engine=COARSE_OPTIC)
    psi = build_reduced_map(model)
    phi = reduced_pulse_map(model)
    p = parameter_values(model)
    u = nominal_inputs(model, phi.inputs)
    u[PULSE_INPUT.slot("pointing_L").start] = 0.02
    x = initial_state(model, r_L=(0.01, 0.0, 3.0), v_L=(0.1, 0.0, 8.0), w_B=(0.0, 5.0, 0.0))
    z_next = np.asarray(psi.step(np.asarray(psi.project(x, p)).ravel(), u, p, 0.2)[0]).ravel()
    x_next = np.asarray(phi.step(x, u, p, 0.2)[0]).ravel()
    z_of_x = np.asarray(psi.project(x_next, p)).ravel()
    assert np.max(np.abs(z_of_x - z_next)) <= 1e-12 * np.max(np.abs(z_next))

    chain = build_pulse_map_derivatives(phi)
    assert chain.hessian is not None
    X, U = ca.MX.sym("x", STATE.size), ca.MX.sym("u", u.size)
    xn, engine = phi.step(X, U, p, 0.2)
    rng = np.random.default_rng(4)
    lam_x, lam_e = rng.normal(size=STATE.size), rng.normal(size=ENGINE.size)
    v = ca.vertcat(X, U)
    lagrangian = ca.dot(ca.DM(lam_x), xn) + ca.dot(ca.DM(lam_e), engine)
    ad = ca.Function("ad", [X, U], [ca.jacobian(xn, v), ca.hessian(lagrangian, v)[0]])
    J_ad, H_ad = (np.asarray(m) for m in ad(x, u))
    J = np.asarray(chain.jacobian(x, u, p, 0.2)[2])
    H = np.asarray(chain.hessian(x, u, p, 0.2, lam_x, lam_e))
    assert np.max(np.abs(J - J_ad)) < 1e-9 * np.max(np.abs(J_ad))
    assert np.max(np.abs(H - H_ad)) < 1e-9 * np.max(np.abs(H_ad))
