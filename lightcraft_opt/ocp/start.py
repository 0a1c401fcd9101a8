"""Where a cold solve starts: a flight of the problem's own model and inputs.

Multiple shooting starts from states and inputs at every node. A start whose nodes are a
flight of the problem's own map Φ under inputs the problem allows has closed dynamics
gaps, so the solver begins on the dynamics' manifold and only has to improve it:

- **the director** (control/director.py, docs/director.md), where it applies: the beam's
  pointing is free and the laser is the one it can steer, the waist size model (the focus
  an input). It flies Φ pulse by pulse in closed loop from x0, every input the problem
  holds at its value, every free one clipped to its bounds and slew limits; the RCS off
  (held at the problem's values). Under the linear beam model the director loses Flight 5
  above 30 m (docs/director.md), so it does not apply there. Where the director loses
  the craft in the problem's wind (beam_tracking_focus.toml over 260 pulses, 10 s: in its
  3 m/s crosswind the director loses the craft at 6.3 s, 66 m), its flight in calm air,
  whose gaps in the wind are again what the wind does over one pulse.
- **the nominal rollout** otherwise (:func:`rollout`): the beam under the craft, the
  flight's pulse energy, rolled forward through Φ in the problem's wind.
- **the nominal rollout in calm air**, where the problem's wind blows the nominal rollout
  out of the beam (the optic catches no light, so Φ has no gradient to follow back). The
  calm flight's gaps are closed in calm air; in the problem's wind each node's gap is what
  the wind does over one pulse (in problem (a)'s 3 m/s crosswind, climbing: up to 1 cm
  and 0.5 m/s, where the whole flight drifts metres), so it is near-feasible.

Each comes back as a :class:`Start` that says which it is and how it flew (the highest
altitude, the largest drift from the pad), for the result's message. A near-feasible start
(``Start.flown``: the director's or the calm flight) is handed to IPOPT as a warm start:
its barrier parameter starts small and the bounds push it barely (CompiledOcp), since
IPOPT's default first iterations (barrier 0.1, bounds pushed 1 %) throw such a start away
(on problems/beam_tracking_focus.toml the violation rose from 0.05 to 25 in one step and
the solve never recovered; on problems/crosswind_climb.toml from the calm flight it took
far more iterations and time; docs/ocp.md, figures:
bench/README.md#after-issue-27-shared-evaluation-flown-starts-two-hessians-2026-12-03).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import cast

import numpy as np

from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.options import DirectorOptions, DirectorRcs
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import ENGINE, PARAMETERS, STATE
from lightcraft_opt.model import BeamSizeModel
from lightcraft_opt.ocp.problem import OcpProblem
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = [
    "CONVEXIFIED_FIRST",
    "Guess",
    "Start",
    "StartKind",
    "director_applies",
    "director_start",
    "flown_on",
    "flown_start",
    "guessed_nodes",
    "nominal_start",
    "rollout",
    "scenario_start",
    "wind_scaled",
]


class StartKind(Enum):
    """How the nodes of a cold start were made."""

    DIRECTOR = "director"  # the director's closed-loop flight through Φ
    DIRECTOR_CALM = "director_calm"  # the same in calm air
    ROLLOUT = "rollout"  # the nominal policy rolled through Φ
    CALM = "calm"  # the nominal policy rolled through Φ in calm air
    GIVEN = "given"  # the caller's initial guess
    HELD_DESIGN = "held_design"  # the design problem solved with its design held
    GROWN = "grown"  # the problem solved over shorter horizons, then flown on (grown_start.py)


#: The starts a cold solve leaves with the convexified Hessian first (OcpOptions.
#: convex_iterations): the director's flights, and a design problem's held optimum
#: (problems/design_flight5.toml: 159 iterations, 57 s, against 551, 344 s, without).
CONVEXIFIED_FIRST = frozenset(
    {StartKind.DIRECTOR, StartKind.DIRECTOR_CALM, StartKind.HELD_DESIGN, StartKind.GROWN}
)


@dataclass(frozen=True)
class Start:
    """A cold start of multiple shooting.

    Attributes
    ----------
    kind : how it was made.
    X : (N + 1, STATE.size) states at the nodes (docs/frames.md).
    U : (N, map-input size) inputs, one row per pulse.
    seconds : wall time to make it [s].
    iterations : the solver's iterations that made it (HELD_DESIGN), else 0.
    instead : why the start the options asked for (a held design's optimum, a grown one)
        was not made and this one was, or "" when it is the start asked for.
    """

    kind: StartKind
    X: np.ndarray
    U: np.ndarray
    seconds: float = 0.0
    iterations: int = 0
    instead: str = ""

    @property
    def flown(self) -> bool:
        """Whether the nodes are a flight that stayed in the beam under inputs the problem
        allows, near-feasible: the director's, or the nominal one in calm air (module
        docstring), or a shorter horizon's optimum flown on by them (GROWN)."""
        return self.kind in (
            StartKind.DIRECTOR,
            StartKind.DIRECTOR_CALM,
            StartKind.CALM,
            StartKind.GROWN,
        )

    def describe(self) -> str:
        """One line: how it was made and how it flew (altitude, drift from the pad)."""
        r = self.X[:, STATE.index("r_L")]
        drift = float(np.max(np.hypot(r[:, 0], r[:, 1])))
        made = f"{self.iterations} iterations, " if self.iterations else ""
        instead = f" ({self.instead})" if self.instead else ""
        return (
            f"started from {_FLIGHT_NAMES[self.kind]}{instead}: "
            f"highest {float(r[:, 2].max()):.1f} m, "
            f"drift at most {100 * drift:.1f} cm ({made}{self.seconds:.1f} s)"
        )


