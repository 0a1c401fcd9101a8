"""The laser beam: its size along the beam and its transverse fluence (docs/physics.md#beam).

Geometry (docs/frames.md): the beam rises from the ground straight up, along +z of the
launch-site frame L. Its axis passes through the lateral point ``pointing_L`` (east,
north) [m], a per-pulse input (:data:`lightcraft_opt.layout.PULSE_INPUT`). A point of L
at (x, y, z) sits at beam-plane coordinates ``(xi, eta) = (x, y) - pointing_L`` from the
axis and at range z along the beam (the L up coordinate).

Size along the beam (outer side a of the beam, or diameter for a disc) [m]:

- ``LINEAR``:  a(z) = a0 + theta z, with a0 = ``beam_side`` (paper Table 1,
  docs/references.md#paper-table-1, at launch) and
  theta = ``beam_divergence`` (full angle).
- ``WAIST``:   a(z) = a0 sqrt((1 - z/f)^2 + (z/z_R)^2), the side of a beam of fixed
  quality (M^2) that leaves the director with the Table 1 side a0 and a wavefront converging
  toward the geometric focus f, the ``focus`` input; z_R = ``beam_rayleigh_range`` is the
  Rayleigh range of that beam leaving collimated, pi (a0/2)^2 / (M^2 lambda) (Siegman,
  *Lasers*, 1986, ch. 17; docs/references.md#siegman). a(0) = a0 for every focus, so the
  launch beam always matches Table 1. f -> infinity is the collimated beam, whose far field
  a0 z/z_R is the LINEAR model's growth with theta = a0 / z_R. The waist sits at
  z_w = f / (1 + (f/z_R)^2) <= z_R / 2, no farther whatever the focus; at z = f the side is
  the diffraction-limited spot a0 f / z_R, the smallest the director can put at that range.

Transverse profiles (:class:`lightcraft_opt.model.BeamProfile`), pulse energy E [J],
soft-edge width w = ``beam_edge_width`` [m], logistic s(t) = (1 + tanh(t/2)) / 2:

- ``HOLLOW_SQUARE`` (unstable-resonator output), outer side a, hole side b = h a with
  h = ``beam_hole_ratio``::

      F = E / (a^2 - b^2) [W(a) - W(b)],   W(s) = S(xi; s) S(eta; s),
      S(x; s) = s((s/2 + x)/w) - s((x - s/2)/w)
              = (tanh((s/2 + x)/(2w)) + tanh((s/2 - x)/(2w))) / 2.

  docs/physics.md#hollow-square writes the soft box as s((s/2 - |x|)/w) with |x| smoothed as
  sqrt(x^2 + eps^2). The difference of two logistics used here is exactly that box
  (with the true |x|) times (1 - e^{-s/w}) s((s/2 + |x|)/w), a factor between
  1 - e^{-s/(2w)} and 1: the same soft edge, but smooth without any eps, exactly zero
  for s = 0 (a hole ratio of 0 gives a plain square), and its integral over x is
  *exactly* s. So F integrates over the plane to E exactly (up to rounding), for any
  a, b, w.
  The hole is dark only up to its own soft edges: at the hole's centre the fluence
  is sech^2(b/(4w)) - sech^2(a/(4w)) ~ 4 e^{-b/(2w)} of the ring's (3 % for Flight 5's
  b = 2.9 cm, w = 3 mm), and the hole holds the edge leak ~ 4 b w ln 2 / (a^2 - b^2) of E
  (5.5 % for Flight 5), which vanishes with w (tests/symbolic/test_beam.py).
- ``TOP_HAT``: a soft disc of diameter a, radius R = a/2, rho^2 = xi^2 + eta^2::

      F = E s((R^2 - rho^2)/(2 R w)) / (2 pi R w softplus(R/(2w))),

  whose edge is s((R - rho)/w) to first order at the rim. It is a function of rho^2
  (no sqrt, smooth at the axis) and its plane integral is exactly 2 pi R w
  ln(1 + e^{R/(2w)}) = pi R^2 + 2 pi R w ln(1 + e^{-R/(2w)}), so F integrates to E
  exactly. The top droops by e^{-R/(2w)} at the centre (0.25 % for R/w = 12).
- ``GAUSSIAN``: 1/e^2 diameter a, w0 = a/2: F = 2 E / (pi w0^2) exp(-2 rho^2 / w0^2);
  exact integral E; the edge width is not used.
"""

from __future__ import annotations

import math
from typing import TypeVar

import casadi as ca

from lightcraft_opt.layout import PARAMETERS, PULSE_INPUT
from lightcraft_opt.model import BeamProfile, BeamSizeModel, Laser

__all__ = ["beam_side", "build_beam", "fluence", "logistic"]

# Symbolic type of one call: all SX, all MX, or all DM (numeric evaluation).
Expr = TypeVar("Expr", ca.SX, ca.MX, ca.DM)


