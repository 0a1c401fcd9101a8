"""The layouts of the controllers' own vectors (control/): what the nutation MPC's
prediction model linearises, and the director's quadratic programme.

Built from the model's layouts (:mod:`lightcraft_opt.layout.vectors`) where they share
slots, so a slot's unit and frame have one owner. Frames: docs/frames.md.
"""

from __future__ import annotations

from collections.abc import Sequence

from lightcraft_opt.layout.vector_layout import VectorLayout
from lightcraft_opt.layout.vectors import B123, EAST_NORTH, map_input_layout
from lightcraft_opt.options import RcsProfile

__all__ = ["CONING_ERROR_STATE", "coning_input_layout"]

Spec = list[tuple[str, int, str, str, tuple[str, ...]]]


def _spec(layout: VectorLayout, names: Sequence[str]) -> Spec:
    """The spec rows of ``layout``'s slots ``names``, in that order (unit, frame and
    components as ``layout`` has them)."""
    return [(s.name, s.size, s.unit, s.frame, s.components) for s in map(layout.slot, names)]


#: The error-state entries (ERROR_STATE) the nutation controllers' prediction model is
#: linearised in (control/prediction_model.py): the lateral position and velocity and the
#: transverse attitude and rate, the counterparts, in order, of the coning coordinates
#: r_Y, v_Y, h_Y, c_B (CONING). Left out: the vertical channel, the turn about b1 and its
#: rate (a gauge), the spin and the bookkeeping.
CONING_ERROR_STATE = VectorLayout(
    "coning error state",
    [
        ("r_L", 2, "m", "L", EAST_NORTH),
        ("v_L", 2, "m/s", "L", EAST_NORTH),
        ("theta_B", 2, "rad", "B", B123[1:]),
        ("w_B", 2, "rad/s", "B", B123[1:]),
    ],
)


def coning_input_layout(n_thrusters: int) -> VectorLayout:
    """The map-input slots the nutation controllers' prediction model takes, in order: the
    beam's ``pointing_L`` (2) [m] and the phase-locked RCS's ``rcs_thrust``, ``rcs_cos``,
    ``rcs_sin`` (``n_thrusters`` each) [N] (:func:`~.vectors.map_input_layout`,
    PHASE_LOCKED)."""
    full = map_input_layout(n_thrusters, False, RcsProfile.PHASE_LOCKED)
    names = ("pointing_L", "rcs_thrust", "rcs_cos", "rcs_sin")
    return VectorLayout("coning input", _spec(full, names))
