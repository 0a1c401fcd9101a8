"""The structured Φ (named sub-Functions composed in MX) against the flat SX Φ it replaced.

Reference: flat_pulse_map.build_flat_pulse_map, the construction every earlier test and
figure was made with. Both evaluate the same expressions in the same order, so they must
agree to rounding: values to 1e-12 relative (they agree to the last bit on this machine),
first derivatives by casadi's AD through either graph to 1e-9 relative (AD through an MX
composition sums the chain in another order).

Cases: every coast scheme, every RCS profile, a gyrostat (despun carrier, RK4), the
Table 1 flights of models/ (RK4 with steps short enough for the 216 Hz coning), random
states away from the pad, inputs off the nominal and a non-unit quaternion (Φ depends on
its direction only).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from support.models import COARSE_OPTIC, flight5_rcs_coarse, table1_flight5
from support.paths import MODELS

from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import (
    PARAMETERS,
    STATE,
    RcsProfile,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import Carrier
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.reference_pulse_map import build_flat_pulse_map

CARRIER = Carrier(
    mass=0.010,
    inertia=(2.0e-5, 3.1e-5, 2.6e-5, 0.3e-5, -0.2e-5, 0.4e-5),
    position_B=(0.004, 0.002, -0.003),
)
VALUE_RTOL = 1e-12
DERIVATIVE_RTOL = 1e-9


CASES = {
    "flight5-default": (lambda: load_model(MODELS / "flight5.toml"), PulseMapOptions()),
    "flight7-split": (
        lambda: load_model(MODELS / "flight7.toml"),
        PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=8, dense=4),
    ),
    "flight16-split4": (
        lambda: load_model(MODELS / "flight16.toml"),
        PulseMapOptions(substeps=8, dense=8),
    ),
    "record-rk4": (
        lambda: load_model(MODELS / "record-2000-10-02.toml"),
        PulseMapOptions(scheme=CoastScheme.RK4, substeps=48, dense=4),
    ),
    "gyrostat-rk4": (
        lambda: table1_flight5(carrier=CARRIER, engine=COARSE_OPTIC),
        PulseMapOptions(scheme=CoastScheme.RK4, substeps=48, dense=2),
    ),
    "rcs-subintervals": (
        flight5_rcs_coarse,
        PulseMapOptions(
            substeps=8, dense=4, rcs_profile=RcsProfile.SUBINTERVALS, rcs_subintervals=4
        ),
    ),
    "rcs-phase-locked": (
        flight5_rcs_coarse,
        PulseMapOptions(substeps=8, dense=2, rcs_profile=RcsProfile.PHASE_LOCKED),
    ),
}

#: AD through the flat graph of a full optic takes seconds a map: first derivatives on these.
DERIVATIVE_CASES = {"flight7-split", "gyrostat-rk4", "rcs-subintervals", "rcs-phase-locked"}


def _random_point(model, phi, rng):
    """A state climbing off the axis, tilted, coning, with a non-unit quaternion; inputs
    off the nominal (pointing, focus, energy, RCS levels); a time into the flight."""
    x = initial_state(model)
    x[STATE.index("r_L")] = rng.normal(0, 0.02, 3) + np.array([0, 0, 3 + 20 * rng.random()])
    x[STATE.index("v_L")] = rng.normal(0, 0.5, 3) + np.array([0, 0, 10])
    q = np.array([1.0, *rng.normal(0, 0.05, 3)])
    x[STATE.index("q_LB")] = 1.3 * q / np.linalg.norm(q)
    x[STATE.index("w_B")] = x[STATE.index("w_B")] + rng.normal(0, 3.0, 3)
    u = nominal_inputs(model, phi.inputs)
    u = u + rng.normal(0, 0.01, u.size) * np.maximum(np.abs(u), 1e-3)
    return x, u, parameter_values(model), 0.3 + rng.random()


@functools.cache
def _maps(case: str):
    make_model, options = CASES[case]
    model = make_model()
    return model, build_pulse_map(model, options), build_flat_pulse_map(model, options)


@pytest.fixture(scope="module", params=list(CASES))
def maps(request):
    return _maps(request.param)


@pytest.fixture(scope="module", params=sorted(DERIVATIVE_CASES))
def small_maps(request):
    return _maps(request.param)


def _close(a, b, rtol):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = np.maximum(np.abs(b), 1.0)
    return np.max(np.abs(a - b) / scale)


def test_structured_values_equal_the_flat_map(maps):
    model, phi, flat = maps
    rng = np.random.default_rng(7)
    for _ in range(3):
        args = _random_point(model, phi, rng)
        for f, g in ((phi.dense, flat.dense), (phi.step, flat.step)):
            for got, want in zip(f(*args), g(*args), strict=True):
                assert _close(got, want, VALUE_RTOL) <= VALUE_RTOL
    assert phi.inputs == flat.inputs and phi.period == flat.period


def test_structured_first_derivatives_equal_the_flat_map(small_maps):
    model, phi, flat = small_maps
    args = _random_point(model, phi, np.random.default_rng(11))
    for f in (phi.step, flat.step):
        assert f.size_in(2) == (PARAMETERS.size, 1)
    jac_s = phi.step.jacobian()
    jac_f = flat.step.jacobian()
    outs_s, outs_f = phi.step(*args), flat.step(*args)
    for got, want in zip(jac_s(*args, *outs_s), jac_f(*args, *outs_f), strict=True):
        assert _close(got, want, DERIVATIVE_RTOL) <= DERIVATIVE_RTOL


def test_structured_map_is_built_from_named_pieces(maps):
    _, phi, _ = maps
    pieces = phi.pieces
    assert pieces is not None
    names = {pieces.normalise.name(), pieces.jump.name(), pieces.substep.name()}
    assert names == {"normalise_attitude", "pulse_jump", "coast_substep"}
    assert pieces.substeps == phi.options.substeps
    assert pieces.step_length * pieces.substeps == pytest.approx(phi.period, rel=1e-15)
    # the composed graph calls the pieces instead of inlining them
    assert phi.dense.is_a("MXFunction")
    assert phi.dense.n_instructions() < 100
