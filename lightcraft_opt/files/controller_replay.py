"""replay.csv: what a closed loop told its controller and what the controller answered, to the
last bit, for replaying its steps elsewhere (the exported C controller's test program,
files/controller_export.py; docs/director.md#exported-c).

One row per pulse: ``flight`` (flights of one file, the controller's memory reset between
them), ``k``, ``t_s`` (the pulse time [s]), ``use`` (how the step ended: 0 solved, its first
outputs; 1 the fallback, a failed or an injected failed solve; 2 a late solve, the step's
fallback outputs), then the state the controller was told (trajectory.csv's state columns,
``x_m`` ... ``engine_load``: L and B frames, SI) and the map input it returned (pulses.csv's and
solution.csv's input columns, ``pointing_x_m`` ...; docs/outputs.md). Every number is written
with 17 significant digits, which reads back to the same double.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from lightcraft_opt.control.result import ClosedLoopResult, ControllerStatus
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.ocp_outputs import input_columns
from lightcraft_opt.files.plan import STATE_COLUMNS
from lightcraft_opt.layout import STATE, VectorLayout

__all__ = ["STEP_USE", "read_replay", "replay_columns", "replayable", "write_replay_csv"]

#: ``use`` of each status (module docstring).
STEP_USE = {
    ControllerStatus.SOLVED: 0,
    ControllerStatus.FALLBACK_FAILED: 1,
    ControllerStatus.FALLBACK_LATE: 2,
}


def replay_columns(inputs: VectorLayout) -> list[str]:
    """replay.csv's header for a plant with map-input layout ``inputs``."""
    return ["flight", "k", "t_s", "use", *STATE_COLUMNS, *input_columns(inputs)]


def replayable(result: ClosedLoopResult) -> bool:
    """Whether ``result``'s controller was told a state every pulse and ended every step in
    a status a replay repeats (a step Function's: solved or a fallback)."""
    n = result.pulses_commanded
    return result.told.shape == (n, STATE.size) and all(
        s in STEP_USE for s in result.log.status[:n]
    )


def write_replay_csv(results: Sequence[ClosedLoopResult], inputs: VectorLayout, path: Path) -> Path:
    """``results`` (flights of one controller, in order) as replay.csv at ``path``. Raises
    ParameterError for a flight whose controller was told nothing (an open loop) or ended a
    step in a status a replay cannot repeat."""
    lines = [",".join(replay_columns(inputs))]
    for f, result in enumerate(results):
        n = result.pulses_commanded
        if result.told.shape != (n, STATE.size):
            raise ParameterError("result", "an open loop told its controller nothing to replay")
        for k in range(n):
            status = result.log.status[k]
            if status not in STEP_USE:
                raise ParameterError("result", f"pulse {k}: a {status.value} step has no replay")
            row = [f, k, float(result.pulse_t[k]), STEP_USE[status]]
            values = np.r_[result.told[k], result.commanded[k]]
            lines.append(
                ",".join([*(str(v) for v in row[:2]), repr(row[2]), str(row[3])])
                + ","
                + ",".join(f"{v:.17g}" for v in values)
            )
    path.write_text("\n".join(lines) + "\n")
    return path


def read_replay(path: Path) -> dict[str, np.ndarray]:
    """replay.csv back: ``flight``, ``k``, ``use`` (n,) integers, ``t`` (n,), ``x`` (n,
    STATE.size), ``u`` (n, map-input size)."""
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    nx = STATE.size
    return {
        "flight": table[:, 0].astype(int),
        "k": table[:, 1].astype(int),
        "t": table[:, 2],
        "use": table[:, 3].astype(int),
        "x": table[:, 4 : 4 + nx],
        "u": table[:, 4 + nx :],
    }
