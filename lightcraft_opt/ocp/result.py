"""The result of an optimal control solve: numpy only, with a status (docs/architecture.md#rule-9).

A failed or infeasible solve is a result too: its status says so in words and it carries
the solver's last iterate, never a raw exception. An iterate whose dynamics gaps are open
(``dynamics_closed`` false) is no trajectory of Φ: its summary shows no altitude, drift or
energy as achieved. :class:`PlanReplay` is what the plan did when the simulator flew it
again (ocp/replay.py).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from lightcraft_opt.layout import STATE, VectorLayout
from lightcraft_opt.ocp.sensitivity import Sensitivities
from lightcraft_opt.presenters import Presentable
from lightcraft_opt.simulation.result import SimulationStatus
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

__all__ = ["OcpResult", "OcpStatus", "PlanReplay", "ScenarioOutcome"]


class OcpStatus(Enum):
    """How an optimal control solve ended."""

    SOLVED = "solved"  # converged to the requested tolerance
    ACCEPTABLE = "acceptable"  # converged to the solver's looser acceptable level
    MAX_ITER = "max_iter"  # iteration limit reached first
    TIME_LIMIT = "time_limit"  # the wall-clock limit (OcpOptions.time_limit) came first
    INFEASIBLE = "infeasible"  # the solver found the constraints (locally) infeasible, or
    # its constraint violation stalled (OcpOptions.stall_iterations, ocp/stall.py)
    FAILED = "failed"  # anything else: evaluation error, line search or QP failure, a solve
    # that nearly met its constraints and then diverged (ocp/stall.py) ...


@dataclass(frozen=True, eq=False)
class PlanReplay:
    """A plan's inputs flown again by the simulator, against the OCP's prediction.

    Made by :func:`~lightcraft_opt.ocp.replay.replay_plan`: the inputs ``u`` held pulse by
    pulse from the result's x0 at its t0, through the simulator's Φ at full accuracy, with
    the simulator's end-of-flight rules (simulation/flight_log.py).

    Attributes
    ----------
    status, message : how the replayed flight ended (``duration_reached``: it flew every
        pulse of the plan) and the simulator's words.
    pulse_map : options of the Φ that flew it.
    quadrature : (radial, azimuthal) points of the optic quadrature of the model it flew.
    pulses : pulses flown (the horizon N unless the flight ended early).
    t : (n,) times of the nodes reached [s]; n = pulses + 1 unless it landed.
    x : (n, STATE.size) replayed states at those nodes (docs/frames.md).
    max_position_gap : largest |r_L replayed - r_L predicted| over the nodes reached [m].
    max_gap_node : the node k (state before pulse k; N after the last) where it is largest.
    final_altitude, planned_final_altitude : altitude above the pad at the replay's last
        node, and the prediction's at node N [m].
    max_offset_over_capture_radius, planned_max_offset_over_capture_radius : largest
        |offset_L| / R_c over the pulses fired, replayed and predicted [-].
    faults : why the plan does not fly, one sentence each; empty when it flies.
    """

    status: SimulationStatus
    message: str
    pulse_map: PulseMapOptions
    quadrature: tuple[int, int]
    pulses: int
    t: np.ndarray
    x: np.ndarray
    max_position_gap: float
    max_gap_node: int
    final_altitude: float
    planned_final_altitude: float
    max_offset_over_capture_radius: float
    planned_max_offset_over_capture_radius: float
    faults: tuple[str, ...] = ()

    @property
    def flies(self) -> bool:
        """True when the replay flew every pulse, close to the prediction (no faults)."""
        return not self.faults

    @property
    def stays_in_beam(self) -> bool:
        """False when the replayed flight left the beam."""
        return self.status is not SimulationStatus.LEFT_BEAM

    def summary(self) -> str:
        """One line: the largest gap and where, final altitude and beam offset, replayed
        against planned; then the faults, if any."""
        m, q = self.pulse_map, self.quadrature
        line = (
            f"flown by Φ ({m.scheme.value}, {m.substeps} substeps, {q[0]} x {q[1]} optic "
            f"quadrature): {self.status.value} after "
            f"{self.pulses} pulses; position gap up to {100 * self.max_position_gap:.3g} cm "
            f"(node {self.max_gap_node}); final altitude {self.final_altitude:.3f} m "
            f"(planned {self.planned_final_altitude:.3f}); beam offset up to "
            f"{self.max_offset_over_capture_radius:.3f} of the capture radius (planned "
            f"{self.planned_max_offset_over_capture_radius:.3f})"
        )
        return line + ("" if self.flies else f"; DOES NOT FLY: {'; '.join(self.faults)}")


@dataclass(frozen=True, eq=False)
class ScenarioOutcome:
    """One scenario of a robust solve (ocp/scenarios.py): its plan and what it cost.

    Attributes
    ----------
    name, weight : the scenario's, the weight normalised (the weights sum to 1).
    cost : J_s, the sum of its objective terms ``cost_terms`` (n_terms,).
    x : (N + 1, STATE.size) its predicted states, x[0] its launch state.
    u : (N, map-input size) its map inputs (a drop-out's energy 0).
    engine : (N, 11) Φ's engine outputs per pulse.
    """

    name: str
    weight: float
    cost: float
    cost_terms: np.ndarray
    x: np.ndarray
    u: np.ndarray
    engine: np.ndarray

    def state(self, name: str) -> np.ndarray:
        """State slot ``name`` at the nodes: (N + 1,) or (N + 1, size)."""
        s = STATE.slot(name)
        col = self.x[:, s.start : s.stop]
        return col[:, 0] if s.size == 1 else col


@dataclass(frozen=True, eq=False)
class OcpResult(Presentable):
    """An optimal control solve: optimal inputs, predicted trajectory, how it went.

    Attributes
    ----------
    status, message : how it ended, and the solver's own words.
    solver : the solver used (``OcpSolver`` value).
    cost : objective value at the returned iterate [cost units of the terms].
    cost_terms : (n_terms,) each objective term's value, in the problem's order.
    cost_term_names : (n_terms,) their names (:meth:`OcpProblem.term_names`:
        ``lateral_offset[pad]``, ``control_rate[pointing_L]`` ...); () when not given.
    iterations : NLP iterations.
    solve_time : wall time of the solve [s] (the NLP build is ``build_time``).
    build_time : wall time to build the transcription and solver, 0 when reused [s].
    constraint_violation : largest violation of any constraint or bound at the returned
        iterate, in the NLP's scaled units (gaps: states over their natural size).
    dynamics_gap : largest dynamics gap |x_{k+1} - Φ(x_k, u_k)| (and |x_0 - x0|) at the
        returned iterate, in the same scaled units; NaN when not measured.
    dynamics_closed : the gaps are within the solve's tolerance: ``x`` is Φ's trajectory
        under ``u``, and its altitude, drift and energy are results. False: no flyable plan.
    t : (N + 1,) node times [s]; pulse k fires at t[k].
    x : (N + 1, STATE.size) predicted states at the nodes (docs/frames.md), x[0] = x0.
    u : (N, map-input size) optimal map inputs, one row per pulse; labels in ``inputs``.
    engine : (N, 11) Φ's engine outputs per pulse (layout.ENGINE): captured
        energy [J], impulse_B [N s, B], angular_impulse_B [N m s, B], offset_L [m, L],
        liner_loss [kg], health [-].
    inputs : layout of a row of ``u``.
    w, lam_x, lam_g : the NLP's (scaled) primal and dual solution, for a warm start.
    replay : the plan flown again by the simulator at full accuracy (:class:`PlanReplay`,
        ``OcpOptions.replay``); None when not replayed (the message says why).
    design : {design variable: value [SI, unit in ``design_units``]} the optimiser chose
        (ocp/design.py); empty without a design.
    design_units : {design variable: its SI unit}.
    sensitivities : the optimal cost's derivative with respect to each held parameter
        (ocp/sensitivity.py; ``OcpOptions.sensitivities`` or
        :meth:`~lightcraft_opt.ocp.solve.CompiledOcp.sensitivities`); None when not asked.
    scenarios : one :class:`ScenarioOutcome` per scenario of a robust problem (empty
        otherwise); ``x``, ``u``, ``engine`` are then the first scenario's, ``cost`` and
        ``cost_terms`` the objective's (the weighted mean, or the worst scenario's).
    """

    status: OcpStatus
    message: str
    solver: str
    cost: float
    iterations: int
    solve_time: float
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    engine: np.ndarray
    inputs: VectorLayout
    build_time: float = 0.0
    constraint_violation: float = float("nan")
    dynamics_gap: float = float("nan")
    dynamics_closed: bool = True
    cost_terms: np.ndarray = field(default_factory=lambda: np.empty(0))
    cost_term_names: tuple[str, ...] = ()
    w: np.ndarray = field(default_factory=lambda: np.empty(0))
    lam_x: np.ndarray = field(default_factory=lambda: np.empty(0))
    lam_g: np.ndarray = field(default_factory=lambda: np.empty(0))
    replay: PlanReplay | None = None
    design: dict[str, float] = field(default_factory=dict)
    design_units: dict[str, str] = field(default_factory=dict)
    sensitivities: Sensitivities | None = None
    scenarios: tuple[ScenarioOutcome, ...] = ()

    @property
    def success(self) -> bool:
        """True when the solver converged (SOLVED or ACCEPTABLE)."""
        return self.status in (OcpStatus.SOLVED, OcpStatus.ACCEPTABLE)

    def after_failed_resolve(self, failed: OcpResult) -> OcpResult:
        """This cold solve, done after the re-solve ``failed`` fell short: its message
        says so first, its iterations and solve time count both."""
        how = failed.message.split(";")[0]
        return dataclasses.replace(
            self,
            message=f"the re-solve from the previous result ended {failed.status.value} "
            f"after {failed.iterations} iterations ({how}), so it was solved cold: " + self.message,
            iterations=self.iterations + failed.iterations,
            solve_time=self.solve_time + failed.solve_time,
        )

    @property
    def horizon(self) -> int:
        """N, pulses."""
        return int(self.u.shape[0])

    def state(self, name: str) -> np.ndarray:
        """State slot ``name`` at the nodes: (N + 1,) or (N + 1, size)."""
        s = STATE.slot(name)
        col = self.x[:, s.start : s.stop]
        return col[:, 0] if s.size == 1 else col

    def input(self, name: str) -> np.ndarray:
        """Map-input slot ``name`` per pulse: (N,) or (N, size)."""
        s = self.inputs.slot(name)
        col = self.u[:, s.start : s.stop]
        return col[:, 0] if s.size == 1 else col

    def _term_rows(self) -> list[tuple[str, str]]:
        """One summary row per objective term, its name and value (the cost is their sum)."""
        names = self.cost_term_names or tuple(f"term {i + 1}" for i in range(self.cost_terms.size))
        return [(f"  {n}", f"{v:.6g}") for n, v in zip(names, self.cost_terms, strict=True)]

    @property
    def laser_energy(self) -> float:
        """Total energy the laser fires over the horizon [J]."""
        return float(np.sum(self.input("energy")))

    def summary(self) -> str:
        """The solve on one screen: how it ended, then what it achieved, with units."""
        r = self.state("r_L")
        rows = [
            ("status", f"{self.status.value} ({self.message})"),
            ("solver", f"{self.solver}, {self.iterations} iterations"),
            ("times", f"solve {self.solve_time:.3f} s, build {self.build_time:.3f} s"),
            ("cost", f"{self.cost:.6g}"),
            *self._term_rows(),
            ("violation", f"{self.constraint_violation:.3g} (scaled)"),
            ("horizon", f"{self.horizon} pulses, {float(self.t[-1] - self.t[0]):.3f} s"),
        ]
        rows += [
            (f"scenario {o.name!r}", f"cost {o.cost:.6g}, weight {o.weight:.3g}")
            for o in self.scenarios
        ]
        rows += [
            (f"design {name}", f"{value:.6g} {self.design_units.get(name, '')}".rstrip())
            for name, value in self.design.items()
        ]
        if self.dynamics_closed:
            rows += [
                ("laser energy", f"{self.laser_energy:.2f} J"),
                ("final altitude", f"{float(r[-1, 2]):.3f} m"),
                ("max drift", f"{float(np.max(np.hypot(r[:, 0], r[:, 1]))):.4f} m"),
                ("final position", f"({r[-1, 0]:.3f}, {r[-1, 1]:.3f}, {r[-1, 2]:.3f}) m"),
            ]
        else:
            rows.append(("no flyable plan", self.open_dynamics()))
        rows.append(("replay", "not replayed" if self.replay is None else self.replay.summary()))
        if self.sensitivities is not None:
            rows += self.sensitivities.summary_rows()
        width = max(len(n) for n, _ in rows)
        return "\n".join(["OcpResult", *(f"  {n:<{width}}  {v}" for n, v in rows)])

    def open_dynamics(self) -> str:
        """Why an iterate with open dynamics gaps is no plan, in words."""
        return (
            f"the dynamics gaps stay open, up to {self.dynamics_gap:.3g} (scaled): the states "
            "do not follow Φ, so the altitude, drift and energy of this iterate are no results"
        )

    def __repr__(self) -> str:
        achieved = (
            f"laser energy {self.laser_energy:.1f} J, "
            f"final altitude {float(self.state('r_L')[-1, 2]):.3f} m"
            if self.dynamics_closed
            else f"no flyable plan (dynamics gap {self.dynamics_gap:.3g})"
        )
        return (
            f"<OcpResult {self.status.value}: cost {self.cost:.6g}, {self.iterations} "
            f"iterations, {self.horizon} pulses, {achieved}>"
        )
