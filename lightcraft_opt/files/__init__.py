"""Files, the edge where units and paths live: readers named for what they describe, writers
named ``*_outputs``, and the TOML schema reader they all share.

Readers: :mod:`.model` (:func:`load_model`), :mod:`.problem` (:func:`load_problem`) over
:mod:`.problem_tables`, :mod:`.closed_loop` (:func:`load_closed_loop`), :mod:`.campaign`
(:func:`load_campaign`), :mod:`.track` (:func:`read_track`); :mod:`.schema` converts keys
with units to SI for all of them. Writers: :mod:`.simulation_outputs`, :mod:`.ocp_outputs`,
:mod:`.closed_loop_outputs`, :mod:`.calibration_outputs`; beside their summaries
:mod:`.result_archive` writes result.json and result.npz, the exact result that
:mod:`.results` (:func:`load_result`) reads back.
"""

from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.files.closed_loop import ClosedLoopProblem, load_closed_loop
from lightcraft_opt.files.model import load_laser, load_model, load_record, load_site
from lightcraft_opt.files.problem import ProblemFile, load_problem
from lightcraft_opt.files.results import load_result
from lightcraft_opt.files.track import read_track

__all__ = [
    "ClosedLoopProblem",
    "ProblemFile",
    "load_campaign",
    "load_closed_loop",
    "load_laser",
    "load_model",
    "load_problem",
    "load_record",
    "load_result",
    "load_site",
    "read_track",
]
