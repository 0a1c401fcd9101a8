"""Scenarios of a robust design: S cases of the flight that share one design
(docs/design.md#robust-design).

A :class:`Scenario` says what differs from the problem's own case: entries of p set
(``parameters``: the wind ...) or scaled (``scales``: the coupling, ``impulse_per_pulse``
the impulse per pulse at the reference energy, I0 = Cm E0), the launch state moved
(``offset_L`` [m, L east/north] added to r_L, the attitude leaned by ``tilt`` [rad] toward
``tilt_azimuth`` [rad, clockwise from north], layout.tilted_attitude) and pulses the laser
misses (``dropouts``: the energy that reaches the craft is 0 at those pulses). Every
change is affine in the problem's x0 and p, so a compiled solve takes new x0 and p and
moves each scenario with them: ``x0_s = A_s x0 + b_s``, ``p_s = k_s * p + c_s``.

:class:`Scenarios` holds the cases with their objective (``EXPECTED``: Σ_s w_s J_s with the
weights normalised to sum to 1; ``WORST``: max_s J_s) and ``shared_pulses``, the first
pulses whose inputs are equal in every scenario (non-anticipativity: what is fired before
the case is known). :func:`draw_scenarios` draws S cases from spreads
(:class:`ScenarioDraws`) with a seed. Numpy only.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE, tilted_attitude
from lightcraft_opt.model.checks import checked_vector, number, set_frozen

__all__ = [
    "MAX_SCENARIOS",
    "Scenario",
    "ScenarioDraws",
    "ScenarioObjective",
    "Scenarios",
    "check_scenarios",
    "draw_scenarios",
]

#: Most scenarios a problem takes: the NLP and its solve grow linearly with S.
MAX_SCENARIOS = 64


class ScenarioObjective(Enum):
    """How the scenarios' costs J_s make the objective."""

    EXPECTED = "expected"  # Σ_s w_s J_s, weights normalised to sum to 1
    WORST = "worst"  # max_s J_s, by an epigraph variable τ >= J_s


@dataclass(frozen=True, eq=False)
class Scenario:
    """One case of the flight (module docstring).

    Attributes
    ----------
    name : a label, unique among the scenarios.
    weight : > 0, its probability up to normalisation (EXPECTED).
    parameters : {PARAMETERS slot: value [SI, the slot's frame]} set in p (e.g.
        ``wind_speed_ref`` [m/s], ``wind_direction_from`` [rad]).
    scales : {PARAMETERS slot: factor} multiplying p's entries (e.g.
        ``{"impulse_per_pulse": 0.9}``: 10 % less coupling).
    offset_L : (2,) launch offset [m, L east/north] added to x0's r_L.
    tilt, tilt_azimuth : launch lean [rad] in [0, pi/2) and its direction [rad, clockwise
        from north], applied to x0's attitude q_LB.
    dropouts : pulses k (0..N-1) the laser misses: their energy is 0 in this scenario.
    """

    name: str
    weight: float = 1.0
    parameters: Mapping[str, float | tuple[float, ...]] = field(default_factory=dict)
    scales: Mapping[str, float] = field(default_factory=dict)
    offset_L: tuple[float, float] = (0.0, 0.0)
    tilt: float = 0.0
    tilt_azimuth: float = 0.0
    dropouts: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError("scenario.name", f"must be a non-empty text, got {self.name!r}")
        where = f"scenarios[{self.name}]"
        weight = number(f"{where}.weight", self.weight)
        if weight <= 0:
            raise ParameterError(f"{where}.weight", f"must be positive, got {weight!r}")
        set_frozen(self, "weight", weight)
        values: dict[str, tuple[float, ...]] = {}
        for name, value in dict(self.parameters).items():
            size = self._slot(f"{where}.parameters", name)
            v = checked_vector(f"{where}.parameters.{name}", np.ravel(value), size)
            values[name] = tuple(v.tolist())
        set_frozen(self, "parameters", values)
        scales: dict[str, float] = {}
        for name, factor in dict(self.scales).items():
            self._slot(f"{where}.scales", name)
            if name in values:
                raise ParameterError(f"{where}.scales.{name}", "is also set in parameters")
            scales[name] = number(f"{where}.scales.{name}", factor)
        set_frozen(self, "scales", scales)
        offset = checked_vector(f"{where}.offset_L", self.offset_L, 2)
        set_frozen(self, "offset_L", (float(offset[0]), float(offset[1])))
        tilt = number(f"{where}.tilt", self.tilt)
        if not 0 <= tilt < math.pi / 2:
            raise ParameterError(f"{where}.tilt", f"must lie in [0, pi/2) rad, got {tilt!r}")
        set_frozen(self, "tilt", tilt)
        set_frozen(self, "tilt_azimuth", number(f"{where}.tilt_azimuth", self.tilt_azimuth))
        try:
            pulses = sorted({int(k) for k in self.dropouts})
        except (TypeError, ValueError):
            raise ParameterError(
                f"{where}.dropouts", f"must be pulse indices, got {self.dropouts!r}"
            ) from None
        if any(k < 0 for k in pulses):
            raise ParameterError(f"{where}.dropouts", f"pulses count from 0, got {pulses}")
        set_frozen(self, "dropouts", tuple(pulses))

    @staticmethod
    def _slot(where: str, name: str) -> int:
        if name not in PARAMETERS:
            raise ParameterError(
                f"{where}.{name}", f"no such parameter; see {list(PARAMETERS.names)}"
            )
        return PARAMETERS.slot(name).size

    # ----------------------------------------------------------------- affine maps
    def state_map(self) -> tuple[np.ndarray, np.ndarray]:
        """(A (STATE.size, STATE.size), b (STATE.size,)): this scenario's launch state
        x0_s = A x0 + b (the lean turns q_LB in L, linear in q_LB; the offset moves r_L)."""
        A = np.eye(STATE.size)
        q = STATE.slot("q_LB")
        if self.tilt:
            basis = np.eye(4)
            turned = [tilted_attitude(basis[i], self.tilt, self.tilt_azimuth) for i in range(4)]
            A[q.start : q.stop, q.start : q.stop] = np.column_stack(turned)
        b = np.zeros(STATE.size)
        r = STATE.slot("r_L").start
        b[r : r + 2] = self.offset_L
        return A, b

    def parameter_map(self) -> tuple[np.ndarray, np.ndarray]:
        """(k, c), each (PARAMETERS.size,): this scenario's p_s = k * p + c."""
        k, c = np.ones(PARAMETERS.size), np.zeros(PARAMETERS.size)
        for name, value in self.parameters.items():
            idx = PARAMETERS.index(name)
            k[idx], c[idx] = 0.0, value
        for name, factor in self.scales.items():
            k[PARAMETERS.index(name)] = factor
        return k, c

    def x0_of(self, x0: np.ndarray) -> np.ndarray:
        """(STATE.size,) this scenario's launch state from the problem's ``x0``."""
        A, b = self.state_map()
        return A @ np.asarray(x0, dtype=float) + b

    def p_of(self, p: np.ndarray) -> np.ndarray:
        """(PARAMETERS.size,) this scenario's parameters from the problem's ``p``."""
        k, c = self.parameter_map()
        return k * np.asarray(p, dtype=float) + c


