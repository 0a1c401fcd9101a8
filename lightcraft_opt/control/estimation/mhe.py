"""The moving-horizon estimator: the last N pulses fitted at once, one QP a pulse.

The window holds N + 1 nodes, the states s_0 .. s_N at the last N + 1 pulses (fewer at the
start of a flight), and the process noises w_j between them (multiple shooting). Its cost
(docs/estimation.md#moving-horizon-estimation)::

    ‖s_0 - s̄_0‖²_{P̄_0⁻¹}  +  Σ_{j<N} ‖w_j‖²_{Q_j⁻¹}  +  Σ_j Σ_readings ‖y - h(s_j, dt)‖²_{R⁻¹}

subject to s_{j+1} = f(s_j, u_j, t_j) + w_j. Each pulse is one real-time iteration:

1. shift: a node is added at the pulse (its guess the prediction of the last solution);
   the oldest leaves when there are more than N + 1, and the arrival cost (s̄_0, P̄_0)
   moves to the new first node by one extended Kalman filter step, its readings' update
   and the prediction, linearised at the estimator's own solution of the node that left;
2. the readings that arrived are placed at the nodes their times belong to (latency);
3. one Gauss-Newton QP about the guess (control/estimation/mhe_qp.py, HPIPM), whose
   solution is the new guess; its last node is the estimate.

On a linear model with Gaussian noise the last node equals the Kalman filter's estimate at
every pulse, the first N included: the arrival cost is then the filter's prediction at
the first node, and the window's least squares the rest of the filter's (the check in
tests/control/estimation/test_mhe_kalman.py).

The covariance returned is the last node's block of the inverse of the QP's Hessian
(reduced by its dynamics), computed by the Kalman covariance recursion along the window
from P̄_0 with the QP's own Jacobians.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from lightcraft_opt.control.estimation.curvature import curvature_entries, second_order_terms
from lightcraft_opt.control.estimation.estimate import Estimate, Innovation
from lightcraft_opt.control.estimation.kalman import joseph_update, symmetric
from lightcraft_opt.control.estimation.mhe_options import MheOptions, MheStats
from lightcraft_opt.control.estimation.mhe_qp import mhe_qp_function, mhe_qp_sizes
from lightcraft_opt.control.estimation.model import EstimationModel
from lightcraft_opt.control.estimation.reading import Reading
from lightcraft_opt.control.mpc_qp import QpStatus
from lightcraft_opt.control.options import ControllerFault
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.checks import checked_vector

__all__ = ["MovingHorizonEstimator"]

#: Two times closer than this [s] are the same time (a reading taken at a pulse).
_SAME_TIME = 1e-9


@dataclass
class _Node:
    """One pulse of the window: its time [s], the guess of s, the input fired there, the
    noise Q of the stage it starts and its root L (L Lᵀ = Q; None at the last node), its
    readings (sensor, y, dt), its f, F (None: to evaluate), the pulses since they
    were evaluated at the guess (0: exact; more: f moved to the guess to first order) and
    the stage's second-order terms (mean shift, spread; None without ``second_order``)."""

    t: float
    s: np.ndarray
    u: np.ndarray | None = None
    noise: np.ndarray | None = None
    noise_root: np.ndarray | None = None
    readings: list[tuple[str, np.ndarray, float]] = field(default_factory=list)
    linear: tuple[np.ndarray, np.ndarray] | None = None
    age: int = 0
    curvature: tuple[np.ndarray, np.ndarray] | None = None


