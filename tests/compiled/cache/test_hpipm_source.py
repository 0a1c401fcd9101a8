"""Generated C that calls HPIPM (compiled/cache/hpipm_source.py): built against the casadi
wheel's HPIPM and BLASFEO, with the options casadi 3.8 leaves unset given HPIPM's defaults.

Reference: the interpreted QP Function (casadi's HPIPM plugin). The director's QP shape
(states pinned at stage 0, free after, bounded inputs, some bounds active) solved from a
cold and from a shifted warm start must give the interpreter's primal and dual solution to
the last bit. Before the fix, the same QP hit HPIPM's iteration cap in C on every call
(``dual_gap_max`` was stack garbage), which the step Function reports as a failed solve.
"""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from lightcraft_opt.compiled.cache import compile_function
from lightcraft_opt.compiled.cache.hpipm_source import fixed_source, uses_hpipm
from lightcraft_opt.control.director_qp import DirectorQp
from lightcraft_opt.control.options import MpcSolver

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="needs a C compiler")


def _qp_inputs(qp: DirectorQp, rng: np.random.Generator) -> list[np.ndarray]:
    """A stable stage QP: A near the identity, B random, a gradient pushing the inputs
    onto their bounds (|du| <= 0.3)."""
    N, nz, nu = qp.horizon, qp.nz, qp.nu
    A = np.hstack([np.eye(nz) + 0.05 * rng.standard_normal((nz, nz)) for _ in range(N)])
    B = np.hstack([rng.standard_normal((nz, nu)) for _ in range(N)])
    g = 3.0 * rng.standard_normal(qp.n_w)
    d = 0.1 * rng.standard_normal(qp.n_a)
    lbx, ubx = np.full(qp.n_w, -np.inf), np.full(qp.n_w, np.inf)
    lbx[:nz] = ubx[:nz] = rng.standard_normal(nz)
    for j in range(N):
        k = j * (nz + nu) + nz
        lbx[k : k + nu], ubx[k : k + nu] = -0.3, 0.3
    return [A, B, g, d, lbx, ubx, np.zeros(qp.n_w), np.zeros(qp.n_w), np.zeros(qp.n_a)]


def test_the_compiled_qp_gives_the_interpreters_solution_to_the_last_bit(tmp_path, monkeypatch):
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(tmp_path))
    rng = np.random.default_rng(5)
    nz, nu, N = 4, 2, 6
    H = rng.standard_normal((nz + nu, nz + nu))
    qp = DirectorQp(H @ H.T + np.eye(nz + nu), np.eye(nz), N, MpcSolver.HPIPM, 30, 1e-6)
    compiled = compile_function(qp.function, hpipm=True)
    assert compiled.class_name() == "External"
    args = _qp_inputs(qp, rng)
    for _ in range(2):  # cold, then warm from the shifted solution
        interpreted = [np.asarray(v) for v in qp.function(*args)]
        assert qp.function.stats()["success"]
        assert qp.function.stats()["iter_count"] < 30
        native = [np.asarray(v) for v in compiled(*args)]
        du = interpreted[0][nz : nz + nu].ravel()
        assert np.any(np.isclose(np.abs(du), 0.3))  # some bound is active
        for a, b in zip(native, interpreted, strict=True):
            assert np.array_equal(a, b)
        w, lam_x, lam_a = (interpreted[k].ravel() for k in (0, 2, 3))
        args[6:] = [np.r_[w[nz + nu :], w[-(2 * nz + nu) :]][: qp.n_w], lam_x, lam_a]


def test_a_source_without_the_known_copy_is_refused():
    assert uses_hpipm("#include <hpipm_d_ocp_qp_ipm.h>\nint f(void) { return 0; }")
    assert not uses_hpipm("int f(void) { return 0; }")
    with pytest.raises(ValueError, match=r"hpipm_source\.py"):
        fixed_source("#include <hpipm_d_ocp_qp_ipm.h>\nint f(void) { return 0; }")
