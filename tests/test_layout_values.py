"""A model's numbers in the layouts: a slot indexes numpy arrays, the launch state of a
coning craft, and the map input saturated to the hardware's limits (issue 29).

References: the slot's own slice (``STATE.index``); the coning angle of the invariants
(symbolic/terms/invariants.py: the angle from b1 to H) and the closed-loop file's
``[initial] coning_deg``; the limits of models/flight5-rcs.toml (a 10 cm beam reach, focus
1-1000 m, 420 J the laser's most, four 0.2 N thrusters), and the thrust of a
phase-locked input sampled over a coning turn.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import (
    STATE,
    RcsProfile,
    initial_state,
    map_input_layout,
    nominal_inputs,
    parameter_values,
    saturated_inputs,
)
from lightcraft_opt.symbolic.terms.invariants import build_invariants

MODEL = load_model(REPO_ROOT / "models" / "flight5-rcs.toml")
TOP = 0.2  # N, each thruster
REACH = 0.1  # m


# --------------------------------------------------------------------------- slots
def test_a_slot_indexes_numpy_arrays():
    """``X[..., STATE.slot("w_B")]`` is the slot's block of a trajectory (a copy, one
    entry kept as a column); assignment works; ``.slice`` is the view."""
    X = np.arange(3.0 * STATE.size).reshape(3, STATE.size)
    w = STATE.slot("w_B")
    np.testing.assert_array_equal(X[..., w], X[:, STATE.index("w_B")])
    np.testing.assert_array_equal(X[1, w], STATE.get("w_B", X[1]))
    assert X[:, STATE.slot("spin")].shape == (3, 1)
    x = np.zeros(STATE.size)
    x[w] = (1.0, 2.0, 3.0)
    assert STATE.get("w_B", x).tolist() == [1.0, 2.0, 3.0]
    assert w.slice == STATE.index("w_B")
    assert np.shares_memory(X[:, w.slice], X) and not np.shares_memory(X[:, w], X)


# --------------------------------------------------------------------------- launch state
@pytest.mark.parametrize(("degrees", "azimuth"), [(5.0, 0.3), (30.0, -2.0)])
def test_initial_state_takes_a_coning_angle_and_its_direction(degrees, azimuth):
    """The invariants read the angle back to 1e-12; H's transverse part (A w_⊥ for a
    centred rotor) points at ``coning_azimuth`` from b2 toward b3; w_B[b1] stays 0."""
    x = initial_state(MODEL, coning=math.radians(degrees), coning_azimuth=azimuth)
    coning = float(build_invariants()(x, parameter_values(MODEL))[3])
    assert coning == pytest.approx(math.radians(degrees), rel=1e-12)
    w = STATE.get("w_B", x)
    assert w[0] == 0.0
    assert math.atan2(w[2], w[1]) == pytest.approx(azimuth, abs=1e-12)
    rest = initial_state(MODEL)
    others = np.ones(STATE.size, bool)
    others[STATE.slot("w_B")] = False
    np.testing.assert_array_equal(x[others], rest[others])


def test_initial_state_coning_is_the_closed_loop_files():
    """problems/nutation_suppression.toml's [initial] (5 degrees at 17.2) is
    ``initial_state(model, coning=..., coning_azimuth=...)`` to the last bit."""
    problem = load_closed_loop(REPO_ROOT / "problems" / "nutation_suppression.toml")
    x = initial_state(problem.model, coning=math.radians(5.0), coning_azimuth=math.radians(17.2))
    np.testing.assert_array_equal(problem.x0, x)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"coning": -0.1}, r"coning: must lie in \[0, 90\) degrees"),
        ({"coning": math.pi / 2}, r"coning: must lie in \[0, 90\) degrees"),
        ({"coning": math.nan}, "coning: must be finite"),
        ({"coning": 0.1, "coning_azimuth": math.inf}, "coning_azimuth: must be finite"),
        ({"coning": 0.1, "w_B": (1.0, 0.0, 0.0)}, r"coning: needs w_B\[b1\] = 0"),
        ({"coning": 0.1, "spin": 0.0}, "coning: a craft without spin cannot cone"),
    ],
)
def test_initial_state_refuses_a_coning_it_cannot_make(kwargs, message):
    with pytest.raises(ParameterError, match=message):
        initial_state(MODEL, **kwargs)


# --------------------------------------------------------------------------- limits
def test_held_inputs_are_clipped_entry_by_entry():
    """Pointing per axis to the reach, focus into its range, energy into [0, the laser's
    most], each held level into [0, max]; an input inside comes back unchanged."""
    lay = map_input_layout(4, False)
    u = lay.pack(
        {
            "pointing_L": (0.86, -0.05),
            "focus": 0.5,
            "energy": 1e6,
            "rcs_thrust": (-0.1, 0.3, 0.1, 0.2),
        }
    )
    out = saturated_inputs(MODEL, u, lay)
    assert lay.get("pointing_L", out).tolist() == [REACH, -0.05]
    assert lay.get("focus", out) == MODEL.laser.focus_range[0]
    assert lay.get("energy", out) == MODEL.laser.pulse_energy_max
    assert lay.get("rcs_thrust", out).tolist() == [0.0, TOP, 0.1, TOP]
    u[lay.index("energy")] = -5.0
    assert lay.get("energy", saturated_inputs(MODEL, u, lay)) == 0.0
    inside = nominal_inputs(MODEL, lay)
    np.testing.assert_array_equal(saturated_inputs(MODEL, inside, lay), inside)
    np.testing.assert_array_equal(saturated_inputs(MODEL, inside), inside)  # the default layout
    sub = map_input_layout(4, False, RcsProfile.SUBINTERVALS, 3)
    levels = np.linspace(-0.3, 0.5, 12)
    v = nominal_inputs(MODEL, sub)
    v[sub.index("rcs_thrust")] = levels
    assert np.array_equal(sub.get("rcs_thrust", saturated_inputs(MODEL, v, sub)),
                          np.clip(levels, 0.0, TOP))  # fmt: skip


def test_phase_locked_thrust_is_projected_into_its_envelope():
    """Random phase-locked inputs: after saturation every thruster's thrust over a coning
    turn lies in [0, max] and the amplitudes keep their direction; saturating again
    changes nothing but round-off, and an input strictly inside comes back unchanged."""
    lay = map_input_layout(4, False, RcsProfile.PHASE_LOCKED)
    rng = np.random.default_rng(3)
    phase = np.linspace(0.0, 2 * math.pi, 721)
    for _ in range(200):
        u = nominal_inputs(MODEL, lay)
        for name, scale in (("rcs_thrust", 0.4), ("rcs_cos", 0.3), ("rcs_sin", 0.3)):
            u[lay.index(name)] = scale * rng.standard_normal(4)
        out = saturated_inputs(MODEL, u, lay)
        mean, c, s = (lay.get(k, out) for k in ("rcs_thrust", "rcs_cos", "rcs_sin"))
        thrust = mean[:, None] + c[:, None] * np.cos(phase) + s[:, None] * np.sin(phase)
        assert thrust.min() >= -1e-15 and thrust.max() <= TOP + 1e-15
        c0, s0 = lay.get("rcs_cos", u), lay.get("rcs_sin", u)
        np.testing.assert_allclose(c * s0, s * c0, atol=1e-15)  # same direction
        assert np.all(c * c0 >= 0) and np.all(s * s0 >= 0)
        np.testing.assert_allclose(saturated_inputs(MODEL, out, lay), out, rtol=0, atol=1e-16)
    inside = nominal_inputs(MODEL, lay)
    for name, value in (("rcs_thrust", 0.1), ("rcs_cos", 0.05), ("rcs_sin", -0.05)):
        inside[lay.index(name)] = value
    np.testing.assert_array_equal(saturated_inputs(MODEL, inside, lay), inside)


def test_saturation_refuses_what_it_cannot_read():
    with pytest.raises(ParameterError, match="u: needs 8 values"):
        saturated_inputs(MODEL, np.zeros(3), map_input_layout(4, False))
    no_rcs = load_model(REPO_ROOT / "models" / "flight5.toml")
    with pytest.raises(ParameterError, match="has no RCS"):
        saturated_inputs(no_rcs, np.zeros(8), map_input_layout(4, False))