class MovingHorizonEstimator:
    """A moving-horizon estimator (module docstring) on any :class:`EstimationModel`.

    It meets the :class:`~lightcraft_opt.control.estimation.Estimator` protocol. The
    model's optional ``start(x0) -> s0`` and ``parts(s) -> (z, x, slow)`` (model.py) map
    a full state to s and s to what an :class:`Estimate` holds; without them s0 = x0 and
    z = x = s, no slow states. The estimate's covariance is that of s.

    Parameters
    ----------
    model : the discrete model (predictions, noises, measurements, with Jacobians).
    options : :class:`MheOptions`.

    Attributes
    ----------
    name : "mhe".
    last : :class:`MheStats` of the last step.
    qp : the compiled QP Function (``mhe_qp``), built once.
    innovations : the :class:`Innovation` of each reading of the latest step taken at its
        newest node (in time: y - h at the node's prediction, S = H P⁻ Hᵀ + R with P⁻ the
        last covariance predicted, the EKF's on a linear model); a late reading, fitted
        at an older node, has none.
    """

    name = "mhe"

    def __init__(self, model: EstimationModel, options: MheOptions | None = None) -> None:
        self.model = model
        self.options = options if options is not None else MheOptions()
        self.n = n = len(model.names)
        self.prior = self.options.prior_covariance(model.names)
        self._curved = curvature_entries(
            model, self.options.second_order, "MheOptions.second_order"
        )
        N = self.options.horizon
        self.qp = mhe_qp_function(n, N, self.options.max_iter, self.options.tol)
        n_w, n_a = mhe_qp_sizes(n, N)
        # the QP's inputs and outputs, filled in place and handed over without copies:
        # each (n, n) block is stored transposed, which is casadi's column-major order
        self._A, self._B = np.zeros((N, n, n)), np.zeros((N, n, n))
        self._d, self._H, self._g = np.zeros(N * n), np.zeros((N + 1, n, n)), np.zeros(n_w)
        self._w, self._cost = np.zeros(n_w), np.zeros(1)
        self._lam_x, self._lam_a = np.zeros(n_w), np.zeros(n_a)
        self._buffer, self._eval = self.qp.buffer()
        for i, a in enumerate((self._A, self._B, self._d, self._H, self._g)):
            self._buffer.set_arg(i, a.data.cast("B"))
        for i, a in enumerate((self._w, self._cost, self._lam_x, self._lam_a)):
            self._buffer.set_res(i, a.data.cast("B"))
        self._noise: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._eye = np.eye(n)
        self._nodes: list[_Node] = []
        self._pending: list[Reading] = []
        self._t_left = -math.inf
        self._mean = np.zeros(n)
        self._cov = self.prior.copy()
        self._last_cov = self.prior.copy()  # the covariance last returned
        self.last = MheStats(QpStatus.SOLVED)
        self.innovations: list[Innovation] = []

    # ----------------------------------------------------------------- the protocol
    def reset(self, x0: np.ndarray, t0: float = 0.0) -> None:
        """Start a flight at time ``t0`` [s] from the full state ``x0`` (the model's
        ``start`` maps it to s) as the prior mean, with the options' prior covariance."""
        start = getattr(self.model, "start", None)
        s0 = np.asarray(start(x0) if start is not None else x0, dtype=float).ravel()
        self._mean = checked_vector("x0", s0, self.n)
        self._cov = self.prior.copy()
        self._last_cov = self.prior.copy()
        self._nodes = [_Node(float(t0), self._mean.copy())]
        self._pending, self._t_left = [], -math.inf
        self.last = MheStats(QpStatus.SOLVED, nodes=1)
        self.innovations = []

    def step(
        self,
        readings: Sequence[Reading],
        u_fired: np.ndarray | None,
        t: float,
        *,
        fault: ControllerFault | None = None,
    ) -> Estimate:
        """The estimate at pulse time ``t`` [s].

        ``readings``: those that arrived since the last step (any latency); ``u_fired``:
        the input fired at the last pulse, which adds a node at ``t``; None (the first
        step of a flight) adds none, ``t`` must then be the last node's time. ``fault``
        injects a QP failure (RAISE, NON_FINITE; closed_loop.py). Never raises for a
        failed QP: the step falls back to the prediction and says so in :attr:`last`.
        """
        clock = time.perf_counter()
        if not self._nodes:
            raise ParameterError("x0", "reset(x0, t0) the estimator before its first step")
        if u_fired is None:
            if abs(t - self._nodes[-1].t) > _SAME_TIME:
                raise ParameterError(
                    "u_fired", f"None adds no node: t = {t} must be the last node's time"
                )
        else:
            self._add_node(np.asarray(u_fired, dtype=float), float(t))
        queue, self._pending = [*self._pending, *readings], []
        newest = self._nodes[-1]
        dropped, in_time = 0, []
        for reading in queue:
            before = len(newest.readings)
            dropped += not self._place(reading)
            if len(newest.readings) > before:
                in_time.append(reading)
        self.innovations = self._innovations(newest, in_time)
        if len(self._nodes) > self.options.horizon + 1:
            self._move_arrival_cost()
        status, message, iterations, solve_time, cov = self._iterate(fault)
        self._last_cov = cov
        s = self._nodes[-1].s
        fallback = status is not QpStatus.SOLVED
        parts = getattr(self.model, "parts", None)
        z, x, slow = parts(s) if parts is not None else (s.copy(), s.copy(), {})
        seconds = time.perf_counter() - clock
        self.last = MheStats(
            status,
            message,
            fallback,
            iterations,
            solve_time,
            seconds,
            len(self._nodes),
            sum(len(node.readings) for node in self._nodes),
            dropped,
        )
        return Estimate(float(t), np.asarray(z), np.asarray(x), cov, dict(slow), seconds)

    # ----------------------------------------------------------------- the window
    def _add_node(self, u: np.ndarray, t: float) -> None:
        """Shift: a node at ``t``, its guess predicted from the last (held at the last
        when the prediction is not finite: the step then falls back)."""
        last = self._nodes[-1]
        last.u = u
        f, F = self._linearise(last, self._last_cov)
        finite = bool(np.all(np.isfinite(f)) and np.all(np.isfinite(F)))
        last.linear = (f, F) if finite else None
        self._nodes.append(_Node(t, f.copy() if finite else last.s.copy()))

    def _move_arrival_cost(self) -> None:
        """Drop the first node; the arrival cost moves to the next one by one EKF step
        linearised at the node's solution ŝ: the update with its readings, then the
        prediction (s̄ ← f(ŝ) + F (s̄⁺ - ŝ), P̄ ← F P̄⁺ Fᵀ + Q). Should the model give
        no finite answer there, the new first node's guess becomes s̄ and P̄ grows by Q:
        a bad pulse never poisons the arrival cost."""
        node = self._nodes.pop(0)
        s_hat, mean, P = node.s, self._mean, self._cov
        for sensor, y, dt in node.readings:
            h, Hm = self._measure(sensor, s_hat, dt)
            R = self._noise_of(sensor)[0]
            mean, P, _ = joseph_update(mean, P, y - h - Hm @ (mean - s_hat), Hm, R)
        assert node.u is not None
        if node.linear is not None and node.age == 0:
            f, F = node.linear
        else:
            f, F = self._linearise(node, P)
        assert node.noise is not None
        mean, P = f + F @ (mean - s_hat), symmetric(F @ P @ F.T + node.noise)
        if np.all(np.isfinite(mean)) and np.all(np.isfinite(P)):
            self._mean, self._cov = mean, P
        else:
            grown = self._cov + node.noise
            self._mean = self._nodes[0].s.copy()
            self._cov = grown if np.all(np.isfinite(grown)) else self._cov
        self._t_left = node.t

    def _innovations(self, node: _Node, readings: list[Reading]) -> list[Innovation]:
        """The innovations of ``readings``, just placed at the newest ``node``, against
        its prediction: P⁻ = F P Fᵀ + Q of the stage into it from the covariance last
        returned (the prior at a flight's first node)."""
        if not readings:
            return []
        P = self._cov
        if len(self._nodes) > 1:
            stage = self._nodes[-2]
            if stage.linear is None or stage.noise is None:
                return []  # no finite prediction: the step falls back
            F = stage.linear[1]
            P = symmetric(F @ self._last_cov @ F.T + stage.noise)
        out = []
        for reading, (sensor, y, dt) in zip(readings, node.readings[-len(readings) :], strict=True):
            h, Hm = self._measure(sensor, node.s, dt)
            S = symmetric(Hm @ P @ Hm.T + self._noise_of(sensor)[0])
            out.append(Innovation(reading, y - h, S))
        return out

    def _place(self, reading: Reading) -> bool:
        """Put a reading at the node its time belongs to (the first node at or after
        it); one taken after the last node waits. False: not usable (dropped)."""
        y = np.asarray(reading.y, dtype=float).ravel()
        if reading.t <= self._t_left + _SAME_TIME or not np.all(np.isfinite(y)):
            return False
        for node in self._nodes:
            if reading.t <= node.t + _SAME_TIME:
                node.readings.append((reading.sensor, y, max(0.0, node.t - reading.t)))
                return True
        self._pending.append(reading)
        return True

    # ----------------------------------------------------------------- one iteration
    def _iterate(
        self, fault: ControllerFault | None
    ) -> tuple[QpStatus, str, int, float, np.ndarray]:
        """Linearise at the guess, solve the QP, move the guess; (status, message,
        iterations, solve time, covariance of the last node)."""
        nodes, N, n = self._nodes, self.options.horizon, self.n
        m = len(nodes) - 1
        pad = N - m  # stages before the first node: s held still (F = I, no noise)
        A, B, d, H, g = self._A, self._B, self._d, self._H, self._g
        A[:pad], B[:pad], d[: pad * n], g[:] = self._eye, 0.0, 0.0, 0.0
        H[:] = 0.0
        info = symmetric(np.linalg.inv(self._cov))
        H[0] = info
        g[:n] = info @ (nodes[0].s - self._mean)
        cov_pred, cov = self._cov, self._cov
        fresh = set(self._to_relinearize())
        linear = self._linearised_readings()
        for i, node in enumerate(nodes):
            j = pad + i
            if node.readings:
                # the readings' Gauss-Newton terms: Hᵀ R⁻¹ H and -Hᵀ R⁻¹ (y - h)
                information, gradient = np.zeros((n, n)), np.zeros(n)
                for r, (sensor, y, _) in enumerate(node.readings):
                    h, Hm = linear[i, r]
                    weighted = Hm.T @ self._noise_of(sensor)[1]
                    information += weighted @ Hm
                    gradient -= weighted @ (y - h)
                H[j] += information
                g[2 * n * j : 2 * n * j + n] += gradient
                # the Kalman update in information form: P⁺ = (P⁻¹ + Hᵀ R⁻¹ H)⁻¹
                cov = symmetric(np.linalg.solve(self._eye + cov @ information, cov))
            if i == m:
                break
            if i in fresh:  # at the node's filtered covariance, for the curvature's terms
                node.linear, node.age = self._linearise(node, cov), 0
            assert node.linear is not None
            f, F = node.linear
            assert node.noise_root is not None and node.noise is not None
            A[j], B[j] = F.T, node.noise_root.T
            d[j * n : (j + 1) * n] = f - nodes[i + 1].s
            cov_pred = symmetric(F @ cov @ F.T + node.noise)
            cov = cov_pred
        if not all(np.all(np.isfinite(v)) for v in (A, B, d, H, g, cov_pred)):
            for node in nodes:
                node.linear = None
            return QpStatus.NON_FINITE, "non-finite linearisation", 0, 0.0, self._last_cov
        clock = time.perf_counter()
        if fault is ControllerFault.RAISE:
            status, message, iterations = QpStatus.FAILED, "injected solver failure", 0
        else:
            status, message, iterations = self._solve()
        solve_time = time.perf_counter() - clock
        if fault is ControllerFault.NON_FINITE or not np.all(np.isfinite(self._w)):
            status, message = QpStatus.NON_FINITE, f"{message}; the answer is not finite"
        if status is not QpStatus.SOLVED:
            return status, message, iterations, solve_time, cov_pred
        for i, node in enumerate(nodes):
            k = 2 * n * (pad + i)
            delta = self._w[k : k + n]
            node.s = node.s + delta
            if node.linear is not None:
                f, F = node.linear
                node.linear, node.age = (f + F @ delta, F), node.age + 1
        return status, message, iterations, solve_time, cov

    def _to_relinearize(self) -> list[int]:
        """The stages whose f, F are evaluated afresh this pulse: those without any, and
        of those moved to first order, the ``relinearize`` evaluated longest ago (the
        newest first among equals); all of them when ``relinearize`` is None."""
        stages = self._nodes[:-1]
        missing = [i for i, node in enumerate(stages) if node.linear is None]
        moved = [i for i, node in enumerate(stages) if node.linear is not None and node.age]
        budget = self.options.relinearize
        if budget is None:
            return missing + moved
        moved.sort(key=lambda i: (-stages[i].age, -i))
        return missing + moved[: max(0, budget - len(missing))]

    def _solve(self) -> tuple[QpStatus, str, int]:
        """One call of the compiled QP on the filled inputs: (status, message, iterations)."""
        try:
            self._eval()
        except RuntimeError as err:
            return QpStatus.FAILED, str(err), 0
        stats = self._buffer.stats()
        raw = str(stats.get("return_status", "unknown"))
        iterations = int(stats.get("iter_count", -1))
        if self._buffer.ret() == 0 and stats.get("success", False):
            return QpStatus.SOLVED, f"hpipm: {raw}", iterations
        if iterations >= self.options.max_iter:
            return QpStatus.MAX_ITER, f"hpipm: {raw} (iteration cap)", iterations
        return QpStatus.FAILED, f"hpipm: {raw}", iterations

    # ----------------------------------------------------------------- the model
    def _linearise(self, node: _Node, cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(f, F) of the stage ``node`` starts, at its guess. When the stage joins, its noise
        (Q and its root, on the node) is set and, with ``second_order`` entries, the
        second-order terms over ``cov`` (the node's filtered covariance then) are kept on
        it: f gains the mean's at every evaluation, the noise their spread."""
        assert node.u is not None
        f, F = self._predict(node.s, node.u, node.t)
        if self._curved and node.curvature is None and np.all(np.isfinite(f)):
            node.curvature = second_order_terms(
                self.model, node.s, f, cov, node.u, node.t, self._curved
            )
        if node.noise is None:
            Q = np.asarray(self.model.process_noise(node.s, node.u, node.t), dtype=float)
            if node.curvature is not None:
                Q = Q + node.curvature[1]
            node.noise_root = _root(Q)
            node.noise = node.noise_root @ node.noise_root.T
        if node.curvature is not None:
            f = f + node.curvature[0]
        return f, F

    def _predict(self, s: np.ndarray, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        f, F = self.model.predict(s, u, t)
        return np.asarray(f, dtype=float).ravel(), np.asarray(F, dtype=float)

    def _measure(self, sensor: str, s: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        h, Hm = self.model.measure(sensor, s, dt)
        return np.asarray(h, dtype=float).ravel(), np.atleast_2d(np.asarray(Hm, dtype=float))

    def _linearised_readings(self) -> dict[tuple[int, int], tuple[np.ndarray, np.ndarray]]:
        """{(node, reading): (h, H)} of every reading of the window at its node's guess:
        by the model's ``measure_many``, one call a sensor, where it has one (model.py),
        else by ``measure`` a reading."""
        nodes = self._nodes
        many = getattr(self.model, "measure_many", None)
        if many is None:
            return {
                (i, r): self._measure(sensor, node.s, dt)
                for i, node in enumerate(nodes)
                for r, (sensor, _, dt) in enumerate(node.readings)
            }
        by_sensor: dict[str, list[tuple[int, int]]] = {}
        for i, node in enumerate(nodes):
            for r, (sensor, _, _) in enumerate(node.readings):
                by_sensor.setdefault(sensor, []).append((i, r))
        linear = {}
        for sensor, keys in by_sensor.items():
            S = np.array([nodes[i].s for i, _ in keys])
            dts = np.array([nodes[i].readings[r][2] for i, r in keys])
            ys, Hs = many(sensor, S, dts)
            for key, h, Hm in zip(keys, ys, Hs, strict=True):
                linear[key] = (np.asarray(h, dtype=float).ravel(), np.atleast_2d(Hm))
        return linear

    def _noise_of(self, sensor: str) -> tuple[np.ndarray, np.ndarray]:
        """(R, R⁻¹) of a sensor, asked of the model once."""
        if sensor not in self._noise:
            R = np.atleast_2d(np.asarray(self.model.measurement_noise(sensor), dtype=float))
            self._noise[sensor] = (R, np.linalg.inv(R))
        return self._noise[sensor]


# --------------------------------------------------------------------------- linear algebra
def _root(Q: np.ndarray) -> np.ndarray:
    """L with L Lᵀ = Q for a symmetric positive semidefinite Q (its eigen-decomposition;
    the columns of zero eigenvalues are zero); NaN for a Q that is not finite."""
    if not np.all(np.isfinite(Q)):
        return np.full(Q.shape, np.nan)
    lam, V = np.linalg.eigh(symmetric(Q))
    return V * np.sqrt(np.clip(lam, 0.0, None))
