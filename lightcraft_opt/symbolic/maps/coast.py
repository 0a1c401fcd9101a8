"""Fixed-step coasts between pulses: RK4 substeps, or a splitting that rotates the
spinning body exactly.

Both are pure casadi expressions (differentiable, usable inside Φ). The coning mode
of a 10,000 RPM craft is at |H|/I ~ 1356 rad/s (216 Hz), eight times the pulse rate:
RK4 needs steps of ~0.2 ms to resolve it (docs/physics.md#coning-rates).

Splitting (Strang, second order; docs/references.md#strang-1968): the right-hand side
f = f_fast + f_slow, where f_fast is the torque-free motion of the axisymmetric spinning body
in a non-rotating site frame. That part has a closed form (Goldstein 5.6,
docs/references.md#goldstein): with H_B the angular momentum, I_t the transverse and J the
rotor axial moment,

    w_B(h)  = Rot(b1, +Omega_n h) w_B,          Omega_n = (J w_R - I_t w1) / I_t
    R_LB(h) = Rot(h_L, |H| h / I_t) R_LB Rot(b1, -Omega_n h)

(w_R = w1 + spin; H fixed in L). f_slow (translation, aerodynamic, RCS and friction
torques, Earth rate) is smooth on the pulse time scale and is stepped by RK4:
slow(h/2), fast(h), slow(h/2). The fast part needs an axisymmetric mass
distribution about S* (no carrier, RCS tank on the axis): the builder checks it.

Time-varying inputs (RCS thrust over the interval, layout.map_input_layout): every
scheme evaluates the right-hand side only at its stage times, so a smooth input
(PHASE_LOCKED) is sampled where the scheme samples its slow forces and the order is
kept (time is the slow flow's extra state; Yoshida's (docs/references.md#yoshida-1990) backward
slow step stays inside its substep). Inputs that jump (SUBINTERVALS) come as one right-hand side
per substep, constant on it: the substeps must align with the jumps.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import casadi as ca

from lightcraft_opt.errors import OptionError
from lightcraft_opt.layout import STATE
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.assemble import assemble
from lightcraft_opt.symbolic.terms.gyrostat import angular_momentum, gyrostat_accelerations
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.rotation import dcm, quat_derivative, quat_multiply

__all__ = ["coning_rate_B", "exact_spin_flow", "rk4_coast", "split_coast"]

Rhs = Callable[[ca.SX, ca.SX], ca.SX]  # (t, x) -> xdot
#: One right-hand side for the whole coast, or one per substep (inputs constant on each).
Rhses = Rhs | Sequence[Rhs]


def _on_step(rhs: Rhses, k: int, steps: int) -> Rhs:
    """The right-hand side of substep k."""
    if callable(rhs):
        return rhs
    if len(rhs) != steps:
        raise ValueError(f"{len(rhs)} right-hand sides for {steps} substeps")
    return rhs[k]


def rk4_coast(rhs: Rhses, t0: ca.SX, x0: ca.SX, dt: ca.SX, steps: int) -> list[ca.SX]:
    """Classical RK4 with ``steps`` equal steps over [t0, t0 + dt].

    ``rhs`` is one (t, x) -> xdot, or one per step. Returns the state after every step
    (``steps`` entries, the last is x(t0 + dt)).
    """
    h = dt / steps
    x, out = x0, []
    for k in range(steps):
        t = t0 + k * h
        f = _on_step(rhs, k, steps)
        k1 = f(t, x)
        k2 = f(t + h / 2, x + h / 2 * k1)
        k3 = f(t + h / 2, x + h / 2 * k2)
        k4 = f(t + h, x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x)
    return out


def _axis_angle_quaternion(phi: ca.SX) -> ca.SX:
    """Unit quaternion of the rotation vector phi (axis * angle), smooth at phi = 0."""
    theta2 = ca.sumsqr(phi)
    theta = ca.sqrt(theta2 + 1e-300)
    # sin(theta/2)/theta with its series below 1e-4 rad (error < 1e-17)
    half_sinc = ca.if_else(theta2 < 1e-8, 0.5 - theta2 / 48, ca.sin(theta / 2) / theta)
    return ca.vertcat(ca.cos(theta / 2), half_sinc * phi)


def coning_rate_B(x: ca.SX, p: ca.SX) -> ca.SX:
    """Rate [rad/s] at which the transverse angular momentum H_⊥ (and w_⊥) turns in the
    despun frame B about +b1 during torque-free motion: the coning (nutation) rate seen
    in B, the ω of the PHASE_LOCKED RCS profile.

    Derivation (axisymmetric craft: every particle of I_B on b1, so I_B is diagonal with
    I_B22 = I_B33): H_B = (C w1 + J ψ̇, A w2, A w3) with C = I_B11 + J and
    A = I_B22 + I (symbolic/terms/gyrostat.py; docs/physics.md#gyrostat). Torque-free, in B,
    dH_B/dt = -w_B × H_B gives dH1/dt = 0 and

        dH2/dt = -(H1 - A w1)/A H3,    dH3/dt = +(H1 - A w1)/A H2,

    so H_⊥ turns about +b1 at ω = (H1 - A w1) / A, constant (w1 is constant in the
    gauge of docs/frames.md). In the gauge's usual state w1 = 0 this is ω = H1 / A
    = J ψ̇ / A; in general ω = (J (w1 + ψ̇) + (I_B11 - A) w1) / A. It is the rate of
    :func:`exact_spin_flow`'s rotation of w_B (same formula), and for Flight 5
    at 10,000 RPM (J = 602.7, A = I = 465.3 g cm^2) 1356.43 rad/s (216 Hz), the
    J spin / (I cos θ) of docs/physics.md#coning-rates at small cone angle θ. It differs from
    the rate at which b1 cones about H in N, |H| / A, by the factor cos θ only.

    Parameters
    ----------
    x : state (layout.STATE).
    p : parameters (layout.PARAMETERS).

    Returns
    -------
    ω [rad/s], positive for a positive rotor spin.
    """
    mp = mass_properties(x, p)
    I_t = mp.I + mp.I_B[1, 1]
    w = STATE.get("w_B", x)
    H_B = angular_momentum(w, STATE.get("spin", x), mp.I_B, mp.J, mp.I)
    return _coning_rate(H_B, w, I_t)


def _coning_rate(H_B: ca.SX, w_B: ca.SX, I_t: ca.SX) -> ca.SX:
    """ω = (H1 - A w1) / A (:func:`coning_rate_B`), from quantities already built."""
    return (H_B[0] - I_t * w_B[0]) / I_t


def exact_spin_flow(x: ca.SX, p: ca.SX, h: ca.SX) -> ca.SX:
    """Torque-free motion of the axisymmetric spinning body over h [s], in closed form.

    Changes only q_LB and w_B (B frame); everything else is held. w_B turns about b1 at
    :func:`coning_rate_B`.
    """
    mp = mass_properties(x, p)
    I_t = mp.I + mp.I_B[1, 1]
    w = STATE.get("w_B", x)
    spin = STATE.get("spin", x)
    q = STATE.get("q_LB", x)
    H_B = angular_momentum(w, spin, mp.I_B, mp.J, mp.I)
    omega_n = _coning_rate(H_B, w, I_t)
    c, s = ca.cos(omega_n * h), ca.sin(omega_n * h)
    w_new = ca.vertcat(w[0], c * w[1] - s * w[2], s * w[1] + c * w[2])
    H_L = ca.mtimes(dcm(q), H_B)
    q_precess = _axis_angle_quaternion(H_L * h / I_t)
    q_body = ca.vertcat(ca.cos(omega_n * h / 2), -ca.sin(omega_n * h / 2), 0, 0)
    q_new = quat_multiply(quat_multiply(q_precess, q), q_body)
    return assemble(STATE, {"q_LB": q_new, "w_B": w_new}, base=x)


def _fast_rhs(x: ca.SX, p: ca.SX, model: Model) -> ca.SX:
    """f_fast: the torque-free rotation in a non-rotating frame (what exact_spin_flow solves)."""
    mp = mass_properties(x, p)
    w = STATE.get("w_B", x)
    spin = STATE.get("spin", x)
    w_dot, spin_dot = gyrostat_accelerations(
        w, spin, ca.SX.zeros(3), 0, mp.I_B, mp.J, mp.I, massless_carrier=not model.craft.has_carrier
    )
    q_dot = quat_derivative(STATE.get("q_LB", x), w)
    return assemble(STATE, {"q_LB": q_dot, "w_B": w_dot, "spin": spin_dot})


def check_splitting_applies(model: Model) -> None:
    """The exact fast flow needs an axisymmetric craft; raise OptionError otherwise."""
    craft = model.craft
    if craft.has_carrier:
        raise OptionError(
            "coast scheme 'split' needs an axisymmetric spinning body; this craft has a "
            "despun carrier: use 'rk4'"
        )


def split_coast(
    rhs: Rhses,
    p: ca.SX,
    model: Model,
    t0: ca.SX,
    x0: ca.SX,
    dt: ca.SX,
    steps: int,
    order: int = 2,
) -> list[ca.SX]:
    """Strang splitting: RK4 on f - f_fast for h/2, exact fast flow for h, RK4 for h/2
    (``order`` 2), or Yoshida's composition of it (``order`` 4).

    ``rhs`` is one (t, x) -> xdot, or one per step. Returns the state after every step,
    like :func:`rk4_coast`.
    """
    check_splitting_applies(model)

    def slow_of(f: Rhs) -> Rhs:
        def slow(t: ca.SX, x: ca.SX) -> ca.SX:
            return f(t, x) - _fast_rhs(x, p, model)

        return slow

    def strang(slow: Rhs, t: ca.SX, x: ca.SX, h: ca.SX) -> ca.SX:
        x = rk4_coast(slow, t, x, h / 2, 1)[-1]
        x = exact_spin_flow(x, p, h)
        return rk4_coast(slow, t + h / 2, x, h / 2, 1)[-1]

    h = dt / steps
    x, out = x0, []
    for k in range(steps):
        t = t0 + k * h
        slow = slow_of(_on_step(rhs, k, steps))
        x = strang(slow, t, x, h) if order == 2 else _yoshida(slow, p, t, x, h)
        out.append(x)
    return out


def _yoshida(slow: Rhs, p: ca.SX, t: ca.SX, x: ca.SX, h: ca.SX) -> ca.SX:
    """Yoshida's fourth-order composition of three Strang steps (c1, c0, c1) h, with the two
    slow half-steps that meet between Strang steps merged into one RK4 step of their summed
    length (the exact slow flows compose; RK4's local error stays O(h^5)): four slow RK4
    steps a substep instead of six."""
    tau = t
    for length, fast in ((_Y1 / 2, _Y1), ((_Y1 + _Y0) / 2, _Y0), ((_Y0 + _Y1) / 2, _Y1)):
        x = rk4_coast(slow, tau, x, length * h, 1)[-1]
        tau = tau + length * h
        x = exact_spin_flow(x, p, fast * h)
    return rk4_coast(slow, tau, x, _Y1 / 2 * h, 1)[-1]


_Y1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_Y0 = 1.0 - 2.0 * _Y1
