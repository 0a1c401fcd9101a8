"""Aerodynamic friction torque on the spinning rotor about b1 (paper Eq. 6; disk model).

The paper is the seed paper (docs/references.md#paper-eq-6).

Frames (docs/frames.md): the torque acts on the rotor R about the spin axis b1; a
positive value speeds up a rotor spinning positively about b1. ``w_rotor`` is the rotor
angular rate about b1 relative to N (the air turns with the Earth at 7.3e-5 rad/s: negligible), i.e.
``w_B[b1] + spin``. The torque is odd in ``w_rotor`` and opposes it.

Models (:class:`~lightcraft_opt.model.SpinDecayModel`):

- ``NONE``: T = 0.
- ``EXPONENTIAL`` (paper Eq. 6, T = J w_dot with an exponential decay): T = -J w / tau,
  tau = ``spin_time_constant`` from p, so w(t) = w0 exp(-t / tau).
- ``ROTATING_DISK`` (docs/physics.md#spin-decay): a disk of radius R = D / 2 spinning in
  still air, nu = mu / rho, Re = |w| R^2 / nu,

      laminar    T_lam  = 0.616 pi rho R^4 sqrt(nu |w|^3)          (von Karman)
      turbulent  T_turb = 0.073 rho w^2 R^5 (nu / (R^2 |w|))^(1/5)  (Schlichting)

  and T = -disk_faces max(T_lam, T_turb) sign(w). Both formulas are the moment
  coefficients C_M = 3.87 Re^(-1/2) and 0.146 Re^(-1/5) of Schlichting's
  T = C_M rho w^2 R^5 / 2, which count *both* faces of a free disk: ``disk_faces = 1``
  is one disk wetted on both sides, 0.5 a single face. Sources:
  docs/references.md#von-karman-1921 and docs/references.md#schlichting.

Smoothness of the disk model. |w| is regularised as a = sqrt(w^2 + eps^2) with
:data:`SPIN_EPS` = 1e-9 rad/s and sign(w) as w / a, so T is odd, smooth, and
T ~ |w|^(3/2) -> 0 at w = 0 with a finite derivative. The max is the p-norm

    max(T_lam, T_turb) ~ T_lam (1 + x^k)^(1/k),  x = T_turb / T_lam = 0.0377 Re^(3/10),

with k = :data:`SMOOTH_MAX_ORDER` = 8: scale-free (no torque scale to choose, unlike
log-sum-exp), never below the true max, at most 2^(1/8) - 1 = 9 % above it at the
crossover Re ~ 5.5e4 (where the real flow is transitional anyway), 0.4 % above it
for Flight 5 at 10,000 RPM (Re ~ 2.4e5). Writing it through the ratio x avoids
underflow of T^k at small w.
"""

from __future__ import annotations

import math
from typing import TypeVar

import casadi as ca

from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import PARAMETERS
from lightcraft_opt.model import SpinDecayModel

__all__ = [
    "SMOOTH_MAX_ORDER",
    "SPIN_EPS",
    "build_spin_decay",
    "rotating_disk_torque",
    "spin_decay_torque",
]

# Symbolic type of one call: all SX, all MX, or all DM (numeric evaluation).
Expr = TypeVar("Expr", ca.SX, ca.MX, ca.DM)

SPIN_EPS = 1e-9
"""Regularisation of |w| in the disk model, sqrt(w^2 + SPIN_EPS^2) [rad/s]."""

SMOOTH_MAX_ORDER = 8
"""Order k of the p-norm smooth max between laminar and turbulent disk torque [-]."""

_LAMINAR = 0.616 * math.pi  # von Karman: C_M = 3.87 Re^(-1/2), both faces
_TURBULENT = 0.073  # Schlichting: C_M = 0.146 Re^(-1/5), both faces


def rotating_disk_torque(w_rotor: Expr, rho: Expr, mu: Expr, radius: Expr) -> Expr:
    """Smooth magnitude of max(laminar, turbulent) friction torque of a free disk [N m].

    Parameters
    ----------
    w_rotor : scalar disk angular rate relative to the air [rad/s].
    rho : air density [kg/m^3].
    mu : dynamic viscosity [Pa s].
    radius : disk radius R [m].

    Returns
    -------
    Non-negative, even in ``w_rotor``: both faces of one disk (module docstring).
    """
    a = ca.sqrt(w_rotor * w_rotor + SPIN_EPS**2)
    nu = mu / rho
    laminar = _LAMINAR * rho * radius**4 * ca.sqrt(nu * a**3)
    reynolds = a * radius**2 / nu
    ratio = (_TURBULENT / _LAMINAR) * reynolds ** (3 / 10)  # T_turb / T_lam
    k = SMOOTH_MAX_ORDER
    return laminar * (1 + ratio**k) ** (1 / k)


def spin_decay_torque(
    w_rotor: Expr, J: Expr, rho: Expr, mu: Expr, p: Expr, model: SpinDecayModel
) -> Expr:
    """Axial friction torque on the rotor about b1 [N m] (paper Eq. 6 or disk model).

    Parameters
    ----------
    w_rotor : scalar rotor rate about b1 relative to N [rad/s].
    J : scalar rotor axial moment of inertia [kg m^2] (EXPONENTIAL only).
    rho : scalar air density [kg/m^3].
    mu : scalar air dynamic viscosity [Pa s] (ROTATING_DISK only).
    p : (PARAMETERS.size,) parameter vector: ``spin_time_constant`` [s]
        (EXPONENTIAL), ``diameter`` [m] and ``disk_faces`` [-] (ROTATING_DISK).
    model : which law (structural).

    Returns
    -------
    Scalar torque [N m], odd in ``w_rotor``, negative for positive ``w_rotor``.
    """
    if not isinstance(model, SpinDecayModel):
        raise OptionError(
            f"spin decay model must be one of {[m.value for m in SpinDecayModel]}, got {model!r}"
        )
    if model is SpinDecayModel.NONE:
        return 0 * w_rotor
    if model is SpinDecayModel.EXPONENTIAL:
        return -J * w_rotor / PARAMETERS.get("spin_time_constant", p)
    radius = PARAMETERS.get("diameter", p) / 2
    magnitude = rotating_disk_torque(w_rotor, rho, mu, radius)
    sign = w_rotor / ca.sqrt(w_rotor * w_rotor + SPIN_EPS**2)
    return -PARAMETERS.get("disk_faces", p) * magnitude * sign


def build_spin_decay(model: SpinDecayModel) -> ca.Function:
    """casadi.Function ``spin_decay(w_rotor, J, rho, mu, p) -> T``.

    See :func:`spin_decay_torque`; ``T`` is the axial torque on the rotor [N m].
    """
    w = ca.SX.sym("w_rotor")
    J = ca.SX.sym("J")
    rho = ca.SX.sym("rho")
    mu = ca.SX.sym("mu")
    p = ca.SX.sym("p", PARAMETERS.size)
    torque = spin_decay_torque(w, J, rho, mu, p, model)
    return ca.Function(
        "spin_decay", [w, J, rho, mu, p], [torque], ["w_rotor", "J", "rho", "mu", "p"], ["T"]
    )
