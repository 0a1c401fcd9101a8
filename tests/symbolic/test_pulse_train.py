"""Physics of pulse trains through the pulse map Φ (symbolic/maps/pulse_map.py).

References:

- a vertical pulse train without drag: each centred pulse adds I0 / m to the climb rate
  (paper Eq. 12b, Table 1 impulse: the seed paper,
  docs/references.md#paper-eq-12 and docs/references.md#paper-table-1), and between pulses the
  inverse-square pull, to first order in z / R, is the linear ODE z'' = -g0 (1 - 2 z / R) with
  an exact cosh/sinh solution;
- momentum bookkeeping (Newton's and Euler's laws in the rotating site frame): over a
  window of pulses, the change of m v_L and of H_L equals the impulses Φ reports plus the
  integrals of the external forces and moments, integrated along the hybrid system by
  CVODES (laser off between pulses, the jumps of pulse_jump.py at the pulses);
- Φ's Jacobians against central finite differences (docs/architecture.md#rule-3).

The models are built here from the dataclasses (tests/support/models.py, ``table1_flight5``)
with the engine spelled out, so tuned model-file values and engine defaults do not move these
tests.
"""

from __future__ import annotations

import math
from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences, state_step_scale
from support.models import table1_flight5

from lightcraft_opt.layout import (
    ENGINE as ENGINE_LAYOUT,
)
from lightcraft_opt.layout import (
    PARAMETERS,
    PULSE_INPUT,
    STATE,
    initial_state,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import (
    Aerodynamics,
    BeamSizeModel,
    Engine,
    Environment,
    Liner,
    Model,
    Propellant,
    Site,
    SpinDecay,
    SpinDecayModel,
    Wind,
)
from lightcraft_opt.symbolic.maps.coast_rhs import coast_terms
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_jump import pulse_jump
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.terms.gravity import (
    EARTH_GM,
    WGS84_A,
    WGS84_F,
    dcm_EL,
    earth_rate_L,
    gravity_E,
    site_position_E,
)
from lightcraft_opt.symbolic.terms.invariants import build_invariants
from lightcraft_opt.symbolic.terms.rotation import cross, dcm

EPS = np.finfo(float).eps

# The engine of these tests, every field that shapes the impulses written out: a ring
# 1 cm above P so the angular impulse has its arm term (h b1 - cm_B) x G_F too.
ENGINE = Engine(
    capture_radius=0.055,
    shadow_radius=0.0075,
    ring_radius=0.05,
    ring_height=0.01,
    blast_angle=0.15,
    health_floor=0.3,
    health_pulse=100.0,
    health_width=8.0,
    quadrature_radial=8,
    quadrature_azimuthal=32,
)


def _engine_report(eng: ca.DM) -> dict[str, np.ndarray]:
    """Φ's second output split by name (layout.ENGINE, imported as ENGINE_LAYOUT)."""
    flat = np.asarray(eng, dtype=float).ravel()
    return {name: flat[ENGINE_LAYOUT.index(name)] for name in ENGINE_LAYOUT.names}


def _R_LB(x: np.ndarray) -> np.ndarray:
    """R_LB (3, 3) of state x, by the library's dcm (the frame of the reported impulses)."""
    q = ca.SX.sym("q", 4)
    return np.asarray(ca.Function("R_LB", [q], [dcm(q)])(STATE.get("q_LB", x)), dtype=float)


def _b1_L(q: np.ndarray) -> np.ndarray:
    """First column of R_LB for the unit quaternion q = (w, x, y, z): b1 in L."""
    w, x, y, z = q
    return np.array([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])


def full_flight5(**craft_changes: object) -> Model:
    """Flight 5 with everything on: aerodynamics, disk spin decay, rotating Earth, J2."""
    base = table1_flight5()
    changes: dict[str, object] = {
        "engine": ENGINE,
        "spin_decay": SpinDecay(SpinDecayModel.ROTATING_DISK),
        **craft_changes,
    }
    return replace(base, craft=replace(base.craft, **changes))  # type: ignore[arg-type]


# --------------------------------------------------------------------------- 1. closed form
def drag_free_vertical_flight5() -> Model:
    """Flight 5 at the north pole: no air loads, no spin decay, inertial site frame, no J2,
    a beam that keeps its size (divergence 0) and an engine that never tires."""
    base = table1_flight5()
    craft = replace(
        base.craft,
        aero=Aerodynamics(cd_scale=0.0, cl_scale=0.0, cm_scale=0.0),
        spin_decay=SpinDecay(SpinDecayModel.NONE),
        engine=replace(ENGINE, health_floor=1.0),
    )
    return replace(
        base,
        craft=craft,
        site=Site("north pole", math.pi / 2, 0.0, 0.0),
        laser=replace(base.laser, divergence=0.0, size_model=BeamSizeModel.LINEAR),
        environment=Environment(gravity_j2=False, earth_rotation=False),
    )


def test_vertical_pulse_train_without_drag_matches_the_linearised_inverse_square_flight():
    """24 pulses from the pad (0.92 s, up to 18.4 m and 37.9 m/s): height and climb rate
    after every pulse against z'' = -g0 (1 - 2 z / R) between kicks of I0 / m.

    At the pole the site's up is the geocentric radial, R the polar radius b = a (1 - f)
    plus the site height. The gradient term 2 g0 z / R adds 4.3e-6 m and 1.8e-5 m/s by
    the last pulse, over four orders above the tolerances, so the check sees the
    inverse-square gradient, not just g0.
    """
    model = drag_free_vertical_flight5()
    phi = build_pulse_map(model, PulseMapOptions(substeps=8))
    p = parameter_values(model)
    u = nominal_inputs(model)
    period = phi.period
    I0 = model.flight.impulse_per_pulse
    mass = model.craft.mass

    R = WGS84_A * (1 - WGS84_F) + model.site.height
    g0 = EARTH_GM / R**2
    k = math.sqrt(2 * g0 / R)

    def coast(z: float, v: float, t: float) -> tuple[float, float]:
        """Exact flow of z'' = k^2 (z - R/2), written with cosh - 1 = 2 sinh^2(k t / 2)
        so that R/2 ~ 3e6 m never cancels against z."""
        c1 = 2 * math.sinh(k * t / 2) ** 2
        s = math.sinh(k * t)
        return z + (z - R / 2) * c1 + v * s / k, v + v * c1 + (z - R / 2) * k * s

    n_pulses = 24
    x = initial_state(model)  # on the pad, at rest, upright, spinning, on the beam axis
    z_ref, v_ref = 0.0, 0.0
    iz, ivz = STATE.slot("r_L").start + 2, STATE.slot("v_L").start + 2
    for k_pulse in range(n_pulses):
        x_next, eng = phi.step(x, u, p, k_pulse * period)
        x = np.asarray(x_next, dtype=float).ravel()
        report = _engine_report(eng)
        z_ref, v_ref = coast(z_ref, v_ref + I0 / mass, period)
        t = (k_pulse + 1) * period

        # A centred upright craft gets I0 exactly (the coupling's normalisation): the same
        # 256-point quadrature summed twice, equal to ~1e2 ulps.
        assert report["impulse_B"][0] == pytest.approx(I0, rel=1e-14)
        # The neglected 3 g0 z^2 / R^2 (the whole Taylor remainder of (1 + z/R)^-2 beyond
        # the linear term is below it for z > 0) bounds the model error of the reference:
        # |dz| <= da t^2 / 2 and |dv| <= da t (the cosh(k t) growth of the linear ODE is
        # 1 + 2e-6 here, inside the factor 1.01). Round-off: 1e3 ulps of the height and
        # speed covers the ~600 fixed steps and 24 kicks.
        da = 3 * g0 * (z_ref / R) ** 2
        assert abs(x[iz] - z_ref) <= 1.01 * da * t**2 / 2 + 1e3 * EPS * z_ref
        assert abs(x[ivz] - v_ref) <= 1.01 * da * t + 1e3 * EPS * abs(v_ref)

        # By symmetry nothing pushes sideways or tips: what is left is round-off (1e-17 m
        # and 1e-16 rad measured); 1e-12 would need four orders of growth in 24 pulses.
        assert np.max(np.abs(STATE.get("r_L", x)[:2])) < 1e-12
        assert np.max(np.abs(STATE.get("v_L", x)[:2])) < 1e-12
        b1 = _b1_L(STATE.get("q_LB", x))
        assert math.atan2(math.hypot(b1[0], b1[1]), b1[2]) < 1e-12
        assert np.max(np.abs(report["impulse_B"][1:])) < 1e-14 * I0
    assert x[iz] > 15.0  # the whole train was airborne


# --------------------------------------------------------------------------- 2. bookkeeping
def _force_and_moment_quadrature(model: Model, period: float) -> ca.Function:
    """CVODES over one coast from t0: ``(x0, p, t0) -> (x, F, M)`` with F = ∫ F_L dt [N s]
    and M = ∫ (M_L - W_L x H_L) dt [N m s] as quadratures.

    F_L is assembled here: the aerodynamic and RCS forces rotated to L, the model's gravity
    (inverse-square, plus J2 when ``gravity_j2``) at the position from the Earth's centre,
    and the rotating-frame terms of L, -2 m W x v_L - m W x (W x R_L), written out. M_L is
    the aerodynamic and RCS moment plus the spin-decay torque on b1, about S*; -W_L x H_L
    turns dH/dt in N into the rate of H's L components.
    """
    x = ca.SX.sym("x", STATE.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    t0 = ca.SX.sym("t0")
    tau = ca.SX.sym("tau")
    terms = coast_terms(t0 + tau, x, ca.SX(0, 1), p, model)
    R_LB = dcm(STATE.get("q_LB", x))
    r_L, v_L = STATE.get("r_L", x), STATE.get("v_L", x)
    m = terms["mass"]
    lat, lon = PARAMETERS.get("site_latitude", p), PARAMETERS.get("site_longitude", p)
    R_EL = dcm_EL(lat, lon)
    R_from_centre_L = (
        ca.mtimes(R_EL.T, site_position_E(lat, lon, PARAMETERS.get("site_height", p))) + r_L
    )
    j2 = model.environment.gravity_j2
    g_L = ca.mtimes(R_EL.T, gravity_E(ca.mtimes(R_EL, R_from_centre_L), j2))
    W_L = earth_rate_L(lat)
    F_L = (
        ca.mtimes(R_LB, terms["F_aero_B"] + terms["F_rcs_B"])
        + m * g_L
        - 2 * m * cross(W_L, v_L)
        - m * cross(W_L, cross(W_L, R_from_centre_L))
    )
    H_L = build_invariants()(x, p)[0]
    M_B = terms["M_aero_B"] + terms["M_rcs_B"] + ca.vertcat(terms["spin_torque"], 0, 0)
    dH_L = ca.mtimes(R_LB, M_B) - cross(W_L, H_L)
    dae = {
        "t": tau,
        "x": x,
        "p": ca.vertcat(p, t0),
        "ode": terms["xdot"],
        "quad": ca.vertcat(F_L, dH_L),
    }
    integ = ca.integrator(
        "coast_with_impulse_integrals",
        "cvodes",
        dae,
        0.0,
        period,
        {
            "abstol": 1e-12,
            "reltol": 1e-12,
            "quad_err_con": True,
            "max_num_steps": 1_000_000,
            "linear_multistep_method": "adams",
            "nonlinear_solver_iteration": "functional",
        },
    )
    xs, ps, ts = ca.MX.sym("x0", STATE.size), ca.MX.sym("p", PARAMETERS.size), ca.MX.sym("t0")
    out = integ(x0=xs, p=ca.vertcat(ps, ts))
    qf = out["qf"]
    return ca.Function(
        "coast_quad", [xs, ps, ts], [out["xf"], qf[:3], qf[3:]], ["x0", "p", "t0"], ["x", "F", "M"]
    )


def _jump_function(model: Model, n_u: int) -> ca.Function:
    """pulse_jump as a Function ``(x, u, p) -> x_plus`` (Φ with no coast is not exposed)."""
    x = ca.SX.sym("x", STATE.size)
    u = ca.SX.sym("u", n_u)
    p = ca.SX.sym("p", PARAMETERS.size)
    x_plus, _ = pulse_jump(x, u[: PULSE_INPUT.size], p, model)
    return ca.Function("jump", [x, u, p], [x_plus], ["x", "u", "p"], ["x_plus"])


def test_momentum_and_angular_momentum_bookkeeping_over_ten_pulses():
    """Flight 5, everything on, 1 cm east of the beam axis at 3 m climbing at 5 m/s: the
    hybrid system over 10 pulses (jumps of pulse_jump, CVODES coasts).

    At each pulse, what the jump adds to m v_L and to H_L is exactly the impulse Φ reports,
    rotated to L (m at t_k^-: Eq. 12b; air mode loses no mass). Over the window,
    m v(t_10) - m v(t_0) = Σ R_LB(t_k) G_F,k + ∫ F_L dt and likewise for H_L, with the
    Earth's rotation on (Coriolis alone moves m v by ~1e-5 N s here, 1e4 tolerances).
    Φ's own fixed-step coast against CVODES is tests/symbolic/test_pulse_map.py's subject.
    """
    model = full_flight5()
    phi = build_pulse_map(model, PulseMapOptions(substeps=1, dense=1))  # reports only
    p = parameter_values(model)
    u = nominal_inputs(model)
    jump = _jump_function(model, u.size)
    coast = _force_and_moment_quadrature(model, phi.period)
    invariants = build_invariants()

    def momenta(x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        H_L, _, _, _, mass = invariants(x, p)
        mass = float(mass)
        return mass, mass * STATE.get("v_L", x), np.asarray(H_L, dtype=float).ravel()

    x = initial_state(model, r_L=(0.01, 0.0, 3.0), v_L=(0.0, 0.0, 5.0))
    _, P_start, H_start = momenta(x)
    impulses_L, angular_impulses_L = np.zeros(3), np.zeros(3)
    force_integral, moment_integral = np.zeros(3), np.zeros(3)
    throughput_P, throughput_H = 0.0, float(np.linalg.norm(H_start))
    lateral = 0.0
    for k in range(10):
        t_k = k * phi.period
        report = _engine_report(phi.step(x, u, p, t_k)[1])
        R_LB = _R_LB(x)
        G_F_L = R_LB @ report["impulse_B"]
        G_M_L = R_LB @ report["angular_impulse_B"]
        lateral = max(lateral, float(np.max(np.abs(report["impulse_B"][1:]))))

        mass_minus, P_minus, H_minus = momenta(x)
        x_plus = np.asarray(jump(x, u, p), dtype=float).ravel()
        mass_plus, P_plus, H_plus = momenta(x_plus)
        assert mass_plus == mass_minus  # air mode: nothing ablates, m(t_k^+) = m(t_k^-)
        # Round-off of a difference of momenta: 1e2 ulps of their size (measured 1e-16).
        assert np.max(np.abs(P_plus - P_minus - G_F_L)) <= 1e-14 * np.linalg.norm(P_plus)
        assert np.max(np.abs(H_plus - H_minus - G_M_L)) <= 1e-14 * np.linalg.norm(H_plus)

        x_end, F, M = (np.asarray(a, dtype=float).ravel() for a in coast(x_plus, p, t_k))
        # renormalise once per interval, as coast_reference does (drift ~1e-12)
        x_end[STATE.index("q_LB")] /= np.linalg.norm(STATE.get("q_LB", x_end))
        impulses_L += G_F_L
        angular_impulses_L += G_M_L
        force_integral += F
        moment_integral += M
        throughput_P += float(np.linalg.norm(G_F_L) + np.linalg.norm(F))
        throughput_H += float(np.linalg.norm(G_M_L) + np.linalg.norm(M))
        x = x_end

    _, P_end, H_end = momenta(x)
    # The offset makes the bookkeeping non-trivial: lateral impulses of a few % of I0.
    assert lateral > 1e-2 * model.flight.impulse_per_pulse
    # CVODES holds the states and the quadratures to 1e-12 per step; 1e-9 of the momentum
    # that flowed through the window leaves a factor 1e3 for the accumulation over the
    # ~10^3 steps of ten coasts (measured: 4e-13 for m v, 2e-12 for H).
    residual_P = P_end - P_start - impulses_L - force_integral
    residual_H = H_end - H_start - angular_impulses_L - moment_integral
    assert np.max(np.abs(residual_P)) <= 1e-9 * throughput_P
    assert np.max(np.abs(residual_H)) <= 1e-9 * throughput_H


def test_delrin_pulse_gives_the_pre_pulse_mass_the_reported_impulse():
    """Delrin liner (mass lost at each pulse): m(t_k^-) (v+ - v-) = R_LB G_F (paper Eq. 12b,
    the ablated mass leaves with the craft's velocity) and the liner loses exactly the
    reported ablation. Using m(t_k^+) instead would differ by Δm / m = 2.5e-4 relative."""
    liner = Liner(mass=0.003, radius=0.045, axial_offset=0.0)
    model = full_flight5(
        propellant=Propellant.DELRIN,
        liner=liner,
        engine=replace(ENGINE, ablation=20e-9, spent_coupling=0.0637 / 420.0),
    )
    phi = build_pulse_map(model, PulseMapOptions(substeps=1, dense=1))
    p = parameter_values(model)
    u = nominal_inputs(model)
    jump = _jump_function(model, u.size)
    invariants = build_invariants()
    x = initial_state(model, r_L=(0.01, -0.005, 2.0), v_L=(0.2, 0.0, 4.0), tilt=0.03)
    report = _engine_report(phi.step(x, u, p, 0.0)[1])
    x_plus = np.asarray(jump(x, u, p), dtype=float).ravel()
    m_minus = float(invariants(x, p)[4])
    m_plus = float(invariants(x_plus, p)[4])
    R_LB = _R_LB(x)

    loss = float(report["liner_loss"][0])
    # the liner really ablates: ~8 ug, 2.5e-4 of the mass, far above the tolerances below
    assert loss > 1e-4 * m_minus
    # mass bookkeeping: to round-off of the ~0.03 kg mass (a few ulps)
    assert m_minus - m_plus == pytest.approx(loss, abs=16 * EPS * m_minus)
    G_F_L = R_LB @ report["impulse_B"]
    dP = m_minus * (STATE.get("v_L", x_plus) - STATE.get("v_L", x))
    # 1e2 ulps of the momentum jump (measured 2e-16); m(t_k^+) would be off by 2.5e-4
    assert np.max(np.abs(dP - G_F_L)) <= 1e-14 * np.linalg.norm(G_F_L)


# --------------------------------------------------------------------------- 3. Jacobians
def test_pulse_map_jacobians_match_finite_differences():
    """Φ.step's Jacobians w.r.t. x, u, p and t at a flying state: 1.5 cm off the beam axis,
    2 degrees of tilt, coning (w_B transverse 3.2 rad/s), climbing at 5 m/s at 3 m,
    10,000 RPM, in a sheared, veering wind with a gust under way (so d/dt is not zero).

    Four substeps (each a Yoshida triple of Strang steps): the graph is the same
    substep repeated, so correctness of AD does not depend on the count, and the AD
    Jacobian of the 4-substep map takes ~5 s to build (8 substeps: ~11 s).
    """
    wind = Wind(
        speed_ref=3.0,
        direction_from=math.radians(250.0),
        veer=0.01,
        gust_L=(1.0, -0.5, 0.2),
        gust_start=0.3,
        gust_duration=1.0,
    )
    base = full_flight5()
    model = replace(base, environment=replace(base.environment, wind=wind))
    phi = build_pulse_map(model, PulseMapOptions(substeps=4, dense=4))
    p = parameter_values(model)
    u = nominal_inputs(model)
    x = initial_state(
        model,
        r_L=(0.015, -0.01, 3.0),
        v_L=(0.3, -0.2, 5.0),
        tilt=math.radians(2.0),
        tilt_azimuth=0.7,
        w_B=(0.0, 3.0, -1.0),
    )
    # FD steps are 1e-5 (|value| + scale), so the scale must be each entry's natural size
    # where the value is 0 or small; the default 1e-4 suits neither end here:
    # - zero masses (liner, RCS: 1e-9 kg steps), rates (w_B[b1]) and beam pointing
    #   (1e-9 m) would be stepped so finely that the round-off of the 1047 rad/s spin,
    #   eps |f| / h, reaches 2-5e-7 of the largest entry: masses scale with the craft,
    #   rates with 1 rad/s, the pointing with 1 cm;
    # - the floor exceeds the inertias (~5e-5 kg m^2, and the carrier's zeros) and would
    #   step them by 2-3e-5 relative, moving the ~50 rad coning phase of one interval by
    #   1.6e-3 rad, whose central-difference error (Δφ)^2 / 6 ~ 4e-7 nears rtol. Nonzero
    #   parameters step 1e-5 of themselves, the carrier's inertia 1e-5 of the craft's.
    x_scale = state_step_scale(model.craft.mass)
    u_scale = PULSE_INPUT.pack({"pointing_L": (1e-2, 1e-2), "focus": 1.0, "energy": 1.0})
    p_scale = np.where(p != 0.0, 1e-3 * np.abs(p), 1e-4)
    p_scale[PARAMETERS.index("carrier_inertia")] = model.craft.inertia_transverse
    # rtol 1e-6 (the helper's): with these steps the truncation and round-off of central
    # differences stay below ~1e-7 of each block's largest entry; a wrong chain rule is O(1).
    assert_jacobians_match_finite_differences(
        phi.step, [x, u, p, 0.5], scale=[x_scale, u_scale, p_scale, 1e-4]
    )
