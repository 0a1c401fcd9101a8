"""The controller factory (control/factory.py): each ControllerKind builds its controller
with the options it is given, the director's nutation MPC only where it applies.

Reference: the kinds' definitions (ControllerKind's docstring) and the director's RCS
choice (DirectorRcs): "nutation" flies the nutation MPC alongside on a craft with RCS.
The MPC, LQR and director are stand-ins recording what they were built from (their own
tests fly them); the open loop is the real one, cheap to build.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from support.paths import MODELS

import lightcraft_opt.control.factory as factory
from lightcraft_opt.control.closed_loop import plant_options
from lightcraft_opt.control.controllers import OpenLoopController
from lightcraft_opt.control.factory import build_controller
from lightcraft_opt.control.options import (
    ControllerKind,
    DirectorOptions,
    DirectorRcs,
    MpcOptions,
)
from lightcraft_opt.errors import OptionError
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import map_input_layout

RCS = load_model(MODELS / "flight5-rcs.toml")
PLAIN = load_model(MODELS / "flight5.toml")


def plant_of(model):  # type: ignore[no-untyped-def]
    """A stand-in plant Φ: only its map-input layout (what the controllers read)."""
    rcs = len(model.craft.rcs.thrusters) if model.craft.rcs else 0
    options = plant_options(model)
    return SimpleNamespace(
        inputs=map_input_layout(rcs, model.craft.has_carrier, options.rcs_profile)
    )


@pytest.fixture
def built(monkeypatch):  # type: ignore[no-untyped-def]
    """Stand-ins for the MPC, LQR, director and prediction model; what each was built
    from, in build order."""
    log: list[tuple[str, dict]] = []

    def stand_in(name: str, *fields: str):  # type: ignore[no-untyped-def]
        def build(*args, **kw):  # type: ignore[no-untyped-def]
            record = {**dict(zip(fields, args, strict=False)), **kw}
            log.append((name, record))
            return SimpleNamespace(name=name, **record)

        return build

    # the names the factory builds with (imported at its top)
    monkeypatch.setattr(factory, "coning_model", lambda model, **kw: ("model", model))
    monkeypatch.setattr(factory, "MpcController", stand_in("mpc", "model", "options"))
    monkeypatch.setattr(factory, "LqrController", stand_in("lqr", "model", "prediction", "weights"))
    monkeypatch.setattr(
        factory, "DirectorController", stand_in("director", "model", "inputs", "options")
    )
    return log


def test_each_kind_builds_its_controller_with_the_options_given(built):
    """mpc: the MPC with the MPC's options on the model's prediction model; lqr: the LQR
    with the MPC's weights; director: the director with its options; none: the open loop
    on the plant's input layout. A kind may be given by its value."""
    plant = plant_of(RCS)
    mpc_options = MpcOptions(horizon=7, time_budget=None)
    director_options = DirectorOptions(horizon=6)
    kw = dict(mpc=mpc_options, director=director_options)

    made = build_controller(ControllerKind.MPC, RCS, plant, **kw)
    assert made.name == "mpc" and made.options is mpc_options
    assert made.prediction == ("model", RCS)

    made = build_controller("lqr", RCS, plant, **kw)
    assert made.name == "lqr" and made.weights is mpc_options.weights
    assert made.prediction == ("model", RCS)

    made = build_controller(ControllerKind.DIRECTOR, RCS, plant, compiled=False, **kw)
    assert made.name == "director" and made.options is director_options
    assert made.inputs is plant.inputs and made.compiled is False
    assert made.nutation is None  # rcs = "tilt": the director fires the thrusters itself

    made = build_controller(ControllerKind.NONE, RCS, plant, **kw)
    assert isinstance(made, OpenLoopController) and made.name == "none"
    assert [name for name, _ in built] == ["mpc", "lqr", "director"]


def test_the_director_flies_the_nutation_mpc_only_on_a_craft_with_rcs(built):
    """rcs = "nutation": on the RCS craft the director gets the nutation MPC, built from
    the MPC's options; on a craft without RCS there is nothing for it to fire."""
    options = DirectorOptions(rcs=DirectorRcs.NUTATION)
    mpc_options = MpcOptions(horizon=5)
    made = build_controller("director", RCS, plant_of(RCS), mpc=mpc_options, director=options)
    assert made.nutation.name == "mpc" and made.nutation.options is mpc_options
    made = build_controller("director", PLAIN, plant_of(PLAIN), director=options)
    assert made.nutation is None
    assert [name for name, _ in built] == ["mpc", "director", "director"]


def test_defaults_are_the_options_defaults(built):
    made = build_controller("mpc", RCS, plant_of(RCS))
    assert made.options == MpcOptions()
    made = build_controller("director", RCS, plant_of(RCS))
    assert made.options == DirectorOptions()


@pytest.mark.parametrize("kind", ["pid", "MPC", None])
def test_an_unknown_kind_lists_the_kinds(kind):
    with pytest.raises(OptionError) as err:
        build_controller(kind, RCS, plant_of(RCS))  # type: ignore[arg-type]
    assert str(err.value) == (
        f"build_controller.kind must be one of ['mpc', 'lqr', 'director', 'none'], got {kind!r}"
    )
