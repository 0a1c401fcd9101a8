"""A vertical coast in calm air with the shipped gravity (docs/physics.md#gravity).

Reference: the Coriolis deflection of a body thrown straight up (Landau and Lifshitz,
*Mechanics*, section 39; docs/references.md#landau-lifshitz). To first order in
the Earth's rate Omega, with the latitude phi and g the plumb-line gravity at the pad, the
body drifts east by

    x_east(t) = -Omega cos(phi) (v0 t^2 - g t^3 / 3),

which at the landing t = 2 v0 / g is (4/3) Omega cos(phi) v0^3 / g^2 to the west, and not at
all north: the only north push left is the J2-only field's deflection of the vertical, a
constant a_N = 1.8e-5 m/s^2 at White Sands (tests/symbolic/test_gravity.py). Inverse-square
gravity, the paper's, would add 1.4e-2 m/s^2 north (29 mm in this flight's first 2.4 s).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from support.paths import MODELS

from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import initial_state, parameter_values
from lightcraft_opt.simulation.coast_reference import simulate_coast
from lightcraft_opt.simulation.result import SimulationStatus
from lightcraft_opt.symbolic.terms.gravity import EARTH_RATE, build_gravity

V0 = 20.0  # launch speed, straight up [m/s]


def test_vertical_coast_drifts_only_by_the_coriolis_deflection():
    """models/flight5.toml as shipped (J2 gravity, Earth rotating, calm air) with the
    aerodynamic loads off (at C_D = 0.73 drag stops the 32.5 g craft at 6.7 m instead of
    20 m, so the drag-free formula would not apply): launched up at 20 m/s from the pad, it
    lands after 2 v0 / g, (4/3) Omega cos(phi) v0^3 / g^2 = 6.85 mm west of the pad, and the
    east offset follows x_east(t) all the way. The tolerance is the size of the terms the
    first-order formula drops, Omega T (3e-4) of the drift. North: 1/2 a_N t^2 to 2 um (the
    second-order Coriolis push of the eastward velocity), well under 1 mm."""
    model = load_model(MODELS / "flight5.toml")
    aero = replace(model.craft.aero, cd_scale=0.0, cl_scale=0.0, cm_scale=0.0)
    model = replace(model, craft=replace(model.craft, aero=aero))
    assert model.environment.gravity_j2 and model.environment.earth_rotation
    assert model.environment.wind.speed_ref == 0.0
    p = parameter_values(model)
    a_pad = np.asarray(build_gravity(model.environment)([0, 0, 0], [0, 0, 0], p)).ravel()
    g, a_north = -a_pad[2], a_pad[1]
    cos_phi = math.cos(model.site.latitude)

    result = simulate_coast(model, 5.0, x0=initial_state(model, v_L=(0.0, 0.0, V0)))

    assert result.status is SimulationStatus.LANDED
    t, r = result.t, result.state("r_L")
    assert math.isclose(t[-1], 2 * V0 / g, rel_tol=1e-4)  # g falls 6e-6 over the 20 m
    west_at_landing = 4 / 3 * EARTH_RATE * cos_phi * V0**3 / g**2
    order = EARTH_RATE * t[-1]  # the relative size of the terms dropped
    assert abs(-r[-1, 0] - west_at_landing) <= order * west_at_landing
    east = -EARTH_RATE * cos_phi * (V0 * t**2 - g * t**3 / 3)
    assert np.max(np.abs(r[:, 0] - east)) <= order * west_at_landing
    assert np.max(np.abs(r[:, 1] - 0.5 * a_north * t**2)) <= 2e-6
    assert np.max(np.abs(r[:, 1])) < 2e-4
