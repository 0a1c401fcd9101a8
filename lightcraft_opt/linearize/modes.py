"""Pulse-to-pulse multipliers of a linear model, their modes, and controllability.

The eigenvalues of A (:mod:`.state_space`) are the pulse-to-pulse multipliers (Floquet
multipliers of the hybrid flow): |λ| > 1 grows by |λ| a pulse.

Modes (:class:`ModeKind`) are classified by participation factors (Pérez-Arriaga,
Verghese & Schweppe 1982, IEEE Trans. PAS 101(9); docs/references.md#perez-arriaga-1982):
p_ki = |l_ki r_ki|, dimensionless, grouped by the states of each kind; a mode belongs to the
group with the largest share. The beam-riding modes load the lateral offset, lateral velocity
and tilt; the coning (nutation) modes the transverse rates w_B[b2, b3] (216 Hz for Flight 5,
aliased at the 26 Hz pulse rate).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import control
import numpy as np

from lightcraft_opt.errors import ParameterError


class ModeKind(Enum):
    """Which states a pulse-to-pulse mode loads (participation factors)."""

    BEAM_RIDING = "beam_riding"  # lateral offset, lateral velocity, tilt
    CONING = "coning"  # transverse angular velocity w_B[b2, b3] (nutation)
    VERTICAL = "vertical"  # altitude and vertical speed
    AXIAL = "axial"  # spin, turn about b1 and its gauge w_B[b1]
    CONSUMABLE = "consumable"  # liner_mass, rcs_mass, pulses


_KIND_OF_SLOT = {
    "r_L": ModeKind.BEAM_RIDING,
    "v_L": ModeKind.BEAM_RIDING,
    "theta_B": ModeKind.BEAM_RIDING,
    "q_LB": ModeKind.BEAM_RIDING,
    "w_B": ModeKind.CONING,
    "spin": ModeKind.AXIAL,
    "liner_mass": ModeKind.CONSUMABLE,
    "rcs_mass": ModeKind.CONSUMABLE,
    "engine_load": ModeKind.CONSUMABLE,
}


def _kind_of(name: str) -> ModeKind:
    slot, _, comp = name.partition("[")
    if slot not in _KIND_OF_SLOT:
        raise ParameterError("sys", f"state {name!r} is not a state of linearize()'s models")
    if comp.startswith("up") and slot in ("r_L", "v_L"):
        return ModeKind.VERTICAL
    if comp.startswith("b1") and slot in ("theta_B", "w_B"):
        return ModeKind.AXIAL
    return _KIND_OF_SLOT[slot]


@dataclass(frozen=True)
class Multipliers:
    """Pulse-to-pulse multipliers (eigenvalues of A) and what each mode loads.

    Attributes
    ----------
    values : (n,) complex multipliers, largest |λ| first.
    participation : (n, n_states) participation factors |l_ki r_ki| of mode i in state
        k, each row summing to 1 (dimensionless, independent of the state units).
    kinds : (n,) the kind of each mode: the state group with the largest share.
    states : names of the states (columns of ``participation``).
    dt : pulse period [s].
    """

    values: np.ndarray
    participation: np.ndarray
    kinds: tuple[ModeKind, ...]
    states: tuple[str, ...]
    dt: float

    @property
    def magnitude(self) -> np.ndarray:
        """(n,) |λ|: growth factor per pulse [-]."""
        return np.abs(self.values)

    @property
    def growth_rate(self) -> np.ndarray:
        """(n,) ln|λ| / T: growth rate [1/s] (negative: decays)."""
        with np.errstate(divide="ignore"):
            return np.log(self.magnitude) / self.dt

    @property
    def angle(self) -> np.ndarray:
        """(n,) arg λ [rad per pulse]: a mode at ω appears at ω T, aliased into (-π, π]."""
        return np.angle(self.values)

    def of_kind(self, *kinds: ModeKind) -> Multipliers:
        """The modes of the given kinds only."""
        sel = [i for i, k in enumerate(self.kinds) if k in kinds]
        return Multipliers(
            self.values[sel],
            self.participation[sel],
            tuple(self.kinds[i] for i in sel),
            self.states,
            self.dt,
        )

    def largest(self) -> float:
        """max |λ| (NaN when there is no mode)."""
        return float(np.max(self.magnitude)) if self.values.size else float("nan")

    def __str__(self) -> str:
        """A table, one row per mode, largest |λ| first: |λ|, its angle per pulse [deg],
        the growth rate [1/s], the kind and the state it loads most (its share)."""
        rows = [
            f"{'mode':>4}  {'|λ|':>8}  {'angle':>8}  {'growth':>9}  {'kind':<11}  most in",
            f"{'':>4}  {'':>8}  {'deg':>8}  {'1/s':>9}  {'':<11}",
        ]
        for i in range(self.values.size):
            top = int(np.argmax(self.participation[i]))
            rows.append(
                f"{i:>4}  {self.magnitude[i]:>8.5f}  {np.degrees(self.angle[i]):>8.2f}  "
                f"{self.growth_rate[i]:>9.3g}  {self.kinds[i].value:<11}  "
                f"{self.states[top]} ({self.participation[i, top]:.0%})"
            )
        return "\n".join(rows)


def state_space_matrices(sys: control.StateSpace) -> tuple[np.ndarray, np.ndarray]:
    """(A (n, n), B (n, m)) of ``sys`` as float arrays."""
    return np.asarray(sys.A, dtype=float), np.asarray(sys.B, dtype=float)


def multipliers(sys: control.StateSpace) -> Multipliers:
    """Eigenvalues of ``sys.A`` with participation factors and a kind per mode.

    ``sys`` is a model from :func:`linearize` (its state names say which kind each state
    is). For a defective A (repeated neutral multipliers, e.g. the consumables of a
    ``FULL`` model), where left eigenvectors are ill-defined, the participation falls
    back to |r_ki|^2 of the unit right eigenvector.
    """
    A, _ = state_space_matrices(sys)
    values, V = np.linalg.eig(A)
    order = np.argsort(-np.abs(values), kind="stable")
    values, V = values[order], V[:, order]
    W = np.linalg.inv(V) if np.linalg.cond(V) < 1e10 else None
    P = np.abs(V * W.T) if W is not None else np.abs(V) ** 2
    P = P / np.maximum(P.sum(axis=0), np.finfo(float).tiny)
    states = tuple(sys.state_labels)
    kinds_of_state = [_kind_of(s) for s in states]
    kinds: list[ModeKind] = []
    for i in range(values.size):
        share = {
            k: P[[j for j, ks in enumerate(kinds_of_state) if ks is k], i].sum() for k in ModeKind
        }
        kinds.append(max(share, key=lambda k: share[k]))
    return Multipliers(values, P.T.copy(), tuple(kinds), states, float(sys.dt))


def beam_riding_modes(sys: control.StateSpace) -> Multipliers:
    """The multipliers of the modes that load lateral offset, lateral velocity and tilt
    (:attr:`ModeKind.BEAM_RIDING`), largest first."""
    return multipliers(sys).of_kind(ModeKind.BEAM_RIDING)


@dataclass(frozen=True)
class Controllability:
    """Which states the inputs of a discrete linear model reach.

    Attributes
    ----------
    rank : numerical rank of the controllability matrix [B, AB, ..., A^(n-1) B].
    singular_values : (n,) of that matrix, block columns scaled to unit norm.
    uncontrollable : (n, n - rank) orthonormal directions the inputs never reach.
    modes : the uncontrollable multipliers: eigenvalues of A on the uncontrollable
        directions (Kalman decomposition, A = [[A_c, *], [0, A_u]] in the basis
        [controllable, uncontrollable]).
    states : state names (rows of ``uncontrollable``).
    """

    rank: int
    singular_values: np.ndarray
    uncontrollable: np.ndarray
    modes: np.ndarray
    states: tuple[str, ...]

    @property
    def controllable(self) -> bool:
        return self.rank == len(self.states)

    @property
    def stabilisable(self) -> bool:
        """Every uncontrollable multiplier lies strictly inside the unit circle."""
        return bool(np.all(np.abs(self.modes) < 1.0))

    def describe(self) -> str:
        """The uncontrollable directions in words: largest state loadings of each."""
        parts = []
        for d in self.uncontrollable.T:
            top = np.argsort(-np.abs(d))[:3]
            parts.append(
                " + ".join(f"{d[j]:.2f} {self.states[j]}" for j in top if abs(d[j]) > 0.05)
            )
        return "; ".join(parts) or "none"


def controllability(sys: control.StateSpace, *, tol: float = 1e-9) -> Controllability:
    """Rank of the controllability matrix and the uncontrollable directions and modes.

    Parameters
    ----------
    tol : relative tolerance: a singular value below ``tol`` times the largest counts as
        zero.

    The numbers depend on the state units (SI here); the block columns A^k B are
    scaled to unit norm so that slowly growing powers do not swamp the rank test.
    Couplings weaker than ``tol`` count as none: e.g. pointing reaches the altitude of a
    hovering craft only through the Coriolis term 2 Ω × v of the lateral velocity it
    makes, ~1e-9 of its lateral reach, so at the default tolerance r_L[up], v_L[up] are
    uncontrollable without the energy input.
    """
    A, B = state_space_matrices(sys)
    n = A.shape[0]
    blocks, Ak_B = [], B
    for _ in range(n):
        norm = np.linalg.norm(Ak_B)
        blocks.append(Ak_B / norm if norm > 0 else Ak_B)
        Ak_B = A @ Ak_B
    U, s, _ = np.linalg.svd(np.hstack(blocks))
    s = np.concatenate([s, np.zeros(max(0, n - s.size))])[:n]
    rank = int(np.sum(s > tol * s[0])) if s[0] > 0 else 0
    Uu = U[:, rank:]
    modes = np.linalg.eigvals(Uu.T @ A @ Uu) if rank < n else np.empty(0, complex)
    return Controllability(rank, s, Uu, modes.astype(complex), tuple(sys.state_labels))
