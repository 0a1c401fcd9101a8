"""Engine: captured energy and pulse impulses (docs/physics.md#table-1, docs/physics.md#engine).

References: the seed paper's Table 1 (docs/references.md#paper-table-1; first-pulse impulse
0.0637 N s and 0.195 N s, velocity jumps 1.960 and 6.720 m/s, docs/physics.md#table-1);
docs/physics.md#engine (restoring lateral impulse, tipping away from the beam axis, collapse
once the beam leaves the optic near 9-10 cm, health step near pulse 100, ablation mu E_cap,
kernel peak at d0); projected-area geometry (a beam wider than the optic gives
E_cap ~ cos(tilt), a beam inside the projected optic is caught whole); a fine polar grid
(midpoint in r, equal sectors) as the independent integrator of the fluence over the optic.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences

from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import (
    PARAMETERS,
    PULSE_INPUT,
    STATE,
    initial_state,
    parameter_values,
)
from lightcraft_opt.model import BeamSizeModel, ImpulseModel, Model
from lightcraft_opt.symbolic.terms.beam import beam_side, fluence
from lightcraft_opt.symbolic.terms.engine import ENGINE_OUTPUT_NAMES, build_engine, health
from lightcraft_opt.symbolic.terms.rotation import dcm

F5 = load_model("models/flight5.toml")
F16 = load_model("models/flight16.toml")
ENERGY = 420.0  # J, Table 1


# --------------------------------------------------------------------------- helpers
def _with_engine(model: Model, **changes: object) -> Model:
    engine = dataclasses.replace(model.craft.engine, **changes)  # type: ignore[arg-type]
    return dataclasses.replace(model, craft=dataclasses.replace(model.craft, engine=engine))


def _params(model: Model, **changes: float) -> np.ndarray:
    p = parameter_values(model)
    for name, value in changes.items():
        p[PARAMETERS.index(name)] = value
    return p


def _pulse(pointing: tuple[float, float] = (0.0, 0.0), focus: float = 500.0) -> np.ndarray:
    return PULSE_INPUT.pack({"pointing_L": pointing, "focus": focus, "energy": ENERGY})


@functools.cache
def _engine(model: Model) -> ca.Function:
    return build_engine(model)


def _run(
    model: Model, x: np.ndarray, pulse: np.ndarray | None = None, p: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    pulse = _pulse() if pulse is None else pulse
    out = _engine(model)(x, pulse, parameter_values(model) if p is None else p)
    return {name: np.asarray(v).ravel() for name, v in zip(ENGINE_OUTPUT_NAMES, out, strict=True)}


def _in_L(x: np.ndarray, v_B: np.ndarray) -> np.ndarray:
    return np.asarray(dcm(ca.DM(STATE.get("q_LB", x)))) @ v_B


def _fine_annulus_energy(model: Model, p: np.ndarray, offset: float) -> float:
    """Fluence integrated over the optic annulus of an upright craft whose optic centre is
    ``offset`` east of the beam axis: 1500 radial midpoints x 720 sectors (fluence evaluated
    on DM arrays, vectorised)."""
    e = model.craft.engine
    edges = np.linspace(e.shadow_radius, e.capture_radius, 1501)
    r = 0.5 * (edges[1:] + edges[:-1])
    phi = 2 * np.pi * (np.arange(720) + 0.5) / 720
    R, PHI = np.meshgrid(r, phi)
    xi, eta = offset + R * np.cos(PHI), R * np.sin(PHI)
    a = beam_side(ca.DM(e.ring_height), ca.DM(500.0), ca.DM(p), model.laser)
    F = fluence(ca.DM(xi.ravel()), ca.DM(eta.ravel()), a, ca.DM(ENERGY), ca.DM(p), model.laser)
    F = np.asarray(F).reshape(R.shape)
    return float(np.sum(F * R) * (edges[1] - edges[0]) * 2 * np.pi / 720)


# --------------------------------------------------------------------------- captured energy
@pytest.mark.parametrize(("quadrature", "accuracy"), [((8, 32), 1e-3), ((12, 48), 5e-5)])
@pytest.mark.parametrize("model", [F5, F16], ids=["flight5", "flight16"])
def test_quadrature_matches_fine_grid_to_documented_accuracy(
    model: Model, quadrature: tuple[int, int], accuracy: float
) -> None:
    """engine.py's documented accuracy for the Table 1 beams, offsets 0 to 8 cm."""
    m = _with_engine(model, quadrature_radial=quadrature[0], quadrature_azimuthal=quadrature[1])
    p = parameter_values(m)
    for offset in (0.0, 0.01, 0.03, 0.05, 0.08):
        e_cap = _run(m, initial_state(m, r_L=(offset, 0.0, 0.0)), p=p)["energy_captured"][0]
        assert abs(e_cap - _fine_annulus_energy(m, p, offset)) < accuracy * ENERGY


