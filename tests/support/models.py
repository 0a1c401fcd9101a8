"""Test models: the craft of the seed paper's Table 1 (docs/references.md#paper-table-1) built
directly from the dataclasses (SI)."""

from __future__ import annotations

import math
from dataclasses import replace

from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import RcsProfile
from lightcraft_opt.model import (
    Aerodynamics,
    Carrier,
    Craft,
    Engine,
    Environment,
    Flight,
    Laser,
    Model,
    Site,
    SpinDecay,
)
from lightcraft_opt.symbolic.maps.options import CoastScheme, PulseMapOptions
from support.paths import MODELS

RPM = 2 * math.pi / 60


def table1_flight5(**craft_changes: object) -> Model:
    """Flight 5 (#200-5/6, air) from Table 1 in SI, calm air, Earth rotating."""
    craft = Craft(
        name="#200-5/6",
        diameter=0.1222,
        mass=0.0325,
        inertia_axial=602.7e-7,
        inertia_transverse=465.3e-7,
        spin=10_000 * RPM,
    )
    craft = replace(craft, **craft_changes)  # type: ignore[arg-type]
    return Model(
        name="flight5-test",
        craft=craft,
        site=Site("WSMR", math.radians(32.4), math.radians(-106.4), 1194.0),
        laser=Laser("PLVTS", 420.0, 26.0, 18e-6, 10.6e-6),
        flight=Flight(
            pulse_energy=420.0, pulse_rate=26.0, beam_side=0.071974, impulse_per_pulse=0.0637
        ),
    )


def torque_free(model: Model, carrier: Carrier | None = None) -> Model:
    """The same craft with every torque switched off, the site frame inertial and gravity
    inverse-square (the analytic references: Kepler invariants, the 1/r^2 gradient)."""
    craft = replace(
        model.craft,
        aero=Aerodynamics(cd_scale=0.0, cl_scale=0.0, cm_scale=0.0),
        spin_decay=SpinDecay(),
        carrier=carrier,
    )
    inverse_square = Environment(gravity_j2=False, earth_rotation=False)
    return replace(model, craft=craft, environment=inverse_square)


#: The cheapest optic quadrature that is still the full engine model (2 radii x 8 sectors):
#: for tests of Φ's structure and derivatives, not of its accuracy.
COARSE_OPTIC = Engine(quadrature_radial=2, quadrature_azimuthal=8)


def coarse_optic(model: Model) -> Model:
    """``model`` with its own engine at a 2 x 8 optic quadrature (the rest of the engine as
    its file gives it): cheap closed loops of the controllers, whose tests compare two
    flights of the same model."""
    engine = replace(model.craft.engine, quadrature_radial=2, quadrature_azimuthal=8)
    return replace(model, craft=replace(model.craft, engine=engine))


def flight5_rcs_coarse() -> Model:
    """models/flight5-rcs.toml (Flight 5 with its four rim thrusters) with :data:`COARSE_OPTIC`."""
    model = load_model(MODELS / "flight5-rcs.toml")
    return replace(model, craft=replace(model.craft, engine=COARSE_OPTIC))


#: Options of Φ for the RCS profiles whose substep inputs differ from the coast inputs: the
#: coning rate ω(x_+) feeds every substep (PHASE_LOCKED), substeps read different levels of u
#: (SUBINTERVALS). Shared by the tests of Φ's derivative chains.
RCS_PHASE_LOCKED_MAP = PulseMapOptions(substeps=4, dense=2, rcs_profile=RcsProfile.PHASE_LOCKED)
RCS_SUBINTERVALS_MAP = PulseMapOptions(
    scheme=CoastScheme.SPLIT,
    substeps=4,
    dense=2,
    rcs_profile=RcsProfile.SUBINTERVALS,
    rcs_subintervals=2,
)
