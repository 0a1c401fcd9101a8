"""The estimation model on Ψ: the reduced pulse map with the wind, the coupling and the moments.

The estimated vector is s = (z, σ): Ψ's state z (REDUCED_STATE, docs/frames.md) and the slow
states σ, each a random walk:

- ``"wind"``: the mean wind at the profile's reference height, east and north in L [m/s]
  (``wind_L[east]``, ``wind_L[north]``). Ψ reads the wind from p as a speed and the
  direction it blows from (``wind_speed_ref``, ``wind_direction_from``); the shape of the
  profile (shear, roughness, veer) stays the model's. The east/north pair is the better
  chart: the speed/direction chart is singular in calm air (the direction is then
  undefined, and a speed of zero is on its boundary), where the flights start; east/north
  is linear in the wind vector everywhere;
- ``"coupling"``: the engine's coupling coefficient C [N s/J], the impulse a pulse of the
  reference energy gives over that energy (``Flight.coupling_coefficient``); it enters p as
  ``impulse_per_pulse`` = C x ``reference_pulse_energy``;
- ``"inertia"``: the rotor's transverse and axial dry moments as scales of the model's [-]
  (``inertia[transverse]``, ``inertia[axial]``; p's ``rotor_transverse_inertia_dry``,
  ``rotor_axial_inertia_dry``). Ψ turns the cone by |H| T / A a pulse (52 rad for Flight 5),
  so 1 % of A moves its phase by 0.5 rad a pulse; a gyro makes the scale observable
  (docs/estimation.md#what-the-director-needs).

Between pulses s[k+1] = (Ψ(z, u, p(σ), t), σ) + w, w ~ N(0, Q) (:class:`ProcessNoise`), and
its Jacobian is

    F = [[∂Ψ/∂z, ∂Ψ/∂p · ∂p/∂σ], [0, I]]

from Ψ's explicit chain over compiled pieces (psi_chain.py: the chain of
symbolic/maps/reduced_map_derivatives.py in the columns an estimator needs), the same map
the director plans with (:func:`estimation_model` builds its model the director's
way, with the optic quadrature of ``DirectorOptions``). The wind columns chain the pieces'
Jacobians in the two wind entries of p; the coupling column is exact from the energy
column of ∂Ψ/∂u: the impulses depend on the coupling and the pulse energy
through their product only, and the energy also counts the engine's load (pulse_jump.py),
so ∂Ψ/∂C = (E / C) (∂Ψ/∂E − e_load / E_ref). This holds where nothing ablates (the air mode,
or a liner with ``ablation`` 0); elsewhere the coupling is refused. The moments' columns
chain the pieces' Jacobians in the two moments' entries of p, the jump's included (it sees
them; psi_chain.py), checked against central differences of the whole prediction
(tests/control/estimation/test_psi_estimation_model.py).

A sensor is a casadi Function ``h(x, p, dt) -> y`` on the FULL state x (STATE) and its noise
covariance R; the model composes it with Ψ's ``lift`` and differentiates the composition
(``measure``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, fields

import casadi as ca
import numpy as np

from lightcraft_opt.compiled import DERIVATIVE_INSTRUCTION_LIMIT, compile_by_default
from lightcraft_opt.compiled.cache import DEFAULT_FLAGS, DERIVATIVE_FLAGS, compile_all
from lightcraft_opt.control.estimation.buffered import Evaluator
from lightcraft_opt.control.estimation.psi_chain import (
    SlowColumns,
    estimator_jump,
    estimator_stage,
    estimator_substep,
    measurement_function,
    prediction_function,
)
from lightcraft_opt.control.options import DirectorOptions
from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, REDUCED_STATE, parameter_values
from lightcraft_opt.linear.signal_names import entry_names
from lightcraft_opt.model import Model, Propellant
from lightcraft_opt.model.checks import checked_number
from lightcraft_opt.symbolic.maps.reduced_map import build_reduced_map
from lightcraft_opt.symbolic.maps.reduced_map_derivatives import value_stage

__all__ = [
    "SLOW_STATES",
    "SLOW_UNITS",
    "ProcessNoise",
    "PsiEstimationModel",
    "estimated_names",
    "estimated_units",
    "estimation_model",
    "slow_truths",
]

#: The slow states a model can carry, with the entries each adds to s.
SLOW_STATES: dict[str, tuple[str, ...]] = {
    "wind": ("wind_L[east]", "wind_L[north]"),
    "coupling": ("coupling",),
    "inertia": ("inertia[transverse]", "inertia[axial]"),
}
#: The SI unit of each slow slot's entries: the wind in L [m/s], the coupling [N s/J], the
#: moments over the model's [-].
SLOW_UNITS: dict[str, str] = {"wind": "m/s", "coupling": "N s/J", "inertia": "-"}
_WIND_P = ("wind_speed_ref", "wind_direction_from")
_SPEED, _DIRECTION = (PARAMETERS.slot(n).start for n in _WIND_P)
_IMPULSE = PARAMETERS.slot("impulse_per_pulse").start
_REFERENCE_ENERGY = PARAMETERS.slot("reference_pulse_energy").start
#: the rotor's dry moments [kg m²] the ``inertia`` slow states scale (transverse, axial)
_INERTIA = tuple(
    PARAMETERS.slot(n).start for n in ("rotor_transverse_inertia_dry", "rotor_axial_inertia_dry")
)
_ENERGY = PULSE_INPUT.slot("energy").start
_NZ = REDUCED_STATE.size
_H = REDUCED_STATE.index("H_L")
_CONE = REDUCED_STATE.index("coning")
_CALM = 1e-9  # m/s: below this the wind's direction is undefined (module docstring)
_NO_CHART = np.zeros((2, 2))  # the wind chart's stand-in without wind, or in calm air


def slow_truths(p: np.ndarray) -> dict[str, float]:
    """What the wind and coupling slow states stand for in the parameters ``p``
    (PARAMETERS.size,): the mean wind at the reference height in L, east and north [m/s]
    (its speed blowing from its direction: -speed sin, -speed cos), and the coupling, the
    impulse a pulse of the reference energy gives over that energy [N s/J]."""
    speed, frm = float(p[_SPEED]), float(p[_DIRECTION])
    return {
        "wind_L[east]": -speed * math.sin(frm),
        "wind_L[north]": -speed * math.cos(frm),
        "coupling": float(p[_IMPULSE] / p[_REFERENCE_ENERGY]),
    }


def estimated_names(slow: Iterable[str] = tuple(SLOW_STATES)) -> tuple[str, ...]:
    """The entries of s, in order: Ψ's state's (``"r_L[east]"``, ...), then those of the
    ``slow`` slots (keys of :data:`SLOW_STATES`, in the order given)."""
    return tuple(entry_names(REDUCED_STATE)) + tuple(n for s in slow for n in SLOW_STATES[s])


def estimated_units(slow: Iterable[str] = tuple(SLOW_STATES)) -> dict[str, str]:
    """{entry of s: its SI unit} in :func:`estimated_names`' order: Ψ's state's slot
    units (``"m"``, ``"kg m^2/s"``, ``"-"`` ...), then :data:`SLOW_UNITS`."""
    units = {n: REDUCED_STATE.slot(n.split("[")[0]).unit for n in entry_names(REDUCED_STATE)}
    return units | {n: SLOW_UNITS[s] for s in slow for n in SLOW_STATES[s]}


@dataclass(frozen=True)
class ProcessNoise:
    """Standard deviations of the process noise w a pulse, one per block of s (SI).

    Ψ's own error against Φ (docs/beam_riding.md#reduced-map: one pulse's velocity 0.27 cm/s
    median, 0.87 max, along coning flights) and what it cannot know (gusts, the plant's
    dispersion) set them:

    - ``velocity`` [m/s], each L axis: 3e-3, Ψ's median one-pulse velocity error;
    - ``position`` [m], each L axis: 6e-5, that velocity error over half a pulse (26 Hz);
    - ``angular_momentum`` [kg m²/s], each L axis: 1e-4, 1.6e-3 of Flight 5's |H| (0.063):
      a tilt of 0.09° a pulse. An off-centre pulse tips H by 0.1-1°, and the plant's
      tipping is uncertain by 5-20 % of that (its blast angle, coupling and aerodynamic
      moments are dispersed by 5, 5 and 20 % in the campaigns). With 1e-5 the filter
      believed its own tipping, and a gyro's innovations ran to rad/s (the gyro sees H
      across b1 to 5e-7 kg m²/s); 1e-4 kept 29-31 of 40 dispersed tracked flights in the
      beam against 22 (docs/estimation.md#what-the-director-needs);
    - ``coning`` [-]: 1e-3, the coning angle's change by aerodynamic torques within a
      pulse interval, which Ψ leaves out (about 0.06°);
    - ``mass`` [kg] (liner, RCS propellant) 1e-9 and ``load`` [reference pulses] 1e-6: Ψ
      counts them exactly; a floor keeps the covariance positive definite;
    - ``wind`` [m/s] each of east/north: 0.05 a pulse, a random walk of 0.25 m/s over a
      second (26 pulses): a slow mean wind with the gusts in it;
    - ``coupling``, relative: 1e-3 of C a pulse, a drift of 1 % over 100 pulses (the air
      engine's health step near pulse 100 is in Ψ already);
    - ``inertia``, relative: 0.01, how well the craft's transverse moment A is known (the
      campaigns disperse the rotor's inertias by 1 %). Ψ turns the coning offset c by
      |H| T / A a pulse (8 turns for Flight 5), so an error of 1 % in A puts the cone's
      phase at the next pulse 2π · 8 · 0.01 = 0.5 rad off: a noise along c's turn (the
      direction J c, J the quarter turn), of standard deviation |H| T / A · ``inertia``.
      Without it the filter believes its phase, which cameras alone barely see
      (docs/estimation.md), and a 1 % heavier rotor puts it on the wrong side of the cone
      within a few pulses. Where the ``inertia`` slow states estimate the moments, it
      stands for what they have not learnt yet;
    - ``inertia_drift``, relative a pulse: 1e-4, the slow states ``inertia`` (the rotor's
      transverse and axial dry moments over the model's) as random walks: the moments do
      not change; this keeps the filter listening.
    """

    position: float = 6e-5
    velocity: float = 3e-3
    angular_momentum: float = 1e-4
    coning: float = 1e-3
    mass: float = 1e-9
    load: float = 1e-6
    wind: float = 0.05
    coupling: float = 1e-3
    inertia: float = 0.01
    inertia_drift: float = 1e-4

    def __post_init__(self) -> None:
        for f in fields(self):
            checked_number("ProcessNoise", f.name, getattr(self, f.name), 0.0)
            if getattr(self, f.name) <= 0:
                raise OptionError(f"ProcessNoise.{f.name} must be > 0, got {getattr(self, f.name)}")

    def scaled(self, factor: float) -> ProcessNoise:
        """Every standard deviation times ``factor`` (> 0)."""
        return ProcessNoise(**{f.name: getattr(self, f.name) * factor for f in fields(self)})


def estimation_model(
    model: Model, quadrature: tuple[int, int] = DirectorOptions().quadrature
) -> Model:
    """The estimator's model of ``model``: the same craft with an optic quadrature of
    ``quadrature`` (radial, azimuthal), as ``control.director.director_model`` builds the
    director's (default ``DirectorOptions().quadrature``), so both share one compiled Ψ."""
    return model.with_optic_quadrature(*quadrature)


class PsiEstimationModel:
    """The :class:`~lightcraft_opt.control.estimation.model.EstimationModel` on Ψ with slow
    states (module docstring).

    Parameters
    ----------
    model : the estimator's model (its numbers are what it believes; see
        :func:`estimation_model`).
    sensors : {name: (h, R)}: ``h(x, p, dt) -> y`` a casadi Function on the full state x
        (STATE), p (PARAMETERS) and dt [s], the time from the reading to the node it ends
        at; R (m, m) the noise covariance of y [y's units²].
    slow : the slow states, a sub-tuple of ("wind", "coupling", "inertia") (:data:`SLOW_STATES`),
        kept in that order in s.
    noise : the process noise (:class:`ProcessNoise`, default its defaults).
    p : the model's parameter vector (default its model's); the slow states overwrite
        their entries.
    compiled : compile the pieces (None: ``compiled.compile_by_default``).

    Attributes
    ----------
    names : the entries of s: Ψ's (``"r_L[east]"``, ...) then the slow ones.
    state_size : how many of them are Ψ's (REDUCED_STATE.size).
    psi : the reduced map; period : pulse period [s]; p : the base parameters.
    slow : the slow states kept.
    """

    def __init__(
        self,
        model: Model,
        sensors: Mapping[str, tuple[ca.Function, np.ndarray]],
        *,
        slow: Sequence[str] = ("wind", "coupling"),
        noise: ProcessNoise | None = None,
        p: np.ndarray | None = None,
        compiled: bool | None = None,
    ) -> None:
        slow = tuple(slow)
        if any(s not in SLOW_STATES for s in slow) or len(set(slow)) != len(slow):
            raise OptionError(f"slow must be a sub-tuple of {tuple(SLOW_STATES)}, got {slow!r}")
        self.slow = tuple(s for s in SLOW_STATES if s in slow)
        self.noise = noise or ProcessNoise()
        if not isinstance(self.noise, ProcessNoise):
            raise OptionError(f"noise must be ProcessNoise, got {self.noise!r}")
        self.model = model
        self.p = parameter_values(model) if p is None else np.array(p, dtype=float)
        if "wind" in self.slow and model.environment.wind.table_height:
            raise ParameterError(
                "environment.wind", "a wind table does not read p: the wind cannot be estimated"
            )
        if "coupling" in self.slow and (
            model.craft.propellant is not Propellant.AIR
            and self.p[PARAMETERS.slot("ablation").start] != 0
        ):
            raise ParameterError(
                "craft.engine.ablation", "the coupling is estimated only where nothing ablates"
            )
        self.psi = psi = build_reduced_map(model)
        self.period = psi.period
        want = compile_by_default() if compiled is None else bool(compiled)
        # the entries of p the slow states move, each a column S_p of the stage
        entries = (_SPEED, _DIRECTION) * ("wind" in self.slow) + _INERTIA * ("inertia" in self.slow)
        shape = (model, psi.options.substeps, psi.options.dense, entries, want)
        stage = estimator_stage(psi, estimator_jump(*shape), estimator_substep(*shape))
        self._stage = Evaluator(stage)  # the calm wind's columns
        self._compiled = want
        self._values: ca.Function | None = None  # Ψ's value chain, for predict_many
        self._points: dict[int, Evaluator] = {}  # by the number of rows
        self.names: tuple[str, ...] = estimated_names(self.slow)
        self.n = len(self.names)
        self.state_size = _NZ
        self._wind = _NZ if "wind" in self.slow else None
        self._coupling = self.names.index("coupling") if "coupling" in self.slow else None
        self._inertia = self.names.index("inertia[transverse]") if "inertia" in self.slow else None
        self._Q = np.diag(np.square(self._sigmas()))
        self._transverse = float(model.craft.inertia_transverse)  # A [kg m²]
        noises, measures = [], []
        for name, (h, R) in sensors.items():
            R = np.atleast_2d(np.asarray(R, dtype=float))
            m = h.size1_out(0)
            if R.shape != (m, m) or np.any(np.linalg.eigvalsh(0.5 * (R + R.T)) <= 0):
                raise ParameterError(
                    f"sensors[{name!r}]", f"R must be ({m}, {m}) and positive definite"
                )
            noises.append(R)
            measures.append(self._measurement(name, h))
        lift = psi.lift
        if want:
            # a camera's h carries its frame back over dt: thousands of instructions, some
            # 45 µs a call interpreted, 6 compiled (bench/README.md, estimation.py)
            *measures, lift = compile_all(
                [(f, DERIVATIVE_FLAGS) for f in [*measures, lift]],
                max_instructions=DERIVATIVE_INSTRUCTION_LIMIT,
                what="the sensors' measurements and Ψ's lift",
            )[0]
        self._lift = Evaluator(lift)
        self._sensors: dict[str, tuple[Evaluator, np.ndarray]] = {
            name: (Evaluator(f), R) for name, f, R in zip(sensors, measures, noises, strict=True)
        }
        columns = SlowColumns(
            self._wind,
            self._coupling,
            self._inertia,
            float(self.p[_REFERENCE_ENERGY]),
            (float(self.p[_INERTIA[0]]), float(self.p[_INERTIA[1]])),
        )
        self._prediction = Evaluator(prediction_function(stage, columns))
        self._mapped: dict[tuple[str, int], Evaluator] = {}  # (sensor, rows): measure_many's
        self._in_s = {
            name: Evaluator(measurement_function(f, columns))
            for name, f in zip(sensors, measures, strict=True)
        }

    # -- the slow states in p ---------------------------------------------------------------

    def slow_values(self, p: np.ndarray | None = None) -> np.ndarray:
        """The slow states σ that ``p`` (default the model's) holds: the wind at the reference
        height (east, north) [m/s], C [N s/J], the rotor's moments over the model's [-]."""
        p = self.p if p is None else p
        truth = slow_truths(p)
        out: list[float] = []
        if "wind" in self.slow:
            out += [truth["wind_L[east]"], truth["wind_L[north]"]]
        if "coupling" in self.slow:
            out.append(truth["coupling"])
        if "inertia" in self.slow:
            out += [p[i] / self.p[i] for i in _INERTIA]
        return np.array(out)

    def parameters(self, s: np.ndarray) -> np.ndarray:
        """p with the slow states of s in it (module docstring)."""
        p = self.p.copy()
        if self._wind is not None:
            east, north = s[self._wind], s[self._wind + 1]
            speed = math.hypot(east, north)
            p[_SPEED] = speed
            if speed > _CALM:
                p[_DIRECTION] = math.atan2(-east, -north)
        if self._coupling is not None:
            p[_IMPULSE] = s[self._coupling] * p[_REFERENCE_ENERGY]
        if self._inertia is not None:
            for j, i in enumerate(_INERTIA):
                p[i] = self.p[i] * s[self._inertia + j]
        return p

    def parameters_many(self, S: np.ndarray) -> np.ndarray:
        """(k, PARAMETERS.size): :meth:`parameters` of each row of S (k, n)."""
        P = np.repeat(self.p[None, :], S.shape[0], axis=0)
        if self._wind is not None:
            east, north = S[:, self._wind], S[:, self._wind + 1]
            speed = np.hypot(east, north)
            P[:, _SPEED] = speed
            windy = speed > _CALM  # else the model's direction: undefined in calm air
            P[windy, _DIRECTION] = np.arctan2(-east[windy], -north[windy])
        if self._coupling is not None:
            P[:, _IMPULSE] = S[:, self._coupling] * self.p[_REFERENCE_ENERGY]
        if self._inertia is not None:
            for j, i in enumerate(_INERTIA):
                P[:, i] = self.p[i] * S[:, self._inertia + j]
        return P

    def start(self, x0: np.ndarray) -> np.ndarray:
        """s of the full state x0 (STATE): Ψ's ``project`` of it and the model's slow states."""
        z = np.asarray(self.psi.project(np.asarray(x0, dtype=float), self.p)).ravel()
        return np.concatenate([z, self.slow_values()])

    def parts(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
        """(z, x, slow): what an Estimate holds of s: Ψ's z, its lift x (STATE) and the slow
        states by name (SI)."""
        s = np.asarray(s, dtype=float).ravel()
        slow = {n: float(v) for n, v in zip(self.names[_NZ:], s[_NZ:], strict=True)}
        return s[:_NZ].copy(), self.lift(s), slow

    def lift(self, s: np.ndarray) -> np.ndarray:
        """The full state (STATE) Ψ's ``lift`` builds from s's z."""
        return self._lift(s[:_NZ], self.parameters(s))[:, 0]

    def _sigmas(self) -> np.ndarray:
        q = self.noise
        per_slot = {
            "r_L": q.position,
            "v_L": q.velocity,
            "H_L": q.angular_momentum,
            "coning": q.coning,
            "liner_mass": q.mass,
            "rcs_mass": q.mass,
            "engine_load": q.load,
        }
        sig = [per_slot[s.name] for s in REDUCED_STATE.slots for _ in range(s.size)]
        if "wind" in self.slow:
            sig += [q.wind, q.wind]
        if "coupling" in self.slow:
            sig.append(q.coupling * float(self.slow_values()[self.names.index("coupling") - _NZ]))
        if "inertia" in self.slow:
            sig += [q.inertia_drift, q.inertia_drift]
        return np.array(sig)

    # -- the protocol ------------------------------------------------------------------------

    def _input(self, u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, dtype=float).ravel()
        size = self.psi.inputs.size
        if u.size == size:
            return u
        if u.size >= PULSE_INPUT.size and size == PULSE_INPUT.size:
            return u[:size]
        if u.size == PULSE_INPUT.size:  # the pulse alone: the thrusters at rest
            return np.concatenate([u, np.zeros(size - u.size)])
        raise ParameterError("u", f"needs {size} entries (Ψ's inputs) or the pulse's, got {u.size}")

    def predict(self, s: np.ndarray, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(s_next (n,), F (n, n)): Ψ from s with ``u`` fired at ``t`` [s] (Ψ's inputs: the
        pulse's pointing [m, L east/north], focus [m], energy [J], then held RCS levels) and
        the slow states held; F its Jacobian (module docstring)."""
        s = np.asarray(s, dtype=float).ravel()
        u = self._input(u)
        p = self.parameters(s)
        z = s[:_NZ]
        chart = _wind_chart(p) if self._wind is not None else _NO_CHART
        gain = float(u[_ENERGY]) / s[self._coupling] if self._coupling is not None else 0.0
        out = self._prediction(z, u, p, t, _NO_CHART if chart is None else chart, gain)
        z_next = out[:, 0]
        F = np.eye(self.n)
        F[:_NZ] = out[:, 1:]
        if chart is None and self._wind is not None:  # calm: the wind's columns are each
            col = 2 + _NZ  # ∂/∂speed with the wind along its axis (the stage's S_p[:, 0])
            for j, frm in enumerate((-0.5 * math.pi, math.pi)):  # from the west, the south
                q = p.copy()
                q[_DIRECTION] = frm
                F[:_NZ, self._wind + j] = self._stage(z, u, q, t)[:, col]
        s_next = s.copy()
        s_next[:_NZ] = z_next
        return s_next, F

    def predict_many(self, S: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        """(k, n): :meth:`predict`'s s_next from each row of S (k, n), by one call of Ψ's
        value chain (its pieces compiled, cached by structure) mapped over the rows: the
        unscented filter's sigma points (ukf.py). A row where Ψ is undefined (a coning
        offset beyond 1) comes back non-finite."""
        S = np.atleast_2d(np.asarray(S, dtype=float))
        k = S.shape[0]
        self.prepare_many(k)
        out = S.copy()
        out[:, :_NZ] = self._points[k](S[:, :_NZ].T, self._input(u), self.parameters_many(S).T, t).T
        return out

    def prepare_many(self, k: int) -> None:
        """Build (compile or load) :meth:`predict_many`'s Function for k rows now, so that
        its first call costs what the others do."""
        if k not in self._points:
            if self._values is None:
                self._values = self._value_stage()
            self._points[k] = Evaluator(_mapped_values(self._values, k))

    def _value_stage(self) -> ca.Function:
        """Ψ's value chain over its own pieces, compiled (cached by structure) unless the
        model was built interpreted: no Jacobians, which the sigma points do not need."""
        jump, substep = self.psi.jump, self.psi.substep
        if self._compiled:
            jump, substep = compile_all(
                [(jump, DEFAULT_FLAGS), (substep, DEFAULT_FLAGS)],
                max_instructions=DERIVATIVE_INSTRUCTION_LIMIT,
                what="Ψ's value pieces",
            )[0]
        return value_stage(jump, substep, self.psi.options.substeps, self.psi.period)

    def process_noise(self, s: np.ndarray, u: np.ndarray, t: float) -> np.ndarray:
        """Q (n, n): :class:`ProcessNoise` squared on the diagonal, plus the cone's phase
        noise along J c (``ProcessNoise.inertia``: |H| T / A turns c a pulse)."""
        Q = self._Q.copy()
        s = np.asarray(s, dtype=float).ravel()
        phase = self._cone_turn(s)
        sigma = self.noise.inertia
        turn = (-float(s[_CONE.start + 1]) * phase * sigma, float(s[_CONE.start]) * phase * sigma)
        i = _CONE.start  # the block += turn turnᵀ, in Python floats (numpy's dozen calls cost
        for a in range(2):  # more than the arithmetic)
            for b in range(2):
                Q[i + a, i + b] += turn[a] * turn[b]
        return Q

    def _cone_turn(self, s: np.ndarray) -> float:
        """|H| T / A [rad]: how far Ψ turns the coning offset c in a pulse from s (|H| as
        numpy's norm)."""
        H = s[_H]
        return math.sqrt(float(H @ H)) * self.period / self._transverse

    def sample_next(
        self, s: np.ndarray, u: np.ndarray, t: float, rng: np.random.Generator
    ) -> np.ndarray:
        """A draw of s at the next pulse from the true ``s`` (n,) with ``u`` fired at ``t``
        [s]: Ψ, then the noise :meth:`process_noise` describes, drawn as the process it
        linearises: Q's diagonal added, and the cone's phase noise (standard deviation
        |H| T / A · ``ProcessNoise.inertia``, along J c in Q) as a turn of the coning offset
        c, which keeps |c| (a draw along J c would grow |c|² by the turn's variance a pulse:
        27 % for Flight 5, whose turn has a standard deviation of 0.52 rad). What a
        consistency check flies as the truth of the estimators' own model."""
        s = np.asarray(s, dtype=float).ravel()
        sigma = np.sqrt(np.diag(self._Q))  # Q without the turn: its diagonal
        out = self.predict_many(s[None, :], u, t)[0] + sigma * rng.normal(size=self.n)
        turn = self._cone_turn(s) * self.noise.inertia * rng.normal()
        c1, c2 = out[_CONE]
        out[_CONE] = (
            math.cos(turn) * c1 - math.sin(turn) * c2,
            math.sin(turn) * c1 + math.cos(turn) * c2,
        )
        return out

    def _measurement(self, name: str, h: ca.Function) -> ca.Function:
        """``measure_<name>(z, p, dt) -> [y H_z H_p]``: h at Ψ's lift of z, its Jacobians in z
        and in the slow states' entries of p (wind speed, direction, impulse_per_pulse), side
        by side."""
        z, p, dt = ca.SX.sym("z", _NZ), ca.SX.sym("p", PARAMETERS.size), ca.SX.sym("dt")
        y = h(self.psi.lift(z, p), p, dt)
        slots = ca.vertcat(p[_SPEED], p[_DIRECTION], p[_IMPULSE])
        return ca.Function(
            f"measure_{name}",
            [z, p, dt],
            [ca.horzcat(y, ca.jacobian(y, z), ca.jacobian(y, slots))],
            ["z", "p", "dt"],
            ["y_Hz_Hp"],
            {"cse": True},
        )

    def measure(self, sensor: str, s: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(y (m,), H (m, n)): sensor ``sensor``'s reading ``dt`` [s] before the node of s
        (its units and frame) and its Jacobian in s."""
        if sensor not in self._sensors:
            raise ParameterError(
                "sensor", f"unknown {sensor!r}; the model has {list(self._sensors)}"
            )
        f, in_s = self._sensors[sensor][0], self._in_s[sensor]
        s = np.asarray(s, dtype=float).ravel()
        p = self.parameters(s)
        chart = _wind_chart(p) if self._wind is not None else _NO_CHART
        out = in_s(s[:_NZ], p, dt, _NO_CHART if chart is None else chart)
        H = out[:, 1:]
        if chart is None and self._wind is not None:  # calm: ∂/∂speed, the wind along each axis
            for j, d in enumerate((-0.5 * math.pi, math.pi)):
                q = p.copy()
                q[_DIRECTION] = d
                H[:, self._wind + j] = f(s[:_NZ], q, dt)[:, 1 + _NZ]
        return out[:, 0].copy(), H

    def measure_many(
        self, sensor: str, S: np.ndarray, dts: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(Y (k, m), H (k, m, n)): :meth:`measure` of each row of S (k, n) with its dt
        (k,) [s], by one call of the sensor's Function mapped over the rows (a row in calm
        air by :meth:`measure`): the same numbers, one call instead of k."""
        if sensor not in self._sensors:
            raise ParameterError(
                "sensor", f"unknown {sensor!r}; the model has {list(self._sensors)}"
            )
        S = np.atleast_2d(np.asarray(S, dtype=float))
        k = S.shape[0]
        P = np.array([self.parameters(row) for row in S])
        charts = [_wind_chart(p) if self._wind is not None else _NO_CHART for p in P]
        key = (sensor, k)
        if key not in self._mapped:
            self._mapped[key] = Evaluator(self._in_s[sensor].function.map(k))
        out = self._mapped[key](
            S[:, :_NZ].T,
            P.T,
            np.asarray(dts, dtype=float).reshape(1, k),
            np.hstack([_NO_CHART if c is None else c for c in charts]),
        )
        blocks = out.reshape(out.shape[0], k, 1 + self.n).transpose(1, 0, 2)
        Y, H = blocks[:, :, 0].copy(), blocks[:, :, 1:].copy()
        for i, chart in enumerate(charts):
            if chart is None:  # calm air: the wind's columns as measure has them
                Y[i], H[i] = self.measure(sensor, S[i], float(np.ravel(dts)[i]))
        return Y, H

    def measurement_noise(self, sensor: str) -> np.ndarray:
        """R (m, m) of ``sensor``."""
        if sensor not in self._sensors:
            raise ParameterError(
                "sensor", f"unknown {sensor!r}; the model has {list(self._sensors)}"
            )
        return self._sensors[sensor][1].copy()


def _mapped_values(value: ca.Function, k: int) -> ca.Function:
    """``psi_points(Z, u, P, t) -> Z_next``: ``value(z, u, p, t) -> (z_next, engine)``
    (Ψ's value chain) of each column of Z (14, k) with its column of P (PARAMETERS.size, k),
    the same u and t."""
    Z, P = ca.MX.sym("Z", _NZ, k), ca.MX.sym("P", PARAMETERS.size, k)
    u, t = ca.MX.sym("u", value.size1_in(1)), ca.MX.sym("t")
    return ca.Function(
        "psi_points", [Z, u, P, t], [value.map(k)(Z, u, P, t)[0]], ["Z", "u", "P", "t"], ["Z_next"]
    )


def _wind_chart(p: np.ndarray) -> np.ndarray | None:
    """(2, 2) ∂(speed, direction from)/∂(east, north) of p's wind, the rows of a Jacobian
    in (speed, direction) that make it one in the wind's east and north [m/s] (L); None in
    calm air, where the direction is undefined."""
    speed = float(p[_SPEED])
    if speed <= _CALM:
        return None
    frm = float(p[_DIRECTION])
    return np.array(
        [
            [-math.sin(frm), -math.cos(frm)],
            [-math.cos(frm) / speed, math.sin(frm) / speed],
        ]
    )