@dataclass(frozen=True, eq=False)
class Scenarios:
    """S scenarios sharing one design (module docstring).

    Attributes
    ----------
    cases : 1 .. :data:`MAX_SCENARIOS` scenarios, names unique.
    objective : EXPECTED (weighted mean of the costs) or WORST (largest cost).
    shared_pulses : the first pulses whose inputs are equal in every scenario, 0 .. N
        (0: each scenario has its own inputs; N: one open-loop plan for all).
    """

    cases: tuple[Scenario, ...]
    objective: ScenarioObjective = ScenarioObjective.EXPECTED
    shared_pulses: int = 0

    def __post_init__(self) -> None:
        cases = (self.cases,) if isinstance(self.cases, Scenario) else tuple(self.cases)
        if not 1 <= len(cases) <= MAX_SCENARIOS:
            raise ParameterError(
                "scenarios.cases", f"needs 1 to {MAX_SCENARIOS} scenarios, got {len(cases)}"
            )
        for i, case in enumerate(cases):
            if not isinstance(case, Scenario):
                raise ParameterError(f"scenarios.cases[{i}]", f"must be a Scenario, got {case!r}")
        names = [c.name for c in cases]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise ParameterError("scenarios.cases", f"names repeat: {repeated}")
        set_frozen(self, "cases", cases)
        if not isinstance(self.objective, ScenarioObjective):
            raise ParameterError(
                "scenarios.objective",
                f"must be one of {[o.value for o in ScenarioObjective]}, got {self.objective!r}",
            )
        n = self.shared_pulses
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 0:
            raise ParameterError(
                "scenarios.shared_pulses", f"must be an integer >= 0 (pulses), got {n!r}"
            )
        set_frozen(self, "shared_pulses", int(n))

    @property
    def size(self) -> int:
        """S, the number of scenarios."""
        return len(self.cases)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.cases)

    @property
    def weights(self) -> np.ndarray:
        """(S,) the weights normalised to sum to 1."""
        w = np.array([c.weight for c in self.cases])
        return w / w.sum()

    def check(self, horizon: int, designed_p: np.ndarray, energy_free: bool) -> None:
        """Raise a ParameterError naming the field when the scenarios do not fit a problem
        of ``horizon`` pulses whose design sets the entries ``designed_p`` of p (a scenario
        may not set or scale them) and whose pulse energy is free or not (drop-outs need
        it free)."""
        if self.shared_pulses > horizon:
            raise ParameterError(
                "scenarios.shared_pulses",
                f"{self.shared_pulses} is beyond the horizon of {horizon} pulses",
            )
        designed = set(np.asarray(designed_p, dtype=int).tolist())
        for case in self.cases:
            where = f"scenarios[{case.name}]"
            late = [k for k in case.dropouts if k >= horizon]
            if late:
                raise ParameterError(
                    f"{where}.dropouts", f"pulses {late} are beyond the horizon 0..{horizon - 1}"
                )
            if case.dropouts and not energy_free:
                raise ParameterError(
                    f"{where}.dropouts",
                    "a drop-out holds the pulse energy at 0: the energy must be free",
                )
            for kind, names in (("parameters", case.parameters), ("scales", case.scales)):
                for name in names:
                    slot = PARAMETERS.slot(name)
                    if designed & set(range(slot.start, slot.stop)):
                        raise ParameterError(
                            f"{where}.{kind}.{name}",
                            "is designed: the design sets it in every scenario",
                        )


