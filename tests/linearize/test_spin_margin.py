"""Stability-constrained spin (linearize/spin_margin.py): the least launch spin keeping the
beam-riding multipliers at or below a limit along a climb, against the mass centre's place.

References: the bisection's own invariant (the limit lies between μ at the found spin and μ
a tolerance below it); gyroscopic stiffness (between the coning resonances μ falls with spin);
the resonances themselves, where the coning rate J ω / I is a multiple of the pulse rate
(ω = 2π f n I / J: Flight 5's n × 1204 RPM, docs/linearize.md); a direct eigenvalue
computation of Φ's Jacobian by central differences in the error-state chart, against the
chained derivatives the scan uses; the mass centre moved by exactly the asked amount (its
definition, cm_B[b1] - ring_height, for both handles). Φ at 8 substeps (docs/beam_riding.md).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, parameter_values
from lightcraft_opt.linear.linear_model import REDUCED_STATES
from lightcraft_opt.linear.operating_points import climb_point
from lightcraft_opt.linear.signal_names import select_entries
from lightcraft_opt.linearize import pulse_map_jacobian
from lightcraft_opt.linearize.climb_spin import climb_spin
from lightcraft_opt.linearize.mass_centre import (
    MassCentreHandle,
    mass_centre_from_ring,
    model_with_mass_centre,
)
from lightcraft_opt.linearize.spin_margin import (
    RPM,
    SpinMarginOptions,
    SpinMarginStatus,
    climb_worst_multiplier,
    least_stable_spin,
)
from lightcraft_opt.linearize.spin_margin_sweep import spin_margin_sweep
from lightcraft_opt.linearize.stability_grid import climb_multipliers
from lightcraft_opt.model import Carrier, SpinDecay, SpinDecayModel
from lightcraft_opt.plots import plot_spin_margin, spin_margin_figure
from lightcraft_opt.simulation import simulate_coast
from lightcraft_opt.symbolic.maps.error_state import ERROR_STATE, build_error_state
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

MAP = PulseMapOptions(substeps=8, dense=8)
#: A short climb: the 30 m node (1 cm off the axis) sets μ for Flight 5 as shipped.
CLIMB = {"altitudes": (20.0, 30.0), "offsets": (0.01,), "pulse_map_options": MAP}


@pytest.fixture(scope="module")
def flight5():
    return load_model(REPO_ROOT / "models" / "flight5.toml")


@pytest.fixture(scope="module")
def jac(flight5):
    """Φ (8 substeps) of Flight 5 with its chained Jacobian, built once for the module."""
    return pulse_map_jacobian(build_pulse_map(flight5, MAP))


def mu(model, spin, options, jac) -> float:
    return float(np.max(climb_worst_multiplier(model, spin, options, jac)))


def test_the_found_spin_meets_the_limit_and_a_tolerance_below_does_not(flight5, jac):
    options = SpinMarginOptions(
        limit=1.03, spin_range=(8000 * RPM, 14000 * RPM), grid_step=1000 * RPM, **CLIMB
    )
    behind = model_with_mass_centre(flight5, -0.04)  # the mass centre 4 cm behind the ring
    scan = least_stable_spin(behind, options, pulse_map=jac)
    assert scan.status is SpinMarginStatus.FOUND
    assert 0 < scan.least_spin - scan.below_spin <= options.tolerance
    # the bisection's invariant, and μ recomputed there
    assert scan.multiplier_at_least <= options.limit < scan.multiplier_below
    assert mu(behind, scan.least_spin, options, jac) == scan.multiplier_at_least
    assert mu(behind, scan.below_spin, options, jac) > options.limit
    # μ is continuous across the tolerance: it equals the limit to its slope x 1 RPM
    assert scan.multiplier_below - scan.multiplier_at_least < 2e-5
    assert scan.multiplier_at_least == pytest.approx(options.limit, abs=2e-5)
    assert 10000 * RPM < scan.least_spin < 11500 * RPM  # 10,605 RPM measured
    assert scan.limiting_node == (30.0, 0.01)
    above = scan.spins >= scan.least_spin
    assert scan.held_fraction == np.mean(scan.multipliers[above] <= options.limit) > 0
    assert scan.evaluations == scan.spins.size + math.ceil(math.log2(1000 / 1))


def test_between_the_coning_resonances_the_multipliers_fall_with_spin(flight5, jac):
    """Gyroscopic stiffness: midway between the resonances μ falls at every step; at the
    resonances (coning rate J ω / I a multiple n of the pulse rate: the coning mode
    aliased onto itself, Flight 5 n x 1204 RPM) μ jumps, and the scan's grid says so."""
    craft, rate = flight5.craft, flight5.flight.pulse_rate
    resonance = 2 * math.pi * rate * craft.inertia_transverse / craft.inertia_axial  # rad/s
    assert resonance / RPM == pytest.approx(1204.4, abs=0.1)
    options = SpinMarginOptions(limit=1.0, spin_decay=False, **CLIMB)  # one spin at all nodes
    midway = [(n + 0.5) * resonance for n in range(4, 16)]  # 5,420 ... 18,670 RPM
    between = np.array([mu(flight5, s, options, jac) for s in midway])
    assert np.all(np.diff(between) < 0)
    assert between[0] > 1.07 and between[-1] < 1.025  # 1.0764 -> 1.0206 measured
    # near 8 x 1204 RPM (9,635): the two side bands, 1.18 and 1.13 against 1.050 midway
    near = np.arange(9300.0, 9900.0, 50.0) * RPM
    peak = max(mu(flight5, s, options, jac) for s in near)
    assert peak > between[3] + 0.05
    # the grid's monotonicity check sees those bands
    scan = least_stable_spin(
        flight5,
        replace(options, spin_range=(9000 * RPM, 10000 * RPM), grid_step=50 * RPM),
        pulse_map=jac,
    )
    assert scan.status is SpinMarginStatus.NOT_REACHED and not scan.monotone


