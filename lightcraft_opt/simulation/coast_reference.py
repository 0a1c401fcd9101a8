"""Reference coast: the continuous model with the laser off, by variable-step CVODES.

The independent check of the pulse map's fixed-step coasts, and a ballistic-flight
simulator in its own right. It integrates interval by interval at the flight's pulse
period and finds the landing by secant steps on the integrated flow.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, input_layout, parameter_values
from lightcraft_opt.model import Model
from lightcraft_opt.model.checks import checked_duration, checked_number, checked_vector
from lightcraft_opt.simulation.flight_measures import flight_result
from lightcraft_opt.simulation.result import SimulationResult, SimulationStatus
from lightcraft_opt.symbolic.maps.coast_rhs import build_coast_rhs

__all__ = ["SimulationOptions", "coast_integrator", "simulate_coast"]


@dataclass(frozen=True)
class SimulationOptions:
    """How :func:`simulate_coast` and :func:`coast_integrator` integrate the coast (the
    pulse map's coasts are fixed-step:
    :class:`~lightcraft_opt.symbolic.maps.options.PulseMapOptions`).

    Attributes
    ----------
    rtol, atol : relative and absolute tolerances of the variable-step coast
        integrator (CVODES, Adams method with functional iteration) [-].
    samples_per_interval : dense-output rows per pulse interval (>= 1).
    stop_on_landing : end the flight when the mass centre returns below the pad.
    """

    rtol: float = 1e-9
    atol: float = 1e-11
    samples_per_interval: int = 8
    stop_on_landing: bool = True

    def __post_init__(self) -> None:
        for name in ("rtol", "atol"):
            checked_number("SimulationOptions", name, getattr(self, name), 0.0, 1.0)
        if not isinstance(self.samples_per_interval, int) or self.samples_per_interval < 1:
            raise OptionError(
                "SimulationOptions.samples_per_interval must be a positive integer, "
                f"got {self.samples_per_interval!r}"
            )


def coast_integrator(model: Model, samples: int, options: SimulationOptions) -> ca.Function:
    """CVODES over one coast of any length: ``(x0, t0, dt, u, p) -> x``.

    Time is scaled to tau in [0, 1] (t = t0 + dt tau), so one Function serves every
    interval length. Inputs: ``x0`` (state), ``t0`` (start [s]), ``dt`` (length [s]),
    ``u``, ``p``; output ``x`` of shape (STATE.size, samples): the states at
    t0 + dt k / samples, k = 1..samples.
    """
    rhs = build_coast_rhs(model)
    nu = rhs.size1_in(2)
    tau = ca.SX.sym("tau")
    x = ca.SX.sym("x", STATE.size)
    t0 = ca.SX.sym("t0")
    dt = ca.SX.sym("dt")
    u = ca.SX.sym("u", nu)
    p = ca.SX.sym("p", PARAMETERS.size)
    dae = {"t": tau, "x": x, "p": ca.vertcat(t0, dt, u, p), "ode": dt * rhs(t0 + dt * tau, x, u, p)}
    grid = [k / samples for k in range(1, samples + 1)]
    integ = ca.integrator(
        "coast_cvodes",
        "cvodes",
        dae,
        0.0,
        grid,
        {
            "abstol": options.atol,
            "reltol": options.rtol,
            "max_num_steps": 1_000_000,
            # non-stiff, oscillatory (216 Hz coning): Adams with functional iteration
            "linear_multistep_method": "adams",
            "nonlinear_solver_iteration": "functional",
        },
    )
    x0 = ca.MX.sym("x0", STATE.size)
    t0m = ca.MX.sym("t0")
    dtm = ca.MX.sym("dt")
    um = ca.MX.sym("u", nu)
    pm = ca.MX.sym("p", PARAMETERS.size)
    xf = integ(x0=x0, p=ca.vertcat(t0m, dtm, um, pm))["xf"]
    return ca.Function(
        "coast_interval", [x0, t0m, dtm, um, pm], [xf], ["x0", "t0", "dt", "u", "p"], ["x"]
    )


def _landing(
    step: ca.Function,
    x_prev: np.ndarray,
    t_prev: float,
    dt_guess: float,
    uk: np.ndarray,
    pk: np.ndarray,
) -> tuple[float, np.ndarray]:
    """Time and state where r_L[up] crosses 0 after (t_prev, x_prev), by secant steps
    on the integrated flow (not on interpolated samples)."""
    iz = STATE.slot("r_L").start + 2
    a, za = 0.0, float(x_prev[iz])
    b = dt_guess
    xb = np.asarray(step(x_prev, t_prev, b, uk, pk))[:, -1]
    for _ in range(30):
        zb = float(xb[iz])
        if abs(zb) < 1e-12 or zb == za:
            break
        a, b, za = b, b - zb * (b - a) / (zb - za), zb
        xb = np.asarray(step(x_prev, t_prev, b, uk, pk))[:, -1]
    return t_prev + b, xb


def simulate_coast(
    model: Model,
    duration: float,
    *,
    x0: Sequence[float] | np.ndarray | None = None,
    u: Sequence[float] | np.ndarray | None = None,
    p: Sequence[float] | np.ndarray | None = None,
    options: SimulationOptions | None = None,
) -> SimulationResult:
    """Coast ``model`` for ``duration`` seconds with the laser off (CVODES).

    Parameters
    ----------
    model : the craft, site and environment.
    duration : s, > 0.
    x0 : initial state (layout STATE; default :func:`initial_state`).
    u : constant continuous input (RCS thrust [N], motor torque [N m]); default zeros.
    p : parameter vector (default :func:`parameter_values` of ``model``).
    options : tolerances and output density.

    Returns
    -------
    SimulationResult with status ``landed`` (mass centre back below the pad, the last
    row interpolated to z = 0), ``duration_reached`` or ``failed`` (integrator error,
    with what was finished so far).
    """
    opts = options or SimulationOptions()
    duration = checked_duration(duration)
    craft = model.craft
    ulay = input_layout(craft.thruster_count, craft.has_carrier)
    xk = checked_vector("x0", initial_state(model) if x0 is None else x0, STATE.size)
    uk = checked_vector("u", np.zeros(ulay.size) if u is None else u, ulay.size)
    pk = checked_vector("p", parameter_values(model) if p is None else p, PARAMETERS.size)

    interval = 1.0 / model.flight.pulse_rate
    n_full = int(np.floor(duration / interval + 1e-9))
    lengths = [interval] * n_full
    if duration - n_full * interval > 1e-12:
        lengths.append(duration - n_full * interval)
    samples = opts.samples_per_interval
    step = coast_integrator(model, samples, opts)
    iz = STATE.slot("r_L").start + 2
    qs = STATE.index("q_LB")

    times = [0.0]
    states = [xk]
    status, message = SimulationStatus.DURATION_REACHED, ""
    t0 = 0.0
    for length in lengths:
        try:
            block = np.asarray(step(xk, t0, length, uk, pk)).T
        except RuntimeError as err:
            status = SimulationStatus.FAILED
            message = f"coast integrator failed at t={t0:.6g} s: {err}"
            break
        if not np.all(np.isfinite(block)):
            status, message = SimulationStatus.FAILED, f"non-finite state after t={t0:.6g} s"
            break
        tb = t0 + length * np.arange(1, samples + 1) / samples
        below = block[:, iz] < 0.0
        if opts.stop_on_landing and np.any(below):
            i = int(np.argmax(below))
            t_prev, x_prev = (times[-1], states[-1]) if i == 0 else (tb[i - 1], block[i - 1])
            times.extend(tb[:i])
            states.extend(block[:i])
            z_prev, z_next = x_prev[iz], block[i, iz]
            guess = (tb[i] - t_prev) * z_prev / (z_prev - z_next)
            t_land, x_land = _landing(step, x_prev, t_prev, guess, uk, pk)
            times.append(t_land)
            states.append(x_land)
            status = SimulationStatus.LANDED
            break
        block[-1, qs] /= np.linalg.norm(block[-1, qs])  # renormalise once per interval
        times.extend(tb)
        states.extend(block)
        xk = block[-1]
        t0 = tb[-1]

    return flight_result(model, np.asarray(times), np.vstack(states), pk, status, message)