def logistic(t: Expr) -> Expr:
    """s(t) = 1 / (1 + e^{-t}), written as (1 + tanh(t/2)) / 2 so neither the value nor
    its derivatives overflow for large |t| (elementwise)."""
    return 0.5 * (1 + ca.tanh(0.5 * t))


def beam_side(z: Expr, focus: Expr, p: Expr, laser: Laser) -> Expr:
    """Outer side a(z) of the beam at range z (module docstring).

    Parameters
    ----------
    z : range along the beam, i.e. the L up coordinate of the point (any shape,
        elementwise) [m].
    focus : geometric focus f of the director, the ``focus`` pulse input (WAIST only) [m].
    p : (PARAMETERS.size,) parameters; reads ``beam_side`` a0 [m], ``beam_divergence``
        theta [rad] (LINEAR), ``beam_rayleigh_range`` z_R [m] (WAIST).
    laser : the size model (structural).

    Returns
    -------
    a : outer side (hollow square), diameter (top hat) or 1/e^2 diameter (Gaussian),
        same shape as z [m]. a(0) equals ``beam_side`` in both models.
    """
    a0 = PARAMETERS.get("beam_side", p)
    if laser.size_model is BeamSizeModel.LINEAR:
        return a0 + PARAMETERS.get("beam_divergence", p) * z
    z_r = PARAMETERS.get("beam_rayleigh_range", p)
    return a0 * ca.sqrt((1 - z / focus) ** 2 + (z / z_r) ** 2)


def _soft_box(x: Expr, side: Expr, w: Expr) -> Expr:
    """S(x; s): 1-D soft box of width s centred on 0, integral exactly s."""
    half = 0.5 * side
    return 0.5 * (ca.tanh((half + x) / (2 * w)) + ca.tanh((half - x) / (2 * w)))


def fluence(xi: Expr, eta: Expr, a: Expr, energy: Expr, p: Expr, laser: Laser) -> Expr:
    """Fluence F of a pulse at beam-plane coordinates (xi, eta) (module docstring).

    Parameters
    ----------
    xi, eta : east and north distance of the point from the beam axis, L frame
        (any shape, elementwise) [m].
    a : beam size at the point's range, from :func:`beam_side` [m].
    energy : pulse energy E [J].
    p : (PARAMETERS.size,) parameters; reads ``beam_hole_ratio`` h [-] (hollow square)
        and ``beam_edge_width`` w [m] (hollow square, top hat).
    laser : the profile (structural).

    Returns
    -------
    F : fluence, energy per area perpendicular to the beam [J/m^2]; its integral over
        the (xi, eta) plane is E exactly for every profile.
    """
    w = PARAMETERS.get("beam_edge_width", p)
    if laser.profile is BeamProfile.HOLLOW_SQUARE:
        b = PARAMETERS.get("beam_hole_ratio", p) * a
        outer = _soft_box(xi, a, w) * _soft_box(eta, a, w)
        hole = _soft_box(xi, b, w) * _soft_box(eta, b, w)
        return energy / (a * a - b * b) * (outer - hole)
    rho2 = xi * xi + eta * eta
    if laser.profile is BeamProfile.TOP_HAT:
        radius = 0.5 * a
        t = radius / (2 * w)
        softplus = t + ca.log1p(ca.exp(-t))  # ln(1 + e^t) for t > 0, without overflow
        area = 2 * math.pi * radius * w * softplus
        return energy / area * logistic((radius * radius - rho2) / (2 * radius * w))
    w0 = 0.5 * a
    return 2 * energy / (math.pi * w0 * w0) * ca.exp(-2 * rho2 / (w0 * w0))


def build_beam(laser: Laser) -> ca.Function:
    """casadi.Function ``beam_fluence(xi_eta, z, pulse, p) -> F``.

    Inputs: ``xi_eta`` (2,) beam-plane coordinates from the axis, L east/north [m];
    ``z`` range (L up) [m]; ``pulse`` (PULSE_INPUT.size,) per-pulse input (its
    ``focus`` [m] and ``energy`` [J] are read; ``pointing_L`` is already in xi_eta);
    ``p`` (PARAMETERS.size,). Output: ``F`` fluence [J/m^2] (:func:`fluence`).
    """
    xi_eta = ca.SX.sym("xi_eta", 2)
    z = ca.SX.sym("z")
    pulse = ca.SX.sym("pulse", PULSE_INPUT.size)
    p = ca.SX.sym("p", PARAMETERS.size)
    a = beam_side(z, PULSE_INPUT.get("focus", pulse), p, laser)
    F = fluence(xi_eta[0], xi_eta[1], a, PULSE_INPUT.get("energy", pulse), p, laser)
    return ca.Function(
        "beam_fluence", [xi_eta, z, pulse, p], [F], ["xi_eta", "z", "pulse", "p"], ["F"]
    )
