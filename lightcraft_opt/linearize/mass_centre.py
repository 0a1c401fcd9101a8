"""The mass centre's place along b1 against the optic, and a model with it moved.

The position is the system mass centre's along b1 from the optic's ring plane at launch
(B frame, positions from P: docs/physics.md#mass-rcs), ``cm_B[b1] − ring_height``: the
lever arm of the engine's impulses about the mass centre (docs/physics.md#sector-model).
A :class:`MassCentreHandle` moves it: the carrier's position ``carrier_position_B[b1]`` when
the craft has a carrier (the mass moves: the moments about the mass centre follow by the
parallel-axis theorem), else the ring's height ``ring_height`` (the optic moves against the
mass, the moments held: for a craft without a carrier nothing else in the model is referred
to the mass centre's place along b1; the aerodynamic moments are about the mass centre
wherever it is, docs/physics.md#aero).
"""

from __future__ import annotations

import math
from dataclasses import replace
from enum import Enum

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import initial_state, parameter_values
from lightcraft_opt.layout.designed import model_with_parameters
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties

__all__ = ["MassCentreHandle", "handle_for", "mass_centre_from_ring", "model_with_mass_centre"]


class MassCentreHandle(Enum):
    """What moves the mass centre against the optic along b1."""

    CARRIER = "carrier"  # carrier_position_B[b1]: the carrier's mass moves
    RING = "ring"  # engine.ring_height: the optic moves, the mass and its moments stay


def mass_centre_from_ring(model: Model) -> float:
    """The system mass centre's position along b1 from the optic's ring plane at launch [m]
    (B frame; > 0: the mass centre ahead of the ring, toward the nose):
    ``cm_B[b1] − ring_height`` (docs/physics.md#mass-rcs; positions in B from P)."""
    x0 = initial_state(model)
    p = parameter_values(model)
    cm_b1 = float(mass_properties(ca.DM(x0), ca.DM(p)).cm_B[0])
    return cm_b1 - model.craft.engine.ring_height


def handle_for(model: Model, handle: MassCentreHandle | str | None) -> MassCentreHandle:
    if handle is None:
        has_carrier = model.craft.carrier is not None
        return MassCentreHandle.CARRIER if has_carrier else MassCentreHandle.RING
    try:
        chosen = MassCentreHandle(handle)
    except ValueError:
        allowed = [h.value for h in MassCentreHandle]
        raise ParameterError("handle", f"must be one of {allowed}, got {handle!r}") from None
    if chosen is MassCentreHandle.CARRIER and model.craft.carrier is None:
        raise ParameterError("handle", f"{model.name!r} has no carrier to move; use 'ring'")
    return chosen


def model_with_mass_centre(
    model: Model, position: float, handle: MassCentreHandle | str | None = None
) -> Model:
    """``model`` with its launch mass centre ``position`` [m] along b1 from the ring plane
    (:func:`mass_centre_from_ring`), moved by ``handle`` (default: the carrier if the craft
    has one, else the ring; module docstring). The new model's own checks run."""
    if not math.isfinite(position):
        raise ParameterError("positions", f"must be finite [m], got {position!r}")
    kind = handle_for(model, handle)
    shift = position - mass_centre_from_ring(model)  # the mass centre moves by this
    if kind is MassCentreHandle.RING:
        engine = replace(model.craft.engine, ring_height=model.craft.engine.ring_height - shift)
        return replace(model, craft=replace(model.craft, engine=engine))
    carrier = model.craft.carrier
    assert carrier is not None  # handle_for
    x0 = initial_state(model)
    total = float(mass_properties(ca.DM(x0), ca.DM(parameter_values(model))).mass)
    # cm_B = (Σ others + m_c c) / M: c moves by M shift / m_c; the ring stays
    c = np.array(carrier.position_B, dtype=float)
    c[0] += total * shift / carrier.mass
    return model_with_parameters(model, {"carrier_position_B": c})
