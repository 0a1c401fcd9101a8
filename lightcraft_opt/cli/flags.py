"""Flags shared by several commands, each with its range and the reason for it."""

from __future__ import annotations

from lightcraft_opt.cli.args import integer, real
from lightcraft_opt.model.checks import MAX_DURATION
from lightcraft_opt.model.limits import MAX_WIND_SPEED, WHY_MAX_WIND_SPEED
from lightcraft_opt.ocp.problem import MAX_HORIZON

# The ranges of the numeric flags, each with its reason (cli/args.py).
DURATION = real(
    0.0,
    MAX_DURATION,
    low_open=True,
    unit="s",
    why="an hour at most: a lightcraft flight lasts seconds",
)


WIND_SPEED = real(0.0, MAX_WIND_SPEED, unit="m/s", why=WHY_MAX_WIND_SPEED)


LAUNCH_SPEED = real(
    -340.0, 340.0, unit="m/s", why="below the speed of sound: the aerodynamics are subsonic"
)


TILT = real(
    0.0,
    90.0,
    high_open=True,
    unit="deg",
    why="the angle of the axis from the vertical; --tilt-azimuth-deg sets where it leans",
)


OFFSET = real(
    -1000.0, 1000.0, unit="cm", why="10 m from the beam axis at most: beyond, the beam cannot reach"
)


DROPOUT = real(0.0, 1.0, why="a probability (at 1 no pulse fires: status never_fired)")


SEED = integer(0, why="numpy seeds are non-negative")


HORIZON = integer(
    1, MAX_HORIZON, why=f"{MAX_HORIZON} pulses: 200 s at 26 Hz, ten times the longest flight"
)


TIME_LIMIT = real(0.0, 86400.0, low_open=True, unit="s", why="a day at most")


BUDGET_MS = real(
    0.0, 60000.0, low_open=True, unit="ms", why="a minute at most; a pulse leaves 38 ms"
)


RUNS = integer(1, 1_000_000, why="the summary reads every run's row into memory")

#: What a command says when its solver stopped at its iteration limit.
ITERATION_LIMIT = "iteration limit ({n}) reached: not converged; run again with a larger --max-iter"


#: Help of --animate (simulate, closed-loop).
ANIMATE_HELP = (
    "also write flight.gif: the flight animated, at most 120 frames (the path, the craft's "
    "body axis b1 and the beam the laser last fired, with the time); drawing it takes "
    "seconds to a minute"
)
