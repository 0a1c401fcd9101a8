"""flight.gif: a flight animated, its craft's axis and the beam over time
(plots/animation.py; issue 29, item 7).

References: the flight's own record. The drawn body axis b1 leans from the vertical by the
tilt the simulator recorded (flight_measures computes it from the state by casadi, the
animation by numpy from the quaternion); each frame's segment starts at the craft's
position at that sample; the beam drawn is the last pulse fired by then, its edge a ring
at that pulse's altitude (flight3d.fired_beam); the GIF holds one image per frame. Every
line stays inside its axes.
"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from support.figure_checks import display_points, drawn
from support.paths import REPO_ROOT

import lightcraft_opt as lc
from lightcraft_opt.cli import main
from lightcraft_opt.control.result import (
    ClosedLoopResult,
    ControllerLog,
    ControllerStatus,
    StepStats,
)
from lightcraft_opt.files.outputs import beam_size_of
from lightcraft_opt.layout import parameter_values
from lightcraft_opt.plots.animation import (
    MAX_FRAMES,
    animation_fps,
    body_axis_L,
    flight_animation,
    frame_samples,
    save_gif,
)
from lightcraft_opt.plots.flight3d import OUTLINE_POINTS

MODEL = REPO_ROOT / "models" / "flight5.toml"
FRAMES = 12


@pytest.fixture(scope="module")
def model() -> lc.Model:
    return lc.load_model(MODEL)


@pytest.fixture(scope="module")
def flight(model):
    """0.3 s of Flight 5 launched tilted 5 degrees, so that b1 leans."""
    x0 = lc.initial_state(model, tilt=np.radians(5.0), tilt_azimuth=np.radians(30.0))
    return lc.simulate(model, 0.3, x0=x0, compiled=False)


@pytest.fixture(scope="module")
def movie(flight, model):
    beam_size = beam_size_of(model.laser, parameter_values(model))
    return flight_animation(flight, laser=model.laser, beam_size=beam_size, max_frames=FRAMES)


def test_the_drawn_axis_leans_by_the_recorded_tilt(flight):
    b1 = body_axis_L(flight)
    assert np.allclose(np.linalg.norm(b1, axis=1), 1.0, atol=1e-12)
    assert np.allclose(np.arccos(np.clip(b1[:, 2], -1, 1)), flight.tilt, atol=1e-9)
    assert flight.tilt.max() > np.radians(4.0)  # it does lean


def test_frames_are_at_most_max_frames_first_and_last_included():
    assert list(frame_samples(5, 10)) == [0, 1, 2, 3, 4]
    picked = frame_samples(1000)
    assert len(picked) == MAX_FRAMES and picked[0] == 0 and picked[-1] == 999
    assert animation_fps(np.linspace(0.0, 10.0, 101)) == pytest.approx(10.0)  # flight time
    assert animation_fps(np.linspace(0.0, 0.1, 50)) == 25.0  # as fast as a GIF plays well


def test_each_frame_draws_the_craft_its_axis_and_the_last_beam_inside_the_axes(movie, flight):
    assert len(movie.samples) == FRAMES
    r = flight.state("r_L")
    ax = movie.figure.axes[0]
    update = movie.animation._func  # the frame function FuncAnimation calls
    pulses = flight.pulses.t
    for frame in (0, FRAMES // 2, FRAMES - 1):
        update(frame)
        i = movie.samples[frame]
        renderer = drawn(movie.figure)
        box = ax.get_window_extent(renderer)
        x, y, z = movie.artists["axis"].get_data_3d()
        assert np.allclose([x[0], y[0], z[0]], r[i])  # from the craft
        assert np.allclose(movie.artists["craft"].get_data_3d(), r[i][:, None])
        east, _, zs = movie.artists["beam_edge"].get_data_3d()
        fired = pulses[pulses <= flight.t[i]]
        assert len(east) == (OUTLINE_POINTS if len(fired) else 0)
        if len(fired):  # at the last pulse's altitude
            assert np.allclose(zs, np.interp(fired[-1], flight.t, r[:, 2]))
        assert f"t = {flight.t[i]:.2f} s" in movie.artists["clock"].get_text()
        for name in ("path", "craft", "axis", "beam_edge", "beam_axis"):
            points = display_points(movie.artists[name])
            assert len(points) > 0 or name.startswith("beam"), name
            inside = (
                (points[:, 0] >= box.x0 - 1)
                & (points[:, 0] <= box.x1 + 1)
                & (points[:, 1] >= box.y0 - 1)
                & (points[:, 1] <= box.y1 + 1)
            )
            assert inside.all(), (name, frame)


def test_the_gif_has_one_image_a_frame(movie, tmp_path):
    path = save_gif(movie, tmp_path / "flight.gif", dpi=40)
    with Image.open(path) as gif:
        assert gif.n_frames == FRAMES


def test_simulate_animate_writes_flight_gif(tmp_path):
    out = tmp_path / "run"
    argv = ["simulate", str(MODEL), "--duration", "0.05", "--interpreted", "--animate"]
    assert main([*argv, "--out", str(out)]) == 0
    with Image.open(out / "flight.gif") as gif:
        assert gif.n_frames >= 2


def test_a_closed_loop_saved_with_animate_writes_flight_gif(flight, tmp_path):
    k = len(flight.pulses.t)
    looped = ClosedLoopResult(
        flight=flight,
        log=ControllerLog.of("none", [StepStats(ControllerStatus.SOLVED)] * k),
        pulse_t=flight.pulses.t,
        coning=np.zeros(k + 1),
        tilt=np.zeros(k + 1),
        offset=np.zeros(k),
        rcs_used=np.zeros(k + 1),
        commanded=flight.pulses.u,
        dropped=np.zeros(k, bool),
        p_plant=np.zeros(0),
    )
    folder = looped.save(tmp_path / "loop", figures=False, animate=True)
    with Image.open(folder / "flight.gif") as gif:
        assert gif.n_frames == min(len(flight.t), MAX_FRAMES)
