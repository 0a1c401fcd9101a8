"""What the moving-horizon estimator is asked (:class:`MheOptions`) and what one of its
steps did (:class:`MheStats`): control/estimation/mhe.py is how."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lightcraft_opt.control.estimation.curvature import checked_names
from lightcraft_opt.control.estimation.kalman import prior_sigmas
from lightcraft_opt.control.mpc_qp import QpStatus
from lightcraft_opt.errors import OptionError
from lightcraft_opt.model.checks import checked_int, checked_number

__all__ = ["MAX_WINDOW", "MheOptions", "MheStats"]

#: Longest window: 10 s of pulses; the QP grows with it and a pulse leaves 38 ms.
MAX_WINDOW = 260


@dataclass(frozen=True)
class MheOptions:
    """How the moving-horizon estimator fits its window.

    Attributes
    ----------
    horizon : N, pulses in the window (N + 1 nodes), in [1, 260].
    prior_sigma : the prior standard deviation of every entry of s, in its SI unit, > 0.
    prior_sigmas : ((name, sigma), ...) overrides of ``prior_sigma``; a name is an entry
        of the model's ``names`` (``"r_L[east]"``) or the part before its bracket
        (``"r_L"``: all three).
    max_iter : HPIPM's iteration cap, >= 1 (the QP has no bounds: it takes one or two).
    tol : HPIPM's tolerance on the absolute residuals, in (0, 1).
    relinearize : a number in [1, horizon] (default 1): that many stages (those evaluated
        longest ago; a new stage is evaluated when it joins) have their f and F evaluated
        afresh at the guess each pulse, the others' f moved to the new guess to first order
        (f + F δs) with their F kept: fewer model calls (Ψ's Jacobian costs 0.1-0.2 ms a
        stage compiled), the same answer on a linear model; None, or the horizon: every
        stage, the plain real-time iteration. On 50 flights of Ψ 1 raised the NEES from
        25.5 to 27.4 (default noises; 17.5 to 17.8 at a tenth) and left the RMSE within 6 %
        either way, for a step 1.6 times faster (docs/estimation.md, the step times).
    second_order : entries of s (or slot names) across which each stage keeps the model's
        curvature, as the EKF's option of that name (curvature.py): a stage evaluated
        afresh gains the second-order terms over its node's filtered covariance, its f the
        mean's and its noise the spread's, at m (m + 1) model evaluations for m entries.
        Empty (the default): Gauss-Newton on f alone.
    """

    horizon: int = 15
    prior_sigma: float = 1.0
    prior_sigmas: tuple[tuple[str, float], ...] = ()
    max_iter: int = 20
    tol: float = 1e-8
    relinearize: int | None = 1
    second_order: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        checked_int("MheOptions", "horizon", self.horizon, 1, MAX_WINDOW, "10 s of pulses")
        checked_number("MheOptions", "prior_sigma", self.prior_sigma, 0.0)
        if not isinstance(self.prior_sigmas, tuple):
            raise OptionError(
                f"MheOptions.prior_sigmas must be a tuple of (name, sigma), got "
                f"{self.prior_sigmas!r}"
            )
        for pair in self.prior_sigmas:
            if not (isinstance(pair, tuple) and len(pair) == 2 and isinstance(pair[0], str)):
                raise OptionError(
                    f"MheOptions.prior_sigmas must hold (name, sigma) pairs, got {pair!r}"
                )
            checked_number("MheOptions", f"prior_sigmas[{pair[0]!r}]", pair[1], 0.0)
        checked_int("MheOptions", "max_iter", self.max_iter, 1)
        checked_number("MheOptions", "tol", self.tol, 0.0, 1.0)
        if self.relinearize is not None:
            checked_int(
                "MheOptions", "relinearize", self.relinearize, 1, self.horizon, "the horizon"
            )
        checked_names("MheOptions.second_order", self.second_order)

    def prior_covariance(self, names: Sequence[str]) -> np.ndarray:
        """(n, n) diagonal prior covariance of s whose entries are ``names``; an override
        that names no entry is an OptionError listing them."""
        sigma, unmatched = prior_sigmas(self.prior_sigmas, names, self.prior_sigma)
        if unmatched:
            raise OptionError(
                f"MheOptions.prior_sigmas: {unmatched[0]!r} names no entry of the model, "
                f"whose entries are {list(names)}"
            )
        return np.diag(sigma**2)


@dataclass(frozen=True)
class MheStats:
    """One step of the estimator.

    Attributes
    ----------
    status : how the QP ended (SOLVED; MAX_ITER, FAILED, NON_FINITE: the step fell back).
    message : HPIPM's word, or why the step fell back.
    fallback : the estimate is the prediction (the QP failed), not the window's fit.
    iterations : HPIPM's (0 when it was not called); solve_time : of the QP [s].
    step_time : of the whole step [s].
    nodes : in the window, <= N + 1.
    readings : in the window; dropped : readings this step could not use (taken before
        the window's first node, or not finite).
    """

    status: QpStatus
    message: str = ""
    fallback: bool = False
    iterations: int = 0
    solve_time: float = 0.0
    step_time: float = 0.0
    nodes: int = 0
    readings: int = 0
    dropped: int = 0
