"""The hardware's limits on the map input u, and an input saturated to them.

The limits are the model's (frames and units: docs/frames.md):

- ``pointing_L`` [m]: the beam director reaches ``laser.pointing_limit`` on each axis of
  L (east, north);
- ``focus`` [m]: within ``laser.focus_range``;
- ``energy`` [J]: from 0 (no pulse) to ``laser.pulse_energy_max``;
- ``rcs_thrust`` [N]: each thruster pushes from 0 to its ``max_thrust`` at every instant:
  a HOLD or SUBINTERVALS level in [0, max]; a PHASE_LOCKED mean m with amplitudes c, s
  (thrust m + c cos + s sin) needs sqrt(c^2 + s^2) <= min(m, max - m);
- ``motor_torque`` [N m]: the model sets no limit.

Φ clips nothing (a smooth map for the optimiser, :func:`~.vectors.map_input_layout`):
whoever sets the inputs keeps them inside. The MPC and the director do it by their
constraints; the LQR controller, :func:`lightcraft_opt.linearize.lqr_policy` and a user's
own controller (through ``ConingFrame.map_input``) by :func:`saturated_inputs`.
"""

from __future__ import annotations

import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout.vector_layout import VectorLayout
from lightcraft_opt.layout.vectors import map_input_layout
from lightcraft_opt.model import Model

__all__ = ["saturated_inputs"]


def saturated_inputs(model: Model, u: np.ndarray, layout: VectorLayout | None = None) -> np.ndarray:
    """``u`` inside the hardware's limits (module docstring); an input already inside is
    returned unchanged (a copy); a NaN stays NaN.

    Pointing, focus, energy and held thrust levels are clipped entry by entry. The
    phase-locked thrust is projected onto its envelope: each amplitude capped at max/2,
    then every mean raised by the same amount, the least that lifts each to its
    amplitude (a common level adds lift, and no torque for a ring of thrusters along b1
    at equal radius, so the commanded torques survive), and finally clipped to
    [amplitude, max - amplitude].

    Parameters
    ----------
    model : whose laser and thrusters set the limits.
    u : a map input (``layout.size``,).
    layout : its layout (a pulse map's ``inputs``); default the model's with held RCS
        levels (:func:`~.vectors.map_input_layout`).
    """
    craft = model.craft
    lay = layout or map_input_layout(craft.thruster_count, craft.has_carrier)
    out = np.array(u, dtype=float).reshape(-1)
    if out.size != lay.size:
        raise ParameterError("u", f"needs {lay.size} values ({lay.name}), got {out.size}")
    laser = model.laser
    lim = laser.pointing_limit
    for name, lo, hi in (
        ("pointing_L", -lim, lim),
        ("focus", *laser.focus_range),
        ("energy", 0.0, laser.pulse_energy_max),
    ):
        if name in lay:
            out[lay.index(name)] = np.clip(out[lay.index(name)], lo, hi)
    if "rcs_thrust" not in lay:
        return out
    if craft.rcs is None:
        raise ParameterError("layout", f"has rcs_thrust but {model.name!r} has no RCS")
    top = np.array([t.max_thrust for t in craft.rcs.thrusters], dtype=float)
    levels = lay.index("rcs_thrust")
    if "rcs_cos" not in lay:  # HOLD, SUBINTERVALS (sub-interval-major: top repeats)
        size = levels.stop - levels.start
        out[levels] = np.clip(out[levels], 0.0, np.tile(top, size // top.size))
        return out
    cos, sin = lay.index("rcs_cos"), lay.index("rcs_sin")
    c, s = out[cos], out[sin]
    amp = np.hypot(c, s)
    half = top / 2
    scale = np.where(amp > half, half / np.maximum(amp, 1e-300), 1.0)
    c, s, amp = c * scale, s * scale, amp * scale
    out[cos], out[sin] = c, s
    lift = max(0.0, float(np.max(amp - out[levels])))
    out[levels] = np.clip(out[levels] + lift, amp, top - amp)
    return out
