"""The discrete LQR gain on matrices, from the discrete algebraic Riccati equation (scipy).

Minimising Σ x'Qx + u'Ru + 2 x'N u over x[k+1] = A x[k] + B u[k] gives u = -K x with

    S = A'SA - (A'SB + N)(B'SB + R)^-1 (B'SA + N') + Q,
    K = (B'SB + R)^-1 (B'SA + N'),

S the stabilising solution (cost-to-go x'Sx), solved by ``scipy.linalg.solve_discrete_are``
(the generalised Schur method). This is what ``control.dlqr`` computes when slycot is not
installed, in the same operations; tests/linear/test_riccati.py checks the two agree. The
controllers take the gain from here, so they never import python-control (seconds to
import, docs/architecture.md#contracts).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg

from lightcraft_opt.errors import ParameterError

__all__ = ["checked_weight", "dlqr_gain"]


def checked_weight(
    name: str, w: np.ndarray | Sequence[float], n: int, definite: bool
) -> np.ndarray:
    """(n, n) symmetric weight from a matrix or its diagonal; positive (semi)definite.

    Raises
    ------
    ParameterError naming ``name`` for a wrong shape, a non-finite entry, an asymmetric
    matrix, or a negative (for ``definite``, non-positive) eigenvalue.
    """
    W = np.asarray(w, dtype=float)
    if W.ndim == 1:
        W = np.diag(W)
    if W.shape != (n, n) or not np.all(np.isfinite(W)):
        raise ParameterError(name, f"must be a finite ({n}, {n}) matrix or {n} diagonal entries")
    if not np.allclose(W, W.T, rtol=1e-12, atol=0.0):
        raise ParameterError(name, "must be symmetric")
    low = float(np.min(np.linalg.eigvalsh(W)))
    if low < 0.0 or (definite and low <= 0.0):
        kind = "definite" if definite else "semidefinite"
        raise ParameterError(name, f"must be positive {kind}; smallest eigenvalue {low:.3g}")
    return W


def dlqr_gain(
    A: np.ndarray,
    B: np.ndarray,
    Q: np.ndarray,
    R: np.ndarray,
    N: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Discrete LQR on matrices: minimise Σ x'Qx + u'Ru + 2 x'N u (module docstring).

    Parameters
    ----------
    A : (n, n), B : (n, m) the model x[k+1] = A x[k] + B u[k].
    Q : (n, n), R : (m, m), N : (n, m) weights; [[Q, N], [N', R]] positive semidefinite,
        R positive definite.

    Returns
    -------
    K : (m, n) the gain of u = -K x; S : (n, n) the Riccati solution (cost-to-go x'Sx).

    Raises
    ------
    ParameterError when R is not positive definite, or when the Riccati equation has no
    stabilising solution or the matrices do not fit (e.g. (A, B) not stabilisable).
    """
    Am = np.array(A, ndmin=2, dtype=float)
    Bm = np.array(B, ndmin=2, dtype=float)
    n, m = Bm.shape
    Qm = np.array(Q, ndmin=2, dtype=float)
    Rm = np.array(R, ndmin=2, dtype=float)
    Nm = np.zeros((n, m)) if N is None else np.array(N, ndmin=2, dtype=float)
    checked_weight("R", Rm, m, definite=True)
    try:
        S = scipy.linalg.solve_discrete_are(Am, Bm, Qm, Rm, s=Nm)
        K = scipy.linalg.solve(Bm.T @ S @ Bm + Rm, Bm.T @ S @ Am + Nm.T)
    except (ValueError, np.linalg.LinAlgError) as err:
        raise ParameterError("Q, R", f"the discrete Riccati equation failed: {err}") from err
    return K, S
