"""What a tracker's sensors read of the state: a camera, a pair of tracking mounts, a gyro,
a spin counter (docs/estimation.md#sensors).

Every builder returns a named casadi Function ``<sensor>(x, p, dt) -> y`` of the full state
x (:data:`~lightcraft_opt.layout.STATE`, docs/frames.md#state-vector) at a pulse node (just
before the pulse fires), the parameters p (:data:`~lightcraft_opt.layout.PARAMETERS`) and
the time ``dt`` [s] by which the sample precedes the node. They are plain SX functions of
x and p, so an estimator evaluates them on Ψ's ``lift(z, p)``. The gyro and the spin
counter are read at the nodes: their ``dt`` is unused, and kept so that every sensor is
called alike.

**The camera's coast backwards.** A frame taken ``dt`` before the node sees the craft where
it was then. Between two pulses only gravity, the rotating frame's terms and the air act
on the mass centre, and in air the craft's axis b1 cones about its angular momentum H many
times a coast (216 Hz for Flight 5). :func:`position_before` integrates the point-mass
coast backwards by one classical Runge-Kutta step of ``-dt``::

    d r_L / dt = v_L,    d v_L / dt = a_site(r_L, v_L) + F_air / m

with ``a_site`` the plant's gravity and frame terms (symbolic/terms/gravity.py) and
``F_air`` the plant's aerodynamic load (symbolic/terms/aero.py, drag, lift and Magnus) with
b1 turned onto H: the coning-averaged axis. The mean wind of p blows; a gust (a function of
time) does not. It leaves out the RCS thrust (``F dt² / 2m``; none on Flight 5), the gust's
push within ``dt``, and what the coning's turning angle of attack adds to the loads at the
mean one. Measured against the plant's dense coast (32 states a coast) along a Flight 5
climb to 11-14 m/s, where the drag reaches 40 m/s², the error is at most 0.048 mm at 0.5
degrees of coning and 0.36 mm at 3 degrees, for every ``dt`` up to one pulse period
(tests/symbolic/test_measurements.py); gravity alone would leave 21-27 mm.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, STATE
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.terms.aero import aero_loads
from lightcraft_opt.symbolic.terms.atmosphere import us1976
from lightcraft_opt.symbolic.terms.gravity import site_acceleration_L
from lightcraft_opt.symbolic.terms.gyrostat import angular_momentum
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.rotation import dcm
from lightcraft_opt.symbolic.terms.wind import mean_wind_L

__all__ = [
    "bearings_from",
    "build_camera_position",
    "build_gyro",
    "build_spin_sensor",
    "build_stereo_bearings",
    "position_before",
]


def _symbols() -> tuple[ca.SX, ca.SX, ca.SX]:
    return ca.SX.sym("x", STATE.size), ca.SX.sym("p", PARAMETERS.size), ca.SX.sym("dt")


def _axis_frame(x: ca.SX, p: ca.SX) -> ca.SX:
    """R_LH: a frame whose first axis is H's direction in L (b1 turned onto H by the
    shortest rotation, Rodrigues' formula; singular only at a coning angle of 180 deg)."""
    mp = mass_properties(x, p)
    R_LB = dcm(STATE.get("q_LB", x))
    H_B = angular_momentum(STATE.get("w_B", x), STATE.get("spin", x), mp.I_B, mp.J, mp.I)
    h_B = H_B / ca.norm_2(H_B)
    a = ca.DM([1.0, 0.0, 0.0])  # b1 in B
    v = ca.cross(a, h_B)
    c = ca.dot(a, h_B)
    K = ca.skew(v)
    R_BH = ca.DM.eye(3) + K + ca.mtimes(K, K) / (1 + c)  # turns b1 onto h, in B
    return ca.mtimes(R_LB, R_BH)


def position_before(x: ca.SX, p: ca.SX, dt: ca.SX, model: Model) -> ca.SX:
    """r_L of the mass centre ``dt`` before the node x: the point-mass coast backwards
    (module docstring).

    Parameters
    ----------
    x : (STATE.size,) state at the node, L and B frames (docs/frames.md).
    p : (PARAMETERS.size,) parameters (mass, aerodynamics, site, mean wind).
    dt : time before the node [s], >= 0 and at most a pulse period for the stated accuracy.
    model : its structure (aerodynamic model, wind profile, gravity switches).

    Returns
    -------
    (3,) position relative to the pad, L frame [m]; x's own r_L at dt = 0.
    """
    env, aero = model.environment, model.craft.aero
    mass = mass_properties(x, p).mass
    R_LH = _axis_frame(x, p)
    w_rotor = STATE.get("w_B", x)[0] + STATE.get("spin", x)

    def accel(r: ca.SX, v: ca.SX) -> ca.SX:
        rho = us1976(PARAMETERS.get("site_height", p) + r[2])[0]
        v_air_H = ca.mtimes(R_LH.T, v - mean_wind_L(r, p, env.wind))
        F_H = aero_loads(v_air_H, w_rotor, rho, p, aero)[0]
        return site_acceleration_L(r, v, p, env) + ca.mtimes(R_LH, F_H) / mass

    r, v, h = STATE.get("r_L", x), STATE.get("v_L", x), -dt
    k1r, k1v = v, accel(r, v)
    k2r, k2v = v + h / 2 * k1v, accel(r + h / 2 * k1r, v + h / 2 * k1v)
    k3r, k3v = v + h / 2 * k2v, accel(r + h / 2 * k2r, v + h / 2 * k2v)
    k4r = v + h * k3v
    return r + h / 6 * (k1r + 2 * k2r + 2 * k3r + k4r)


