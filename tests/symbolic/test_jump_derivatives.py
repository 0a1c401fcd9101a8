"""The jump's derivatives through the optic's quadrature (symbolic/maps/jump_derivatives.py)
against casadi's SX AD of the whole jump (pulse_map_derivatives._piece_derivatives).

Both differentiate the same jump by different routes (the structured one cuts it at the
optic's pose, its three energy moments and E_ref), so they agree to rounding: 1e-10 of the
largest entry. Cases cover what the cut must carry: the linear beam and the waist beam
(whose E_ref and fluence depend on the focus), the top-hat and Gaussian profiles, a Delrin
craft (the liner's fmin and if_else read E_cap), an odd radial count, three sectors (the
fewest whose energies carry the three moments), a tilted craft off the beam axis. The chain
over the pieces is checked against AD through Φ and finite differences in
test_pulse_map_derivatives.py, which now runs through this cut.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support.models import table1_flight5
from support.paths import MODELS

from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, STATE, initial_state, parameter_values
from lightcraft_opt.model import BeamProfile, BeamSizeModel, Engine, ImpulseModel, Model
from lightcraft_opt.symbolic.maps.jump_derivatives import structured_jump_derivatives
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import (
    _piece_derivatives,
    build_derivative_pieces,
)
from lightcraft_opt.symbolic.maps.pulse_map_pieces import build_pulse_map_pieces
from lightcraft_opt.symbolic.maps.reduced_map import reduced_pulse_map

RTOL = 1e-10


def _optic(model: Model, radial: int, azimuthal: int, **engine: object) -> Model:
    changed = replace(
        model.craft.engine, quadrature_radial=radial, quadrature_azimuthal=azimuthal, **engine
    )
    return replace(model, craft=replace(model.craft, engine=changed))


def _laser(model: Model, **laser: object) -> Model:
    return replace(model, laser=replace(model.laser, **laser))


def _flight5() -> Model:
    return load_model(MODELS / "flight5.toml")


CASES = {
    "linear-beam": lambda: _optic(_flight5(), 2, 8),
    "waist-beam": lambda: _optic(_laser(_flight5(), size_model=BeamSizeModel.WAIST), 3, 8),
    "top-hat-waist": lambda: _optic(
        _laser(_flight5(), size_model=BeamSizeModel.WAIST, profile=BeamProfile.TOP_HAT), 2, 6
    ),
    "gaussian": lambda: _optic(_laser(_flight5(), profile=BeamProfile.GAUSSIAN), 2, 8),
    "delrin": lambda: _optic(load_model(MODELS / "flight16.toml"), 2, 8),
    "three-sectors": lambda: _optic(_flight5(), 2, 3),  # the fewest the moments allow
}


def _point(model: Model, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(x, pulse, p, adjoint): a tilted, spinning craft 2-3 cm off the beam axis at 12 m,
    the beam focused at 40 m with 300 J, random adjoints."""
    rng = np.random.default_rng(seed)
    x = initial_state(model, r_L=(0.021, -0.013, 12.0), v_L=(0.3, -0.2, 9.0), tilt=0.08)
    x[STATE.index("w_B")] += rng.normal(0, 3.0, 3)
    pulse = np.zeros(PULSE_INPUT.size)
    pulse[PULSE_INPUT.slot("pointing_L")] = (0.004, -0.006)
    pulse[PULSE_INPUT.slot("focus")] = 40.0
    pulse[PULSE_INPUT.slot("energy")] = 300.0
    return x, pulse, parameter_values(model), rng.normal(0, 1.0, STATE.size + 11)


#: Designed entries of p (the OCP's design, v = (x, pulse, p[design])) with the waist beam:
#: the rotor's mass and moment (the pose's mass centre, K), the ring's height (the pose and
#: E_ref's range), the Rayleigh range (the beam's size at each point and at E_ref's), the
#: edge width (the fluence itself), the reference energy (E_ref's and the engine load's).
DESIGNS = {
    "waist-beam": (
        "rotor_mass_dry",
        "rotor_transverse_inertia_dry",
        "ring_height",
        "beam_rayleigh_range",
        "beam_edge_width",
        "reference_pulse_energy",
    ),
    "delrin": ("rotor_mass_dry", "impulse_per_pulse"),
}


def _design(names: tuple[str, ...]) -> tuple[int, ...]:
    return tuple(sorted(PARAMETERS.slot(name).start for name in names))


