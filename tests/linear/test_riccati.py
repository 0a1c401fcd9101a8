"""The discrete LQR gain from scipy's Riccati solver (linear/riccati.py).

References: python-control's ``control.dlqr`` (the gain the controllers took before, which
solves the same equation: to 1e-10 relative, i.e. rounding of a well-conditioned Riccati
solution); the scalar Riccati equation's closed form; the definition of the stabilising
solution (every multiplier of A - B K inside the unit circle, S symmetric positive
semidefinite). The nutation MPC's and LQR controller's own models are checked against
control.dlqr in tests/control/test_mpc.py, the hover model of linearize.lqr in
tests/linearize/test_linearize.py.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.linear import dlqr_gain

#: python-control and scipy solve the same equation; they differ by rounding only.
RELATIVE = 1e-10


def assert_python_control_agrees(
    A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray, N: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """dlqr_gain's K and S against control.dlqr's, to RELATIVE in the Frobenius norm."""
    K, S = dlqr_gain(A, B, Q, R, N)
    K_ref, S_ref, _ = control.dlqr(A, B, Q, R, *(() if N is None else (N,)))
    assert np.linalg.norm(K - K_ref) <= RELATIVE * np.linalg.norm(K_ref)
    assert np.linalg.norm(S - S_ref) <= RELATIVE * np.linalg.norm(S_ref)
    return K, S


def random_system(rng: np.random.Generator, n: int, m: int) -> tuple[np.ndarray, ...]:
    """A with largest multiplier 1.3 (unstable), generic B (controllable), and weights
    [[Q, N], [N', R]] positive definite."""
    A = rng.normal(size=(n, n))
    A *= 1.3 / np.max(np.abs(np.linalg.eigvals(A)))
    B = rng.normal(size=(n, m))
    W = rng.normal(size=(n + m, n + m))
    W = W @ W.T + 0.1 * np.eye(n + m)
    return A, B, W[:n, :n], W[n:, n:], W[:n, n:]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_stabilisable_systems_match_python_control(seed):
    """Random unstable, controllable systems with and without a cross weight."""
    rng = np.random.default_rng(seed)
    A, B, Q, R, N = random_system(rng, 6, 2)
    for cross in (None, N):
        K, S = assert_python_control_agrees(A, B, Q, R, cross)
        assert np.max(np.abs(np.linalg.eigvals(A - B @ K))) < 1.0
        np.testing.assert_allclose(S, S.T, rtol=1e-12, atol=0.0)


def test_an_uncontrollable_but_stable_mode_is_left_alone():
    """Stabilisable, not controllable: a decaying mode no input reaches (multiplier 0.5)
    keeps its multiplier in A - B K; the rest is stabilised as control.dlqr does."""
    rng = np.random.default_rng(3)
    A, B, Q, R, _ = random_system(rng, 4, 1)
    A = np.block([[A, np.zeros((4, 1))], [np.zeros((1, 4)), np.array([[0.5]])]])
    B = np.vstack([B, np.zeros((1, 1))])
    Q = np.block([[Q, np.zeros((4, 1))], [np.zeros((1, 4)), np.ones((1, 1))]])
    K, _ = assert_python_control_agrees(A, B, Q, R)
    closed = np.linalg.eigvals(A - B @ K)
    assert np.min(np.abs(closed - 0.5)) < 1e-12
    assert np.max(np.abs(closed)) < 1.0


def test_scalar_riccati_closed_form():
    """x[k+1] = a x + b u, cost q x^2 + r u^2: b² s² + (r (1 - a²) - q b²) s - q r = 0,
    s the positive root, k = a b s / (b² s + r)."""
    a, b, q, r = 1.3, 0.7, 2.0, 0.5
    lin = r * (1 - a**2) - q * b**2
    s = (-lin + math.sqrt(lin**2 + 4 * b**2 * q * r)) / (2 * b**2)
    K, S = dlqr_gain(np.array([[a]]), np.array([[b]]), np.array([[q]]), np.array([[r]]))
    assert S[0, 0] == pytest.approx(s, rel=1e-13)
    assert K[0, 0] == pytest.approx(a * b * s / (b**2 * s + r), rel=1e-13)


def test_no_stabilising_solution_and_bad_weights_are_parameter_errors():
    """An unstable mode no input reaches has no stabilising solution; R must be positive
    definite; the error names the weights."""
    A = np.diag([1.5, 0.5])
    B = np.array([[0.0], [1.0]])
    with pytest.raises(ParameterError, match="Q, R: the discrete Riccati equation failed"):
        dlqr_gain(A, B, np.eye(2), np.eye(1))
    with pytest.raises(ParameterError, match="R: must be positive definite"):
        dlqr_gain(np.eye(2), np.eye(2), np.eye(2), -np.eye(2))
