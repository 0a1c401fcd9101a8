"""Memory stays flat over long closed loops: the loop, the controllers and the caches
behind them keep nothing from one flight to the next.

Reference: the memory a flight needs is handed back when the flight is over. A short
flight (1 s, 26 pulses) is flown again and again by the same controller (its plan and
warm starts reset before each flight, its Functions and QP workspace reused), the results
dropped. After three flights to warm up, two counts must not grow:

- the bytes malloc has handed out and not had back (glibc's mallinfo2: what casadi's C++,
  HPIPM and numpy's buffers hold). The resident size (/proc/self/statm) is no measure
  here: it stayed flat even with every result kept, their bytes fitting in heap freed by
  the flights before;
- the objects the garbage collector tracks (what Python code keeps).

One thing is held on purpose: the keys of the QP's stats. casadi interns each key of the
dict it hands back, and a key no live string holds is added to CPython's table of interned
strings and dropped again on every solve; that churn grows the table once, by about 1 MB,
at a solve set by how many strings the imported packages interned (the MPC's loop,
measured: 0.96 MB at its 21st flight after warm-up when python-control is not imported,
nothing in 40 flights when it is). Holding one set of keys keeps the table still; a leak
still shows.

Bounds, from what a leak would add: a result kept each flight adds 17 KB or more of
malloc a flight (0.38 MB over the MPC's loop, 0.2 to 2 MB over the director's, measured)
and 4 to 5 tracked objects; the bounds are 128 KB over the loop, which a C leak of 500 B
a pulse would also cross, and 10 objects. Measured growth on a flat loop: -16 to 0
bytes and -1 to 0 objects. The models are small (2 x 8 optic, 4 substeps), so the 676
controller steps take about 3 s.
"""

from __future__ import annotations

import ctypes
import gc
import math
from collections.abc import Callable
from dataclasses import replace

import pytest
from support.models import coarse_optic
from support.paths import MODELS

from lightcraft_opt.control.closed_loop import closed_loop
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.options import DirectorOptions, MpcOptions
from lightcraft_opt.control.prediction_model import coning_model
from lightcraft_opt.control.result import ClosedLoopResult, ControllerStatus
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import STATE, RcsProfile, initial_state
from lightcraft_opt.linear.operating_points import pulse_map_jacobian
from lightcraft_opt.model import BeamSizeModel
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

MALLOC_GROWTH = 128 << 10  # bytes (module docstring)
OBJECT_GROWTH = 10
WARM_UP = 3


class _Mallinfo2(ctypes.Structure):
    """glibc's ``struct mallinfo2`` (malloc.h), all ``size_t``."""

    _fields_ = [
        (name, ctypes.c_size_t)
        for name in (
            "arena", "ordblks", "smblks", "hblks", "hblkhd",
            "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost",
        )
    ]  # fmt: skip


_LIBC = ctypes.CDLL(None)
_MALLINFO2 = getattr(_LIBC, "mallinfo2", None)
pytestmark = pytest.mark.skipif(_MALLINFO2 is None, reason="needs glibc 2.33+ (mallinfo2)")


def _malloc_in_use() -> int:
    """Bytes malloc has handed out and not had back: heap chunks and mmapped ones."""
    assert _MALLINFO2 is not None
    _MALLINFO2.restype = _Mallinfo2
    info = _MALLINFO2()
    return int(info.uordblks + info.hblkhd)


def _mpc_flight() -> tuple[Callable[[], ClosedLoopResult], MpcController | DirectorController]:
    """The nutation MPC on Flight 5 with RCS, from 3 degrees of coning on the pad."""
    model = coarse_optic(load_model(MODELS / "flight5-rcs.toml"))
    options = PulseMapOptions(rcs_profile=RcsProfile.PHASE_LOCKED, substeps=4, dense=2)
    phi = build_pulse_map(model, options)
    spin = model.craft.spin
    grid = dict(spins=[0.9 * spin, spin], altitudes=[0.0, 2.0, 10.0], speeds=[0.0, 5.0, 8.0])
    prediction = coning_model(model, pulse_map=pulse_map_jacobian(phi), **grid)
    mpc = MpcController(model, MpcOptions(time_budget=None), prediction=prediction)
    craft = model.craft
    w_t = craft.inertia_axial * spin * math.tan(math.radians(3.0)) / craft.inertia_transverse
    x0 = initial_state(model, w_B=(0.0, w_t, 0.0))
    return (lambda: closed_loop(model, mpc, 1.0, x0=x0, pulse_map=phi)), mpc


def _director_flight() -> tuple[Callable[[], ClosedLoopResult], MpcController | DirectorController]:
    """The director on Flight 5 under the waist beam, launched 3 cm off the pad axis."""
    model = coarse_optic(load_model(MODELS / "flight5.toml"))
    model = replace(model, laser=replace(model.laser, size_model=BeamSizeModel.WAIST))
    phi = build_pulse_map(model, PulseMapOptions(substeps=4, dense=2))
    director = DirectorController(
        model, phi.inputs, DirectorOptions(time_budget=None), compiled=False
    )
    x0 = initial_state(model).copy()
    x0[STATE.slot("r_L").start] = 0.03
    return (lambda: closed_loop(model, director, 1.0, x0=x0, pulse_map=phi)), director


@pytest.mark.parametrize(
    ("make", "flights"), [(_mpc_flight, 24), (_director_flight, 12)], ids=["mpc", "director"]
)
def test_memory_stays_flat_over_hundreds_of_closed_loop_steps(make, flights):
    fly, controller = make()
    for _ in range(WARM_UP):
        fly()
    # module docstring: the MPC reads the stats of its step Function; the director's QP runs
    # inside its step Function, which hands back no stats dict to churn the table
    held_keys = list(controller.solver_stats()) if isinstance(controller, MpcController) else []
    gc.collect()
    in_use, objects = _malloc_in_use(), len(gc.get_objects())
    steps = 0
    for _ in range(flights):
        result = fly()
        assert all(s is ControllerStatus.SOLVED for s in result.log.status)
        steps += len(result.log.status)
        del result
    gc.collect()
    assert steps == 26 * flights
    grown = _malloc_in_use() - in_use
    kept = len(gc.get_objects()) - objects
    del held_keys  # held until both counts are taken
    assert grown <= MALLOC_GROWTH, f"{grown} bytes more in use after {steps} steps"
    assert kept <= OBJECT_GROWTH, f"{kept} more objects tracked after {flights} flights"