def test_the_scan_multiplier_is_an_eigenvalue_of_central_differences_of_phi(flight5, jac):
    """Direct eigenvalues at one node: A by central differences of Φ in the error-state
    chart (δ ↦ Φ(x ⊕ δ) ⊖ Φ(x), on the kept states), independent of the chained
    derivatives; the scan's beam-riding μ is one of its multipliers."""
    spin, altitude, offset = 8000 * RPM, 20.0, 0.01
    point = climb_point(
        flight5, altitude, 10.0, offset_L=(offset, 0.0), spin=spin, pulse_map=jac.pulse_map
    )
    retract, local = build_error_state()
    step = jac.pulse_map.step
    keep = select_entries(ERROR_STATE, REDUCED_STATES, "states")
    x_next = np.asarray(step(point.x, point.u, point.p, point.t)[0]).ravel()
    h = 1e-6
    A = np.empty((len(keep), len(keep)))
    for col, i in enumerate(keep):
        d = np.zeros(ERROR_STATE.size)
        d[i] = h
        plus, minus = (
            np.asarray(step(retract(point.x, s * d), point.u, point.p, point.t)[0]).ravel()
            for s in (1.0, -1.0)
        )
        diff = np.asarray(local(x_next, plus)).ravel() - np.asarray(local(x_next, minus)).ravel()
        A[:, col] = diff[keep] / (2 * h)
    direct = np.abs(np.linalg.eigvals(A))
    riding, _ = climb_multipliers(flight5, jac, altitude, 10.0, offset, energy=420.0, spin=spin)
    assert riding > 1.0
    assert np.min(np.abs(direct - riding)) < 1e-6
    options = SpinMarginOptions(
        altitudes=(altitude,), offsets=(offset,), spin_decay=False, pulse_map_options=MAP
    )
    assert mu(flight5, spin, options, jac) == riding


