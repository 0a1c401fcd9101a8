"""The casadi side of a design (ocp/design.py): p and x0 with the design put in, and the
model's checks on a design as constraint rows.

The checks (lightcraft_opt/model/craft.py) a design can break: the rotor's launch moments
obey the triangle inequality J <= 2 I, the axial moment stays below the one with all the
mass on the rim, J <= m R^2, and the rim's speed |spin| D / 2 below MAX_RIM_SPEED. The
launch moments come from the dry ones and the liner ring as Craft.dry_rotor_inertia takes
them apart.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from lightcraft_opt.layout import PARAMETERS, STATE
from lightcraft_opt.layout.designed import LAUNCH_SPIN
from lightcraft_opt.model.limits import MAX_RIM_SPEED
from lightcraft_opt.ocp.design import DesignLayout

__all__ = ["designed_parameters", "designed_state", "physical_rows"]

_ROTOR = {"rotor_mass_dry", "rotor_axial_inertia_dry", "rotor_transverse_inertia_dry"}


def designed_parameters(layout: DesignLayout, p: ca.MX, d: ca.MX) -> ca.MX:
    """p (PARAMETERS.size, 1) with the design's entries of p taken from d (n_d,) [SI]."""
    return _replaced(p, layout.p_index, d[np.flatnonzero(layout.in_p).tolist()])


def designed_state(layout: DesignLayout, x0: ca.MX, d: ca.MX) -> ca.MX:
    """x0 (STATE.size,) with the launch spin from d, if designed [SI, frame B]."""
    return _replaced(x0, layout.x_index, d[np.flatnonzero(~layout.in_p).tolist()])


def physical_rows(layout: DesignLayout, p: ca.MX, x0: ca.MX) -> list[tuple[str, ca.MX, float]]:
    """The model's checks on the designed ``p`` and ``x0`` (module docstring) as (what,
    expression, upper bound) rows g <= upper; only those a design moves."""
    names = {v.name for v in layout.variables}
    rows: list[tuple[str, ca.MX, float]] = []
    radius = float(layout.model.craft.diameter) / 2
    if names & (_ROTOR | {"liner_offset"}):
        m, j, i = _launch_rotor(p, x0)
        rows.append(("inertia triangle J - 2 I [kg m^2]", j - 2 * i, 0.0))
        rows.append(("J over the rim's moment m R^2 [-]", j / (m * radius**2), 1.0))
    if LAUNCH_SPIN in names:
        spin = x0[STATE.slot("spin").start]
        rows.append(("(rim speed)^2 [m^2/s^2]", (spin * radius) ** 2, MAX_RIM_SPEED**2))
    return rows


def _replaced(base: ca.MX, index: np.ndarray, values: ca.MX) -> ca.MX:
    """``base`` (n,) with entries ``index`` replaced by ``values`` (len(index),)."""
    if index.size == 0:
        return base
    keep = np.ones(base.size1())
    keep[index] = 0.0
    put = np.zeros((base.size1(), index.size))
    put[index, np.arange(index.size)] = 1.0
    return ca.DM(keep) * base + ca.mtimes(ca.DM(put), values)


def _launch_rotor(p: ca.MX, x0: ca.MX) -> tuple[ca.MX, ca.MX, ca.MX]:
    """(mass [kg], J, I [kg m^2]) of the rotor at launch from the dry values in ``p`` and
    the liner's mass in ``x0`` (Craft.dry_rotor_inertia inverted)."""
    m_dry = p[PARAMETERS.slot("rotor_mass_dry").start]
    j_dry = p[PARAMETERS.slot("rotor_axial_inertia_dry").start]
    i_dry = p[PARAMETERS.slot("rotor_transverse_inertia_dry").start]
    lm = x0[STATE.slot("liner_mass").start]
    r = p[PARAMETERS.slot("liner_radius").start]
    z = p[PARAMETERS.slot("liner_offset").start]
    mass = m_dry + lm
    zc = lm * z / mass
    j = j_dry + lm * r**2
    i = i_dry + lm * r**2 / 2 + lm * (z - zc) ** 2 + m_dry * zc**2
    return mass, j, i
