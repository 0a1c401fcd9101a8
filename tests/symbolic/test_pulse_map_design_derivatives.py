"""Φ's explicit-chain derivatives in v = (x, u, p[design]) (symbolic/maps/
pulse_map_derivatives.py with a design: the OCP's designed entries of p) against two
references, as tests/symbolic/test_pulse_map_derivatives.py does for v = (x, u):

- casadi's AD through the composed Φ (``phi.step``) with the designed entries of p as
  symbols: the same derivatives by another route, equal to rounding (1e-9 relative to the
  largest entry);
- central finite differences of Φ for the Jacobian, and of the chain's own Jacobian for the
  Hessian of the Lagrangian term, at step sizes set per state slot
  (support.jacobian_check.state_step_scale) and 1e-5 relative for the entries of p.

The columns of p[design] are compared per relative change of the entry (scaled by |p_i|):
the derivatives in a moment of inertia [kg m^2] are ~1e7 times those in the state.

Cases, with a coarse 2 x 8 optic: the OCP's map (split, 2 substeps) with the rotor's dry
mass and transverse moment and the impulse per pulse designed; the waist beam with its
Rayleigh range; a despun carrier with its mass and its position along b1 (RK4 over 16
substeps: split needs an axisymmetric body, RK4 a step of about 1/400 s at the spin);
Flight 5's RCS under the PHASE_LOCKED profile with the rotor's moment and the impulse (the
coning rate ω(x_+, p) then depends on the design: its own chain term).
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import state_step_scale
from support.models import COARSE_OPTIC, flight5_rcs_coarse, table1_flight5

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    ENGINE,
    PARAMETERS,
    STATE,
    RcsProfile,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import BeamSizeModel, Carrier
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import (
    build_derivative_pieces,
    build_pulse_map_derivatives,
    chain_derivatives,
)

AD_RTOL = 1e-9
FD_RTOL = 1e-5
SPLIT_2 = PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=2, dense=2)
CARRIER = Carrier(
    mass=0.010,
    inertia=(2.0e-5, 3.1e-5, 2.6e-5, 0.3e-5, -0.2e-5, 0.4e-5),
    position_B=(0.004, 0.002, -0.003),
)


def _waist():
    model = table1_flight5(engine=COARSE_OPTIC)
    laser = replace(model.laser, size_model=BeamSizeModel.WAIST, rayleigh_range=40.0)
    return replace(model, laser=laser)


CASES = {
    "rotor-impulse": (
        lambda: table1_flight5(engine=COARSE_OPTIC),
        SPLIT_2,
        ("rotor_mass_dry", "rotor_transverse_inertia_dry", "impulse_per_pulse"),
    ),
    "waist-rayleigh": (_waist, SPLIT_2, ("beam_rayleigh_range",)),
    "carrier-b1": (
        lambda: table1_flight5(carrier=CARRIER, engine=COARSE_OPTIC),
        PulseMapOptions(scheme=CoastScheme.RK4, substeps=16, dense=2),
        ("carrier_mass", "carrier_position_B"),  # carrier_position_B: its b1 entry
    ),
    "rcs-phase-locked": (
        flight5_rcs_coarse,
        replace(SPLIT_2, rcs_profile=RcsProfile.PHASE_LOCKED),
        ("rotor_transverse_inertia_dry", "impulse_per_pulse"),
    ),
}


def _design(names):
    return tuple(sorted(PARAMETERS.slot(name).start for name in names))


@pytest.fixture(scope="module", params=list(CASES))
def chain(request):
    make_model, options, names = CASES[request.param]
    model = make_model()
    phi = build_pulse_map(model, options)
    design = _design(names)
    rng = np.random.default_rng(3)
    x = initial_state(model, r_L=(0.012, -0.021, 6.0), v_L=(0.3, -0.2, 9.0), tilt=0.05)
    x[STATE.index("w_B")] += rng.normal(0, 3.0, 3)
    u = nominal_inputs(model, phi.inputs)
    u = u + rng.normal(0, 0.02, u.size) * np.maximum(np.abs(u), 1e-2)
    point = (x, u, parameter_values(model), 0.7)
    lam = (rng.normal(size=STATE.size), rng.normal(size=ENGINE.size))
    return model, phi, design, build_pulse_map_derivatives(phi, design=design), point, lam


def _rel(a, b):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _with_design(p, design, values):
    """p (PARAMETERS.size,) with the entries ``design`` set to ``values`` (MX or numbers)."""
    p = np.asarray(p, dtype=float).ravel()
    where = {i: k for k, i in enumerate(design)}
    return ca.vertcat(*(values[where[i]] if i in where else p[i] for i in range(p.size)))


def _column_scale(x, u, p, design):
    """(nv,) 1 for x and u, |p_i| for the designed entries: derivatives per relative change."""
    p_d = np.asarray(p, dtype=float).ravel()[list(design)]
    return np.concatenate([np.ones(x.size + u.size), np.abs(p_d)])


def _ad(phi, point, design, lam):
    x, u, p, t = point
    X, U = ca.MX.sym("x", x.size), ca.MX.sym("u", u.size)
    D = ca.MX.sym("p_d", len(design))
    x_next, engine = phi.step(X, U, _with_design(p, design, D), t)
    v = ca.vertcat(X, U, D)
    lagrangian = ca.dot(ca.DM(lam[0]), x_next) + ca.dot(ca.DM(lam[1]), engine)
    f = ca.Function(
        "ad",
        [X, U, D],
        [ca.jacobian(x_next, v), ca.jacobian(engine, v), ca.hessian(lagrangian, v)[0]],
    )
    p_d = np.asarray(p, dtype=float).ravel()[list(design)]
    return [np.asarray(m) for m in f(x, u, p_d)]


def test_design_chain_values_are_phi(chain):
    _, phi, _, d, point, _ = chain
    x_next, engine, _, _ = d.jacobian(*point)
    want = phi.step(*point)
    assert _rel(x_next, want[0]) == 0.0 and _rel(engine, want[1]) == 0.0


def test_design_chain_jacobian_and_hessian_equal_casadi_ad(chain):
    _, phi, design, d, point, lam = chain
    x, u, p, _ = point
    s = _column_scale(x, u, p, design)
    jac_x, jac_e, hess = _ad(phi, point, design, lam)
    _, _, dx, de = d.jacobian(*point)
    H = np.asarray(d.hessian(*point, *lam))
    assert d.design == design
    assert d.n_v == x.size + u.size + len(design) == H.shape[0] == H.shape[1]
    assert _rel(np.asarray(dx) * s, jac_x * s) < AD_RTOL
    assert _rel(np.asarray(de) * s, jac_e * s) < AD_RTOL
    assert _rel(s[:, None] * H * s, s[:, None] * hess * s) < AD_RTOL
    assert _rel(H, H.T) < 1e-12
    # the design's columns are not all zero: Φ does depend on every designed entry
    n = x.size + u.size
    assert np.all(np.max(np.abs(np.vstack([jac_x, jac_e])[:, n:]), axis=0) > 0)


def test_design_chain_jacobian_and_hessian_equal_finite_differences(chain):
    model, phi, design, d, point, lam = chain
    x, u, p, t = point
    nx, nu = x.size, u.size
    p_d = np.asarray(p, dtype=float).ravel()[list(design)]
    v0 = np.concatenate([x, u, p_d])
    scale = np.concatenate([state_step_scale(model.craft.mass), np.full(nu, 1e-2), 0 * p_d])
    step = 1e-5 * (np.abs(v0) + scale)
    s = _column_scale(x, u, p, design)

    def split(v):
        return v[:nx], v[nx : nx + nu], _with_design(p, design, v[nx + nu :])

    def outputs(v):
        x_next, engine = phi.step(*split(v), t)
        return np.concatenate([np.asarray(x_next).ravel(), np.asarray(engine).ravel()])

    def gradient(v):
        _, _, dx, de = d.jacobian(*split(v), t)
        return np.asarray(dx).T @ lam[0] + np.asarray(de).T @ lam[1]

    J_fd = np.zeros((nx + ENGINE.size, v0.size))
    H_fd = np.zeros((v0.size, v0.size))
    for k in range(v0.size):
        e = np.zeros(v0.size)
        e[k] = step[k]
        J_fd[:, k] = (outputs(v0 + e) - outputs(v0 - e)) / (2 * step[k])
        H_fd[:, k] = (gradient(v0 + e) - gradient(v0 - e)) / (2 * step[k])
    _, _, dx, de = d.jacobian(*point)
    J = np.vstack([np.asarray(dx), np.asarray(de)])
    assert _rel(J * s, J_fd * s) < FD_RTOL
    H = np.asarray(d.hessian(*point, *lam))
    assert _rel(s[:, None] * H * s, s[:, None] * H_fd * s) < FD_RTOL


def test_a_bad_design_names_the_field():
    phi = build_pulse_map(table1_flight5(engine=COARSE_OPTIC), SPLIT_2)
    assert phi.pieces is not None
    i, j = _design(("rotor_mass_dry", "impulse_per_pulse"))
    for bad in ((j, i), (i, i), (PARAMETERS.size,), (-1,)):
        with pytest.raises(ParameterError, match="design"):
            build_derivative_pieces(phi.pieces, hessians=False, design=bad)
    pieces = build_derivative_pieces(phi.pieces, hessians=False, design=(i,))
    with pytest.raises(ParameterError, match="design"):
        chain_derivatives(phi, pieces, design=(i, j))


def test_design_tape_gives_the_same_hessian_bit_for_bit(chain):
    _, _, _, d, point, lam = chain
    *first, tape = d.jacobian_tape(*point)
    for a, b in zip(first, d.jacobian(*point), strict=True):
        assert _rel(a, b) == 0.0
    assert _rel(d.hessian_tape(*point, tape, *lam), d.hessian(*point, *lam)) == 0.0
