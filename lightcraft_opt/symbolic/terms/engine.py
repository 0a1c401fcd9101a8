"""The lightcraft engine: captured energy and the impulses of one pulse (docs/physics.md#engine).

Frames (docs/frames.md): B is the despun body frame, b1 = (1, 0, 0)_B the craft axis,
body positions from P; ``R_LB = dcm(q_LB)``; the mass centre S* is at ``r_L`` in L and at
``cm_B`` from P, so a body point s_B sits at ``r_L + R_LB (s_B - cm_B)`` in L. The beam
(:mod:`lightcraft_opt.symbolic.terms.beam`) rises along L's z through ``pointing_L``.

Captured energy. The optic is the annulus ``shadow_radius < r < capture_radius`` in the
optic plane, perpendicular to b1 through the ring (at ``ring_height`` h along b1 from P);
its point at radius r and body azimuth phi (measured in B from b2 toward b3) is
``s_B = h b1 + r e_r(phi)``, ``e_r(phi) = cos(phi) b2 + sin(phi) b3``. A fixed polar
quadrature covers it: Gauss-Legendre in r (``quadrature_radial`` points, weights r dr)
times ``quadrature_azimuthal`` equal sectors centred at phi_k = 2 pi (k + 1/2) / N.
Each point's L position gives its beam-plane coordinates and range, hence its fluence
F; sector k captures ``E_k = sum_j F_jk w_j (2 pi / N) |b1 . z_L|``: the area of the
tilted optic projected on the beam plane. ``E_cap = sum_k E_k``. A beam lying wholly in
the projected annulus is captured whole at any tilt; a beam much wider than the optic
gives E_cap proportional to cos(tilt).

Quadrature accuracy (tests/symbolic/test_engine.py checks it against a fine polar grid): the
quadrature converges fast while the beam's soft edges (width w) are resolved by the
radial spacing (capture - shadow) / n_r and by the sector arc r 2 pi / N. For the Table 1
(docs/references.md#paper-table-1) beams (Flights 5 and 16, w = 3 mm, offsets 0 to 8 cm) the
error of E_cap is below 1e-3 E with the 8 x 32 default, below 5e-5 E with 12 x 48 and below 2e-6
E with 16 x 64. Sharper edges need more points: for w = 1.5 mm, 8 x 32 is only within ~1e-2 E
and 16 x 64 within ~1e-3 E. The normalisation below makes the first pulse exact anyway.

Normalisation. Table 1's impulse per pulse I0 (``impulse_per_pulse``, measured at
launch with ``reference_pulse_energy`` E0) is what a centred, upright craft at the pad
receives. E_ref is the *same* quadrature for that craft: optic centre on the beam axis
at z = h (mass centre at the pad, at P), b2 east, b3 north, energy E0, the pulse's own
focus. The axial coupling is ``C = I0 / E_ref`` [N s/J] per captured joule, so the
first pulse gives I0 exactly whatever the quadrature's error, and calibrating beam
parameters keeps it so. (In the waist model a(0) does not depend on the focus, so
neither does E_ref when h = 0.)

Axial coupling per captured joule kappa:

- air: ``kappa = C g(n)``, with the engine health (overheating near pulse n_f,
  docs/physics.md#health)
  ``g(n) = 1 - (1 - g_inf) [s((n - n_f)/w_n) - s(-n_f/w_n)] / (1 - s(-n_f/w_n))``,
  n the ``engine_load`` state (energy delivered over E_ref), s the logistic: the step of
  docs/physics.md#health, shifted and scaled so that g(0) = 1 exactly (the first pulse
  gives I0) and g(inf) = g_inf (``health_floor``).
- Delrin: ``kappa = C`` (health 1) while ``liner_mass > 0``, else ``spent_coupling`` g(n)
  (air mode on the bare shroud); the switch is the only if_else. Each pulse ablates
  ``liner_loss = min(ablation E_cap, liner_mass)``: never more than is left.

SECTOR model. Sector k pushes ``dI_k = kappa E_k (b1 + tan(beta) e_r(phi_k))`` (the
``C' E_k (cos(beta) b1 + sin(beta) e_r)`` of docs/physics.md#sector-model, with
C' = kappa / cos(beta), so that the axial impulse of a centred beam is C E_cap, as normalised
above) at the ring point ``R_f e_r(phi_k) + h b1`` from P, i.e.
``rho_k = R_f e_r(phi_k) + h b1 - cm_B`` from S*:

    G_F = kappa (E_cap b1 + tan(beta) D),   D = sum_k E_k e_r(phi_k)  (energy dipole, B),
    G_M = sum_k rho_k x dI_k = kappa R_f (D x b1) + (h b1 - cm_B) x G_F.

Signs (craft offset by d from the beam axis, d_hat pointing from the axis to the craft,
beam inside the optic): the sectors facing the beam axis reach farther into the beam,
so D points toward the axis (-d_hat). Hence beta > 0 makes the lateral impulse
RESTORING (toward the axis: the default 0.15 rad restores), and since D x b1 is along
b1 x d_hat, G_M turns b1 toward d_hat: it TIPS THE AXIS AWAY from the beam axis (for
R_f cos(beta) > (h - cm) sin(beta), always so for a ring near the mass centre), as
the geometric argument of docs/physics.md#impulse-signs says; only spin keeps the craft riding
the beam.

KERNEL model (the alternative of docs/physics.md#kernel-model). d is the horizontal offset of
the optic centre from the beam axis (``offset_L``) resolved in the optic plane, d_B = (0, d.b2,
d.b3), u = |d_B| / d0 (d0 = ``kernel_offset``), I_ax0 = kappa E_cap(0) with E_cap(0) the
quadrature for the optic centre moved onto the axis (same height, attitude, pulse):

    I_ax = kappa E_cap(d),
    I_lat = -k_L I_ax0 (d_B / d0) exp((1 - u^2)/2),
    G_M = k_M I_ax0 R_f (b1 x d_B / d0) exp((1 - u^2)/2) + (h b1 - cm_B) x G_F,

with G_F = I_ax b1 + I_lat applied at the optic centre. Since u d_hat = d_B / d0 and u^2
needs no root, the kernel is smooth at d = 0 with no regularisation. Positive gains
k_L = ``lateral_gain``, k_M = ``tipping_gain`` mean restoring and tipping away (the
signs s_L, s_M of docs/physics.md#kernel-model live in the gains); both peak at |d| = d0 with
magnitudes k_L I_ax0 and k_M I_ax0 R_f.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, TypeVar

import casadi as ca
import numpy as np

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT, STATE
from lightcraft_opt.model import Engine, ImpulseModel, Model, Propellant
from lightcraft_opt.symbolic.terms.beam import beam_side, fluence, logistic
from lightcraft_opt.symbolic.terms.mass_properties import mass_properties
from lightcraft_opt.symbolic.terms.rotation import cross, dcm

__all__ = [
    "ENGINE_OUTPUT_NAMES",
    "PROJECTION_EPS",
    "OpticPose",
    "build_engine",
    "engine_impulse",
    "health",
    "optic_pose",
    "optic_quadrature",
    "point_fluence",
]

# Symbolic type of one call: all SX, all MX, or all DM (numeric evaluation).
Expr = TypeVar("Expr", ca.SX, ca.MX, ca.DM)

ENGINE_OUTPUT_NAMES = (
    "energy_captured",
    "impulse_B",
    "angular_impulse_B",
    "offset_L",
    "liner_loss",
    "health",
)
"""Outputs of :func:`engine_impulse` and of the ``engine`` Function, in order."""

PROJECTION_EPS = 1e-6
"""Regularisation of the projection factor, |b1 . z_L| ~ sqrt((b1 . z_L)^2 + eps^2) [-]:
smooth at 90 degrees of tilt, and changes an upright craft's E_cap by 5e-13 relative."""


