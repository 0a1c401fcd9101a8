"""Functions of a transcription's NLP built alike for one scenario's (ocp/transcription.py)
and a robust problem's (ocp/scenario_shooting.py): the Lagrangian's gradient in the
parameter vector P and the entries of P it reads, for the optimum's sensitivities
(ocp/envelope.py, docs/design.md#sensitivities), and the Gauss-Newton Hessian.
"""

from __future__ import annotations

from collections.abc import Mapping

import casadi as ca
import numpy as np

__all__ = ["gauss_newton_hessian", "lagrangian_gradient", "parameters_read"]


def lagrangian_gradient(nlp: Mapping[str, ca.MX], P: ca.MX) -> ca.Function:
    """casadi.Function ``ocp_lagrangian_gradient_p(w, P, lam_g) -> grad_P``: the gradient of
    the Lagrangian f + lam_gᵀ g of ``nlp`` ({"x": w, "f", "g"}) with respect to its
    parameter symbol ``P``, by casadi's AD through the NLP's own expressions (one reverse
    sweep). At a solution it is the optimal cost's derivative with respect to P (the
    envelope theorem; ocp/sensitivity.py)."""
    w = nlp["x"]
    lam_g = ca.MX.sym("lam_g", nlp["g"].numel())
    lagrangian = nlp["f"] + ca.dot(lam_g, nlp["g"])
    return ca.Function(
        "ocp_lagrangian_gradient_p",
        [w, P, lam_g],
        [ca.gradient(lagrangian, P)],
        ["w", "P", "lam_g"],
        ["grad_P"],
    )


def parameters_read(nlp: Mapping[str, ca.MX], P: ca.MX) -> np.ndarray:
    """(P.size,) bool: the entries of ``P`` that the NLP's f or g depend on (structurally:
    casadi's sparsity of their Jacobians, no evaluation)."""
    read = np.zeros(P.numel(), dtype=bool)
    for expr in (nlp["f"], nlp["g"]):
        read[np.asarray(ca.jacobian_sparsity(expr, P).get_col(), dtype=int)] = True
    return read


def gauss_newton_hessian(
    nlp: Mapping[str, ca.MX], P: ca.MX, residuals: ca.MX, *, upper: bool = True
) -> ca.Function:
    """casadi.Function ``nlp_hess_l(x, p, lam_f, lam_g) -> hess_gamma_x_x``: lam_f 2 JᵀJ, J
    the Jacobian of the least-squares ``residuals`` with respect to the NLP's w (nlpsol's
    ``hess_lag`` option); its upper triangle with ``upper`` (IPOPT), else the whole matrix
    (sqpmethod)."""
    w = nlp["x"]
    lam_f = ca.MX.sym("lam_f")
    lam_g = ca.MX.sym("lam_g", nlp["g"].numel())
    J = ca.jacobian(residuals, w) if residuals.numel() else ca.MX(0, w.numel())
    H = lam_f * 2 * ca.mtimes(J.T, J)
    H = ca.triu(H) if upper else H
    return ca.Function(
        "nlp_hess_l", [w, P, lam_f, lam_g], [H], ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"]
    )
