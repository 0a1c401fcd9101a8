"""Linearisation of the pulse map Φ with python-control: multipliers, controllability, LQR.

One step of Φ (``x[k+1] = Φ(x[k], u[k], p, t_k)``, symbolic/maps/pulse_map.py) about an
operating point (x_op, u_op) gives the discrete-time linear model

    δ[k+1] = A δ[k] + B δu[k],   A = ∂Φ/∂x,  B = ∂Φ/∂u   (exact casadi AD),

sampled at the pulse period T = 1 / pulse_rate, returned as a ``control.StateSpace``
with ``dt = T`` and the layout's names. Its eigenvalues are the pulse-to-pulse
multipliers (Floquet multipliers of the hybrid flow): |λ| > 1 grows by |λ| a pulse.

The numbers underneath (operating points, Φ's Jacobians, A and B as arrays, the discrete
Riccati gain, the focus schedule) are :mod:`lightcraft_opt.linear`, which imports no
python-control; they are re-exported here. The modules here, in the order they build on
each other:

- :mod:`.state_space`: the linear model (:func:`linearize`) in :class:`Coordinates`
  ``FULL`` or ``ERROR_STATE``, by default on :data:`REDUCED_STATES`, and the nutation
  controllers' design model in coning coordinates (:func:`coning_state_space`);
- :mod:`.modes`: multipliers and the kind of each mode (:func:`multipliers`,
  :func:`beam_riding_modes`), and :func:`controllability`;
- :mod:`.state_feedback`: discrete LQR (:func:`lqr`) and its feedback policy
  (:func:`lqr_policy`, saturated to the hardware's limits, :class:`SaturationWarning`);
- :mod:`.stability_grid`: multipliers over spin rate × beam offset
  (:func:`stability_map`);
- :mod:`.beam_riding`: multipliers over altitude × focus schedule × offset
  (:func:`altitude_stability`) and over the beam's side at the craft
  (:func:`side_stability`);
- :mod:`.spin_margin`: the least launch spin keeping the beam-riding multipliers under a
  limit along a climb (:func:`least_stable_spin`), the spin decayed along the climb
  (:mod:`.climb_spin`, :func:`climb_spin`); :mod:`.spin_margin_sweep` against the mass
  centre's position along b1 (:func:`spin_margin_sweep`; :mod:`.mass_centre` moves it).

Only :mod:`.state_space`, :mod:`.modes` and :mod:`.state_feedback` import python-control
(an import-linter contract), and ``import lightcraft_opt`` reaches this package on first use
of ``lc.linearize``. The nutation MPC's prediction model, linear models in coning
coordinates scheduled on spin and altitude, is :mod:`lightcraft_opt.control.prediction_model`;
one of its points is :func:`coning_state_space`.

Everything public is re-exported here: ``from lightcraft_opt.linearize import ...``.
"""

from lightcraft_opt.linear.focus import focus_for_side, reachable_sides, scheduled_focus
from lightcraft_opt.linear.linear_model import REDUCED_STATES, Coordinates
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
from lightcraft_opt.linearize.beam_riding import (
    AltitudeStability,
    FocusSchedule,
    SideStability,
    altitude_stability,
    side_stability,
)
from lightcraft_opt.linearize.climb_spin import climb_spin
from lightcraft_opt.linearize.mass_centre import MassCentreHandle, model_with_mass_centre
from lightcraft_opt.linearize.modes import (
    Controllability,
    ModeKind,
    Multipliers,
    beam_riding_modes,
    controllability,
    multipliers,
)
from lightcraft_opt.linearize.spin_margin import (
    SpinMarginOptions,
    SpinMarginStatus,
    SpinScan,
    least_stable_spin,
)
from lightcraft_opt.linearize.spin_margin_sweep import SpinMarginSweep, spin_margin_sweep
from lightcraft_opt.linearize.stability_grid import StabilityMap, stability_map
from lightcraft_opt.linearize.state_feedback import (
    LqrResult,
    SaturationWarning,
    lqr,
    lqr_policy,
)
from lightcraft_opt.linearize.state_space import coning_state_space, linearize

__all__ = [
    "REDUCED_STATES",
    "AltitudeStability",
    "Controllability",
    "Coordinates",
    "FocusSchedule",
    "LqrResult",
    "MassCentreHandle",
    "ModeKind",
    "Multipliers",
    "OperatingPoint",
    "PointStatus",
    "PulseMapJacobian",
    "SaturationWarning",
    "SideStability",
    "SpinMarginOptions",
    "SpinMarginStatus",
    "SpinMarginSweep",
    "SpinScan",
    "StabilityMap",
    "altitude_stability",
    "beam_riding_modes",
    "climb_point",
    "climb_spin",
    "coning_state_space",
    "controllability",
    "dlqr_gain",
    "error_state",
    "focus_for_side",
    "least_stable_spin",
    "linearize",
    "lqr",
    "lqr_policy",
    "model_with_mass_centre",
    "multipliers",
    "pulse_map_jacobian",
    "reachable_sides",
    "scheduled_focus",
    "side_stability",
    "spin_margin_sweep",
    "stability_map",
    "trim_hover",
]
