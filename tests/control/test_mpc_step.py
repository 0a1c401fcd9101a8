"""The nutation MPC's step as one casadi Function against the Python step it replaces.

Reference: the MPC's step as it was written in Python (tests/support/reference_mpc.py, moved
there from control/mpc.py unchanged): on the same built data, told the same states, the
Function's shell (control/mpc.py) gives the same input to 1e-9 and the same status at every
pulse of closed-loop flights of problems/nutation_suppression.toml's kind (its MPC options,
5 degrees of coning on the pad, its noise, dispersion and drop-outs), with faults injected
(raise, NaN, late, the first at the first pulse, before any plan), with the plan used up by
a run of failures, and with HPIPM's iteration cap reached for real (a solve that raises
out of the Function). Measured: the same statuses, inputs equal to 1.4e-17 or closer (the
last bit of the map input's saturation; the QPs posed are the same to the bit, so HPIPM
answers alike: a 1-ulp difference in the scheduled model grew to 3e-9 in the inputs through
HPIPM at its tolerance 1e-6, before ConingModel.horizon made its powers and turns as the
Function does). The pieces are held to their numpy counterparts alone: the scheduled model
over a horizon (ConingModel.horizon) and the map input with its saturation
(ConingFrame.map_input).

The model is small (Flight 5 with RCS, a 2 x 8 optic quadrature, 4 substeps, a 2 x 3
schedule grid), so a flight of 26 pulses flown by both controllers takes about a second.
"""

from __future__ import annotations

import math
from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences
from support.models import RCS_PHASE_LOCKED_MAP, coarse_optic
from support.paths import MODELS, REPO_ROOT
from support.reference_mpc import ReferenceMpc

from lightcraft_opt.compiled.cache import compiler_version
from lightcraft_opt.control.closed_loop import closed_loop
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.mpc_qp import NutationQp
from lightcraft_opt.control.mpc_step import build_horizon, build_map_input, build_mpc_step
from lightcraft_opt.control.options import ControllerFault, MpcOptions, MpcSolver
from lightcraft_opt.control.prediction_model import ConingModel, coning_model
from lightcraft_opt.control.result import ControllerStatus, StepStats
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.model import load_model
from lightcraft_opt.linear.operating_points import pulse_map_jacobian
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map

PROBLEM = load_closed_loop(REPO_ROOT / "problems" / "nutation_suppression.toml")
RAISE, NON_FINITE, LATE = ControllerFault.RAISE, ControllerFault.NON_FINITE, ControllerFault.LATE


MODEL = coarse_optic(load_model(MODELS / "flight5-rcs.toml"))


@pytest.fixture(scope="module")
def plant() -> PulseMap:
    return build_pulse_map(MODEL, RCS_PHASE_LOCKED_MAP)


@pytest.fixture(scope="module")
def prediction(plant: PulseMap) -> ConingModel:
    spin = MODEL.craft.spin
    grid = dict(spins=[0.9 * spin, spin], altitudes=[0.0, 2.0, 10.0], speeds=[0.0, 5.0, 8.0])
    return coning_model(MODEL, pulse_map=pulse_map_jacobian(plant), **grid)


class _Twin:
    """The Function's shell flying, the reference told the same state and fault each pulse
    (its input compared, not flown); ``faults`` {pulse: fault} injected into both."""

    name = "mpc"

    def __init__(
        self, shell: MpcController, reference: ReferenceMpc, faults: dict[int, ControllerFault]
    ) -> None:
        self.shell, self.reference, self.faults = shell, reference, faults
        self.reset()

    @property
    def last(self) -> StepStats:
        return self.shell.last

    def reset(self) -> None:
        self.shell.reset()
        self.reference.reset()
        self.inputs: list[tuple[np.ndarray, np.ndarray]] = []
        self.statuses: list[tuple[ControllerStatus, ControllerStatus]] = []
        self.used_up: list[bool] = []

    def step(self, x, t=0.0, *, fault=None):  # type: ignore[no-untyped-def]
        fault = self.faults.get(len(self.inputs))
        u = self.shell.step(x, t, fault=fault)
        self.inputs.append((u, self.reference.step(x, t, fault=fault)))
        self.statuses.append((self.shell.last.status, self.reference.last.status))
        return u


