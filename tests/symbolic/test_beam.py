"""Beam fluence and size: energy conservation, the soft box of docs/physics.md#hollow-square,
the hole, size models.

References: docs/physics.md#beam (hollow-square fluence with logistic soft edges, linear and
waist size models, the launch beam sides of the seed paper's Table 1,
docs/references.md#paper-table-1); the closed-form integral of a difference of
logistics (int [s(A + u) - s(u - A)] du = 2A) for the exact normalisation; fine numpy grids
(midpoint rule, spectrally accurate for these smooth, decaying profiles) as the independent
integrator.
"""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np
import pytest
from support.jacobian_check import assert_jacobians_match_finite_differences

from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, parameter_values
from lightcraft_opt.model import BeamProfile, BeamSizeModel, Laser, Model
from lightcraft_opt.symbolic.terms.beam import beam_side, build_beam, fluence

MODEL = load_model("models/flight5.toml")
ENERGY = 420.0  # J, Table 1


def _params(model: Model = MODEL, **changes: float) -> np.ndarray:
    p = parameter_values(model)
    for name, value in changes.items():
        p[PARAMETERS.index(name)] = value
    return p


def _pulse(focus: float = 500.0, energy: float = ENERGY) -> np.ndarray:
    return PULSE_INPUT.pack({"pointing_L": (0.0, 0.0), "focus": focus, "energy": energy})


def _laser(**changes: object) -> Laser:
    return dataclasses.replace(MODEL.laser, **changes)  # type: ignore[arg-type]