_FLIGHT_NAMES = {
    StartKind.DIRECTOR: "the director's flight",
    StartKind.DIRECTOR_CALM: "the director's flight in calm air",
    StartKind.ROLLOUT: "the nominal rollout",
    StartKind.CALM: "the nominal flight in calm air",
    StartKind.GIVEN: "the given guess",
    StartKind.HELD_DESIGN: "the problem solved with its design held",
    StartKind.GROWN: "the problem solved over shorter horizons",
}


#: What a caller may give a cold solve as its start: inputs (N, map-input size), nodes
#: (X (N + 1, STATE.size), U), a :class:`Start` made elsewhere (ocp/grown_start.py), or None.
Guess = np.ndarray | tuple[np.ndarray, np.ndarray] | Start | None


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
    """The director's closed-loop flight of ``problem`` through ``phi``, in the problem's
    wind if it stays in the beam there (every pulse catches at least
    :data:`LEFT_BEAM_CAUGHT` of its energy), else in calm air (module docstring).

    Parameters
    ----------
    problem : bounds, held inputs, slew limits, horizon and model.
    phi : the problem's pulse map (the OCP's own prediction, so the start's gaps close).
    x0 : (STATE.size,) state at the first pulse; p : (PARAMETERS.size,) parameters (the
        director is told the same wind); t0 : first pulse time [s].
    """
    start = time.perf_counter()
    X, U, caught = _directed(problem, phi, x0, p, t0)
    calm = _calm_instead(p, caught)
    if calm is None:
        return Start(StartKind.DIRECTOR, X, U, time.perf_counter() - start)
    X, U, _ = _directed(problem, phi, x0, calm, t0)
    return Start(StartKind.DIRECTOR_CALM, X, U, time.perf_counter() - start)


