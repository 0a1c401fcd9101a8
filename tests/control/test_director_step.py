"""The director's step as one casadi Function (control/director_step.py) against the director
as it stepped in Python before (tests/support/reference_director.py): both are told the same
measured state every pulse of a closed loop on the full map Φ (noise, drop-outs, a crosswind,
injected faults), the reference's input flies, and the two inputs, statuses, plans and
disturbance estimates must agree to 1e-9 (relative). Faults long enough to use the plan up
exercise the fallback to the beam on the craft and the cold start after it; Flight 5 with RCS
exercises the torque's allocation to held thrusts inside the Function.

Model: Flight 5 under the waist beam model (docs/beam_riding.md), interpreted Functions, a
short horizon so that the flights stay quick.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass, field, replace

import numpy as np
import pytest
from support.paths import REPO_ROOT
from support.reference_director import ReferenceDirector

from lightcraft_opt.control.closed_loop import closed_loop
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.director_step import DIRECTOR_DIAGNOSTICS
from lightcraft_opt.control.options import (
    ClosedLoopOptions,
    ControllerFault,
    DirectorOptions,
    MeasurementNoise,
)
from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import STATE, initial_state
from lightcraft_opt.model import BeamSizeModel
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

RTOL = 1e-9
OPTIONS = DirectorOptions(horizon=5, relinearize=3, time_budget=None)


def _waist(name: str):
    m = load_model(REPO_ROOT / "models" / name)
    return replace(m, laser=replace(m.laser, size_model=BeamSizeModel.WAIST))


@dataclass
class Twin:
    """A controller that steps the Function's director and the reference on the same
    measured state, flies the reference's input and records both."""

    function: DirectorController
    reference: ReferenceDirector
    name: str = "director"
    last: StepStats = field(default_factory=lambda: StepStats(ControllerStatus.SOLVED))
    pairs: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)
    statuses: list[tuple[ControllerStatus, ControllerStatus]] = field(default_factory=list)
    plans: list[tuple[object, object]] = field(default_factory=list)
    disturbances: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)

    def reset(self) -> None:
        self.function.reset()
        self.reference.reset()

    def step(self, x, t=0.0, *, fault=None):  # type: ignore[no-untyped-def]
        u_ref = self.reference.step(x, t, fault=fault)
        u_fun = self.function.step(x, t, fault=fault)
        self.pairs.append((u_fun, u_ref))
        self.statuses.append((self.function.last.status, self.reference.last.status))
        self.plans.append((self.function.plan, self.reference.plan))
        self.disturbances.append((self.function.disturbance, self.reference.disturbance.copy()))
        self.last = self.reference.last
        return u_ref


def _close(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.allclose(a, b, rtol=RTOL, atol=RTOL * max(1.0, float(np.max(np.abs(b))))))


def _fly(model, options: ClosedLoopOptions, duration: float, x0=None) -> Twin:
    plant = build_pulse_map(model, PulseMapOptions())
    twin = Twin(
        DirectorController(model, plant.inputs, OPTIONS, compiled=False),
        ReferenceDirector(model, plant.inputs, OPTIONS, compiled=False),
    )
    closed_loop(model, twin, duration, x0=x0, pulse_map=plant, options=options)
    return twin


def _assert_twins(twin: Twin) -> None:
    assert twin.pairs, "no pulse flown"
    for k, (a, b) in enumerate(twin.statuses):
        assert a is b, f"pulse {k}: status {a} against the reference's {b}"
    for k, (u, u_ref) in enumerate(twin.pairs):
        assert _close(u, u_ref), f"pulse {k}: input differs by {np.max(np.abs(u - u_ref)):.3g}"
    for k, (plan, plan_ref) in enumerate(twin.plans):
        assert (plan is None) == (plan_ref is None), f"pulse {k}: a plan on one side only"
        if plan is not None:
            assert _close(plan[0], plan_ref[0]) and _close(plan[1], plan_ref[1]), k
    for k, (d, d_ref) in enumerate(twin.disturbances):
        assert np.allclose(d, d_ref, rtol=RTOL, atol=1e-15), k


