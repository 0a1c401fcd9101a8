"""Φ's linear models as numbers, without python-control: what the controllers linearise with.

One step of Φ (``x[k+1] = Φ(x[k], u[k], p, t_k)``, symbolic/maps/pulse_map.py) about an
operating point (x_op, u_op) gives ``δ[k+1] = A δ[k] + B δu[k]`` (A = ∂Φ/∂x, B = ∂Φ/∂u,
exact casadi AD). The modules, in the order they build on each other:

- :mod:`.signal_names`: the names of layout entries (``slot[component]``);
- :mod:`.operating_points`: points to linearise about (:func:`trim_hover`,
  :func:`climb_point`), Φ's Jacobians (:func:`pulse_map_jacobian`) and the error state
  of a point (:func:`error_state`);
- :mod:`.linear_model`: A and B at a point as numpy arrays (:func:`linear_model`), in
  :class:`Coordinates` ``FULL`` or ``ERROR_STATE``, by default on :data:`REDUCED_STATES`;
- :mod:`.coning`: A and B at a climb point in coning coordinates with the phase-locked
  RCS (:func:`coning_linear_model`), the nutation controllers' design model;
- :mod:`.riccati`: the discrete LQR gain on matrices (:func:`dlqr_gain`, scipy);
- :mod:`.focus`: the focus of a :class:`~lightcraft_opt.model.FocusSchedule` at a
  height (:func:`scheduled_focus`) and the beam's side it makes there;
- :mod:`.observability`: the N-pulse observability Gramian of Φ along a flight from
  named sensors (:func:`~lightcraft_opt.linear.observability.observability`).

numpy, scipy and casadi only: the nutation MPC, the LQR controller and the director
(:mod:`lightcraft_opt.control`) build on these, and python-control, which takes seconds to
import, stays with :mod:`lightcraft_opt.linearize` (the same models as
``control.StateSpace``, their modes, LQR designs and stability maps, for a user;
docs/architecture.md#contracts).
"""

from lightcraft_opt.linear.coning import ConingLinearModel, coning_linear_model
from lightcraft_opt.linear.focus import focus_for_side, reachable_sides, scheduled_focus, side_at
from lightcraft_opt.linear.linear_model import (
    REDUCED_STATES,
    Coordinates,
    LinearModel,
    linear_model,
)
from lightcraft_opt.linear.operating_points import (
    OperatingPoint,
    PointStatus,
    PulseMapJacobian,
    climb_point,
    error_state,
    pulse_map_jacobian,
    trim_hover,
)
from lightcraft_opt.linear.riccati import dlqr_gain
from lightcraft_opt.linear.signal_names import entry_names, select_entries

__all__ = [
    "REDUCED_STATES",
    "ConingLinearModel",
    "Coordinates",
    "LinearModel",
    "OperatingPoint",
    "PointStatus",
    "PulseMapJacobian",
    "climb_point",
    "coning_linear_model",
    "dlqr_gain",
    "entry_names",
    "error_state",
    "focus_for_side",
    "linear_model",
    "pulse_map_jacobian",
    "reachable_sides",
    "scheduled_focus",
    "select_entries",
    "side_at",
    "trim_hover",
]
