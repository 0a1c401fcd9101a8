"""The names of an OCP's objective terms (OcpProblem.term_names): the problem file's own
words, on the result (OcpResult.cost_term_names) and in its summary, next to each value."""

from __future__ import annotations

import dataclasses

import numpy as np
from ocp.test_ocp import lateral_problem
from support.models import table1_flight5
from support.results import made_up_solve

from lightcraft_opt.files.problem_tables import OBJECTIVES
from lightcraft_opt.layout import initial_state
from lightcraft_opt.ocp.problem import (
    OBJECTIVE_KINDS,
    ControlEffort,
    ControlRate,
    FinalAltitude,
    LaserEnergy,
    LateralOffset,
    OffsetFrom,
    TrackReference,
)


def test_each_kind_is_named_as_the_problem_file_names_it() -> None:
    """The name the problem gives a term is the file's table name for its kind."""
    problem = lateral_problem(table1_flight5())
    one_of_each = {
        LaserEnergy: LaserEnergy(),
        FinalAltitude: FinalAltitude(),
        TrackReference: TrackReference(np.zeros((problem.horizon + 1, 3))),
        LateralOffset: LateralOffset(),
        ControlEffort: ControlEffort("pointing_L"),
        ControlRate: ControlRate("pointing_L"),
    }
    assert set(one_of_each) == set(OBJECTIVE_KINDS)
    for name, kind in OBJECTIVES.items():
        term = one_of_each[kind.cls]
        (given,) = dataclasses.replace(problem, objective=(term,)).term_names()
        assert given.split("[")[0] == name


def test_repeats_are_numbered_and_slots_and_references_bracketed() -> None:
    problem = dataclasses.replace(
        lateral_problem(table1_flight5()),
        objective=(
            LateralOffset(weight=1.0, relative_to=OffsetFrom.PAD),
            ControlEffort("pointing_L", weight=1.0),
            LateralOffset(weight=2.0, relative_to=OffsetFrom.PAD),
        ),
    )
    assert problem.term_names() == (
        "lateral_offset[pad]",
        "control_effort[pointing_L]",
        "lateral_offset[pad]#2",
    )


def test_the_summary_names_each_term_with_its_value() -> None:
    model = table1_flight5()
    x = np.tile(initial_state(model), (3, 1))
    problem = lateral_problem(model)
    terms = np.array([0.25, 1.5e-3, 7.0])
    result = made_up_solve(
        x,
        np.zeros((2, problem.inputs.size)),
        problem.inputs,
        cost=float(terms.sum()),
        cost_terms=terms,
        cost_term_names=problem.term_names(),
    )
    lines = result.summary().splitlines()
    for name, value in zip(problem.term_names(), terms, strict=True):
        (line,) = [ln for ln in lines if ln.split()[0] == name]
        assert float(line.split()[1]) == value