def test_beam_inside_the_optic_is_captured_whole() -> None:
    """A 6 cm hollow square (hole 3 cm, 1.5 mm edges) centred on an upright craft lies inside
    the annulus 0.75-5.5 cm: the optic catches the whole pulse, E_cap = E, to the quadrature's
    accuracy (1e-2 at 8 x 32 for edges this sharp, 1e-6 converged)."""
    p = _params(F5, beam_side=0.06, beam_hole_ratio=0.5, beam_edge_width=0.0015)
    assert _fine_annulus_energy(F5, p, 0.0) == pytest.approx(ENERGY, rel=2e-4)
    x = initial_state(F5)
    assert _run(F5, x, p=p)["energy_captured"][0] == pytest.approx(ENERGY, rel=1e-2)
    fine = _with_engine(F5, quadrature_radial=64, quadrature_azimuthal=256)
    assert _run(fine, x, p=p)["energy_captured"][0] == pytest.approx(ENERGY, rel=2e-4)


@pytest.mark.parametrize("tilt_deg", [10.0, 30.0, 60.0])
def test_tilt_projects_a_wide_beam_by_cos_tilt(tilt_deg: float) -> None:
    """A beam much wider than the optic (a 1 m soft square, hole ratio 0: uniform over it):
    the tilted optic intercepts F times its projected area, E_cap(tilt) = cos(tilt) E_cap(0)."""
    p = _params(F5, beam_side=1.0, beam_hole_ratio=0.0)
    upright = _run(F5, initial_state(F5), p=p)["energy_captured"][0]
    x = initial_state(F5, tilt=math.radians(tilt_deg), tilt_azimuth=0.7)
    tilted = _run(F5, x, p=p)["energy_captured"][0]
    assert tilted / upright == pytest.approx(math.cos(math.radians(tilt_deg)), rel=1e-6)


@pytest.mark.parametrize("tilt_deg", [10.0, 20.0, 30.0])
def test_tilt_keeps_a_small_beam_whole(tilt_deg: float) -> None:
    """A beam inside the projected annulus is caught whole at any tilt (the projection factor
    |b1 . z| and the shrunken footprint cancel): E_cap stays E, not E cos(tilt)."""
    p = _params(F5, beam_side=0.06, beam_hole_ratio=0.5, beam_edge_width=0.0015)
    fine = _with_engine(F5, quadrature_radial=64, quadrature_azimuthal=256)
    x = initial_state(fine, tilt=math.radians(tilt_deg), tilt_azimuth=0.3)
    assert _run(fine, x, p=p)["energy_captured"][0] == pytest.approx(ENERGY, rel=2e-4)


# --------------------------------------------------------------------------- first pulse
@pytest.mark.parametrize(
    ("model", "impulse", "dv"),
    [(F5, 0.0637, 1.9600), (F16, 0.195, 6.720)],
    ids=["flight5", "flight16"],
)
def test_first_pulse_is_table1_and_purely_axial(model: Model, impulse: float, dv: float) -> None:
    """Centred, upright, at the pad: exactly Table 1's impulse along b1, Delta v = I0 / m, and
    no lateral or angular impulse (relative 1e-12)."""
    out = _run(model, initial_state(model))
    G_F, G_M = out["impulse_B"], out["angular_impulse_B"]
    assert G_F[0] == pytest.approx(impulse, rel=1e-12)
    assert G_F[0] / model.craft.mass == pytest.approx(dv, abs=5e-4)
    assert np.max(np.abs(G_F[1:])) < 1e-12 * impulse
    assert np.max(np.abs(G_M)) < 1e-12 * impulse * model.craft.engine.ring_radius
    assert out["health"][0] == 1.0
    assert np.all(out["offset_L"] == 0.0)


