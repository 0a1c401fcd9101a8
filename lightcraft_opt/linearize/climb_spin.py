"""The rotor's spin at a point of a climb: the launch spin decayed by its air friction.

A reference climb leaves the pad at t = 0 and rises at a constant ``speed`` [m/s] (L frame,
up), so it reaches ``altitude`` at t = altitude / speed. On the way the rotor's axial
friction (the model's spin-decay law, symbolic/terms/spin_decay.py: the rotating disk of
docs/physics.md#spin-decay for the flight models) slows it,

    J dω/dt = T(ω, ρ(h(t)), μ(h(t))),   h(t) = site height + speed t,

with ω = w_B[b1] + spin the rotor's rate (w_B[b1] = 0 at a climb point), J the rotor's axial
moment at launch and ρ, μ the US 1976 atmosphere (symbolic/terms/atmosphere.py). RK4 in
fixed steps (:data:`STEPS`), one casadi.Function built per decay law. Flight 5 at 10,000
RPM loses about 9 % a second (tests/linearize/test_spin_margin.py checks the decay against
a coast of the full dynamics).
"""

from __future__ import annotations

import functools
import math

import casadi as ca

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, initial_state, parameter_values
from lightcraft_opt.model import Model, SpinDecayModel
from lightcraft_opt.symbolic.terms.atmosphere import us1976
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.spin_decay import spin_decay_torque

__all__ = ["STEPS", "build_climb_spin", "climb_spin"]

#: RK4 steps over a climb (the decay's time scale, ~10 s, is far longer than any climb's).
STEPS = 32


@functools.cache
def build_climb_spin(law: SpinDecayModel) -> ca.Function:
    """casadi.Function ``climb_spin(w0, duration, speed, J, p) -> w``: the rotor rate [rad/s]
    after ``duration`` [s] of a climb at ``speed`` [m/s] from the pad, from ``w0`` [rad/s],
    axial moment ``J`` [kg m^2], parameters ``p`` (module docstring)."""
    w0, duration, speed, J = (ca.SX.sym(n) for n in ("w0", "duration", "speed", "J"))
    p = ca.SX.sym("p", PARAMETERS.size)
    dt = duration / STEPS

    def rate(t: ca.SX, w: ca.SX) -> ca.SX:
        rho, _, _, mu = us1976(PARAMETERS.get("site_height", p) + speed * t)
        return spin_decay_torque(w, J, rho, mu, p, law) / J

    w = w0
    for k in range(STEPS):
        t = k * dt
        k1 = rate(t, w)
        k2 = rate(t + dt / 2, w + dt / 2 * k1)
        k3 = rate(t + dt / 2, w + dt / 2 * k2)
        k4 = rate(t + dt, w + dt * k3)
        w = w + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ca.Function(
        "climb_spin", [w0, duration, speed, J, p], [w], ["w0", "duration", "speed", "J", "p"], ["w"]
    )


def climb_spin(model: Model, launch_spin: float, altitude: float, speed: float) -> float:
    """The rotor's rate [rad/s] at ``altitude`` [m] above the pad of a climb at ``speed``
    [m/s] (> 0) begun at ``launch_spin`` [rad/s] (module docstring)."""
    if not (math.isfinite(speed) and speed > 0):
        raise ParameterError("speed", f"a climb needs a speed > 0 [m/s], got {speed!r}")
    if not (math.isfinite(altitude) and altitude >= 0):
        raise ParameterError("altitude", f"must be >= 0 [m], got {altitude!r}")
    p = parameter_values(model)
    J = float(mass_properties(ca.DM(initial_state(model)), ca.DM(p)).J)
    law = build_climb_spin(model.craft.spin_decay.model)
    return float(law(launch_spin, altitude / speed, speed, J, p))