def test_no_spin_reaches_0_98_on_the_shipped_craft_a_status_not_a_crash(flight5, jac):
    """Near-neutral orbiting: the spin stiffens the tilt, so μ falls toward 1 from above,
    never to 0.98 (docs/design.md#stability-constrained-spin)."""
    options = SpinMarginOptions(spin_range=(6000 * RPM, 20000 * RPM), grid_step=2000 * RPM, **CLIMB)
    scan = least_stable_spin(flight5, options, pulse_map=jac)
    assert scan.status is SpinMarginStatus.NOT_REACHED
    assert math.isnan(scan.least_spin) and math.isnan(scan.held_fraction) and scan.bands == ()
    assert scan.best_spin == options.spin_range[1]
    assert 1.0 < scan.best_multiplier < 1.04  # 1.032 at 20,000 RPM measured
    # a limit the bracket's lowest spin already meets
    low = least_stable_spin(flight5, replace(options, limit=1.3), pulse_map=jac)
    assert low.status is SpinMarginStatus.AT_BRACKET_LOW
    assert low.least_spin == options.spin_range[0] and low.multiplier_at_least <= 1.3


def test_the_spin_decays_along_the_climb_as_the_full_dynamics_and_the_analytic_law(flight5):
    """The disk friction against a coast of the full dynamics (CVODES, laser off) over the
    same second; the exponential law (paper Eq. 6) against w0 exp(-t / τ)."""
    w0, t = 10000 * RPM, 1.0
    x0 = initial_state(flight5, v_L=(0.0, 0.0, 10.0))
    coast = simulate_coast(flight5, t, x0=x0)
    x_end = np.asarray(coast.x)[-1]
    w_end = float(STATE.get("w_B", x_end)[0] + STATE.get("spin", x_end))
    assert coast.t[-1] == pytest.approx(t)
    assert climb_spin(flight5, w0, 10.0 * t, 10.0) == pytest.approx(w_end, rel=2e-4)
    assert w_end / w0 == pytest.approx(0.909, abs=0.002)  # 9 % in the first second
    tau = 15.0
    exponential = replace(
        flight5,
        craft=replace(flight5.craft, spin_decay=SpinDecay(SpinDecayModel.EXPONENTIAL, tau)),
    )
    assert climb_spin(exponential, w0, 30.0, 10.0) == pytest.approx(
        w0 * math.exp(-3.0 / tau), rel=1e-9
    )
    with pytest.raises(ParameterError) as err:
        SpinMarginOptions(speed=0.0)
    assert err.value.field == "SpinMarginOptions.speed"
    assert SpinMarginOptions(speed=0.0, spin_decay=False).speed == 0.0


def test_the_mass_centre_moves_by_the_asked_amount(flight5):
    assert mass_centre_from_ring(flight5) == 0.0  # no liner, no carrier: P, on the ring
    moved = model_with_mass_centre(flight5, -0.03)  # the ring 3 cm ahead of the mass
    assert moved.craft.engine.ring_height == pytest.approx(0.03, abs=1e-15)
    assert mass_centre_from_ring(moved) == pytest.approx(-0.03, abs=1e-15)
    p0, p1 = parameter_values(flight5), parameter_values(moved)
    changed = np.flatnonzero(p0 != p1)
    assert changed.tolist() == [PARAMETERS.slot("ring_height").start]
    # with a carrier the carrier moves: the mass centre follows by m_c / M
    carrier = Carrier(0.005, (2e-6, 1e-6, 1e-6, 0.0, 0.0, 0.0), (0.01, 0.002, 0.0))
    gyrostat = replace(flight5, craft=replace(flight5.craft, carrier=carrier))
    start = mass_centre_from_ring(gyrostat)
    assert start == pytest.approx(0.005 * 0.01 / (0.0325 + 0.005), rel=1e-12)
    shifted = model_with_mass_centre(gyrostat, start + 0.004)
    assert shifted.craft.carrier is not None
    assert shifted.craft.carrier.position_B[0] == pytest.approx(0.01 + 0.0375 * 0.004 / 0.005)
    assert shifted.craft.carrier.position_B[1:] == (0.002, 0.0)
    assert shifted.craft.engine.ring_height == 0.0
    assert mass_centre_from_ring(shifted) == pytest.approx(start + 0.004, abs=1e-15)
    ring = model_with_mass_centre(gyrostat, start + 0.004, handle="ring")
    assert ring.craft.carrier == carrier
    assert mass_centre_from_ring(ring) == pytest.approx(start + 0.004, abs=1e-15)