@pytest.mark.parametrize("focus", [5.0, 71.0, 500.0])
def test_first_pulse_is_table1_whatever_the_focus(focus: float) -> None:
    """Waist model: the launch beam side is Table 1's for every focus input, so the first
    pulse is too."""
    laser = dataclasses.replace(F5.laser, size_model=BeamSizeModel.WAIST)
    m = dataclasses.replace(F5, laser=laser)
    out = _run(m, initial_state(m), pulse=_pulse(focus=focus))
    assert out["impulse_B"][0] == pytest.approx(0.0637, rel=1e-12)


# --------------------------------------------------------------------------- off the beam axis
@pytest.mark.parametrize("model", [F5, F16], ids=["flight5", "flight16"])
@pytest.mark.parametrize("direction_deg", [0.0, 130.0])
def test_offset_restores_and_tips_away(model: Model, direction_deg: float) -> None:
    """Sector model, default blast angle +0.5 rad: the lateral impulse points toward the beam
    axis, the angular impulse turns b1 away from it; both grow with the offset up to 3 cm and
    collapse with E_cap once the beam leaves the optic (under 0.5 % of E_cap(0) at 10 cm along
    the square's axes, 11 cm near its diagonals, where its corners reach 5.1 cm out)."""
    d_hat = np.array(
        [math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg)), 0.0]
    )  # from the beam axis to the craft, L
    lateral, tipping = [], []
    e0 = _run(model, initial_state(model))["energy_captured"][0]
    gone = 0.10 if direction_deg == 0.0 else 0.11
    for offset in (0.01, 0.02, 0.03, gone):
        x = initial_state(model, r_L=tuple(offset * d_hat))
        out = _run(model, x)
        G_F_L, G_M_L = _in_L(x, out["impulse_B"]), _in_L(x, out["angular_impulse_B"])
        assert np.allclose(out["offset_L"], offset * d_hat[:2], rtol=0, atol=1e-15)
        # lateral impulse along -d_hat; b1 moves along G_M x b1, along +d_hat
        along = float(G_F_L @ d_hat)
        assert along < 0.0
        turn = np.cross(G_M_L, np.array([0.0, 0.0, 1.0]))
        assert float(turn @ d_hat) > 0.0
        # exactly along d_hat on the square's axes; off them the square bends it slightly
        skew = 1e-9 if direction_deg == 0.0 else 0.05
        assert np.linalg.norm(G_F_L[:2] - along * d_hat[:2]) < skew * abs(along)
        assert np.linalg.norm(turn - (turn @ d_hat) * d_hat) < skew * float(turn @ d_hat)
        lateral.append(-along)
        tipping.append(float(turn @ d_hat))
        if offset == gone:
            assert out["energy_captured"][0] < 5e-3 * e0
    assert lateral[0] < lateral[1] < lateral[2]
    assert tipping[0] < tipping[1] < tipping[2]
    assert lateral[3] < 1e-2 * lateral[2] and tipping[3] < 1e-2 * tipping[2]


@pytest.mark.parametrize(("altitude", "sign"), [(10.0, -1.0), (40.0, 1.0)])
def test_a_hollow_beam_wider_than_the_optic_pushes_away_and_tips_toward(
    altitude: float, sign: float
) -> None:
    """Flight 5's hollow square grows from 7.2 cm at launch to 11.2 cm at 40 m, wider than
    the 11 cm optic. An offset then no longer takes the optic's far side out of the beam,
    it moves its near side onto the beam's dark centre: the energy dipole turns round, so
    the lateral impulse points away from the beam axis and the axis tips toward it (the
    reverse of test_offset_restores_and_tips_away, which still holds at 10 m). Above about
    30 m the beam no longer centres the craft (problems/crosswind_climb.toml)."""
    d_hat = np.array([1.0, 0.0, 0.0])  # beam axis to craft, L
    for offset in (0.005, 0.01):
        x = initial_state(F5, r_L=(offset, 0.0, altitude))
        out = _run(F5, x)
        along = float(_in_L(x, out["impulse_B"]) @ d_hat)
        turn = float(np.cross(_in_L(x, out["angular_impulse_B"]), [0.0, 0.0, 1.0]) @ d_hat)
        assert sign * along > 0.0 and sign * turn < 0.0
        assert abs(along) > 1e-3 * out["impulse_B"][0]  # at least 0.1 % of the axial kick


