"""The assembled coast Functions: derivatives against finite differences
(docs/architecture.md#rule-3), and a translational check against the closed form of a drag-free
ballistic arc."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences
from support.models import table1_flight5
from test_mass_and_rcs import LINER, RCS
from test_rotational_dynamics import GYROSTAT_CARRIER

from lightcraft_opt.layout import initial_state, parameter_values
from lightcraft_opt.model import Aerodynamics, Environment, Wind
from lightcraft_opt.simulation.coast_reference import SimulationOptions, simulate_coast
from lightcraft_opt.symbolic.maps.coast_rhs import build_coast_rhs
from lightcraft_opt.symbolic.terms.gravity import EARTH_GM, dcm_EL, site_position_E
from lightcraft_opt.symbolic.terms.invariants import build_invariants

WINDY = Environment(
    wind=Wind(
        speed_ref=3.0,
        direction_from=0.7,
        veer=0.002,
        gust_L=(1.0, -0.5, 0.2),
        gust_start=0.0,
        gust_duration=2.0,
    ),
    gravity_j2=True,
)


def _state(model):
    return initial_state(
        model,
        r_L=(0.3, -0.2, 12.0),
        v_L=(1.0, 0.5, 14.0),
        tilt=0.15,
        tilt_azimuth=0.4,
        w_B=(0.05, 3.0, -2.0),
    )


@pytest.mark.parametrize(
    "changes",
    [{}, {"liner": LINER, "rcs": RCS, "carrier": GYROSTAT_CARRIER}],
    ids=["flight5", "gyrostat_with_liner_and_rcs"],
)
def test_coast_rhs_jacobians_match_finite_differences(changes):
    model = replace(table1_flight5(**changes), environment=WINDY)
    f = build_coast_rhs(model)
    u = np.linspace(0.01, 0.02, f.numel_in(2))
    assert_jacobians_match_finite_differences(f, [0.7, _state(model), u, parameter_values(model)])


def test_invariants_jacobians_match_finite_differences():
    model = table1_flight5(liner=LINER, rcs=RCS)
    assert_jacobians_match_finite_differences(
        build_invariants(), [_state(model), parameter_values(model)]
    )


def test_drag_free_coast_keeps_the_kepler_invariants():
    """No air, no Earth rotation: the mass centre moves in an inverse-square field, so
    its specific energy v^2/2 - GM/|R| and angular momentum R x v are constant."""
    base = table1_flight5()
    craft = replace(base.craft, aero=Aerodynamics(cd_scale=0.0, cl_scale=0.0, cm_scale=0.0))
    inverse_square = Environment(gravity_j2=False, earth_rotation=False)
    model = replace(base, craft=craft, environment=inverse_square)
    res = simulate_coast(
        model,
        5.0,
        x0=initial_state(model, v_L=(2.0, -1.0, 20.0)),
        options=SimulationOptions(rtol=1e-12, atol=1e-12),
    )
    site = model.site
    R_EL = np.asarray(dcm_EL(site.latitude, site.longitude))
    R0 = np.asarray(site_position_E(site.latitude, site.longitude, site.height)).ravel()
    R = R0 + res.state("r_L") @ R_EL.T
    V = res.state("v_L") @ R_EL.T
    energy = 0.5 * np.sum(V**2, axis=1) - EARTH_GM / np.linalg.norm(R, axis=1)
    h = np.cross(R, V)
    # ~ -6.2e7 J/kg, of which ~200 J/kg kinetic: 1e-6 J/kg is 5e-9 of the kinetic part
    assert np.max(np.abs(energy - energy[0])) < 1e-6
    assert np.max(np.linalg.norm(h - h[0], axis=1)) / np.linalg.norm(h[0]) < 1e-10
    assert res.status.value == "landed"  # after ~4.1 s, interpolated to the pad's height
    assert res.state("r_L")[-1, 2] == pytest.approx(0.0, abs=1e-12)
