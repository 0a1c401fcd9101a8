"""The optimum's sensitivities of one compiled problem: the envelope theorem's gradient of
the Lagrangian in the NLP's parameters at a result (ocp/sensitivity.py says what they are,
docs/design.md#sensitivities).
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np

from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.ocp.scenario_shooting import ScenarioShooting
from lightcraft_opt.ocp.sensitivity import Sensitivities, parameter_sensitivities
from lightcraft_opt.ocp.transcription import MultipleShooting

__all__ = ["EnvelopeGradient"]


class EnvelopeGradient:
    """dJ*/dθ of a transcription's optima, its casadi Function built on first use.

    Parameters
    ----------
    transcription : the NLP the results solve.
    """

    def __init__(self, transcription: MultipleShooting | ScenarioShooting) -> None:
        self.transcription = transcription
        #: the Lagrangian's gradient in P and the entries of P it reads
        self._built: tuple[ca.Function, np.ndarray] | None = None

    def __call__(self, result: OcpResult, P: np.ndarray) -> Sensitivities:
        """The held parameters' sensitivities at ``result``, solved with the NLP's parameter
        vector ``P`` (SI): ∂L/∂P at its primal and dual point; empty, with the reason, when
        ``result`` is no optimum or the gradient cannot be had."""
        if not result.success or not result.dynamics_closed:
            return Sensitivities.none(
                f"the solve ended {result.status.value}"
                + ("" if result.dynamics_closed else " with its dynamics gaps open")
                + ": the optimum's derivatives need an optimum"
            )
        tr = self.transcription
        start = time.perf_counter()
        try:
            if self._built is None:
                self._built = (tr.lagrangian_gradient(), tr.parameters_read())
            function, read = self._built
            grad = np.asarray(function(result.w, P, result.lam_g), dtype=float).ravel()
        except RuntimeError as err:  # a Φ without derivatives (a compiled one without them)
            text = str(err).strip()
            reason = text.splitlines()[-1] if text else repr(err)
            return Sensitivities.none(f"no derivative of the NLP in its parameters: {reason}")
        if not np.all(np.isfinite(grad)):
            return Sensitivities.none("the Lagrangian's gradient is not finite at this optimum")
        seconds = time.perf_counter() - start
        x0, p = tr.parameters.index("x0"), tr.parameters.index("p")
        return parameter_sensitivities(
            grad[x0], grad[p], P[x0], P[p], tr.design, read[x0], read[p], seconds
        )