def test_the_step_function_flies_as_the_reference_through_wind_noise_and_dropouts():
    """Flight 5, 3 cm off the pad axis in a 3 m/s crosswind, noisy measurements and 20 %
    drop-outs (the disturbance estimate learns and skips), one second of pulses."""
    model = _waist("flight5.toml")
    wind = replace(model.environment.wind, speed_ref=3.0, direction_from=np.pi / 2)
    model = replace(model, environment=replace(model.environment, wind=wind))
    x0 = initial_state(model).copy()
    x0[STATE.slot("r_L").start] = 0.03
    noise = MeasurementNoise(position=1e-3, velocity=5e-3)
    twin = _fly(model, ClosedLoopOptions(noise=noise, dropout_rate=0.2, seed=3), 1.0, x0)
    _assert_twins(twin)
    solved = [a for a, _ in twin.statuses if a is ControllerStatus.SOLVED]
    assert len(solved) == len(twin.statuses)
    assert np.any([np.any(d != 0) for d, _ in twin.disturbances])


@pytest.mark.parametrize("fault", [ControllerFault.RAISE, ControllerFault.LATE])
def test_faults_that_use_the_plan_up_fall_back_as_the_reference(fault):
    """Faults at pulses 3-9 (seven in a row on a 5-pulse plan): the plan's inputs fly, then
    the beam on the craft; pulse 10 starts cold, and both sides agree throughout."""
    model = _waist("flight5.toml")
    options = ClosedLoopOptions(faults=tuple(range(3, 10)), fault=fault)
    twin = _fly(model, options, 0.6)
    _assert_twins(twin)
    statuses = [a for a, _ in twin.statuses]
    expected = (
        ControllerStatus.FALLBACK_FAILED
        if fault is ControllerFault.RAISE
        else ControllerStatus.FALLBACK_LATE
    )
    assert statuses[3:10] == [expected] * 7
    assert statuses[10] is ControllerStatus.SOLVED
    assert twin.plans[8][0] is None  # used up at the fifth pulse without a solve


def test_the_torque_is_allocated_inside_the_function_as_the_reference_does():
    """Flight 5 with RCS, 2 cm off the axis and leaning: the QP asks for transverse torque and
    the qrqp allocation inside the Function gives the reference's held thrusts."""
    model = _waist("flight5-rcs.toml")
    x0 = initial_state(model).copy()
    x0[STATE.slot("r_L").start] = 0.02
    twin = _fly(model, ClosedLoopOptions(), 0.4, x0)
    _assert_twins(twin)
    plant_inputs = twin.function.inputs
    thrusts = np.array([u[plant_inputs.index("rcs_thrust")] for u, _ in twin.pairs])
    assert np.any(thrusts > 0)


def test_diagnostics_layout_names_the_solve():
    assert DIRECTOR_DIAGNOSTICS.names == ("solved", "cost", "plan_age")


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs a C compiler")
def test_the_compiled_step_flies_as_the_reference(tmp_path, monkeypatch):
    """The step and its fallback compiled to C (Ψ's pieces and HPIPM inside one library
    each; a coarse 2 x 4 optic and 4 pulses of horizon keep gcc's run short) give the
    reference's inputs, faults and all."""
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(tmp_path))
    model = _waist("flight5.toml")
    options = DirectorOptions(horizon=4, relinearize=3, quadrature=(2, 4), time_budget=None)
    plant = build_pulse_map(model, PulseMapOptions(substeps=4, dense=2))
    compiled = DirectorController(model, plant.inputs, options, compiled=False, compile_step=True)
    assert compiled.functions.step.class_name() == "External"
    assert compiled.functions.fallback.class_name() == "External"
    twin = Twin(compiled, ReferenceDirector(model, plant.inputs, options, compiled=False))
    x0 = initial_state(model).copy()
    x0[STATE.slot("r_L").start] = 0.02
    loop = ClosedLoopOptions(faults=(4, 5), fault=ControllerFault.RAISE, dropout_rate=0.1, seed=2)
    closed_loop(model, twin, 0.5, x0=x0, pulse_map=plant, options=loop)
    _assert_twins(twin)
    statuses = [a for a, _ in twin.statuses]
    assert statuses[4] is statuses[5] is ControllerStatus.FALLBACK_FAILED
    assert statuses.count(ControllerStatus.SOLVED) == len(statuses) - 2