def test_sweep_table_and_figure(flight5, jac):
    options = SpinMarginOptions(
        limit=1.03, spin_range=(6000 * RPM, 18000 * RPM), grid_step=2000 * RPM, **CLIMB
    )
    sweep = spin_margin_sweep(flight5, [-0.04, 0.02], options, pulse_map=jac)
    assert sweep.handle is MassCentreHandle.RING
    found, none = SpinMarginStatus.FOUND, SpinMarginStatus.NOT_REACHED
    assert sweep.statuses == (found, none)
    # the mass centre behind the ring rides better: lower μ at 6,000 and 10,000 RPM
    assert np.all(sweep.reference_multipliers[0] < sweep.reference_multipliers[1])
    assert (
        sweep.least_spins[0]
        == least_stable_spin(
            model_with_mass_centre(flight5, -0.04), options, pulse_map=jac
        ).least_spin
    )
    moved = model_with_mass_centre(flight5, -0.04)
    assert sweep.reference_multipliers[0, 0] == mu(moved, 6000 * RPM, options, jac)
    rows = sweep.rows()
    assert rows[0]["mass_centre_b1_m"] == -0.04
    assert rows[0]["least_spin_rpm"] == pytest.approx(sweep.least_spins[0] / RPM)
    assert {"multiplier_at_6000_rpm", "multiplier_at_10000_rpm"} <= set(rows[0])
    assert np.isnan(rows[1]["least_spin_rad_per_s"]) and rows[1]["status"] == "not_reached"
    assert "none" in sweep.summary() and "flight5" in sweep.summary()
    artists = plot_spin_margin(sweep)
    assert len(artists) == 1 + 1 + 2  # the line, the triangle of "none", two references
    assert spin_margin_figure([sweep]).axes[0].get_ylabel() == "least launch spin [RPM]"


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"limit": -1.0}, "SpinMarginOptions.limit"),
        ({"spin_range": (2000.0, 1000.0)}, "SpinMarginOptions.spin_range"),
        ({"tolerance": 0.0}, "SpinMarginOptions.tolerance"),
        ({"altitudes": (0.0, 10.0)}, "SpinMarginOptions.altitudes"),
        ({"offsets": ()}, "SpinMarginOptions.offsets"),
        ({"energy": math.nan}, "SpinMarginOptions.energy"),
        ({"schedule": "nearest"}, "SpinMarginOptions.schedule"),
    ],
)
def test_bad_options_name_the_field(changes, field):
    with pytest.raises(ParameterError) as err:
        SpinMarginOptions(**changes)
    assert err.value.field == field


def test_bad_input_names_the_argument(flight5, jac):
    # a rim beyond 430 m/s: the model's own check, reported on the bracket
    too_fast = SpinMarginOptions(spin_range=(1000 * RPM, 80000 * RPM))
    with pytest.raises(ParameterError, match=r"craft\.spin") as err:
        least_stable_spin(flight5, too_fast, pulse_map=jac)
    assert err.value.field == "SpinMarginOptions.spin_range"
    with pytest.raises(ParameterError) as err:
        spin_margin_sweep(flight5, [], pulse_map=jac)
    assert err.value.field == "positions"
    with pytest.raises(ParameterError, match="no carrier") as err:
        model_with_mass_centre(flight5, 0.01, handle="carrier")
    assert err.value.field == "handle"
    with pytest.raises(ParameterError) as err:
        model_with_mass_centre(flight5, 0.01, handle="liner")
    assert err.value.field == "handle"