@pytest.mark.parametrize(
    ("case", "design"),
    [(case, ()) for case in CASES] + [(case, names) for case, names in DESIGNS.items()],
)
def test_the_cut_equals_ad_of_the_whole_jump(case, design):
    model = CASES[case]()
    design = _design(design)
    pieces = build_pulse_map_pieces(model, PulseMapOptions())
    plain_jacobian, plain_hessian = _piece_derivatives(pieces.jump, (0, 1), True, design)
    built = structured_jump_derivatives(model, design=design)
    assert built is not None
    jacobian, hessian = built
    assert hessian is not None
    x, pulse, p, rho = _point(model, 5)
    rho = rho[: plain_hessian.size1_in(3)]
    expected_jac = np.array(plain_jacobian(x, pulse, p))
    jac = np.array(jacobian(x, pulse, p))
    assert np.abs(expected_jac).max() > 1.0  # the point exercises the engine
    np.testing.assert_allclose(jac, expected_jac, rtol=0, atol=RTOL * np.abs(expected_jac).max())
    expected = [np.array(out) for out in plain_hessian(x, pulse, p, rho)]
    got = [np.array(out) for out in hessian(x, pulse, p, rho)]
    for g, e in zip(got, expected, strict=True):
        np.testing.assert_allclose(g, e, rtol=0, atol=RTOL * np.abs(e).max())
    # the focus and the pointing matter on this point (the cut's E_ref and offset terms)
    focus = STATE.size + PULSE_INPUT.slot("focus").start
    pointing = STATE.size + PULSE_INPUT.slot("pointing_L").start
    assert np.abs(expected[1][pointing, pointing]) > 0
    if model.laser.size_model is BeamSizeModel.WAIST:
        assert np.abs(expected[1][focus, focus]) > 0


def test_the_cut_is_smaller_than_ad_of_the_whole_jump():
    """What the cut is for: the model files' 4 x 16 optic's jump Hessian in under half the
    instructions of casadi's AD of the whole jump."""
    model = _optic(_laser(_flight5(), size_model=BeamSizeModel.WAIST), 4, 16)
    pieces = build_pulse_map_pieces(model, PulseMapOptions())
    _, plain = _piece_derivatives(pieces.jump, (0, 1))
    built = structured_jump_derivatives(model)
    assert built is not None and built[1] is not None and plain is not None
    assert built[1].n_instructions() < 0.5 * plain.n_instructions()


def test_the_kernel_model_two_sectors_and_designed_radii_keep_ad_of_the_whole_jump():
    """The cut needs the SECTOR model's three moments, which two sectors cannot carry, and
    quadrature points that the design does not move."""
    model = table1_flight5(engine=Engine(impulse_model=ImpulseModel.KERNEL))
    assert structured_jump_derivatives(model) is None
    assert structured_jump_derivatives(_optic(_flight5(), 2, 2)) is None
    assert structured_jump_derivatives(_optic(_flight5(), 2, 3)) is not None
    radius = _design(("capture_radius",))  # moves the quadrature's points
    assert structured_jump_derivatives(_optic(_flight5(), 2, 8), design=radius) is None
    pieces = build_pulse_map_pieces(model, PulseMapOptions())
    assert pieces.model is model


@pytest.mark.parametrize(
    ("case", "design"),
    [("linear-beam", ()), ("waist-beam", ()), ("waist-beam", DESIGNS["waist-beam"])],
)
def test_the_reduced_maps_jump_through_its_manifold_equals_ad(case, design):
    """Ψ's jump is the pulse's at lift(project(x)) (symbolic/maps/reduced_map.py): its
    derivatives through the cut and the manifold equal casadi's AD of the whole composed
    jump."""
    model = CASES[case]()
    design = _design(design)
    pieces = reduced_pulse_map(model).pieces
    assert pieces is not None and pieces.model is model and pieces.manifold is not None
    plain_jacobian, plain_hessian = _piece_derivatives(pieces.jump, (0, 1), True, design)
    jacobian, hessian = build_derivative_pieces(pieces, design=design).functions()[2:4]
    assert jacobian.name() == "reduced_pulse_jump_jacobian" and hessian is not None
    x, pulse, p, rho = _point(model, 7)
    rho = rho[: plain_hessian.size1_in(3)]
    expected_jac = np.array(plain_jacobian(x, pulse, p))
    np.testing.assert_allclose(
        np.array(jacobian(x, pulse, p)),
        expected_jac,
        rtol=0,
        atol=RTOL * np.abs(expected_jac).max(),
    )
    expected = [np.array(out) for out in plain_hessian(x, pulse, p, rho)]
    got = [np.array(out) for out in hessian(x, pulse, p, rho)]
    for g, e in zip(got, expected, strict=True):
        np.testing.assert_allclose(g, e, rtol=0, atol=RTOL * np.abs(e).max())
    # the point lies off Ψ's manifold, so the chain through m is exercised
    assert np.abs(np.array(pieces.manifold(x, p)).ravel() - x).max() > 1e-3