def _directed(
    problem: OcpProblem, phi: PulseMap, x0: np.ndarray, p: np.ndarray, t0: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The director's flight (X, U) of :func:`director_start` in the wind of ``p``, and (N,)
    the fraction of each fired pulse's energy the optic caught (as :func:`_rolled`)."""
    lay, N = problem.inputs, problem.horizon
    e = lay.index("energy")
    energy = problem.model.flight.pulse_energy
    low = float(np.min(problem.lower[e])) / energy
    high = float(np.max(problem.upper[e])) / energy
    options = DirectorOptions(
        energy_range=(max(low, 0.0), max(high, low, 0.0)), rcs=DirectorRcs.OFF, time_budget=None
    )
    # a start flies once per solve, for each problem's p: its step is not worth a compile
    director = DirectorController(problem.model, lay, options, p=p, compile_step=False)
    held = ~problem.free
    x = np.asarray(x0, dtype=float)
    X, U, caught = [x], [], []
    u_last = None if problem.u_previous is None else np.asarray(problem.u_previous, dtype=float)
    for k in range(N):
        t = t0 + k * phi.period
        u = np.array(director.step(x, t), dtype=float)
        u[held] = problem.lower[held]
        if u_last is not None:
            u = np.clip(u, u_last - problem.slew, u_last + problem.slew)
        u = np.clip(u, problem.lower, problem.upper)
        x, share = _stepped(phi, x, u, p, t, float(u[e][0]))
        X.append(x)
        U.append(u)
        caught.append(share)
        u_last = u
    return np.array(X), np.array(U).reshape(N, lay.size), np.array(caught)


def flown_on(
    problem: OcpProblem, phi: PulseMap, X: np.ndarray, U: np.ndarray, p: np.ndarray, t0: float
) -> tuple[np.ndarray, np.ndarray]:
    """The nodes (X (N + 1, STATE.size), frames per docs/frames.md; U (N, map-input size),
    pointing in L) of ``problem`` that begin with a shorter horizon's (``X`` (n + 1,
    STATE.size), ``U`` (n, ...), n < N, from the problem's first pulse time ``t0`` [s])
    and go on from its last state, under the slew
    limits from its last input, flown through ``phi`` in the wind of ``p`` (PARAMETERS.size,)
    by the director where it applies, else by the nominal policy (the gap there is the
    optimum's)."""
    n = U.shape[0]
    rest = dataclasses.replace(problem, horizon=problem.horizon - n, u_previous=U[-1])
    t = t0 + n * phi.period
    if director_applies(problem):
        Xr, Ur, _ = _directed(rest, phi, X[-1], p, t)
    else:
        Xr, Ur, _ = _rolled(rest, phi, None, X[-1], p, t)
    return np.vstack([X, Xr[1:]]), np.vstack([U, Ur])


def nominal_start(
    problem: OcpProblem, phi: PulseMap, x0: np.ndarray, p: np.ndarray, t0: float
) -> Start:
    """The nominal rollout of ``problem`` through ``phi``, in the problem's wind if it stays
    in the beam there (every pulse catches at least :data:`LEFT_BEAM_CAUGHT` of its energy),
    else in calm air (module docstring).

    Parameters
    ----------
    problem, phi : as for :func:`director_start`.
    x0 : (STATE.size,) state at the first pulse; p : (PARAMETERS.size,) parameters;
        t0 : first pulse time [s].
    """
    began = time.perf_counter()
    X, U, caught = _rolled(problem, phi, None, x0, p, t0)
    calm = _calm_instead(p, caught)
    if calm is None:
        return Start(StartKind.ROLLOUT, X, U, time.perf_counter() - began)
    X, U, _ = _rolled(problem, phi, None, x0, calm, t0)
    return Start(StartKind.CALM, X, U, time.perf_counter() - began)


def flown_start(
    problem: OcpProblem,
    flight_map: Callable[[], PulseMap],
    phi: PulseMap,
    x0: np.ndarray,
    p: np.ndarray,
    t0: float,
    instead: str = "",
) -> Start:
    """The "flown" start: :func:`director_start` through ``flight_map()`` where the
    director applies (:func:`director_applies`), else :func:`nominal_start` through ``phi``;
    ``instead`` says why the start the options asked for was not made (:class:`Start`).
    x0 : (STATE.size,) state at the first pulse; p : (PARAMETERS.size,); t0 [s]."""
    if director_applies(problem):
        made = director_start(problem, flight_map(), x0, p, t0)
    else:
        made = nominal_start(problem, phi, x0, p, t0)
    return dataclasses.replace(made, instead=instead)


def rollout(
    problem: OcpProblem,
    phi: PulseMap,
    u: np.ndarray | None = None,
    *,
    x0: np.ndarray | None = None,
    p: np.ndarray | None = None,
    t0: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """States at the nodes when Φ is rolled forward from x0.

    The nominal policy: the flight's pulse energy, focus at the far end, the beam axis under
    the craft's mass centre (pointing_L = the craft's east and north position, L), RCS and
    motor off, moved at most by the slew limits and clipped to the bounds (held inputs at
    their values).

    Parameters
    ----------
    problem : gives the bounds, the nominal input and the defaults of x0, p, t0.
    phi : the pulse map.
    u : (N, map-input size) inputs; None for the nominal policy.
    x0, p, t0 : (STATE.size,) initial state, (PARAMETERS.size,) parameters, first pulse
        time [s], if not the problem's.

    Returns
    -------
    X : (N + 1, STATE.size) states at the nodes; once Φ returns a non-finite state (e.g.
        a craft far outside its model) the last finite one is held.
    U : (N, map-input size) the inputs applied.
    """
    x_start = problem.x0 if x0 is None else x0
    X, U, _ = _rolled(
        problem,
        phi,
        u,
        np.asarray(x_start, dtype=float),
        problem.p if p is None else p,
        problem.t0 if t0 is None else t0,
    )
    return X, U


def _rolled(
    problem: OcpProblem,
    phi: PulseMap,
    u: np.ndarray | None,
    x0: np.ndarray,
    p: np.ndarray,
    t0: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`rollout`'s X and U, and (N,) the fraction of each fired pulse's energy the
    optic caught (1 for a pulse fired with no energy; 0 where Φ returned a non-finite
    state)."""
    N, lay = problem.horizon, problem.inputs
    nominal = problem.nominal_input()
    pointing = lay.index("pointing_L")
    energy = lay.index("energy")
    X, U, caught = [np.asarray(x0, dtype=float)], [], []
    u_last = cast("np.ndarray | None", problem.u_previous)
    for k in range(N):
        if u is None:
            uk = nominal.copy()
            uk[pointing] = STATE.get("r_L", X[-1])[:2]
            if u_last is not None:
                uk = np.clip(uk, u_last - problem.slew, u_last + problem.slew)
            uk = np.clip(uk, problem.lower, problem.upper)
            u_last = uk
        else:
            uk = u[k]
        x, share = _stepped(phi, X[-1], uk, p, t0 + k * phi.period, float(uk[energy][0]))
        X.append(x)
        U.append(uk)
        caught.append(share)
    return np.array(X), np.array(U).reshape(N, lay.size), np.array(caught)


def _stepped(
    phi: PulseMap, x: np.ndarray, u: np.ndarray, p: np.ndarray, t: float, fired: float
) -> tuple[np.ndarray, float]:
    """One pulse of a flown start: Φ's next state (x itself where Φ returned a non-finite
    state) and the fraction of the ``fired`` energy [J] the optic caught (1 for a pulse
    fired with no energy; 0 where Φ's state was not finite)."""
    x_next, engine = (np.asarray(v, dtype=float).ravel() for v in phi.step(x, u, p, t))
    if not np.all(np.isfinite(x_next)):
        return x, 0.0
    return x_next, float(ENGINE.get("energy_captured", engine)) / fired if fired > 0 else 1.0


def _calm_instead(p: np.ndarray, caught: np.ndarray) -> np.ndarray | None:
    """(PARAMETERS.size,) ``p`` in calm air when a flight in ``p``'s wind left the beam (a
    pulse caught under :data:`LEFT_BEAM_CAUGHT` of its energy) and that wind blows at
    all; None when the flight keeps its wind."""
    calm = wind_scaled(p, 0.0)
    if np.array_equal(calm, p) or float(np.min(caught, initial=1.0)) >= LEFT_BEAM_CAUGHT:
        return None
    return calm


#: A rollout has left the beam when a pulse's optic catches less than this fraction of the
#: energy fired: the simulator's left-beam rule (simulation/flight_log.py, under 1 %), where
#: Φ has no gradient to follow back. A rollout that only grazes the edge (problem (c)'s
#: gust: 1.03 of the capture radius, most of the light still caught) keeps its own wind.
LEFT_BEAM_CAUGHT = 0.01

#: Parameter slots that OcpOptions.wind_ramp scales (speeds; directions and profiles stay).
_WIND_SPEEDS = ("wind_speed_ref", "gust_L")


def wind_scaled(p: np.ndarray, factor: float) -> np.ndarray:
    """(PARAMETERS.size,) ``p`` with the wind's reference speed and gust (L) scaled by
    ``factor``."""
    out = np.array(p, dtype=float)
    for name in _WIND_SPEEDS:
        out[PARAMETERS.index(name)] *= factor
    return out


def guessed_nodes(
    problem: OcpProblem,
    pulse_map: PulseMap,
    x0: np.ndarray,
    p: np.ndarray,
    t0: float,
    guess: np.ndarray | tuple[np.ndarray, np.ndarray] | None,
) -> tuple[np.ndarray, np.ndarray]:
    """The nodes (X (N + 1, STATE.size), U (N, map-input size)) of a caller's guess: a
    pair used as is, inputs alone rolled out from x0 (frame per docs/frames.md) through
    ``pulse_map``, or, with none, the nominal rollout. Bad shapes raise a ParameterError
    naming ``initial_guess``."""
    N, nu = problem.horizon, problem.inputs.size
    X: np.ndarray | None = None
    U: np.ndarray | None = None
    if isinstance(guess, tuple):
        X = np.asarray(guess[0], dtype=float)
        U = np.asarray(guess[1], dtype=float)
        if X.shape != (N + 1, STATE.size) or not np.all(np.isfinite(X)):
            raise ParameterError("initial_guess", f"states need shape {(N + 1, STATE.size)}")
    elif guess is not None:
        U = np.asarray(guess, dtype=float)
    if U is not None and (U.shape != (N, nu) or not np.all(np.isfinite(U))):
        raise ParameterError("initial_guess", f"inputs need finite shape {(N, nu)}")
    if X is None or U is None:
        return rollout(problem, pulse_map, U, x0=x0, p=p, t0=t0)
    return X, U


def scenario_start(
    held: Start,
    problem: OcpProblem,
    x0: np.ndarray,
    *,
    dropouts: tuple[int, ...] = (),
) -> Start:
    """One scenario's start from ``held``, an optimum of the problem with its design held
    (the nominal one, or the nominal re-solved in this scenario's launch state and air:
    docs/design.md#robust-design): its nodes, node 0 the scenario's launch state ``x0``
    (STATE.size,), and its inputs, the energy of the pulses in ``dropouts`` 0 (that
    scenario's gap opens there alone; ``problem`` gives the input layout)."""
    began = time.perf_counter()
    U = np.array(held.U, dtype=float)
    U[list(dropouts), problem.inputs.index("energy")] = 0.0
    X = np.array(held.X, dtype=float)
    X[0] = x0
    seconds = held.seconds + time.perf_counter() - began
    return Start(held.kind, X, U, seconds, held.iterations)
