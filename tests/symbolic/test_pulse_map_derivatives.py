"""Φ's explicit-chain derivatives (symbolic/maps/pulse_map_derivatives.py) against two references.

- casadi's AD through the composed Φ (``phi.step``): the same derivatives by another
  route, so they agree to rounding (1e-9 relative to the largest entry; 1e-15 here);
- central finite differences of Φ for the Jacobian, and of the chain's own Jacobian for the
  Hessian of the Lagrangian term (docs/architecture.md#rule-3), at step sizes set per
  state slot (support.jacobian_check.state_step_scale).

Cases: the OCP's map (split, 2 substeps, no RCS), and Flight 5 with its RCS under the
PHASE_LOCKED profile (the coning rate ω(x_+) feeds every substep: its own chain term) and
the SUBINTERVALS profile (substeps read different levels of u). A coarse 2 x 8 optic keeps
the symbolic Hessians quick to build.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import state_step_scale
from support.models import (
    COARSE_OPTIC,
    RCS_PHASE_LOCKED_MAP,
    RCS_SUBINTERVALS_MAP,
    flight5_rcs_coarse,
    table1_flight5,
)

from lightcraft_opt.errors import LightcraftError
from lightcraft_opt.layout import ENGINE, STATE, initial_state, nominal_inputs, parameter_values
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import build_pulse_map_derivatives
from lightcraft_opt.symbolic.maps.reference_pulse_map import build_flat_pulse_map

AD_RTOL = 1e-9
FD_RTOL = 1e-5


CASES = {
    "ocp-map": (
        lambda: table1_flight5(engine=COARSE_OPTIC),
        PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=2, dense=2),
    ),
    "rcs-phase-locked": (flight5_rcs_coarse, RCS_PHASE_LOCKED_MAP),
    "rcs-subintervals": (flight5_rcs_coarse, RCS_SUBINTERVALS_MAP),
}


@pytest.fixture(scope="module", params=list(CASES))
def chain(request):
    make_model, options = CASES[request.param]
    model = make_model()
    phi = build_pulse_map(model, options)
    rng = np.random.default_rng(3)
    x = initial_state(model, r_L=(0.012, -0.021, 6.0), v_L=(0.3, -0.2, 9.0), tilt=0.05)
    x[STATE.index("w_B")] += rng.normal(0, 3.0, 3)
    u = nominal_inputs(model, phi.inputs)
    u = u + rng.normal(0, 0.02, u.size) * np.maximum(np.abs(u), 1e-2)
    point = (x, u, parameter_values(model), 0.7)
    lam = (rng.normal(size=STATE.size), rng.normal(size=ENGINE.size))
    return model, phi, build_pulse_map_derivatives(phi), point, lam


def _rel(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _ad(phi, point, lam):
    x, u, p, t = point
    X, U = ca.MX.sym("x", x.size), ca.MX.sym("u", u.size)
    x_next, engine = phi.step(X, U, p, t)
    v = ca.vertcat(X, U)
    lagrangian = ca.dot(ca.DM(lam[0]), x_next) + ca.dot(ca.DM(lam[1]), engine)
    f = ca.Function(
        "ad", [X, U], [ca.jacobian(x_next, v), ca.jacobian(engine, v), ca.hessian(lagrangian, v)[0]]
    )
    return [np.asarray(m) for m in f(x, u)]


def test_chain_values_are_phi(chain):
    _, phi, d, point, _ = chain
    x_next, engine, _, _ = d.jacobian(*point)
    want = phi.step(*point)
    assert _rel(x_next, want[0]) == 0.0 and _rel(engine, want[1]) == 0.0


def test_chain_jacobian_and_hessian_equal_casadi_ad(chain):
    _, _, d, point, lam = chain
    jac_x, jac_e, hess = _ad(chain[1], point, lam)
    _, _, dx, de = d.jacobian(*point)
    H = np.asarray(d.hessian(*point, *lam))
    assert _rel(dx, jac_x) < AD_RTOL
    assert _rel(de, jac_e) < AD_RTOL
    assert _rel(H, hess) < AD_RTOL
    assert _rel(H, H.T) < 1e-12
    assert H.shape == (d.n_v, d.n_v)


def test_tape_gives_the_same_jacobian_and_hessian_bit_for_bit(chain):
    """The Hessian's backward sweep from the Jacobian's tape (what the OCP calls) is the
    self-contained Hessian to the last bit, and the tape's Jacobian is the Jacobian; a tape
    of another point gives that point's curvature, not this one's."""
    _, _, d, point, lam = chain
    *first, tape = d.jacobian_tape(*point)
    for a, b in zip(first, d.jacobian(*point), strict=True):
        assert _rel(a, b) == 0.0
    assert _rel(d.hessian_tape(*point, tape, *lam), d.hessian(*point, *lam)) == 0.0
    x, u, p, t = point
    moved = (x + 1e-3 * np.abs(x), u, p, t)
    H_moved = np.asarray(d.hessian(*moved, *lam))
    from_moved_tape = np.asarray(d.hessian_tape(*moved, d.jacobian_tape(*moved)[4], *lam))
    assert _rel(from_moved_tape, H_moved) == 0.0
    assert _rel(d.hessian_tape(*moved, tape, *lam), H_moved) > 1e-6


def test_chain_jacobian_and_hessian_equal_finite_differences(chain):
    model, phi, d, point, lam = chain
    x, u, p, t = point
    nx = x.size
    v0 = np.concatenate([x, u])
    step = 1e-5 * (
        np.abs(v0) + np.concatenate([state_step_scale(model.craft.mass), np.full(u.size, 1e-2)])
    )

    def outputs(v):
        x_next, engine = phi.step(v[:nx], v[nx:], p, t)
        return np.concatenate([np.asarray(x_next).ravel(), np.asarray(engine).ravel()])

    def gradient(v):
        _, _, dx, de = d.jacobian(v[:nx], v[nx:], p, t)
        return np.asarray(dx).T @ lam[0] + np.asarray(de).T @ lam[1]

    J_fd = np.zeros((nx + ENGINE.size, v0.size))
    H_fd = np.zeros((v0.size, v0.size))
    for k in range(v0.size):
        e = np.zeros(v0.size)
        e[k] = step[k]
        J_fd[:, k] = (outputs(v0 + e) - outputs(v0 - e)) / (2 * step[k])
        H_fd[:, k] = (gradient(v0 + e) - gradient(v0 - e)) / (2 * step[k])
    _, _, dx, de = d.jacobian(*point)
    assert _rel(np.vstack([np.asarray(dx), np.asarray(de)]), J_fd) < FD_RTOL
    assert _rel(d.hessian(*point, *lam), H_fd) < FD_RTOL


def test_chain_needs_a_structured_map():
    model = table1_flight5(engine=COARSE_OPTIC)
    flat = build_flat_pulse_map(model, PulseMapOptions(substeps=2, dense=2))
    with pytest.raises(LightcraftError, match="pieces"):
        build_pulse_map_derivatives(flat)