def health(n: Expr, p: Expr) -> Expr:
    """Air-mode engine health g(n) [-] after n pulses (module docstring).

    Reads ``health_floor`` g_inf, ``health_pulse`` n_f, ``health_width`` w_n from p.
    g(0) = 1 exactly, g -> g_inf for n >> n_f, half-way down near n = n_f.
    """
    floor = PARAMETERS.get("health_floor", p)
    n_f = PARAMETERS.get("health_pulse", p)
    width = PARAMETERS.get("health_width", p)
    start = logistic(-n_f / width)
    step = (logistic((n - n_f) / width) - start) / (1 - start)
    return 1 - (1 - floor) * step


def _quadrature(engine: Engine) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [-1, 1] and the sector azimuths phi_k [rad]."""
    nodes, weights = np.polynomial.legendre.leggauss(engine.quadrature_radial)
    n_phi = engine.quadrature_azimuthal
    phi = 2 * math.pi * (np.arange(n_phi) + 0.5) / n_phi
    return nodes, weights, phi


def optic_quadrature(engine: Engine, p: Expr) -> tuple[Expr, Expr, np.ndarray]:
    """The optic's polar quadrature (module docstring): the radii r_j (n_r, 1) [m] and the
    weights of r dr (n_r, 1) [m^2] (expressions of p's ``shadow_radius`` and
    ``capture_radius``), and the sector azimuths phi_k (N,) [rad]; sector k's energy is
    ``(2 pi / N) |b1 . z_L| sum_j w_j F(r_j, phi_k)``."""
    nodes, weights, phi = _quadrature(engine)
    r_in = PARAMETERS.get("shadow_radius", p)
    r_out = PARAMETERS.get("capture_radius", p)
    half = 0.5 * (r_out - r_in)
    r = 0.5 * (r_out + r_in) + half * ca.DM(nodes)  # (n_r, 1) [m]
    return r, half * ca.DM(weights) * r, phi


def point_fluence(
    xi: Expr, eta: Expr, z: Expr, focus: Expr, energy: Expr, p: Expr, model: Model
) -> Expr:
    """Fluence [J/m^2] at beam-plane coordinates (xi, eta) [m] from the beam axis and range
    z [m], for a pulse of ``focus`` [m] and ``energy`` [J]: what each quadrature point
    receives."""
    a = beam_side(z, focus, p, model.laser)
    return fluence(xi, eta, a, energy, p, model.laser)


def _sector_energies(
    centre: tuple[Expr, Expr, Expr],
    b2_L: Expr,
    b3_L: Expr,
    projection: Expr,
    pulse: Expr,
    p: Expr,
    model: Model,
) -> Expr:
    """Captured energy of each azimuth sector, (1, N) row [J].

    Parameters
    ----------
    centre : (xi, eta, z) of the optic centre: beam-plane coordinates from the beam
        axis and range [m].
    b2_L, b3_L : (3,) body axes b2, b3 in L components.
    projection : |b1 . z_L|, projected-area factor [-].
    pulse, p : per-pulse input (focus, energy) and parameters.
    """
    r, w_r, phi = optic_quadrature(model.craft.engine, p)
    cos_phi = ca.DM(np.cos(phi)).T  # (1, N)
    sin_phi = ca.DM(np.sin(phi)).T
    xi0, eta0, z0 = centre
    xi = xi0 + ca.mtimes(r, b2_L[0] * cos_phi + b3_L[0] * sin_phi)  # (n_r, N) [m]
    eta = eta0 + ca.mtimes(r, b2_L[1] * cos_phi + b3_L[1] * sin_phi)
    z = z0 + ca.mtimes(r, b2_L[2] * cos_phi + b3_L[2] * sin_phi)
    focus, energy = PULSE_INPUT.get("focus", pulse), PULSE_INPUT.get("energy", pulse)
    F = point_fluence(xi, eta, z, focus, energy, p, model)  # [J/m^2]
    return (2 * math.pi / len(phi)) * projection * ca.mtimes(w_r.T, F)


def _reference_energy(pulse: Expr, p: Expr, model: Model) -> Expr:
    """E_ref [J]: the quadrature for a centred, upright craft with its optic at z = h,
    receiving the reference pulse energy (module docstring, Normalisation)."""
    e0 = PARAMETERS.get("reference_pulse_energy", p)
    ref_pulse = ca.vertcat(
        PULSE_INPUT.get("pointing_L", pulse), PULSE_INPUT.get("focus", pulse), e0
    )
    east, north = ca.DM([1.0, 0.0, 0.0]), ca.DM([0.0, 1.0, 0.0])
    upright = ca.sqrt(1 + PROJECTION_EPS**2)
    centre = (0 * e0, 0 * e0, PARAMETERS.get("ring_height", p))
    return ca.sum2(_sector_energies(centre, east, north, upright, ref_pulse, p, model))


@dataclass(frozen=True)
class OpticPose:
    """Where the optic sits in the beam at a pulse (expressions of x, pulse and p).

    Attributes
    ----------
    R_LB : (3, 3) attitude, B to L.
    arm_B : (3,) from the mass centre S* to the optic centre, B [m].
    centre_L : (3,) optic centre, L [m].
    offset_L : (2,) east/north offset of the optic centre from the beam axis, L [m].
    projection : |b1 . z_L| regularised (PROJECTION_EPS) [-].
    """

    R_LB: Any
    arm_B: Any
    centre_L: Any
    offset_L: Any
    projection: Any

    @property
    def centre(self) -> tuple[Any, Any, Any]:
        """(xi, eta, z): the optic centre's beam-plane coordinates and range [m]."""
        return (self.offset_L[0], self.offset_L[1], self.centre_L[2])