def _fly(
    plant: PulseMap,
    prediction: ConingModel,
    faults: dict[int, ControllerFault],
    options: MpcOptions = PROBLEM.mpc,
) -> _Twin:
    """One second of the file's flight (its x0, noise, dispersion, drop-outs and seed) on
    the small model, flown by the shell with the reference alongside."""
    twin = _Twin(
        MpcController(MODEL, options, prediction=prediction),
        ReferenceMpc(MODEL, options, prediction),
        faults,
    )
    run = closed_loop(MODEL, twin, 1.0, x0=PROBLEM.x0, pulse_map=plant, options=PROBLEM.loop)
    assert run.pulses_commanded == len(twin.inputs)
    return twin


def _assert_same(twin: _Twin) -> None:
    shell = [s for s, _ in twin.statuses]
    assert shell == [r for _, r in twin.statuses]
    for k, (u, r) in enumerate(twin.inputs):
        np.testing.assert_allclose(u, r, rtol=1e-9, atol=1e-9, err_msg=f"pulse {k}")


FAULTS = {0: RAISE, 3: NON_FINITE, 4: LATE, 5: LATE, 9: RAISE, 14: NON_FINITE}


@pytest.mark.parametrize(
    ("faults", "fallbacks"),
    [({}, ()), (FAULTS, tuple(FAULTS)), ({k: RAISE for k in range(4, 17)}, tuple(range(4, 17)))],
    ids=["file", "faults", "used-up"],
)
def test_the_step_function_flies_the_python_step(plant, prediction, faults, fallbacks):
    """Statuses equal, inputs to 1e-9; the fallbacks where the faults are, of their kind
    (a late solve that solved is FALLBACK_LATE); a run of 13 failures uses the plan up
    (horizon 10): from the tenth on the operating input flies (RCS amplitudes zero)."""
    twin = _fly(plant, prediction, faults)
    assert len(twin.inputs) == 26
    _assert_same(twin)
    statuses = [s for s, _ in twin.statuses]
    assert [k for k, s in enumerate(statuses) if s.fallback] == list(fallbacks)
    for k, fault in faults.items():
        kind = "FALLBACK_LATE" if fault is LATE else "FALLBACK_FAILED"
        assert statuses[k] is ControllerStatus[kind]
    if fallbacks == tuple(range(4, 17)):
        cos = twin.shell.prediction.map_inputs.index("rcs_cos")
        amplitudes = [np.max(np.abs(u[cos])) for u, _ in twin.inputs]
        assert all(a > 0 for a in amplitudes[4:13])  # the plan of pulse 3, ages 1 to 9
        assert all(a == 0 for a in amplitudes[13:17])  # used up: the operating input


@pytest.mark.parametrize(
    "changed", [{"horizon": 1}, {"horizon": 3}, {"warm_start": False}], ids=["N1", "N3", "cold"]
)
def test_other_horizons_and_cold_starts_fly_the_python_step(plant, prediction, changed):
    """Horizons of 1 (no plan beyond the pulse: every fallback flies the operating input)
    and 3 (used up after three failures in a row), and every solve started cold, with
    faults at pulses 2-4, 6 and 7: the same statuses, inputs to 1e-9 (measured 1.4e-17)."""
    faults = {2: RAISE, 3: RAISE, 4: RAISE, 6: NON_FINITE, 7: LATE}
    twin = _fly(plant, prediction, faults, replace(PROBLEM.mpc, **changed))
    _assert_same(twin)
    assert [k for k, (s, _) in enumerate(twin.statuses) if s.fallback][:5] == list(faults)


@pytest.mark.parametrize("solver", [MpcSolver.OSQP, MpcSolver.IPOPT])
def test_the_other_solvers_fly_the_python_step_too(plant, prediction, solver):
    """OSQP (conic) and IPOPT (nlpsol on the QP written as an NLP) inside the step
    Function, 200 iterations at most, the faults of the file's flight above: the same
    statuses and inputs to 1e-9 as the Python step with the same solver (measured 3e-17;
    OSQP misses its tolerance at about half the pulses, IPOPT at a few, the same ones for
    both). qrqp fails at every pulse of this flight within 200 iterations (10 s), alike."""
    twin = _fly(plant, prediction, FAULTS, replace(PROBLEM.mpc, solver=solver, max_iter=200))
    assert len(twin.inputs) == 26
    _assert_same(twin)
    assert [s for s, _ in twin.statuses].count(ControllerStatus.SOLVED) >= 10


