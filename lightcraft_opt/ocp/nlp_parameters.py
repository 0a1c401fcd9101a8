"""An NLP's dependence on its parameter vector P, for the optimum's sensitivities
(ocp/envelope.py, docs/design.md#sensitivities): the same for one scenario's transcription
(ocp/transcription.py) and for a robust problem's (ocp/scenario_shooting.py).
"""

from __future__ import annotations

from collections.abc import Mapping

import casadi as ca
import numpy as np

__all__ = ["lagrangian_gradient", "parameters_read"]


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