def build_camera_position(model: Model) -> ca.Function:
    """casadi.Function ``camera_position(x, p, dt) -> y``: a camera that gives the craft's
    position, y = r_L [m] (3,) in L at ``dt`` [s] before the node x (module docstring:
    :func:`position_before`)."""
    x, p, dt = _symbols()
    return ca.Function(
        "camera_position", [x, p, dt], [position_before(x, p, dt, model)], ["x", "p", "dt"], ["y"]
    )


def _checked_sites(sites_L: Sequence[Sequence[float]]) -> np.ndarray:
    sites = np.asarray(sites_L, dtype=float)
    if sites.ndim != 2 or sites.shape[1] != 3 or len(sites) < 1:
        raise ParameterError("sites_L", f"needs rows of 3 coordinates in L [m], got {sites_L!r}")
    if not np.all(np.isfinite(sites)):
        raise ParameterError("sites_L", f"must be finite, got {sites_L!r}")
    on = np.hypot(sites[:, 0], sites[:, 1]) == 0.0
    if on.any():
        raise ParameterError(
            f"sites_L[{int(np.argmax(on))}]",
            "a mount must stand off the pad's vertical (its azimuth is measured from the "
            f"line to it), got {sites[int(np.argmax(on))].tolist()}",
        )
    return sites


def bearings_from(r_L: ca.SX, sites_L: Sequence[Sequence[float]]) -> ca.SX:
    """The bearings of the point r_L from tracking mounts at ``sites_L``.

    Parameters
    ----------
    r_L : (3,) the point, L frame [m].
    sites_L : (n, 3) the mounts, L frame [m], each off the pad's vertical.

    Returns
    -------
    (2 n,) (azimuth, elevation) of each mount in turn [rad]. A mount's forward axis f is the
    horizontal unit vector from it toward the pad's vertical, its right axis e = f x up;
    with d = r_L - site: azimuth = atan2(d.e, d.f) (0 on the line to the pad, positive to the
    right), elevation = atan2(d.up, |horizontal d|). Both are smooth while the craft stays
    in front of every mount (d.f > 0), where the azimuth never wraps.
    """
    out = []
    for site in _checked_sites(sites_L):
        f = -site[:2] / np.hypot(site[0], site[1])
        e = np.array([f[1], -f[0]])
        d = r_L - ca.DM(site)
        across, ahead = ca.dot(d[:2], ca.DM(e)), ca.dot(d[:2], ca.DM(f))
        out += [ca.atan2(across, ahead), ca.atan2(d[2], ca.sqrt(across**2 + ahead**2))]
    return ca.vertcat(*out)


def build_stereo_bearings(model: Model, sites_L: Sequence[Sequence[float]]) -> ca.Function:
    """casadi.Function ``stereo_bearings(x, p, dt) -> y``: y (2 n,) the (azimuth, elevation)
    [rad] of the craft's mass centre ``dt`` [s] before the node x, from each mount at
    ``sites_L`` (n, 3) [m, L frame] in turn (:func:`bearings_from`; the position by
    :func:`position_before`)."""
    x, p, dt = _symbols()
    y = bearings_from(position_before(x, p, dt, model), sites_L)
    return ca.Function("stereo_bearings", [x, p, dt], [y], ["x", "p", "dt"], ["y"])


def build_gyro() -> ca.Function:
    """casadi.Function ``gyro(x, p, dt) -> y``: y = w_B (3,) [rad/s], B frame, the body
    rates the state holds (transverse and axial; docs/frames.md's gauge), read at the node
    (``dt`` unused)."""
    x, p, dt = _symbols()
    return ca.Function("gyro", [x, p, dt], [STATE.get("w_B", x)], ["x", "p", "dt"], ["y"])


def build_spin_sensor() -> ca.Function:
    """casadi.Function ``spin_sensor(x, p, dt) -> y``: y (1,) the rotor spin relative to B
    about b1 [rad/s], the state's ``spin`` slot, read at the node (``dt`` unused)."""
    x, p, dt = _symbols()
    return ca.Function("spin_sensor", [x, p, dt], [STATE.get("spin", x)], ["x", "p", "dt"], ["y"])