def _grid_fluence(
    laser: Laser, p: np.ndarray, half: float, step: float, a: float = 0.071974
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(X, Y, F) on a square grid of cell centres, |x|, |y| < half, beam size a [m, J/m^2].

    Evaluates :func:`fluence` on DM arrays (vectorised); the Function wrapping it is
    checked in :func:`test_beam_fluence_function_is_fluence_at_beam_side`."""
    x = np.arange(-half + step / 2, half, step)
    X, Y = np.meshgrid(x, x)
    F = fluence(ca.DM(X.ravel()), ca.DM(Y.ravel()), ca.DM(a), ca.DM(ENERGY), ca.DM(p), laser)
    return X, Y, np.asarray(F).reshape(X.shape)


# --------------------------------------------------------------------------- energy
@pytest.mark.parametrize("profile", list(BeamProfile))
@pytest.mark.parametrize(("side", "edge"), [(0.071974, 0.003), (0.02, 0.005)])
def test_each_profile_integrates_to_the_pulse_energy(
    profile: BeamProfile, side: float, edge: float
) -> None:
    """The normalisations are closed forms, so every profile integrates to E up to rounding,
    for a Table 1 beam and for a small beam whose soft edge is a quarter of its side."""
    p = _params(beam_edge_width=edge)
    _, _, F = _grid_fluence(_laser(profile=profile), p, half=0.15, step=2.5e-4, a=side)
    assert F.sum() * 2.5e-4**2 == pytest.approx(ENERGY, rel=1e-9)


def test_hollow_square_is_physics_md_soft_box_within_documented_bound() -> None:
    """Independent form: the F = E/(a^2 - b^2) [W(a) - W(b)] of docs/physics.md#hollow-square,
    W(s) = s((s/2 - |x|)/w) s((s/2 - |y|)/w), with the true |x|. beam.py's box is that box times
    a factor within e^{-s/(2w)} of 1, so the two fluences differ by at most E/(a^2 - b^2) 2
    (e^{-a/2w} + e^{-b/2w}) everywhere."""
    a, h, w = 0.071974, 0.4, 0.003
    b = h * a
    X, Y, F = _grid_fluence(MODEL.laser, _params(), half=0.08, step=5e-4)

    def s(t: np.ndarray) -> np.ndarray:
        return 1 / (1 + np.exp(-t))

    def box(side: float) -> np.ndarray:
        return s((side / 2 - np.abs(X)) / w) * s((side / 2 - np.abs(Y)) / w)

    F_md = ENERGY / (a * a - b * b) * (box(a) - box(b))
    bound = ENERGY / (a * a - b * b) * 2 * (math.exp(-a / (2 * w)) + math.exp(-b / (2 * w)))
    assert np.max(np.abs(F - F_md)) <= bound
    assert np.max(np.abs(F - F_md)) > bound / 100  # the bound is not vacuous


def test_hollow_square_hole_is_dark_up_to_its_soft_edge() -> None:
    """No energy in the hole but what its soft edge lets in: the fluence at the hole's centre
    is sech^2(b/(4w)) - sech^2(a/(4w)) of the ring's, and the energy inside the hole is the
    edge leak ~ 4 b w ln 2 / (a^2 - b^2) of E (int_{-inf}^0 s(u/w) du = w ln 2 per unit of
    perimeter), which vanishes with w."""
    a, h = 0.071974, 0.4
    b = h * a
    ring = ENERGY / (a * a - b * b)
    leaks = []
    for w in (0.003, 0.001, 0.0003):
        p = _params(beam_edge_width=w)
        centre = float(fluence(ca.DM(0), ca.DM(0), ca.DM(a), ca.DM(ENERGY), ca.DM(p), MODEL.laser))
        expected = 1 / math.cosh(b / (4 * w)) ** 2 - 1 / math.cosh(a / (4 * w)) ** 2
        assert centre / ring == pytest.approx(expected, rel=1e-9)
        _, _, F = _grid_fluence(MODEL.laser, p, half=b / 2, step=b / 800)
        leak = F.sum() * (b / 800) ** 2 / ENERGY
        assert leak == pytest.approx(4 * b * w * math.log(2) / (a * a - b * b), rel=0.1)
        leaks.append(leak)
    assert leaks[2] < 0.006  # 0.3 mm edges: the hole holds under 0.6 % of the pulse


# --------------------------------------------------------------------------- size along the beam
def test_linear_size_grows_with_the_divergence() -> None:
    """LINEAR: a(z) = Table 1 side + divergence z (1 mrad in plvts.toml)."""
    p = _params()
    for z in (0.0, 10.0, 71.0, 500.0):
        a = float(beam_side(ca.DM(z), ca.DM(3.0), ca.DM(p), MODEL.laser))
        assert a == pytest.approx(0.071974 + 1e-3 * z, rel=1e-15)


@pytest.mark.parametrize("focus", [2.0, 30.0, 71.0, 500.0])
def test_waist_is_a_gaussian_beam_of_fixed_quality(focus: float) -> None:
    """WAIST (Siegman ch. 17): a(0) is the Table 1 side for every focus; the waist sits at
    z_w = f / (1 + (f/z_R)^2) <= z_R / 2 with side a0 (f/z_R) / sqrt(1 + (f/z_R)^2), where
    da/dz vanishes; at z = f the side is a0 f / z_R; and the beam's quality is the same for
    every focus: a_w^2 / z_w (waist side squared over its own Rayleigh range, proportional to
    M^2 lambda) equals a0^2 / z_R, the collimated beam's."""
    z_r, a0 = 72.0, 0.071974
    laser = _laser(size_model=BeamSizeModel.WAIST)
    p = _params(beam_rayleigh_range=z_r)
    z = ca.SX.sym("z")
    a = ca.Function("a", [z], [beam_side(z, ca.DM(focus), ca.DM(p), laser)])
    da = ca.Function("da", [z], [ca.jacobian(a(z), z)])
    assert float(a(0.0)) == pytest.approx(a0, rel=1e-14)
    ratio = focus / z_r
    z_waist = focus / (1 + ratio**2)
    a_waist = a0 * ratio / math.sqrt(1 + ratio**2)
    zs = np.linspace(0.0, 1000.0, 100_001)
    sizes = np.asarray(a.map(zs.size)(zs)).ravel()
    assert zs[np.argmin(sizes)] == pytest.approx(z_waist, abs=0.01)
    assert z_waist <= z_r / 2 + 1e-12
    assert float(a(z_waist)) == pytest.approx(a_waist, rel=1e-12)
    assert abs(float(da(z_waist))) < 1e-15
    assert float(a(focus)) == pytest.approx(a0 * ratio, rel=1e-12)
    # the waist's own Rayleigh range: where the side has grown by sqrt(2)
    z_own = z_r * ratio**2 / (1 + ratio**2)
    assert float(a(z_waist + z_own)) == pytest.approx(math.sqrt(2) * a_waist, rel=1e-12)
    assert a_waist**2 / z_own == pytest.approx(a0**2 / z_r, rel=1e-12)


def test_collimated_waist_beam_has_the_linear_far_field() -> None:
    """f -> infinity: a(z) = a0 sqrt(1 + (z/z_R)^2), growing like a0 z / z_R far out: the
    LINEAR model's divergence 1 mrad with z_R = a0 / 1 mrad = 72 m (plvts.toml)."""
    laser = _laser(size_model=BeamSizeModel.WAIST)
    p = _params()
    a = float(beam_side(ca.DM(10_000.0), ca.DM(1e12), ca.DM(p), laser))
    assert a == pytest.approx(0.071974 * math.sqrt(1 + (10_000.0 / 72.0) ** 2), rel=1e-9)
    assert a / 10_000.0 == pytest.approx(1e-3, rel=1e-3)


# --------------------------------------------------------------------------- derivatives
@pytest.mark.parametrize("profile", list(BeamProfile))
@pytest.mark.parametrize("size_model", list(BeamSizeModel))
def test_beam_fluence_jacobian_matches_finite_differences(
    profile: BeamProfile, size_model: BeamSizeModel
) -> None:
    laser = _laser(profile=profile, size_model=size_model)
    f = build_beam(laser)
    assert f.name() == "beam_fluence"
    assert f.name_in() == ["xi_eta", "z", "pulse", "p"] and f.name_out() == ["F"]
    p = _params()
    a = float(beam_side(ca.DM(35.0), ca.DM(60.0), ca.DM(p), laser))
    args: list[np.ndarray | float] = [np.array([0.45 * a, -0.1 * a]), 35.0, _pulse(60.0), p]
    assert float(f(*args)) > 0.0
    scale: list[float | np.ndarray] = [1e-4, 1.0, 1e-4, 1e-4]  # z steps >= 1e-5 m
    assert_jacobians_match_finite_differences(f, args, scale=scale)
    # smooth on the axis too (no |x| or sqrt(0) inside)
    assert_jacobians_match_finite_differences(f, [np.zeros(2), 0.0, _pulse(), p], scale=scale)


def test_beam_fluence_function_is_fluence_at_beam_side() -> None:
    """The Function composes beam_side (at the pulse's focus) and fluence (pulse energy)."""
    laser = _laser(size_model=BeamSizeModel.WAIST)
    p = _params()
    a = beam_side(ca.DM(40.0), ca.DM(25.0), ca.DM(p), laser)
    direct = fluence(ca.DM(0.01), ca.DM(0.02), a, ca.DM(300.0), ca.DM(p), laser)
    via = build_beam(laser)([0.01, 0.02], 40.0, _pulse(focus=25.0, energy=300.0), p)
    assert float(via) == pytest.approx(float(direct), rel=1e-14)