def test_solves_that_fail_raise_out_of_the_function_and_fall_back_quietly(
    plant, prediction, capsys
):
    """An iteration cap of 11 (HPIPM takes 8 to 14 here): solves that reach it fail for
    real, raise out of the step Function (error_on_fail) and fall back as the reference's
    MAX_ITER statuses do, pulse for pulse (the first pulses too, before any plan);
    casadi's print of the failed solver's inputs (kilobytes on stderr) is dropped.
    Measured: pulses 0-4 and 22 fall back, the rest solve."""
    twin = _fly(plant, prediction, {}, replace(PROBLEM.mpc, max_iter=11))
    _assert_same(twin)
    statuses = [s for s, _ in twin.statuses]
    assert statuses.count(ControllerStatus.FALLBACK_FAILED) >= 5
    assert statuses.count(ControllerStatus.SOLVED) >= 15
    assert "Input 0" not in capsys.readouterr().err


def test_a_state_with_nan_falls_back_as_the_python_step_does(prediction):
    """A told state with a NaN entry (position, rate, spin) after three solved pulses: the
    QP refuses its NaN bounds (casadi's "ill-posed" error, raised inside the Function),
    both fall back on the plan and leave the phase tracker alone (a NaN coning is not
    longer than the threshold), and the pulses after it fly as the Python step's: the same
    statuses, inputs to 1e-9."""
    shell = MpcController(MODEL, PROBLEM.mpc, prediction=prediction)
    reference = ReferenceMpc(MODEL, PROBLEM.mpc, prediction)
    x = PROBLEM.x0
    for k, bad in enumerate((None, None, None, 0, None, 11, 13, None, None)):
        told = x.copy()
        if bad is not None:
            told[bad] = np.nan
        u, r = shell.step(told, 0.04 * k), reference.step(told, 0.04 * k)
        assert shell.last.status is reference.last.status
        expected = ControllerStatus.SOLVED if bad is None else ControllerStatus.FALLBACK_FAILED
        assert shell.last.status is expected
        np.testing.assert_allclose(u, r, rtol=1e-9, atol=1e-9, err_msg=f"pulse {k}")


def test_the_step_is_a_pure_function_of_state_and_memory(plant, prediction):
    """The same (x, t, memory) twice gives the same outputs to the bit, and ``mpc_fallback``
    gives the step's own fallback outputs; the shell's memory before a flight is zeros."""
    mpc = MpcController(MODEL, PROBLEM.mpc, prediction=prediction)
    fn = mpc.functions
    assert np.array_equal(mpc.memory, np.zeros(fn.memory.size))
    x = PROBLEM.x0
    mpc.step(x)
    memory = mpc.memory.copy()
    first, again = fn.step(x, 0.04, memory), fn.step(x, 0.04, memory)
    for a, b in zip(first, again, strict=True):
        assert np.array_equal(np.asarray(a), np.asarray(b))
    u, memory_next, _ = fn.fallback(x, 0.04, memory)
    assert np.array_equal(np.asarray(u), np.asarray(first[3]))
    assert np.array_equal(np.asarray(memory_next), np.asarray(first[4]))
    assert fn.memory.get("plan_age", np.asarray(memory_next).ravel()) == 1.0