def optic_pose(x: Expr, pulse: Expr, p: Expr) -> OpticPose:
    """The optic's pose at the pulse (:class:`OpticPose`); x (STATE.size,) reads r_L [m, L],
    q_LB and the mass centre (liner mass), pulse (PULSE_INPUT.size,) its pointing_L [m,
    L east/north]."""
    R_LB = dcm(STATE.get("q_LB", x))
    b1_B = ca.DM([1.0, 0.0, 0.0])
    arm_B = PARAMETERS.get("ring_height", p) * b1_B - mass_properties(x, p).cm_B  # from S*
    centre_L = STATE.get("r_L", x) + ca.mtimes(R_LB, arm_B)
    offset_L = centre_L[0:2] - PULSE_INPUT.get("pointing_L", pulse)
    projection = ca.sqrt(R_LB[2, 0] ** 2 + PROJECTION_EPS**2)
    return OpticPose(R_LB, arm_B, centre_L, offset_L, projection)


def engine_impulse(
    x: Expr,
    pulse: Expr,
    p: Expr,
    model: Model,
    energies: tuple[Expr, Expr] | None = None,
) -> dict[str, Expr]:
    """Captured energy and impulses of one pulse (module docstring).

    Parameters
    ----------
    x : (STATE.size,) state just before the pulse; reads r_L [m, L], q_LB, liner_mass
        [kg], pulses [-] (and the mass centre via mass_properties).
    pulse : (PULSE_INPUT.size,) pointing_L (2) [m, L east/north], focus [m], energy [J].
    p : (PARAMETERS.size,) parameters (beam, engine and mass properties).
    model : structure: beam profile and size model, impulse model, quadrature,
        propellant.
    energies : (E_k (1, N) [J], E_ref [J]): the sector energies and the reference energy
        given instead of computed by the quadrature (SECTOR model only: how the jump's
        structured derivatives, symbolic/maps/jump_derivatives.py, cut the graph).

    Returns
    -------
    dict with
        ``energy_captured`` : E_cap [J];
        ``impulse_B`` : (3,) G_F, force impulse, B frame [N s];
        ``angular_impulse_B`` : (3,) G_M, angular impulse about S*, B frame [N m s];
        ``offset_L`` : (2,) east/north offset of the optic centre from the beam axis [m];
        ``liner_loss`` : ablated liner mass [kg] (0 for air mode);
        ``health`` : thrust fraction of the engine [-] (1 with a Delrin liner left).
    """
    engine = model.craft.engine
    pose = optic_pose(x, pulse, p)
    b2_L, b3_L = pose.R_LB[:, 1], pose.R_LB[:, 2]
    b1_B = ca.DM([1.0, 0.0, 0.0])
    arm_B, centre_L, offset_L = pose.arm_B, pose.centre_L, pose.offset_L
    projection = pose.projection

    if energies is None:
        E_k = _sector_energies(pose.centre, b2_L, b3_L, projection, pulse, p, model)
        E_ref = _reference_energy(pulse, p, model)
    elif engine.impulse_model is ImpulseModel.SECTOR:
        E_k, E_ref = energies
    else:
        raise ParameterError("energies", "given sector energies need the SECTOR impulse model")
    E_cap = ca.sum2(E_k)
    coupling = PARAMETERS.get("impulse_per_pulse", p) / E_ref

    g_air = health(STATE.get("engine_load", x), p)
    if model.craft.propellant is Propellant.AIR:
        kappa, g, liner_loss = coupling * g_air, g_air, 0 * E_cap
    else:
        liner = STATE.get("liner_mass", x)
        full = liner > 0
        kappa = ca.if_else(full, coupling, PARAMETERS.get("spent_coupling", p) * g_air)
        g = ca.if_else(full, 1, g_air)
        liner_loss = ca.fmin(PARAMETERS.get("ablation", p) * E_cap, ca.fmax(liner, 0))

    ring = PARAMETERS.get("ring_radius", p)
    if engine.impulse_model is ImpulseModel.SECTOR:
        _, _, phi = _quadrature(engine)
        dipole_B = ca.vertcat(
            0, ca.mtimes(E_k, ca.DM(np.cos(phi))), ca.mtimes(E_k, ca.DM(np.sin(phi)))
        )
        G_F = kappa * (E_cap * b1_B + ca.tan(PARAMETERS.get("blast_angle", p)) * dipole_B)
        G_M = kappa * ring * cross(dipole_B, b1_B) + cross(arm_B, G_F)
    else:
        E_cap0 = ca.sum2(
            _sector_energies((0, 0, centre_L[2]), b2_L, b3_L, projection, pulse, p, model)
        )
        i_ax0 = kappa * E_cap0
        d0 = PARAMETERS.get("kernel_offset", p)
        d2 = ca.dot(ca.vertcat(offset_L, 0), b2_L)
        d3 = ca.dot(ca.vertcat(offset_L, 0), b3_L)
        bump = ca.exp(0.5 * (1 - (d2 * d2 + d3 * d3) / (d0 * d0))) / d0
        lateral = -PARAMETERS.get("lateral_gain", p) * i_ax0 * bump * ca.vertcat(0, d2, d3)
        G_F = kappa * E_cap * b1_B + lateral
        tip = PARAMETERS.get("tipping_gain", p) * i_ax0 * ring * bump * ca.vertcat(0, -d3, d2)
        G_M = tip + cross(arm_B, G_F)  # b1 x d_B = (0, -d3, d2)

    return {
        "energy_captured": E_cap,
        "impulse_B": G_F,
        "angular_impulse_B": G_M,
        "offset_L": offset_L,
        "liner_loss": liner_loss,
        "health": g,
    }


def build_engine(model: Model) -> ca.Function:
    """casadi.Function ``engine(x, pulse, p) -> (energy_captured, impulse_B,
    angular_impulse_B, offset_L, liner_loss, health)``.

    See :func:`engine_impulse` for shapes, units and frames; ``x`` has STATE.size,
    ``pulse`` PULSE_INPUT.size and ``p`` PARAMETERS.size entries.
    """
    x = ca.SX.sym("x", STATE.size)
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    out = engine_impulse(x, pulse, p, model)
    return ca.Function(
        "engine",
        [x, pulse, p],
        [out[name] for name in ENGINE_OUTPUT_NAMES],
        ["x", "pulse", "p"],
        list(ENGINE_OUTPUT_NAMES),
    )
