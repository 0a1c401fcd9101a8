"""Φ's dense-output sensitivities (symbolic/maps/pulse_map_sensitivities.py) against casadi's AD.

The chain runs each piece in forward mode and carries n directions through the pulse; casadi's
AD through Φ's composed dense output (``phi.dense``) is the same derivative by another route,
so they agree to rounding (1e-9 relative to the largest entry; ~1e-14 here). The seeds are
random in both the state and every parameter, so every column of the pieces' Jacobians in p
is exercised, with the map input u away from its nominal value.

Cases: Flight 5 under the default Yoshida scheme with dense nodes inside the interval, and
Flight 5 with its RCS under PHASE_LOCKED (the coning rate ω(x_+, p) feeds every substep)
and SUBINTERVALS (substeps read different levels of u). A 2 x 8 optic keeps them quick.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from support.models import (
    COARSE_OPTIC,
    RCS_PHASE_LOCKED_MAP,
    RCS_SUBINTERVALS_MAP,
    flight5_rcs_coarse,
    table1_flight5,
)

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, nominal_inputs, parameter_values
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_sensitivities import (
    build_dense_sensitivity,
    build_sensitivity_pieces,
)
from lightcraft_opt.symbolic.maps.reference_pulse_map import build_flat_pulse_map

AD_RTOL = 1e-9
N_DIRECTIONS = 3

CASES = {
    "yoshida-dense": (
        lambda: table1_flight5(engine=COARSE_OPTIC),
        PulseMapOptions(substeps=8, dense=4),
    ),
    "rcs-phase-locked": (flight5_rcs_coarse, RCS_PHASE_LOCKED_MAP),
    "rcs-subintervals": (flight5_rcs_coarse, RCS_SUBINTERVALS_MAP),
}


@pytest.mark.parametrize("case", list(CASES))
def test_dense_sensitivity_equals_casadi_ad(case):
    make_model, options = CASES[case]
    model = make_model()
    phi = build_pulse_map(model, options)
    rng = np.random.default_rng(5)
    x = initial_state(model, r_L=(0.012, -0.021, 6.0), v_L=(0.3, -0.2, 9.0), tilt=0.05)
    x[STATE.index("w_B")] += rng.normal(0, 3.0, 3)
    u = nominal_inputs(model, phi.inputs)
    u = u + rng.normal(0, 0.02, u.size) * np.maximum(np.abs(u), 1e-2)
    p = parameter_values(model)
    S = rng.normal(size=(STATE.size, N_DIRECTIONS))
    p_scale = 1e-2 * np.maximum(np.abs(p), 1e-3)[:, None]
    Q = rng.normal(size=(PARAMETERS.size, N_DIRECTIONS)) * p_scale

    X, dX = build_dense_sensitivity(phi, N_DIRECTIONS)(x, u, p, 0.7, S, Q)

    xs, ps = ca.MX.sym("x", STATE.size), ca.MX.sym("p", PARAMETERS.size)
    Xa, _ = phi.dense(xs, u, ps, 0.7)
    ad = ca.Function("ad", [xs, ps], [Xa, ca.jacobian(ca.vec(Xa), ca.vertcat(xs, ps))])
    X_ref, J_ref = ad(x, p)
    want = np.asarray(J_ref) @ np.vstack([S, Q])
    np.testing.assert_array_equal(np.asarray(X), np.asarray(X_ref))  # the same values
    assert np.asarray(dX).shape == (STATE.size * options.dense, N_DIRECTIONS)
    err = np.max(np.abs(np.asarray(dX) - want)) / np.max(np.abs(want))
    assert err < AD_RTOL, err


def test_sensitivity_needs_the_structured_map_and_matching_directions():
    model = table1_flight5(engine=COARSE_OPTIC)
    options = PulseMapOptions(substeps=2, dense=2)
    with pytest.raises(ParameterError, match=r"phi.*pieces"):
        build_dense_sensitivity(build_flat_pulse_map(model, options), 2)
    phi = build_pulse_map(model, options)
    with pytest.raises(ParameterError, match=r"n_directions.*>= 1"):
        build_dense_sensitivity(phi, 0)
    assert phi.pieces is not None
    with pytest.raises(ParameterError, match=r"sensitivities.*2 directions, not 3"):
        build_dense_sensitivity(phi, 3, build_sensitivity_pieces(phi.pieces, 2))