def test_horizon_function_is_the_scheduled_models_horizon(prediction):
    """ConingModel.horizon (numpy, bilinear, clamped to the grid) against the Function at
    spins and altitudes inside the grid, on its nodes and beyond both ends, with a climb,
    an expected coning and a phase correction: equal to 1e-14 of each matrix's largest
    entry (measured: to the bit). Inside a grid cell its Jacobians match central
    differences (docs/architecture.md#rule-3)."""
    N = 6
    f = build_horizon(prediction, N)
    s0 = MODEL.craft.spin
    coning = np.linspace(0.0, 0.09, N)
    for spin, alt, climb in ((0.95 * s0, 1.3, 6.0), (s0, 2.0, 0.0), (1.2 * s0, -1.0, 3.0),
                             (0.5 * s0, 12.0, 9.0)):  # fmt: skip
        omega = 1.1 * spin
        A, B = prediction.horizon(spin, omega, alt, climb, N, coning=coning, phase=0.3)
        A_f, B_f = (np.asarray(v) for v in f(spin, omega, alt, climb, coning, 0.3))
        A_side, B_side = np.concatenate(list(A), axis=1), np.concatenate(list(B), axis=1)
        assert np.max(np.abs(A_f - A_side)) <= 1e-14 * np.max(np.abs(A_side))
        assert np.max(np.abs(B_f - B_side)) <= 1e-14 * np.max(np.abs(B_side))
    args = f.mx_in()
    flat = ca.Function("mpc_horizon", args, [ca.vec(v) for v in f(*args)])  # columns
    point = [0.95 * s0, 1.1 * s0, 1.3, 6.0, coning + 0.01, 0.3]
    assert_jacobians_match_finite_differences(flat, point, scale=[1.0, 1.0, 0.1, 0.1, 0.01, 0.1])


def test_map_input_function_is_the_frames_map_input_with_its_saturation(prediction):
    """ConingFrame.map_input (numpy: the pointing turned into L, then saturated_inputs)
    against the Function, for inputs inside the limits and far outside them (pointing
    past its reach, amplitudes past half the thrust, means below their amplitude): equal to
    1e-15 (rounding). Inside the limits its Jacobians match central differences."""
    mpc = MpcController(MODEL, PROBLEM.mpc, prediction=prediction)
    f = build_map_input(mpc.frame)
    rng = np.random.default_rng(3)
    m = len(prediction.inputs)
    for scale in (0.01, 0.3, 3.0):
        for _ in range(5):
            du, yaw = scale * rng.standard_normal(m), rng.uniform(-math.pi, math.pi)
            u = mpc.frame.map_input(du, yaw)
            np.testing.assert_allclose(np.asarray(f(du, yaw)).ravel(), u, rtol=0, atol=1e-15)
    inside = np.zeros(m)
    inside[:2] = (0.01, -0.02)  # pointing [m]
    inside[2:6] = 0.1  # mean thrusts [N], amplitudes small below
    inside[6:] = 0.01 * rng.standard_normal(m - 6)
    assert_jacobians_match_finite_differences(f, [inside, 0.7], scale=[0.01, 0.1])


@pytest.mark.slow
@pytest.mark.skipif(compiler_version() is None, reason="needs a C compiler")
def test_compiled_step_is_the_interpreted_one(prediction, tmp_path, monkeypatch):
    """The step and fallback compiled to C against casadi's HPIPM and BLASFEO (~12 s of
    gcc, in a cache folder of its own) give the interpreted Functions' inputs and memory to
    the bit over six pulses from the file's start, a NaN fault among them; a compiled
    Function reports no iterations (-1)."""
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(tmp_path))
    shell = MpcController(MODEL, PROBLEM.mpc, prediction=prediction)
    compiled = MpcController(MODEL, PROBLEM.mpc, prediction=prediction, compiled=True)
    assert compiled.functions.step.class_name() == "External"
    x = PROBLEM.x0
    for k in range(6):
        fault = NON_FINITE if k == 3 else None
        u, u_c = shell.step(x, fault=fault), compiled.step(x, fault=fault)
        assert np.array_equal(u, u_c) and np.array_equal(shell.memory, compiled.memory)
        assert shell.last.status is compiled.last.status
        assert shell.last.iterations > 0 and compiled.last.iterations == -1


def test_a_qp_that_does_not_raise_on_failure_is_refused_naming_qp(prediction):
    """The step tells a failed solve by the error it raises: a QP built without
    ``error_on_fail`` would fly its last iterate as a solution."""
    mpc = MpcController(MODEL, PROBLEM.mpc, prediction=prediction)
    quiet = NutationQp(mpc.qp.data, PROBLEM.mpc.horizon, PROBLEM.mpc.solver, 30, 1e-6)
    with pytest.raises(ParameterError, match=r"^qp: must be built with error_on_fail=True"):
        build_mpc_step(prediction, mpc.frame, quiet, PROBLEM.mpc)