@dataclass(frozen=True)
class ScenarioDraws:
    """Spreads of S drawn scenarios (:func:`draw_scenarios`), standard deviations, SI.

    Attributes
    ----------
    count : S, 1 .. :data:`MAX_SCENARIOS`; the first is the problem's own case
        (``nominal``), the others ``draw 1`` ... ``draw S-1``, weighted equally.
    seed : of numpy's default generator.
    wind_speed : [m/s] on the reference wind speed (clipped at 0).
    wind_direction : [rad] on the direction the wind blows from.
    offset : [m] on each of the launch offset's east and north components.
    tilt : [rad] on each horizontal component of the lean (the lean is their length,
        toward their direction).
    impulse : relative, on the impulse per pulse (the coupling Cm): factor 1 + N(0, s^2).
    dropout_probability : chance that the laser misses a pulse, in [0, 1).
    """

    count: int
    seed: int = 0
    wind_speed: float = 0.0
    wind_direction: float = 0.0
    offset: float = 0.0
    tilt: float = 0.0
    impulse: float = 0.0
    dropout_probability: float = 0.0

    def __post_init__(self) -> None:
        n = self.count
        if isinstance(n, bool) or not isinstance(n, int | np.integer):
            raise ParameterError("scenarios.count", f"must be an integer, got {n!r}")
        if not 1 <= n <= MAX_SCENARIOS:
            raise ParameterError("scenarios.count", f"must lie in 1..{MAX_SCENARIOS}, got {n}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer):
            raise ParameterError("scenarios.seed", f"must be an integer, got {self.seed!r}")
        for name in ("wind_speed", "wind_direction", "offset", "tilt", "impulse"):
            set_frozen(self, name, number(f"scenarios.{name}", getattr(self, name), low=0.0))
        prob = number("scenarios.dropout_probability", self.dropout_probability, low=0.0)
        if prob >= 1:
            raise ParameterError(
                "scenarios.dropout_probability", f"must lie in [0, 1), got {prob!r}"
            )
        set_frozen(self, "dropout_probability", prob)


def draw_scenarios(
    draws: ScenarioDraws,
    p: np.ndarray,
    horizon: int,
    *,
    objective: ScenarioObjective = ScenarioObjective.EXPECTED,
    shared_pulses: int = 0,
) -> Scenarios:
    """S scenarios drawn about the problem's parameters ``p`` (PARAMETERS.size,) for a
    horizon of ``horizon`` pulses (:class:`ScenarioDraws`); the first is the nominal case.
    A spread of 0 draws nothing for that quantity, so its entries stay the problem's."""
    rng = np.random.default_rng(draws.seed)
    p = np.asarray(p, dtype=float)
    speed0 = float(p[PARAMETERS.index("wind_speed_ref")][0])
    direction0 = float(p[PARAMETERS.index("wind_direction_from")][0])
    cases = [Scenario("nominal")]
    for i in range(1, draws.count):
        wind = rng.normal(size=2) * (draws.wind_speed, draws.wind_direction)
        offset = rng.normal(size=2) * draws.offset
        lean = rng.normal(size=2) * draws.tilt  # east, north components
        cm = 1.0 + rng.normal() * draws.impulse
        missed = np.flatnonzero(rng.random(horizon) < draws.dropout_probability)
        parameters: dict[str, float] = {}
        if draws.wind_speed:
            parameters["wind_speed_ref"] = max(0.0, speed0 + wind[0])
        if draws.wind_direction:
            parameters["wind_direction_from"] = direction0 + wind[1]
        tilt = min(float(np.hypot(*lean)), math.pi / 2 * 0.99)
        cases.append(
            Scenario(
                f"draw {i}",
                parameters=parameters,
                scales={"impulse_per_pulse": cm} if draws.impulse else {},
                offset_L=(float(offset[0]), float(offset[1])),
                tilt=tilt,
                tilt_azimuth=float(math.atan2(lean[0], lean[1])) if tilt else 0.0,
                dropouts=tuple(int(k) for k in missed),
            )
        )
    return Scenarios(tuple(cases), objective, shared_pulses)


def check_scenarios(
    scenarios: Scenarios, horizon: int, designed_p: np.ndarray, energy_free: bool
) -> None:
    """Raise a ParameterError naming ``scenarios`` unless it is a :class:`Scenarios` that
    fits the problem (:meth:`Scenarios.check`)."""
    if not isinstance(scenarios, Scenarios):
        raise ParameterError("scenarios", f"must be a Scenarios, got {type(scenarios).__name__}")
    scenarios.check(horizon, designed_p, energy_free)