def test_negative_blast_angle_pushes_away() -> None:
    """The sign of beta alone decides: beta < 0 turns the lateral impulse outward."""
    p = _params(F5, blast_angle=-0.15)
    x = initial_state(F5, r_L=(0.01, 0.0, 0.0))
    assert _in_L(x, _run(F5, x, p=p)["impulse_B"])[0] > 0.0


# --------------------------------------------------------------------------- health and liner
def test_air_mode_health_steps_down_near_pulse_100() -> None:
    """g(0) = 1 exactly, half-way down at n_f = 100, g_inf = 0.3 beyond; the axial impulse
    follows g."""
    p = parameter_values(F5)
    g = ca.Function("g", [n := ca.SX.sym("n")], [health(n, ca.DM(p))])
    assert float(g(0.0)) == 1.0
    assert float(g(100.0)) == pytest.approx(0.65, abs=1e-5)
    assert float(g(60.0)) > 0.99 and float(g(140.0)) < 0.31
    assert float(g(1000.0)) == pytest.approx(0.3, abs=1e-12)
    gs = np.asarray(g.map(401)(np.arange(401.0))).ravel()
    assert np.all(np.diff(gs[:200]) < 0.0) and np.all(np.diff(gs) <= 0.0)
    first = _run(F5, initial_state(F5))["impulse_B"][0]
    x = initial_state(F5)
    x[STATE.index("engine_load")] = 120.0
    out = _run(F5, x)
    assert out["health"][0] == pytest.approx(float(g(120.0)), rel=1e-14)
    assert out["impulse_B"][0] == pytest.approx(first * float(g(120.0)), rel=1e-12)
    assert out["liner_loss"][0] == 0.0


def test_delrin_ablates_mu_ecap_until_the_liner_is_empty() -> None:
    """Flight 16: liner_loss = ablation * E_cap with a liner (health 1 even past pulse 100);
    the last pulse takes only what is left; an empty liner loses nothing and the engine runs
    on spent_coupling times the air-mode health."""
    p = parameter_values(F16)
    mu = F16.craft.engine.ablation
    x = initial_state(F16)
    x[STATE.index("engine_load")] = 300.0
    full = _run(F16, x)
    assert full["liner_loss"][0] == pytest.approx(mu * full["energy_captured"][0], rel=1e-14)
    assert full["health"][0] == 1.0
    assert full["impulse_B"][0] == pytest.approx(0.195, rel=1e-12)
    x[STATE.index("liner_mass")] = 1e-6  # less than one pulse's 8.3 mg
    assert _run(F16, x)["liner_loss"][0] == 1e-6
    x[STATE.index("liner_mass")] = 0.0
    spent = _run(F16, x)
    g = float(health(ca.DM(300.0), ca.DM(p)))
    assert spent["liner_loss"][0] == 0.0
    assert spent["health"][0] == pytest.approx(g, rel=1e-14)
    spent_coupling = F16.craft.engine.spent_coupling
    assert spent_coupling is not None
    expected = spent_coupling * g * spent["energy_captured"][0]
    assert spent["impulse_B"][0] == pytest.approx(expected, rel=1e-12)


