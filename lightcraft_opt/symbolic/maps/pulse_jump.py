"""The jump of the state at a laser pulse (paper Eqs. 12-13, docs/physics.md#jump).

The paper is the seed paper: docs/references.md#paper-eq-12 and
docs/references.md#paper-eq-13.

The pulse lasts 18 us, so bounded forces do nothing during it; the impulses change
the momenta at once:

    m v_L+ = m v_L- + R_LB G_F                  (Eq. 12b, m at t_k^-)
    H_B+ = H_B- + G_M                            (Eq. 13b, free-rotor form:
                                                  Mmat delta[w; psi_dot] = [G_M; G_R])

The axial angular impulse acts on the rotor (the engine is part of it). Position
and attitude do not jump. The liner loses the ablated mass; the pulse counter
advances by the pulse's energy over the reference energy (a dropped pulse counts 0).
"""

from __future__ import annotations

import casadi as ca

from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, STATE
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.assemble import assemble
from lightcraft_opt.symbolic.terms.engine import engine_impulse
from lightcraft_opt.symbolic.terms.gyrostat import gyrostat_accelerations
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.rotation import dcm

__all__ = ["pulse_jump"]


def pulse_jump(
    x: ca.SX,
    pulse: ca.SX,
    p: ca.SX,
    model: Model,
    energies: tuple[ca.SX, ca.SX] | None = None,
) -> tuple[ca.SX, dict[str, ca.SX]]:
    """State just after a pulse, and the engine quantities of that pulse.

    Parameters
    ----------
    x : state just before the pulse (layout STATE).
    pulse : per-pulse input (layout PULSE_INPUT: pointing [m, L], focus [m], energy [J]).
    p : parameters.
    energies : the engine's sector and reference energies given, not computed
        (:func:`~lightcraft_opt.symbolic.terms.engine.engine_impulse`).

    Returns
    -------
    x_plus : state just after.
    engine : the engine model's outputs (energy_captured [J], impulse_B [N s, B],
        angular_impulse_B [N m s, B, about S*], offset_L [m], liner_loss [kg], health).
    """
    eng = engine_impulse(x, pulse, p, model, energies)
    mp = mass_properties(x, p)
    G_F, G_M = eng["impulse_B"], eng["angular_impulse_B"]
    dv_L = ca.mtimes(dcm(STATE.get("q_LB", x)), G_F) / mp.mass
    dw, dspin = gyrostat_accelerations(
        ca.SX.zeros(3),
        0,
        G_M,
        G_M[0],
        mp.I_B,
        mp.J,
        mp.I,
        massless_carrier=not model.craft.has_carrier,
    )
    # the engine load counts energy in reference pulses (a dropped pulse adds 0)
    load = PULSE_INPUT.get("energy", pulse) / PARAMETERS.get("reference_pulse_energy", p)
    jump = assemble(
        STATE,
        {
            "v_L": dv_L,
            "w_B": dw,
            "spin": dspin,
            "liner_mass": -eng["liner_loss"],
            "engine_load": load,
        },
    )
    return x + jump, eng
