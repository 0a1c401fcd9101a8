"""Where a cold solve starts: a flight of the problem's own model and inputs.

Multiple shooting starts from states and inputs at every node. A start whose nodes are a
flight of the problem's own map Φ under inputs the problem allows has closed dynamics
gaps, so the solver begins on the dynamics' manifold and only has to improve it:

- **the director** (control/director.py, docs/director.md), where it applies: the beam's
  pointing is free and the laser is the one it can steer, the waist size model (the focus
  an input). It flies Φ pulse by pulse in closed loop from x0, every input the problem
  holds at its value, every free one clipped to its bounds and slew limits; the RCS off
  (held at the problem's values). Under the linear beam model the director loses Flight 5
  above 30 m (docs/director.md), so it does not apply there.
- **the nominal rollout** otherwise (solve.rollout): the beam under the craft, the
  flight's pulse energy, rolled forward through Φ.

Each comes back as a :class:`Start` that says which it is and how it flew (status, the
highest altitude, the largest drift from the pad), for the result's message. A start that
flew (``Start.flown``) is handed to IPOPT as a near-feasible point: its barrier parameter
starts small and the bounds push it barely (CompiledOcp), since IPOPT's default first
iterations (barrier 0.1, bounds pushed 1 %) throw such a start away (measured on
problems/beam_tracking_focus.toml: the violation rose from 0.05 to 25 in one step and the
solve never recovered; docs/ocp.md).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from enum import Enum

import numpy as np

from lightcraft_opt.layout import STATE
from lightcraft_opt.ocp.problem import OcpProblem
from lightcraft_opt.params import BeamSizeModel
from lightcraft_opt.symbolic.pulse_map import PulseMap

__all__ = ["Start", "StartKind", "director_applies", "director_start"]


class StartKind(Enum):
    """How the nodes of a cold start were made."""

    DIRECTOR = "director"  # the director's closed-loop flight through Φ
    ROLLOUT = "rollout"  # the nominal policy rolled through Φ
    GIVEN = "given"  # the caller's initial guess


@dataclass(frozen=True)
class Start:
    """A cold start of multiple shooting.

    Attributes
    ----------
    kind : how it was made.
    X : (N + 1, STATE.size) states at the nodes (docs/frames.md).
    U : (N, map-input size) inputs, one row per pulse.
    seconds : wall time to make it [s].
    """

    kind: StartKind
    X: np.ndarray
    U: np.ndarray
    seconds: float = 0.0

    @property
    def flown(self) -> bool:
        """Whether the nodes are a closed-loop flight (gaps closed, inputs allowed)."""
        return self.kind is StartKind.DIRECTOR

    def describe(self) -> str:
        """One line: how it was made and how it flew (altitude, drift from the pad)."""
        r = self.X[:, STATE.index("r_L")]
        drift = float(np.max(np.hypot(r[:, 0], r[:, 1])))
        return (
            f"started from the {self.kind.value}'s flight: highest {float(r[:, 2].max()):.1f} m, "
            f"drift at most {100 * drift:.1f} cm ({self.seconds:.1f} s)"
        )


def director_applies(problem: OcpProblem) -> bool:
    """Whether the director can fly ``problem`` (module docstring): pointing free, the
    waist beam, map inputs that start with the pulse input."""
    lay = problem.inputs
    if lay.names[:3] != ("pointing_L", "focus", "energy"):
        return False
    pointing_free = bool(np.any(problem.free[lay.index("pointing_L")]))
    return pointing_free and problem.model.laser.size_model is BeamSizeModel.WAIST


def director_start(
    problem: OcpProblem, phi: PulseMap, x0: np.ndarray, p: np.ndarray, t0: float
) -> Start:
    """The director's closed-loop flight of ``problem`` through ``phi`` (module docstring).

    Parameters
    ----------
    problem : bounds, held inputs, slew limits, horizon and model.
    phi : the problem's pulse map (the OCP's own prediction, so the start's gaps close).
    x0 : (STATE.size,) state at the first pulse; p : (PARAMETERS.size,) parameters (the
        director is told the same wind); t0 : first pulse time [s].
    """
    # imported here: the director's QP and Ψ load python-control's neighbours, which
    # `import lightcraft_opt` must not (tests/test_public_api.py)
    from lightcraft_opt.control.director import DirectorController
    from lightcraft_opt.control.options import DirectorOptions, DirectorRcs

    start = time.perf_counter()
    lay, N = problem.inputs, problem.horizon
    e = lay.index("energy")
    energy = problem.model.flight.pulse_energy
    low = float(np.min(problem.lower[e])) / energy
    high = float(np.max(problem.upper[e])) / energy
    options = DirectorOptions(
        energy_range=(max(low, 0.0), max(high, low, 0.0)), rcs=DirectorRcs.OFF, time_budget=None
    )
    director = DirectorController(problem.model, lay, options, p=p)
    held = ~problem.free
    x = np.asarray(x0, dtype=float)
    X, U = [x], []
    u_last = None if problem.u_previous is None else np.asarray(problem.u_previous, dtype=float)
    for k in range(N):
        t = t0 + k * phi.period
        u = np.array(director.step(x, t), dtype=float)
        u[held] = problem.lower[held]
        if u_last is not None:
            u = np.clip(u, u_last - problem.slew, u_last + problem.slew)
        u = np.clip(u, problem.lower, problem.upper)
        x_next = np.asarray(phi.step(x, u, p, t)[0], dtype=float).ravel()
        x = x_next if np.all(np.isfinite(x_next)) else x
        X.append(x)
        U.append(u)
        u_last = u
    return Start(
        StartKind.DIRECTOR,
        np.array(X),
        np.array(U).reshape(N, lay.size),
        time.perf_counter() - start,
    )
