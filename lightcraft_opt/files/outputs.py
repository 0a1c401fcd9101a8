"""What each result draws and writes: the CLI's figures and files, registered with
:mod:`lightcraft_opt.presenters` so that ``result.plot()`` and ``result.save(folder)``
work from the capability layers, which never import the edges.

An edge module above files/ and plots/ (they are independent siblings, and a save writes
both); ``import lightcraft_opt`` imports it, so the registry is always filled. The plots
are imported on the first ``plot()`` or ``save()``: matplotlib takes seconds to load and
most programs never draw.

Context keywords (what a figure or a file needs beyond the result):

* SimulationResult: ``model`` (summary.json's model hash, the capture circle in
  track.png, the beam in flight.gif), ``capture_radius`` [m], ``animate`` (save writes
  flight.gif too: :mod:`lightcraft_opt.plots.animation`, seconds to a minute); other
  keywords go into summary.json (as the CLI's ``launch_speed_mps``).
* ClosedLoopResult: ``problem`` (a ClosedLoopProblem: title, file, hash, duration, the
  capture radius and the solve budget), or ``title``, ``capture_radius``, ``budget`` [s];
  ``animate`` as for a flight.
* OcpResult: ``problem``, a ProblemFile (from :func:`~lightcraft_opt.files.load_problem`)
  or an OcpProblem (then ``options`` and ``title`` may be given too): required to save.
* CalibrationResult: ``model`` (the report's model and hash), ``model_file`` (then the
  fitted model file is written too), ``track_file`` (named in the report and the fitted
  file), ``flights`` (track_fit.png's whole flights, flown by the caller:
  :func:`~lightcraft_opt.calibration.flights.fit_flights`; without them track_fit.png
  draws the fitted flight over the track's span). The plot flies nothing.
* CampaignResult: none; the campaign's files are copied from its folder.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from lightcraft_opt.calibration.result import CalibrationResult
from lightcraft_opt.campaign.runner import MANIFEST, RUNS, SUMMARY, TIMINGS, CampaignResult
from lightcraft_opt.control.result import ClosedLoopResult
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.calibration_outputs import write_calibration_report, write_fitted_model
from lightcraft_opt.files.closed_loop import ClosedLoopProblem
from lightcraft_opt.files.closed_loop_outputs import (
    steps_table,
    write_closed_loop_summary,
    write_steps_csv,
)
from lightcraft_opt.files.controller_replay import replayable, write_replay_csv
from lightcraft_opt.files.design_outputs import DESIGNED_MODEL, write_designed_model
from lightcraft_opt.files.ocp_outputs import (
    node_flight,
    solution_table,
    write_ocp_summary,
    write_solution_csv,
)
from lightcraft_opt.files.problem import ProblemFile
from lightcraft_opt.files.result_archive import write_archive
from lightcraft_opt.files.simulation_outputs import (
    pulse_table,
    trajectory_table,
    write_pulses_csv,
    write_summary,
    write_trajectory_csv,
)
from lightcraft_opt.layout import VectorLayout, parameter_values
from lightcraft_opt.model import FlightRecord, Laser, Model
from lightcraft_opt.ocp.options import OcpOptions
from lightcraft_opt.ocp.problem import OcpProblem
from lightcraft_opt.ocp.result import OcpResult
from lightcraft_opt.presenters import register
from lightcraft_opt.simulation.flight_log import beam_sides
from lightcraft_opt.simulation.result import SimulationResult

if TYPE_CHECKING:  # the plots load matplotlib: only on the first plot or save
    from lightcraft_opt.plots.figures import MeasuredTrack

__all__ = ["ANIMATION_FILE", "beam_size_of", "save_animation", "save_figures"]


def beam_size_of(laser: Laser, p: np.ndarray) -> Callable[[np.ndarray, float], np.ndarray]:
    """The beam's size [m] at altitudes z [m] for a focus [m], with a flight's parameter
    vector ``p`` (plots.flight3d's ``beam_size``)."""
    return lambda z, focus: beam_sides(z, focus, p, laser)


def save_figures(figures: Mapping[str, Any], folder: Path) -> None:
    """Save each figure as ``folder``/its name at the CLI's resolution."""
    from lightcraft_opt.plots.figures import PLOT_DPI

    for name, fig in figures.items():
        fig.savefig(folder / name, dpi=PLOT_DPI)


#: The animation save(animate=True) writes beside the figures.
ANIMATION_FILE = "flight.gif"


def save_animation(
    flight: SimulationResult, folder: Path, laser: Laser | None, p: np.ndarray | None
) -> Path:
    """flight.gif in ``folder``: the flight's animation
    (:func:`~lightcraft_opt.plots.animation.flight_animation`), with the beam each pulse
    fired when the ``laser`` and the flight's parameters ``p`` are known."""
    from lightcraft_opt.plots.animation import flight_animation, save_gif

    beam_size = None if laser is None or p is None else beam_size_of(laser, p)
    movie = flight_animation(flight, laser=laser, beam_size=beam_size)
    return save_gif(movie, folder / ANIMATION_FILE)


def _draw(figures: bool, plot: Any, folder: Path, *args: Any, **context: Any) -> None:
    """``plot(*args, **context)``'s figures saved into ``folder`` when ``figures``."""
    if figures:
        save_figures(plot(*args, **context), folder)


def _folder(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    return folder


# --------------------------------------------------------------------------- flights
def _flight_plot(
    result: SimulationResult,
    *,
    model: Model | None = None,
    capture_radius: float | None = None,
    record: FlightRecord | None = None,
    track: MeasuredTrack | None = None,
    **_: Any,
) -> dict[str, Any]:
    from lightcraft_opt.plots.figures import flight_figures

    laser, beam_size = None, None
    if model is not None:
        if capture_radius is None:
            capture_radius = model.craft.engine.capture_radius
        laser = model.laser
        beam_size = beam_size_of(laser, parameter_values(model))
    return flight_figures(
        result,
        capture_radius=capture_radius,
        record=record,
        laser=laser,
        beam_size=beam_size,
        track=track,
    )


def _flight_save(
    result: SimulationResult,
    folder: Path,
    *,
    figures: bool = True,
    model: Model | None = None,
    capture_radius: float | None = None,
    record: FlightRecord | None = None,
    track: MeasuredTrack | None = None,
    animate: bool = False,
    **extra: Any,
) -> Path:
    _folder(folder)
    if result.pulses is not None:
        write_pulses_csv(result, folder / "pulses.csv")
    write_trajectory_csv(result, folder / "trajectory.csv")
    write_summary(result, model, folder / "summary.json", **extra)
    _draw(
        figures,
        _flight_plot,
        folder,
        result,
        model=model,
        capture_radius=capture_radius,
        record=record,
        track=track,
    )
    if animate:
        p = None if model is None else parameter_values(model)
        save_animation(result, folder, None if model is None else model.laser, p)
    return folder


def _flight_tables(result: SimulationResult, **_: Any) -> dict[str, dict[str, np.ndarray]]:
    tables = {"trajectory": trajectory_table(result)}
    if result.pulses is not None:
        tables["pulses"] = pulse_table(result)
    return tables


# --------------------------------------------------------------------------- closed loops
def _loop_plot(
    result: ClosedLoopResult,
    *,
    problem: ClosedLoopProblem | None = None,
    title: str | None = None,
    capture_radius: float | None = None,
    budget: float | None = None,
    inputs: VectorLayout | None = None,
) -> dict[str, Any]:
    from lightcraft_opt.plots.closed_loop import closed_loop_figures

    laser, beam_size = None, None
    if problem is not None:
        title = problem.title if title is None else title
        if capture_radius is None:
            capture_radius = problem.model.craft.engine.capture_radius
        if budget is None:
            budgets = {"mpc": problem.mpc.time_budget, "director": problem.director.time_budget}
            budget = budgets.get(result.controller)
        laser = problem.model.laser
        beam_size = beam_size_of(laser, result.p_plant)
    return closed_loop_figures(
        result,
        title=title or "",
        capture_radius=capture_radius,
        budget=budget,
        laser=laser,
        beam_size=beam_size,
        inputs=inputs,
    )


def _loop_save(
    result: ClosedLoopResult,
    folder: Path,
    *,
    figures: bool = True,
    problem: ClosedLoopProblem | None = None,
    animate: bool = False,
    **context: Any,
) -> Path:
    _folder(folder)
    write_trajectory_csv(result.flight, folder / "trajectory.csv")
    write_pulses_csv(result.flight, folder / "pulses.csv")
    write_steps_csv(result, folder / "steps.csv")
    inputs = context.get("inputs")
    if inputs is not None and replayable(result):
        write_replay_csv([result], inputs, folder / "replay.csv")
    write_closed_loop_summary(result, problem, folder / "summary.json")
    _draw(figures, _loop_plot, folder, result, problem=problem, **context)
    if animate:
        laser = None if problem is None else problem.model.laser
        save_animation(result.flight, folder, laser, result.p_plant)
    return folder


def _loop_tables(result: ClosedLoopResult, **_: Any) -> dict[str, dict[str, np.ndarray]]:
    return {**_flight_tables(result.flight), "steps": steps_table(result)}


# --------------------------------------------------------------------------- solves
def _problem_file(
    problem: ProblemFile | OcpProblem | None, options: OcpOptions | None, title: str
) -> ProblemFile:
    if isinstance(problem, ProblemFile):
        return problem
    if isinstance(problem, OcpProblem):
        return ProblemFile(problem, options or OcpOptions(), title, Path(""))
    raise ParameterError(
        "problem",
        "OcpResult.save needs problem=: the ProblemFile (lightcraft_opt.load_problem) or "
        "the OcpProblem solved (its parameters give the tilt, mass and capture fraction)",
    )


def _ocp_plot(
    result: OcpResult,
    *,
    problem: ProblemFile | OcpProblem | None = None,
    title: str | None = None,
    **_: Any,
) -> dict[str, Any]:
    from lightcraft_opt.plots.ocp import ocp_figures

    if isinstance(problem, ProblemFile):
        title = problem.title if title is None else title
        problem = problem.problem
    nodes = node_flight(result, problem) if problem is not None else None
    return ocp_figures(result, problem, title=title or "", nodes=nodes)


def _ocp_save(
    result: OcpResult,
    folder: Path,
    *,
    figures: bool = True,
    problem: ProblemFile | OcpProblem | None = None,
    options: OcpOptions | None = None,
    title: str | None = None,
) -> Path:
    pf = _problem_file(problem, options, title or "")
    _folder(folder)
    write_solution_csv(result, pf.problem, folder / "solution.csv")
    write_ocp_summary(result, pf, folder / "summary.json")
    if result.design and result.dynamics_closed and pf.model_file is not None:
        write_designed_model(pf, result, folder / DESIGNED_MODEL)
    _draw(figures, _ocp_plot, folder, result, problem=pf, title=title)
    return folder


def _ocp_tables(
    result: OcpResult,
    *,
    problem: ProblemFile | OcpProblem | None = None,
    options: OcpOptions | None = None,
    **_: Any,
) -> dict[str, dict[str, np.ndarray]]:
    return {"solution": solution_table(result, _problem_file(problem, options, "").problem)}


# --------------------------------------------------------------------------- fits
def _fit_plot(
    result: CalibrationResult,
    *,
    flights: Mapping[str, SimulationResult] | None = None,
    **_: Any,
) -> dict[str, Any]:
    from lightcraft_opt.plots.calibration import calibration_figures

    return calibration_figures(result, flights=flights)


def _fit_save(
    result: CalibrationResult,
    folder: Path,
    *,
    figures: bool = True,
    model: Model | None = None,
    model_file: str | Path | None = None,
    track_file: str | Path | None = None,
    flights: Mapping[str, SimulationResult] | None = None,
    **extra: Any,
) -> Path:
    _folder(folder)
    if track_file is not None:
        extra = {"track_file": str(track_file), **extra}
    if model_file is not None:
        source = Path(model_file)
        fitted = write_fitted_model(
            result, source, folder / f"{source.stem}-fitted.toml", track_file=track_file
        )
        extra = {"model_file": str(source), "fitted_model_file": fitted.name, **extra}
    write_calibration_report(result, model, folder / "fit_report.json", **extra)
    _draw(figures, _fit_plot, folder, result, flights=flights)
    return folder


# --------------------------------------------------------------------------- campaigns
def _campaign_plot(result: CampaignResult, *, title: str | None = None) -> dict[str, Any]:
    from lightcraft_opt.plots.monte_carlo import monte_carlo_figures

    if title is None:
        title = str(result.summary.get("title", ""))
    return monte_carlo_figures(
        result.table,
        title=title,
        dispersed=result.dispersed,
        capture_radius=result.capture_radius,
    )


def _campaign_save(
    result: CampaignResult, folder: Path, *, figures: bool = True, **context: Any
) -> Path:
    _folder(folder)
    if folder.resolve() != Path(result.out_dir).resolve():
        for name in (MANIFEST, RUNS, TIMINGS, SUMMARY):
            if (Path(result.out_dir) / name).is_file():
                shutil.copyfile(Path(result.out_dir) / name, folder / name)
    write_archive(result, folder)
    _draw(figures, _campaign_plot, folder, result, **context)
    return folder


def _campaign_tables(result: CampaignResult, **_: Any) -> dict[str, dict[str, np.ndarray]]:
    return {"runs": result.table}


register(SimulationResult, plot=_flight_plot, save=_flight_save, tables=_flight_tables)
register(ClosedLoopResult, plot=_loop_plot, save=_loop_save, tables=_loop_tables)
register(OcpResult, plot=_ocp_plot, save=_ocp_save, tables=_ocp_tables)
register(CalibrationResult, plot=_fit_plot, save=_fit_save)
register(CampaignResult, plot=_campaign_plot, save=_campaign_save, tables=_campaign_tables)
