"""The extended Kalman filter at pulse rate, on an :class:`EstimationModel` (docs/estimation.md).

Each step: predict from the last node with the model and the input fired there
(s⁻ = f(s, u, t), P⁻ = F P Fᵀ + Q), then update with each reading that arrived, one at a time
in the Joseph form (P = (I - K H) P (I - K H)ᵀ + K R Kᵀ, which stays symmetric positive
definite in floating point: Bucy and Joseph, docs/references.md). A reading belongs to the node
that ends the coast it was taken in (dt = t_node - t before it). A reading that arrives late (a
node j < k: latency) is put at its node and the filter runs again from there: the short history
keeps each node's prior (s⁻, P⁻), its readings and the input fired after it, so the result is
exactly that of a filter that had the reading in time. A lost frame is no reading.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from lightcraft_opt.control.estimation.buffered import Evaluator
from lightcraft_opt.control.estimation.curvature import (
    checked_names,
    curvature_entries,
    second_order_terms,
)
from lightcraft_opt.control.estimation.estimate import Estimate, Innovation
from lightcraft_opt.control.estimation.kalman import (
    joseph_function,
    joseph_update,
    prior_sigmas,
    symmetric,
)
from lightcraft_opt.control.estimation.model import EstimationModel
from lightcraft_opt.control.estimation.reading import Reading
from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.model.checks import checked_int, checked_number

__all__ = ["EkfOptions", "ExtendedKalmanFilter"]


@dataclass(frozen=True)
class EkfOptions:
    """How the EKF starts and how much it trusts its model.

    Attributes
    ----------
    prior : {entry of s or slot name: prior standard deviation [its SI unit]} (a slot such
        as ``"r_L"`` sets all its entries); the entries not named keep ``prior_default``.
        Later pairs override earlier ones. The defaults: 5 mm and 0.05 m/s on r_L, v_L;
        1e-3 kg m²/s on H_L's east and north (a tilt of 1°), 1e-5 on its up (the spin to
        0.016 %: the spin sets the coning's phase, 8 turns a pulse, so a prior of 1e-3 would
        leave it unknown at the next pulse and the filter's linearisation useless);
        0.02 on the coning offset (1.1°); 2 m/s on the wind; 5e-6 N s/J on the coupling
        (3 % of Flight 5's); 0.01 on the moments' scales (the campaigns' 1 %).
    prior_default : prior standard deviation of the entries not in ``prior`` (the
        bookkeeping: liner and RCS masses [kg], engine load [pulses]), > 0.
    noise_scale : the model's process-noise covariance Q times this, > 0 (tuning).
    history : pulses of history kept for late readings, >= 1; a reading older than that
        is dropped (counted in ``ExtendedKalmanFilter.dropped``).
    second_order : entries of s (or slot names) across which the prediction keeps the
        model's curvature: its mean and covariance gain the second-order terms
        (curvature.py), at m (m + 1) evaluations of the model for m entries. Empty (the
        default): the first-order EKF. ``curvature.BEAM_OFFSET``: the offset in the beam,
        where the capture peaks under a beam pointed at the estimate;
        ``curvature.PSI_CURVES``: every direction where Ψ curves across a tracked craft's
        prior (docs/estimation.md#the-second-order-filter: on flights of Ψ the NEES is
        142.6 first order, 23.6 across the offset, 17.85 across these; band 15.4-18.7).
    """

    prior: tuple[tuple[str, float], ...] = (
        ("r_L", 5e-3),
        ("v_L", 0.05),
        ("H_L", 1e-3),
        ("H_L[up]", 1e-5),
        ("coning", 0.02),
        ("wind_L", 2.0),
        ("coupling", 5e-6),
        ("inertia", 0.01),
    )
    prior_default: float = 1e-6
    noise_scale: float = 1.0
    history: int = 8
    second_order: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name, value in self.prior:
            checked_number("EkfOptions", f"prior[{name!r}]", value, 0.0)
            if value <= 0:
                raise OptionError(f"EkfOptions.prior[{name!r}] must be > 0, got {value}")
        for name in ("prior_default", "noise_scale"):
            checked_number("EkfOptions", name, getattr(self, name), 0.0)
            if getattr(self, name) <= 0:
                raise OptionError(f"EkfOptions.{name} must be > 0, got {getattr(self, name)}")
        checked_int("EkfOptions", "history", self.history, 1)
        checked_names("EkfOptions.second_order", self.second_order)

    def prior_sigmas(self, names: Sequence[str]) -> np.ndarray:
        """(len(names),) the prior standard deviation of each entry of s (a pair naming
        no entry of this model, such as the moments' on a model without them, is unused)."""
        return prior_sigmas(self.prior, names, self.prior_default)[0]


@dataclass
class _Node:
    """A pulse of the history: the prior at it, its readings (in the order they joined),
    the input fired after it, and (s, P) after each of its first readings: a reading that
    joins later starts from the last of them, the same arithmetic as from the prior (a
    frame a pulse late no longer repeats the gyro's update before it)."""

    t: float
    s: np.ndarray
    P: np.ndarray
    readings: list[Reading] = field(default_factory=list)
    u: np.ndarray | None = None
    posts: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)


class ExtendedKalmanFilter:
    """The EKF (module docstring), an :class:`~lightcraft_opt.control.estimation.Estimator`.

    Parameters
    ----------
    model : the estimation model (e.g. :class:`~.psi_model.PsiEstimationModel`); its
        optional ``start(x0)`` and ``parts(s)`` (model.py) map a full state to s and s to
        an Estimate's (z, x, slow); without them s = x0 and z = x = s.
    options : :class:`EkfOptions`.

    Attributes
    ----------
    s, P : the latest estimate and its covariance.
    innovations : the :class:`Innovation` of each reading of the latest step.
    dropped : readings dropped so far, older than the history.
    """

    name = "ekf"

    def __init__(self, model: EstimationModel, options: EkfOptions | None = None) -> None:
        self.model = model
        self.options = options or EkfOptions()
        if not isinstance(self.options, EkfOptions):
            raise OptionError(f"options must be EkfOptions, got {self.options!r}")
        self._P0 = np.diag(np.square(self.options.prior_sigmas(model.names)))
        self._curved = curvature_entries(
            model, self.options.second_order, "EkfOptions.second_order"
        )
        self.innovations: list[Innovation] = []
        self.dropped = 0
        self._nodes: list[_Node] = []
        self._k0 = 0
        self._joseph: dict[int, Evaluator] = {}  # by the reading's size
        self.s = np.zeros(len(model.names))
        self.P = self._P0.copy()

    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None:
        """Start from the full state x0 (STATE, docs/frames.md) as the prior mean, read as s
        by the model's ``start(x0)`` if it has one (else x0 is s), at ``t0`` [s]."""
        start = getattr(self.model, "start", None)
        s0 = np.asarray(start(x0) if start is not None else x0, dtype=float).ravel()
        if s0.size != len(self.model.names):
            raise ParameterError(
                "x0", f"gives {s0.size} entries, the model has {len(self.model.names)}"
            )
        self.s, self.P = s0, self._P0.copy()
        self._nodes = [_Node(float(t0), s0.copy(), self.P.copy())]
        self._k0 = 0
        self.innovations, self.dropped = [], 0

    # -- the two halves ------------------------------------------------------------------------

    def _update(
        self, s: np.ndarray, P: np.ndarray, node_t: float, reading: Reading
    ) -> tuple[np.ndarray, np.ndarray, Innovation]:
        dt = max(node_t - reading.t, 0.0)
        y_hat, H = self.model.measure(reading.sensor, s, dt)
        R = self.model.measurement_noise(reading.sensor)
        nu = np.asarray(reading.y, dtype=float).ravel() - y_hat
        n, m = P.shape[0], nu.size
        if m > n + 1:  # the Function packs S beside the mean
            s, P, S = joseph_update(s, P, nu, H, R)
            return s, P, Innovation(reading, nu, S)
        if m not in self._joseph:
            self._joseph[m] = Evaluator(joseph_function(n, m))
        out = self._joseph[m](s, P, nu, H, R)
        return out[:n, 0], out[:n, 1:], Innovation(reading, nu, out[n:, :m])

    def _filtered(self, node: _Node, record: set[int]) -> tuple[np.ndarray, np.ndarray]:
        """The node's posterior: its prior updated with its readings in order, from the
        last posterior kept (``_Node.posts``, emptied when its prior changes)."""
        s, P = node.posts[-1] if node.posts else (node.s, node.P)
        for reading in node.readings[len(node.posts) :]:
            s, P, innovation = self._update(s, P, node.t, reading)
            node.posts.append((s, P))
            if id(reading) in record:
                self.innovations.append(innovation)
        return s, P

    def _predict(
        self, s: np.ndarray, P: np.ndarray, u: np.ndarray, t: float
    ) -> tuple[np.ndarray, np.ndarray]:
        s_next, F = self.model.predict(s, u, t)
        Q = self.options.noise_scale * self.model.process_noise(s, u, t)
        P_next = F @ P @ F.T + Q
        if self._curved:
            shift, spread = second_order_terms(self.model, s, s_next, P, u, t, self._curved)
            s_next, P_next = s_next + shift, P_next + spread
        return s_next, symmetric(P_next)

    # -- the step --------------------------------------------------------------------------

    def _node_of(self, t: float) -> int:
        """The index in the history of the node that ends the coast ``t`` [s] lies in
        (t_k - T < t <= t_k; the latest node for a later t)."""
        for i, node in enumerate(self._nodes):
            if t <= node.t + 1e-12:
                return i
        return len(self._nodes) - 1

    def step(self, readings: Sequence[Reading], u_fired: np.ndarray | None, t: float) -> Estimate:
        """The estimate at pulse time ``t`` [s] (module docstring): put each reading that
        belongs to a node of the history at it (latency) and filter again from the earliest
        node touched, then predict with ``u_fired`` (the map input fired at the last node;
        None at the first step: no prediction) and update with the new node's readings. The
        late readings join before the prediction, so a step predicts once, not twice, where
        the camera is a pulse late; the estimate is the same."""
        start = time.perf_counter()
        if not self._nodes:
            raise ParameterError("reset", "call reset(x0, t0) before step")
        self.innovations = []
        record: set[int] = set()
        nodes = self._nodes
        if u_fired is None:
            late, new = list(readings), []
        else:
            if len(nodes) > self.options.history:  # the oldest node leaves the history
                nodes.pop(0)
                self._k0 += 1
            now = nodes[-1].t + 1e-12
            late = [r for r in readings if r.t <= now]
            new = [r for r in readings if r.t > now]
        period = (
            float(t) - nodes[-1].t
            if u_fired is not None
            else nodes[1].t - nodes[0].t
            if len(nodes) > 1
            else math.inf
        )
        earliest = self._place(late, record, period)
        for i in range(earliest, len(nodes) - 1):  # filter again up to the last node
            node, nxt = nodes[i], nodes[i + 1]
            s, P = self._filtered(node, record)
            assert node.u is not None
            nxt.s, nxt.P = self._predict(s, P, node.u, node.t)
            nxt.posts = []
        if u_fired is not None:
            last = nodes[-1]
            last.u = np.asarray(u_fired, dtype=float).ravel()
            s, P = self._filtered(last, record)
            s, P = self._predict(s, P, last.u, last.t)
            nodes.append(_Node(float(t), s, P))
            self._place(new, record, period)
        self.s, self.P = self._filtered(nodes[-1], record)
        return self._estimate(float(t), time.perf_counter() - start)

    def _place(self, readings: Sequence[Reading], record: set[int], period: float) -> int:
        """Put each reading at the node of the history whose coast it lies in (a reading
        older than the history is dropped and counted); the earliest node touched (the
        last node's index when none)."""
        nodes = self._nodes
        earliest = len(nodes) - 1
        for reading in readings:
            if self._k0 > 0 and reading.t <= nodes[0].t - period + 1e-12:
                self.dropped += 1  # its node has left the history
                continue
            i = self._node_of(reading.t)
            nodes[i].readings.append(reading)
            record.add(id(reading))
            earliest = min(earliest, i)
        return earliest

    def _estimate(self, t: float, seconds: float) -> Estimate:
        parts = getattr(self.model, "parts", None)
        z, x, slow = parts(self.s) if parts is not None else (self.s.copy(), self.s.copy(), {})
        return Estimate(t, z, x, self.P.copy(), slow, seconds)
