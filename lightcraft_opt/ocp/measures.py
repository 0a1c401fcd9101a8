"""What optimal control problems constrain and reward, as casadi Functions of the state and
of Φ's engine output (the transcription only sums and bounds them).

Frames (docs/frames.md): L is east-north-up at the pad; ``R_LB = dcm(q_LB)`` has b1, the
craft axis, as its first column, so cos(tilt) = b1 . z_L = R_LB[2, 0].
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.layout import ENGINE, PARAMETERS, STATE
from lightcraft_opt.symbolic.terms.rotation import dcm

__all__ = ["build_node_measures", "build_pulse_measures"]


def build_node_measures() -> ca.Function:
    """casadi.Function ``ocp_node_measures(x, p) -> (altitude, drift_L, cos_tilt,
    energy_fired)``.

    Inputs: ``x`` (STATE.size,) state; ``p`` (PARAMETERS.size,).

    Outputs
    -------
    altitude : r_L[up], height of the mass centre above the pad [m].
    drift_L : (2,) r_L east/north, offset of the mass centre from the pad's vertical,
        L frame [m].
    cos_tilt : cosine of the angle between b1 and L up, b1 . z_L [-] (exact for a unit
        quaternion, as Φ returns).
    energy_fired : laser energy fired since the engine load was 0, ``engine_load`` times
        ``reference_pulse_energy`` [J] (the load advances by E / E_ref a pulse:
        symbolic/maps/pulse_jump.py).
    """
    x = ca.SX.sym("x", STATE.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    r_L = STATE.get("r_L", x)
    R_LB = dcm(STATE.get("q_LB", x))
    energy = STATE.get("engine_load", x) * PARAMETERS.get("reference_pulse_energy", p)
    return ca.Function(
        "ocp_node_measures",
        [x, p],
        [r_L[2], r_L[0:2], R_LB[2, 0], energy],
        ["x", "p"],
        ["altitude", "drift_L", "cos_tilt", "energy_fired"],
    )


def build_pulse_measures() -> ca.Function:
    """casadi.Function ``ocp_pulse_measures(engine, p) -> (offset_L, capture_use)``.

    Inputs: ``engine`` (11,) Φ's engine output of one pulse
    (:data:`~lightcraft_opt.layout.ENGINE`); ``p`` (PARAMETERS.size,).

    Outputs
    -------
    offset_L : (2,) east/north offset of the optic centre from the beam axis, L frame [m].
    capture_use : (|offset_L| / capture_radius)^2 [-], smooth everywhere: the squared
        fraction of the capture radius at which the beam axis meets the optic plane.
    """
    eng = ca.SX.sym("engine", ENGINE.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    offset = ENGINE.get("offset_L", eng)
    use = ca.sumsqr(offset) / PARAMETERS.get("capture_radius", p) ** 2
    return ca.Function(
        "ocp_pulse_measures", [eng, p], [offset, use], ["engine", "p"], ["offset_L", "capture_use"]
    )
