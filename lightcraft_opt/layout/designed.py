"""A model with some of its parameters set: the inverse of :func:`parameter_values` for
the entries a design chooses (docs/design.md).

:data:`DESIGNABLE` names what an optimiser may choose: entries of p
(:data:`~lightcraft_opt.layout.vectors.PARAMETERS`) whose model field is one number, and
``launch_spin``, the spin entry of the launch state. :func:`model_with_parameters` returns
the model whose :func:`parameter_values` (and launch spin) are the given values, built
through the model's own dataclasses, so every physical check of the model
(lightcraft_opt/model/craft.py: the inertia triangle, the rim's moment and speed ...) runs
on the design and refuses it with the field named.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout.defaults import parameter_values
from lightcraft_opt.layout.vectors import PARAMETERS
from lightcraft_opt.model import Model

__all__ = ["DESIGNABLE", "LAUNCH_SPIN", "POSITIVE_DESIGN", "model_with_parameters"]

#: The launch state's spin (rotor relative to B) as a design entry [rad/s].
LAUNCH_SPIN = "launch_spin"

#: Design entries -> what each needs of the model (None: nothing) and its SI unit.
DESIGNABLE: Mapping[str, tuple[str | None, str]] = {
    "rotor_mass_dry": (None, "kg"),
    "rotor_axial_inertia_dry": (None, "kg m^2"),
    "rotor_transverse_inertia_dry": (None, "kg m^2"),
    "liner_offset": ("liner", "m"),
    "carrier_mass": ("carrier", "kg"),
    "carrier_position_B": ("carrier", "m"),
    "beam_rayleigh_range": ("waist", "m"),
    "impulse_per_pulse": (None, "N s"),
    LAUNCH_SPIN: (None, "rad/s"),
}

#: Design entries no body or beam has at zero or below (a mass, a moment, a Rayleigh
#: range, an impulse, a spin-stabilised craft's launch spin): their lower bounds must be
#: positive. The liner's offset and the carrier's position are signed.
POSITIVE_DESIGN = frozenset(DESIGNABLE) - {"liner_offset", "carrier_position_B"}


def check_designable(model: Model, name: str, component: int = 0) -> None:
    """Raise a ParameterError naming ``name`` unless ``model`` lets a design choose that
    entry (:data:`DESIGNABLE`; ``component`` of a vector slot, 0-based)."""
    if name not in DESIGNABLE:
        raise ParameterError(name, f"cannot be designed; designable: {sorted(DESIGNABLE)}")
    needs, _ = DESIGNABLE[name]
    size = PARAMETERS.slot(name).size if name in PARAMETERS else 1
    if not 0 <= component < size:
        raise ParameterError(name, f"component {component + 1} of {size}: out of range")
    craft = model.craft
    if needs == "liner" and craft.liner is None:
        raise ParameterError(name, f"{model.name!r} has no liner")
    if needs == "carrier" and craft.carrier is None:
        raise ParameterError(name, f"{model.name!r} has no carrier")
    if needs == "waist" and model.laser.size_model.value != "waist":
        raise ParameterError(
            name,
            f"{model.name!r}'s laser has no waist (size model "
            f"{model.laser.size_model.value!r}): no Rayleigh range acts",
        )


def model_with_parameters(model: Model, values: Mapping[str, float | np.ndarray]) -> Model:
    """``model`` with the :data:`DESIGNABLE` entries of ``values`` {name: SI value (the
    whole slot for a vector slot, frame B)} set, the rest as they were. The rotor's dry
    mass and moments are turned back into the launch mass and moments the craft is given
    (the liner ring added, as :meth:`Craft.dry_rotor_inertia` takes it away). The new
    model's own checks run; its parameter vector equals ``parameter_values(model)`` with
    the values put in (tests/ocp/test_design.py)."""
    for name, value in values.items():
        check_designable(model, name)
        if not np.all(np.isfinite(np.ravel(value))):
            raise ParameterError(name, f"must be finite, got {value!r}")
    p = parameter_values(model)

    def get(name: str) -> float:
        if name in values:
            return float(np.ravel(values[name])[0])
        return float(p[PARAMETERS.index(name)][0])

    craft = model.craft
    m_dry = get("rotor_mass_dry")
    j_dry = get("rotor_axial_inertia_dry")
    i_dry = get("rotor_transverse_inertia_dry")
    liner = craft.liner
    if liner is not None and "liner_offset" in values:
        liner = replace(liner, axial_offset=get("liner_offset"))
    if liner is None:
        mass, j, i = m_dry, j_dry, i_dry
    else:  # Craft.dry_rotor_inertia inverted
        lm, r, z = liner.mass, liner.radius, liner.axial_offset
        mass = m_dry + lm
        zc = lm * z / mass
        j = j_dry + lm * r**2
        i = i_dry + lm * r**2 / 2.0 + lm * (z - zc) ** 2 + m_dry * zc**2
    carrier = craft.carrier
    if carrier is not None:
        position = values.get("carrier_position_B", carrier.position_B)
        carrier = replace(
            carrier,
            mass=get("carrier_mass"),
            position_B=tuple(float(v) for v in np.ravel(position)),  # type: ignore[arg-type]
        )
    spin = float(np.ravel(values[LAUNCH_SPIN])[0]) if LAUNCH_SPIN in values else craft.spin
    new_craft = replace(
        craft,
        mass=mass,
        inertia_axial=j,
        inertia_transverse=i,
        spin=spin,
        liner=liner,
        carrier=carrier,
    )
    laser = model.laser
    if "beam_rayleigh_range" in values:
        laser = replace(laser, rayleigh_range=get("beam_rayleigh_range"))
    flight = replace(model.flight, impulse_per_pulse=get("impulse_per_pulse"))
    if craft.engine.spent_coupling is None:  # it defaulted to the flight's coupling: keep it
        engine = replace(craft.engine, spent_coupling=get("spent_coupling"))
        new_craft = replace(new_craft, engine=engine)
    return replace(model, craft=new_craft, laser=laser, flight=flight)
