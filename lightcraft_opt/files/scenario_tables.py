"""The ``[scenarios]`` table of a problem file: the cases a robust design must serve (edge).

Drawn cases (docs/design.md#robust-design, docs/files/problem.md#keys-scenarios)::

    [scenarios]
    objective = "expected"          # or "worst"
    shared_pulses = 10              # the first pulses fire the same inputs in every case
    count = 8                       # S drawn cases, the first the nominal one
    seed = 1
    wind_speed_spread_mps = 1.0
    wind_direction_spread_deg = 20.0
    offset_spread_mm = 5.0
    tilt_spread_deg = 1.0
    impulse_spread = 0.05           # relative spread of the coupling (impulse per pulse)
    dropout_probability = 0.02

or named cases, one ``[[scenarios.case]]`` each (``count`` and the spreads then absent)::

    [[scenarios.case]]
    name = "gust"
    weight = 1.0
    wind_speed_mps = 5.0
    wind_direction_from_deg = 90.0
    offset_L_mm = [5.0, 0.0]
    tilt_deg = 1.0
    tilt_azimuth_deg = 90.0
    impulse_scale = 0.9
    dropouts = [3, 17]

Values are converted to SI here (ocp/scenarios.py takes SI).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from lightcraft_opt.errors import ParameterError, ProblemFileError
from lightcraft_opt.files.problem_tables import BLOCKS, Table, read_table
from lightcraft_opt.files.schema import INTEGER, NUMBER, TEXT, Spec, choice, join_key, quantity
from lightcraft_opt.ocp.scenarios import (
    Scenario,
    ScenarioDraws,
    ScenarioObjective,
    Scenarios,
    draw_scenarios,
)

__all__ = ["SCENARIOS_TABLE", "SCENARIO_CASE_TABLE", "read_scenarios", "scenario_key"]

#: The keys of ``[scenarios]`` (docs/files/problem.md#keys-scenarios).
SCENARIOS_TABLE: Mapping[str, Spec] = {
    "objective": choice(ScenarioObjective),
    "shared_pulses": INTEGER,
    "count": INTEGER,
    "seed": INTEGER,
    "wind_speed_spread": quantity("speed"),
    "wind_direction_spread": quantity("angle"),
    "offset_spread": quantity("length"),
    "tilt_spread": quantity("angle"),
    "impulse_spread": NUMBER,
    "dropout_probability": NUMBER,
}
#: The keys of a ``[[scenarios.case]]`` (docs/files/problem.md#keys-scenarios-case).
SCENARIO_CASE_TABLE: Mapping[str, Spec] = {
    "name": TEXT,
    "weight": NUMBER,
    "wind_speed": quantity("speed"),
    "wind_direction_from": quantity("angle"),
    "offset_L": quantity("length", "list", 2),
    "tilt": quantity("angle"),
    "tilt_azimuth": quantity("angle"),
    "impulse_scale": NUMBER,
    "dropouts": BLOCKS,
}
#: ``[scenarios]`` field -> ScenarioDraws field.
_DRAWS = {
    "count": "count",
    "seed": "seed",
    "wind_speed_spread": "wind_speed",
    "wind_direction_spread": "wind_direction",
    "offset_spread": "offset",
    "tilt_spread": "tilt",
    "impulse_spread": "impulse",
    "dropout_probability": "dropout_probability",
}


def read_scenarios(src: str, raw: Any, p: np.ndarray, horizon: int) -> Scenarios | None:
    """The ``[scenarios]`` table ``raw`` of the problem file ``src`` (None when absent) as
    Scenarios in SI, drawn about the problem's parameters ``p`` for ``horizon`` pulses."""
    if raw is None:
        return None
    table = read_table(src, raw, "scenarios", SCENARIOS_TABLE, tables=("case",))
    v = table.values
    cases_raw = raw.get("case", [])
    if not isinstance(cases_raw, list) or not all(isinstance(c, dict) for c in cases_raw):
        raise ProblemFileError(
            src, "scenarios.case", "must be an array of tables [[scenarios.case]]"
        )
    drawn = [f for f in _DRAWS if f in v]
    if cases_raw and drawn:
        raise ProblemFileError(
            src,
            table.key(drawn[0]),
            "give either drawn scenarios (count and spreads) or [[scenarios.case]] tables",
        )
    if not cases_raw and "count" not in v:
        raise ProblemFileError(
            src, "scenarios.count", "missing: give count (drawn) or [[scenarios.case]] tables"
        )
    objective = v.get("objective", ScenarioObjective.EXPECTED)
    shared = v.get("shared_pulses", 0)
    try:
        if cases_raw:
            cases = tuple(_case(src, c, i) for i, c in enumerate(cases_raw))
            return Scenarios(cases, objective, shared)
        draws = ScenarioDraws(**{_DRAWS[f]: v[f] for f in drawn})
        return draw_scenarios(draws, p, horizon, objective=objective, shared_pulses=shared)
    except ParameterError as err:
        raise ProblemFileError(src, _file_key(err.field, table), err.reason) from err


def _case(src: str, raw: Mapping[str, Any], i: int) -> Scenario:
    where = f"scenarios.case[{i}]"
    t = read_table(src, raw, where, SCENARIO_CASE_TABLE, required=("name",))
    v = t.values
    parameters = {
        slot: v[field]
        for field, slot in (
            ("wind_speed", "wind_speed_ref"),
            ("wind_direction_from", "wind_direction_from"),
        )
        if field in v
    }
    dropouts = v.get("dropouts", ())
    try:
        return Scenario(
            v["name"],
            v.get("weight", 1.0),
            parameters=parameters,
            scales={"impulse_per_pulse": v["impulse_scale"]} if "impulse_scale" in v else {},
            offset_L=v.get("offset_L", (0.0, 0.0)),
            tilt=v.get("tilt", 0.0),
            tilt_azimuth=v.get("tilt_azimuth", 0.0),
            dropouts=dropouts if isinstance(dropouts, tuple) else (dropouts,),
        )
    except ParameterError as err:
        raise ProblemFileError(src, _case_key(err.field, t), err.reason) from err


def _case_key(field: str, table: Table) -> str:
    """A Scenario field (``scenarios[gust].tilt``) as the case table wrote it."""
    attr = field.rpartition(".")[2]
    attr = {
        "wind_speed_ref": "wind_speed",
        "impulse_per_pulse": "impulse_scale",
        "scenario": "name",
    }.get(attr, attr)
    return table.key(attr) if attr in table.keys or attr in SCENARIO_CASE_TABLE else table.where


def _file_key(field: str, table: Table) -> str:
    """A Scenarios or ScenarioDraws field (``scenarios.count``, ``scenarios.tilt``) or a
    scenario's (``scenarios[draw 3].dropouts``) as the file wrote it."""
    attr = field.rpartition(".")[2]
    back = {d: f for f, d in _DRAWS.items()}
    attr = back.get(attr, attr)
    if attr in SCENARIOS_TABLE:
        return table.key(attr)
    if attr == "cases":
        return "scenarios.case"
    return join_key("scenarios", field.partition(".")[2]) if "." in field else "scenarios"


def scenario_key(field: str, scenarios: Scenarios | None) -> str:
    """A problem's error field about a scenario (``scenarios[gust].dropouts``) as the file
    wrote it (``scenarios.case[2].dropouts``); other fields as they are."""
    if scenarios is None or not field.startswith("scenarios["):
        return field
    name, _, rest = field[len("scenarios[") :].partition("]")
    if name in scenarios.names and not name.startswith("draw ") and name != "nominal":
        return f"scenarios.case[{scenarios.names.index(name)}]{rest}"
    return "scenarios"
