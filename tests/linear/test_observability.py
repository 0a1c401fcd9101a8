"""The observability Gramian (linear/observability.py) against references.

References:

- a closed form: the double integrator measured in position at N instants,
  W_N = [[N, T S1], [T S1, T² S2]] / σ² with S1 = Σ k, S2 = Σ k² over k < N;
- an independent derivation: the Gramian along a flight of Φ equals Sᵀ R⁻¹ S with S the
  sensitivity of the measured positions to the initial error state by central finite
  differences of whole rollouts (retract, fly Φ, read r_L), not a product of Jacobians;
- a direction no sensor can see: the propellant of an RCS the flight never fires moves
  nothing, so its error is unseen from positions (its Cramér-Rao bound is infinite).
"""

from __future__ import annotations

import numpy as np
import pytest
from support.models import table1_flight5

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import STATE, initial_state, nominal_inputs, parameter_values
from lightcraft_opt.linear import pulse_map_jacobian
from lightcraft_opt.linear.observability import observability, observability_gramian
from lightcraft_opt.model import Engine
from lightcraft_opt.symbolic.maps.error_state import ERROR_STATE, build_error_state
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

CHEAP = PulseMapOptions(scheme=CoastScheme.SPLIT, substeps=1, dense=1)


def test_the_double_integrator_has_the_closed_form_gramian():
    T, N, sigma = 0.04, 12, 0.005
    A = np.array([[1.0, T], [0.0, 1.0]])
    W = observability_gramian([A] * (N - 1), np.array([[1.0, 0.0]]), np.array([[sigma**2]]))
    k = np.arange(N)
    S1, S2 = k.sum(), (k**2).sum()
    assert (S1, S2) == (N * (N - 1) // 2, (N - 1) * N * (2 * N - 1) // 6)
    expected = np.array([[N, T * S1], [T * S1, T**2 * S2]]) / sigma**2
    np.testing.assert_allclose(W, expected, rtol=1e-12)


def test_a_sensor_that_changes_along_the_flight():
    """C_k one a pulse: a double integrator seen by position at even pulses and velocity at
    odd ones; W = Σ (C_k M_k)ᵀ R⁻¹ C_k M_k written out, M_k = A^k."""
    T, N, sigma = 0.04, 7, 0.01
    A = np.array([[1.0, T], [0.0, 1.0]])
    C = np.array([[[1.0, 0.0]] if k % 2 == 0 else [[0.0, 1.0]] for k in range(N)])
    W = observability_gramian([A] * (N - 1), C, np.array([[sigma**2]]))
    expected = (
        sum(
            (C[k] @ np.linalg.matrix_power(A, k)).T @ (C[k] @ np.linalg.matrix_power(A, k))
            for k in range(N)
        )
        / sigma**2
    )
    np.testing.assert_allclose(W, expected, rtol=1e-12)
    with pytest.raises(ParameterError, match="C"):
        observability_gramian([A] * (N - 1), C[:-1], np.array([[sigma**2]]))


def test_bad_noise_names_its_argument():
    with pytest.raises(ParameterError, match="R"):
        observability_gramian([np.eye(2)], np.eye(2), -np.eye(2))
    with pytest.raises(ParameterError, match="A\\[0\\]"):
        observability_gramian([np.eye(3)], np.eye(2), np.eye(2))


@pytest.fixture(scope="module")
def flight():
    """Flight 5 (4 x 16 optic, one Strang substep) for 6 pulses from 2 m at 4 m/s, 1 cm
    off the beam and coning slightly, under the nominal inputs (beam on the pad, the
    flight's energy)."""
    model = table1_flight5(engine=Engine(quadrature_radial=4, quadrature_azimuthal=16))
    phi = build_pulse_map(model, CHEAP)
    x0 = initial_state(model, r_L=(0.01, 0.0, 2.0), v_L=(0.0, 0.0, 4.0), w_B=(0.0, 0.3, -0.2))
    u = nominal_inputs(model, phi.inputs)
    p = parameter_values(model)
    N = 6
    X, t = [x0], np.arange(N - 1) * phi.period
    for k in range(N - 1):
        X.append(np.asarray(phi.step(X[-1], u, p, t[k])[0]).ravel())
    return phi, np.array(X), np.tile(u, (N - 1, 1)), p, t


def test_the_gramian_is_the_finite_difference_fisher_information(flight):
    phi, X, U, p, t = flight
    sigma = 0.005
    study = observability(pulse_map_jacobian(phi), X, U, p, t, {"r_L": sigma})
    retract, _ = build_error_state()
    r = STATE.index("r_L")
    n = ERROR_STATE.size
    h = 1e-6

    def positions(d: np.ndarray) -> np.ndarray:
        x = np.asarray(retract(X[0], d)).ravel()
        out = [x[r]]
        for k in range(len(t)):
            x = np.asarray(phi.step(x, U[k], p, t[k])[0]).ravel()
            out.append(x[r])
        return np.concatenate(out)

    S = np.column_stack([(positions(h * e) - positions(-h * e)) / (2 * h) for e in np.eye(n)])
    W = S.T @ S / sigma**2
    scale = np.max(np.abs(W))
    assert np.max(np.abs(study.gramian - W)) < 1e-6 * scale
    assert len(study.states) == n


def test_what_positions_cannot_tell_apart(flight):
    """From positions alone (5 mm) over 6 pulses: Φ's dynamics depend on the craft's mass,
    not on how it splits between liner and RCS propellant, so the direction that trades
    one for the other is unseen (eᵀ W e = 0 to rounding), and so is the engine's load this
    early (the health step sits near pulse 100: flat at 6 pulses). Kept to r_L and v_L
    (the rest taken as known), every entry is seen, the position better than one frame."""
    phi, X, U, p, t = flight
    sigma = 0.005
    jac = pulse_map_jacobian(phi)
    study = observability(jac, X, U, p, t, {"r_L": sigma})
    top = float(study.eigenvalues[-1])
    split = np.zeros(len(study.states))
    split[study.states.index("liner_mass")] = 1.0
    split[study.states.index("rcs_mass")] = -1.0
    split /= np.linalg.norm(split)
    assert split @ study.gramian @ split < 1e-14 * top
    assert study.bound("rcs_mass") == float("inf") and study.bound("engine_load") == float("inf")
    kept = observability(jac, X, U, p, t, {"r_L": sigma}, states=["r_L", "v_L"])
    for name in kept.states:
        assert 0 < kept.bound(name) < np.inf
    for axis in ("east", "north", "up"):
        assert kept.bound(f"r_L[{axis}]") <= sigma
    assert 1 < kept.condition < np.inf
