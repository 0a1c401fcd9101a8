"""Reading a run folder back into its result (the edge): :func:`load_result`.

A folder written by :meth:`~lightcraft_opt.presenters.Presentable.save` or by the CLI
holds result.json and result.npz (:mod:`.result_archive`): the result comes back exactly.
Without them: a campaign folder (campaign.json, runs.csv, summary.json) gives its
:class:`~lightcraft_opt.campaign.runner.CampaignResult`; a flight folder (trajectory.csv,
pulses.csv, summary.json of ``lightcraft simulate``) its
:class:`~lightcraft_opt.simulation.result.SimulationResult`, to the files' 12 significant
digits, without the angular momentum and kinetic energy (not in the CSV) and with the
pulse inputs of pulses.csv only (pointing, focus, energy: no RCS inputs).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.campaign.run_table import read_table
from lightcraft_opt.campaign.runner import MANIFEST, RUNS, SUMMARY, CampaignResult
from lightcraft_opt.errors import LightcraftError
from lightcraft_opt.files.result_archive import ARCHIVE_JSON, read_archive
from lightcraft_opt.files.simulation_outputs import PULSE_COLUMNS, TRAJECTORY_COLUMNS
from lightcraft_opt.layout import PULSE_INPUT, STATE
from lightcraft_opt.simulation.result import PulseRecord, SimulationResult, SimulationStatus

__all__ = ["load_result"]


def load_result(folder: str | Path) -> Any:
    """The result a run folder holds (module docstring): a SimulationResult,
    ClosedLoopResult, OcpResult, CalibrationResult or CampaignResult.

    Raises
    ------
    LightcraftError : the folder holds no result this function reads, naming what it
        looked for.
    """
    where = Path(folder)
    if (where / ARCHIVE_JSON).is_file():
        return read_archive(where)
    if (where / MANIFEST).is_file() and (where / RUNS).is_file():
        return _campaign(where)
    if (where / "trajectory.csv").is_file() and (where / "summary.json").is_file():
        return _flight(where)
    raise LightcraftError(
        f"{where}: no result to load: expected {ARCHIVE_JSON} (written by save() and the "
        f"CLI), a campaign's {MANIFEST} and {RUNS}, or a flight's trajectory.csv and "
        "summary.json"
    )


def _json(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise LightcraftError(f"{path}: cannot read it: {err}") from err
    if not isinstance(data, dict):
        raise LightcraftError(f"{path}: not a JSON object")
    return data


def _csv(path: Path, columns: tuple[str, ...]) -> np.ndarray:
    """The rows of ``path`` (n, len(columns)), its header checked."""
    try:
        header = path.read_text(encoding="utf-8").split("\n", 1)[0].strip().split(",")
        rows = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError) as err:
        raise LightcraftError(f"{path}: cannot read it: {err}") from err
    if tuple(header[: len(columns)]) != columns:
        raise LightcraftError(
            f"{path}: header is not {','.join(columns)} (a folder written before its columns "
            "were renamed, e.g. w1_radps to w1_rad_per_s, pulses to engine_load: run it again)"
        )
    return rows.reshape(-1, len(header))


def _flight(where: Path) -> SimulationResult:
    summary = _json(where / "summary.json")
    traj = _csv(where / "trajectory.csv", TRAJECTORY_COLUMNS)
    col = {name: i for i, name in enumerate(TRAJECTORY_COLUMNS)}
    pulses = None
    if (where / "pulses.csv").is_file():
        rows = _csv(where / "pulses.csv", PULSE_COLUMNS[:17])
        pc = {name: i for i, name in enumerate(PULSE_COLUMNS)}
        u = np.zeros((len(rows), PULSE_INPUT.size))
        u[:, PULSE_INPUT.slot("pointing_L").start : PULSE_INPUT.slot("pointing_L").stop] = rows[
            :, [pc["pointing_x_m"], pc["pointing_y_m"]]
        ]
        u[:, PULSE_INPUT.slot("focus").start] = rows[:, pc["focus_m"]]
        u[:, PULSE_INPUT.slot("energy").start] = rows[:, pc["energy_j"]]
        gap = rows[:, pc["beam_gap_m"]] if rows.shape[1] > pc["beam_gap_m"] else None
        pulses = PulseRecord(
            t=rows[:, pc["t_s"]],
            u=u,
            engine=rows[:, pc["energy_captured_j"] : pc["health"] + 1],
            beam_gap=gap,
        )
    return SimulationResult(
        model_name=str(summary.get("model", "")),
        t=traj[:, col["t_s"]],
        x=traj[:, col["x_m"] : col["x_m"] + STATE.size],
        status=SimulationStatus(summary["status"]),
        message=str(summary.get("message", "")),
        tilt=np.radians(traj[:, col["tilt_deg"]]),
        coning=np.radians(traj[:, col["coning_deg"]]),
        mass=traj[:, col["mass_kg"]],
        pulses=pulses,
    )


def _campaign(where: Path) -> CampaignResult:
    manifest = _json(where / MANIFEST)
    table = read_table(where / RUNS)
    runs = int(manifest.get("runs", 0))
    done = set(np.asarray(table.get("run", np.empty(0)), dtype=int).tolist())
    summary = _json(where / SUMMARY) if (where / SUMMARY).is_file() else {}
    return CampaignResult(
        out_dir=where,
        runs=runs,
        made=0,
        skipped=len(done),
        complete=all(i in done for i in range(runs)),
        table=table,
        summary=summary,
        engine="",
        elapsed=math.nan,
    )