# --------------------------------------------------------------------------- kernel model
def test_kernel_peaks_at_kernel_offset() -> None:
    """Kernel form: |I_lat| = k_L I_ax0 u exp((1 - u^2)/2) peaks at |d| = d0 with value
    k_L I_ax0, |G_M| peaks there with k_M I_ax0 R_f; restoring and tipping away for positive
    gains; I_ax = I_ax0 E_cap(d) / E_cap(0)."""
    m = _with_engine(F5, impulse_model=ImpulseModel.KERNEL)
    e = m.craft.engine
    i_ax0 = _run(m, initial_state(m))["impulse_B"][0]
    e_cap0 = _run(m, initial_state(m))["energy_captured"][0]
    offsets = np.linspace(0.0, 0.1, 201)
    lateral, tipping = [], []
    for d in offsets:
        x = initial_state(m, r_L=(0.0, d, 0.0))
        out = _run(m, x)
        G_F_L, G_M_L = _in_L(x, out["impulse_B"]), _in_L(x, out["angular_impulse_B"])
        lateral.append(-G_F_L[1])
        tipping.append(float(np.cross(G_M_L, [0.0, 0.0, 1.0])[1]) / e.ring_radius)
        assert G_F_L[2] == pytest.approx(i_ax0 * out["energy_captured"][0] / e_cap0, rel=1e-12)
    assert offsets[int(np.argmax(lateral))] == pytest.approx(e.kernel_offset, abs=2.5e-4)
    assert offsets[int(np.argmax(tipping))] == pytest.approx(e.kernel_offset, abs=2.5e-4)
    at_peak = _run(m, initial_state(m, r_L=(0.0, e.kernel_offset, 0.0)))
    assert np.linalg.norm(at_peak["impulse_B"][1:]) == pytest.approx(e.lateral_gain * i_ax0)
    assert np.linalg.norm(at_peak["angular_impulse_B"]) == pytest.approx(
        e.tipping_gain * i_ax0 * e.ring_radius
    )
    assert min(lateral[1:]) > 0.0 and min(tipping[1:]) > 0.0


# --------------------------------------------------------------------------- derivatives
# Finite-difference steps: 1e-5 (|value| + scale). Positions and pointing get a floor of
# 1e-7 m and the pulse counter one of 1e-3 pulses: with the default 1e-9 floor, zero entries
# (a craft on the beam axis, the first pulse) would drown their derivatives in rounding.
X_SCALE = np.full(STATE.size, 1e-4)
X_SCALE[STATE.index("r_L")] = 1e-2
X_SCALE[STATE.slot("engine_load").start] = 100.0
SCALE: list[float | np.ndarray] = [X_SCALE, 1e-2, 1e-4]


def _general_state(model: Model) -> np.ndarray:
    x = initial_state(
        model,
        r_L=(0.012, -0.021, 3.0),
        v_L=(0.1, 0.0, 8.0),
        tilt=0.2,
        tilt_azimuth=1.1,
        w_B=(0.3, -1.0, 2.0),
    )
    x[STATE.index("engine_load")] = 90.0
    return x


@pytest.mark.parametrize(
    "model",
    [F5, F16, _with_engine(F5, impulse_model=ImpulseModel.KERNEL)],
    ids=["flight5-sector", "flight16-delrin", "flight5-kernel"],
)
def test_engine_jacobians_match_finite_differences(model: Model) -> None:
    f = build_engine(model)
    assert f.name() == "engine"
    assert f.name_in() == ["x", "pulse", "p"] and f.name_out() == list(ENGINE_OUTPUT_NAMES)
    x = _general_state(model)
    args = [x, _pulse(pointing=(-0.004, 0.003), focus=40.0), parameter_values(model)]
    out = _run(model, x, args[1], args[2])
    assert out["energy_captured"][0] > 0.5 * ENERGY
    assert np.linalg.norm(out["impulse_B"][1:]) > 0.0 and np.linalg.norm(out["angular_impulse_B"])
    assert_jacobians_match_finite_differences(f, args, scale=SCALE)


def test_kernel_is_smooth_on_the_beam_axis() -> None:
    m = _with_engine(F5, impulse_model=ImpulseModel.KERNEL)
    x = initial_state(m, r_L=(0.0, 0.0, 2.0))
    assert_jacobians_match_finite_differences(
        build_engine(m), [x, _pulse(), parameter_values(m)], scale=SCALE
    )
