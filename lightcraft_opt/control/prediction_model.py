"""Φ's linear models in coning coordinates, scheduled on spin and altitude: the prediction
model of the nutation MPC and of its LQR baseline.

Coordinates: z = (r_Y, v_Y, h_Y, c_B) of :mod:`lightcraft_opt.symbolic.maps.coning_coordinates`
(layout :data:`~lightcraft_opt.layout.CONING`: lateral position and velocity in the
yaw-aligned frame Y, tilt of the angular momentum, coning vector), 8 entries; inputs: the
beam pointing and the phase-locked RCS slots of the map input
(:func:`~lightcraft_opt.layout.coning_input_layout`: ``pointing_L``, ``rcs_thrust``,
``rcs_cos``, ``rcs_sin``: 2 + 3 n).

Each grid point is a climb point (:func:`~lightcraft_opt.linear.climb_point`: upright, centred,
climbing at the nominal climb's speed at that altitude, spinning at that spin) and its
linear model in z (:func:`~lightcraft_opt.linear.coning_linear_model`: the error-state
entries of :data:`~lightcraft_opt.layout.CONING_ERROR_STATE`, r, v, theta_B[b2, b3],
w_B[b2, b3], mapped into z by the exact Jacobians of the coordinates before and after the
pulse: A_z = T1 A T0^-1, B_z = T1 B; why these coordinates and the phase-locked RCS:
:mod:`lightcraft_opt.linear.coning`). One grid point as a python-control StateSpace:
:func:`lightcraft_opt.linearize.coning_state_space`.

Yaw. A coning craft's despun frame turns about its axis by the holonomy of the cone,
2π (1 - cos θ) a coning turn, i.e. ω T (1 - cos θ) a pulse (0.196 rad at 5 degrees,
measured; 0.0078 rad at 1 degree), so the yaw-aligned frame Y of the next pulse is
turned by that much and the L vectors read in it (r, v, h) turn back by it: the
horizon's models carry that turn for the coning expected at each pulse.

Scheduling. In z the coning rows are a rotation by ω T (52 rad a pulse, turning 0.5 rad
for 1 % of spin) times a part that changes slowly with spin; every other row changes
slowly. The grid stores the coning rows turned back by -ω T (``A``, ``B``); a model at any
spin and altitude is the bilinear interpolation of the stored rows, turned forward by the
ω T of that state (:meth:`ConingModel.horizon`, which also steps the spin decay and the
climb over a horizon: a linear time-varying model). Outside the grid the nearest edge is
used. The interpolation error is measured in tests/control/test_mpc.py; what the model leaves out
(the vertical channel, the yaw drift inside a horizon, propellant use, the mean RCS
thrust's lift) is measured there as the prediction error against Φ.
"""

from __future__ import annotations

import io
import math
import os
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from lightcraft_opt.compiled.cache import cache_dir, load_entry, structure_key, write_entry
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import (
    CONING,
    STATE,
    RcsProfile,
    VectorLayout,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.linear.coning import (
    coning_coordinate_jacobian,
    coning_inputs,
    coning_linear_model,
    nominal_climb_speeds,
    turn,
)
from lightcraft_opt.linear.operating_points import (
    PulseMapJacobian,
    climb_point,
    pulse_map_jacobian,
)
from lightcraft_opt.linear.signal_names import entry_names, select_entries
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.coning_coordinates import build_coning_coordinates
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map

__all__ = [
    "DEFAULT_ALTITUDES",
    "DEFAULT_SPINS",
    "ConingModel",
    "coning_model",
    "turn",
]

#: Spins of the default grid, as fractions of the craft's: 1 % apart, so that the
#: parts of the model that ripple with the fraction of a coning turn in an interval (the
#: held torque's effect on c, the amplitudes' on h: ω T moves 0.5 rad for 1 % of spin)
#: interpolate to ~3 % of their (small) size; the spin decays ~9 % a second.
DEFAULT_SPINS = tuple(round(0.80 + 0.01 * k, 2) for k in range(26))
#: Altitudes of the default grid [m]: dense near the pad, where the beam-riding gains
#: change fastest (17.5 -> 10.6 m/s of lateral velocity per m of offset from 0 to 10 m).
DEFAULT_ALTITUDES = (0.0, 0.5, 1.0, 2.0, 4.0, 7.0, 11.0, 16.0, 22.0, 30.0)
_C = CONING.index("c_B")  # the coning rows of z
_L_ROWS = tuple(CONING.index(name) for name in ("r_Y", "v_Y", "h_Y"))  # L vectors read in Y


@dataclass(frozen=True)
class ConingModel:
    """Linear pulse-to-pulse models of Φ in coning coordinates on a spin x altitude grid.

    Attributes
    ----------
    spins : (ns,) rotor spin of the grid points [rad/s], increasing.
    altitudes : (na,) altitude of the grid points [m], increasing.
    speeds : (na,) their vertical speed before the pulse [m/s].
    A : (ns, na, 8, 8) z[k+1] = A z[k] + B du[k], coning rows turned back by -ω T.
    B : (ns, na, 8, m) likewise; du the model inputs' departure from ``u_op``.
    omega_per_spin : (ns, na) ω / spin at the grid point [-] (J / A in the gauge w1 = 0).
    spin_decay : (ns, na) spin after one pulse over spin before [-].
    period : pulse period T [s].
    inputs : the m model inputs' names (``pointing_L[east]``, ``rcs_cos[2]`` ...).
    input_index : (m,) where they sit in the map input.
    map_inputs : the map-input layout (Φ's, PHASE_LOCKED).
    u_op : (map-input size,) the input of every grid point (nominal: beam on the pad axis,
        the flight's energy, RCS off).
    model_name : which model.
    """

    spins: np.ndarray
    altitudes: np.ndarray
    speeds: np.ndarray
    A: np.ndarray
    B: np.ndarray
    omega_per_spin: np.ndarray
    spin_decay: np.ndarray
    period: float
    inputs: tuple[str, ...]
    input_index: np.ndarray
    map_inputs: VectorLayout
    u_op: np.ndarray
    model_name: str

    @property
    def states(self) -> tuple[str, ...]:
        """Names of the 8 entries of z."""
        return tuple(entry_names(CONING))

    def _weights(self, spin: np.ndarray, altitude: np.ndarray) -> tuple[np.ndarray, ...]:
        """Bilinear cell indices and weights of (spin, altitude) points, clamped to the grid."""
        out: list[np.ndarray] = []
        for grid, v in ((self.spins, spin), (self.altitudes, altitude)):
            if grid.size == 1:
                out += [np.zeros(v.shape, int), np.zeros(v.shape)]
                continue
            vc = np.clip(v, grid[0], grid[-1])
            i = np.clip(np.searchsorted(grid, vc) - 1, 0, grid.size - 2)
            out += [i, (vc - grid[i]) / (grid[i + 1] - grid[i])]
        return tuple(out)

    def _at(self, table: np.ndarray, spin: np.ndarray, altitude: np.ndarray) -> np.ndarray:
        i, a, j, b = self._weights(spin, altitude)
        i1 = np.minimum(i + 1, self.spins.size - 1)
        j1 = np.minimum(j + 1, self.altitudes.size - 1)
        ex = (slice(None),) + (None,) * (table.ndim - 2)
        a, b = a[ex], b[ex]
        return (
            (1 - a) * (1 - b) * table[i, j]
            + a * (1 - b) * table[i1, j]
            + (1 - a) * b * table[i, j1]
            + a * b * table[i1, j1]
        )

    def horizon(
        self,
        spin: float,
        omega: float,
        altitude: float,
        climb_rate: float,
        steps: int,
        coning: float | np.ndarray = 0.0,
        phase: float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray]:
        """The linear time-varying model over ``steps`` pulses from the current state.

        Parameters
        ----------
        spin : rotor spin now [rad/s]; decayed over the horizon at the grid's rate per
            pulse here (constant to 2e-4 over the horizon: the spin time constant).
        omega : coning rate in B now [rad/s] (``coning_coordinates``' omega, the
            controller's parameters); scaled with the spin over the horizon.
        altitude : now [m]; advanced by ``climb_rate`` [m/s] a pulse period at a time.
        steps : N >= 1.
        coning : |c| (tan of the coning angle θ) expected at each pulse, (N,) or one for
            all: the yaw frame turns by the despun frame's holonomy ω T (1 - cos θ) a
            pulse (module docstring), which turns the L vectors (r, v, h) read in it.
        phase : added to the coning rows' turn ω T every pulse [rad]: a correction of the
            phase advance from an estimate (controllers.PhaseTracker), for a craft whose
            J / A differs from the model's (1 % of it turns ω T by 0.5 rad).

        Returns
        -------
        A : (N, 8, 8), B : (N, 8, m): z[j+1] = A[j] z[j] + B[j] du[j].
        """
        alts = altitude + climb_rate * self.period * np.arange(steps)
        decay = self._at(self.spin_decay, np.array([spin]), alts[:1])[0]
        # decay^k as a running product, and the turns below entry by entry: the operations
        # the MPC's step Function makes (control/mpc_step.py), so that both round alike
        spins = spin * np.cumprod(np.r_[1.0, np.full(steps - 1, decay)])
        A = self._at(self.A, spins, alts)
        B = self._at(self.B, spins, alts)
        omegas = omega * spins / spin
        for M in (A, B):
            _turn_rows(M, _C, omegas * self.period + phase)
        tan = np.broadcast_to(np.asarray(coning, dtype=float), (steps,))
        yaw = omegas * self.period * (1.0 - 1.0 / np.sqrt(1.0 + tan**2))
        if np.any(yaw):
            for rows in _L_ROWS:
                for M in (A, B):
                    _turn_rows(M, rows, -yaw)
        return A, B

    def at(
        self, spin: float, omega: float, altitude: float, phase: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray]:
        """(A (8, 8), B (8, m)) of one pulse at this spin [rad/s], coning rate [rad/s] and
        altitude [m], the coning turn corrected by ``phase`` [rad] (:meth:`horizon`)."""
        A, B = self.horizon(spin, omega, altitude, 0.0, 1, phase=phase)
        return A[0], B[0]


def _turn_rows(M: np.ndarray, rows: slice, angle: np.ndarray) -> None:
    """Turn the two ``rows`` of each stage's matrix M[j] (N, rows, cols) by ``angle[j]``
    [rad] in place: ``turn(angle) @ M[:, rows]``, written entry by entry (c a - s b, s a + c
    b)."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    a, b = M[:, rows.start].copy(), M[:, rows.start + 1].copy()
    M[:, rows.start] = c * a + (-s) * b
    M[:, rows.start + 1] = s * a + c * b


def coning_model(
    model: Model,
    *,
    pulse_map: PulseMap | PulseMapJacobian | None = None,
    options: PulseMapOptions | None = None,
    spins: Sequence[float] | np.ndarray | None = None,
    altitudes: Sequence[float] | np.ndarray = DEFAULT_ALTITUDES,
    speeds: Sequence[float] | np.ndarray | None = None,
    cache: bool | str | os.PathLike[str] = False,
) -> ConingModel:
    """Linearise Φ on a grid of spin and altitude in coning coordinates (module docstring).

    Parameters
    ----------
    model : the controller's model (its numbers are the controller's belief).
    pulse_map : Φ with the PHASE_LOCKED RCS profile, or its
        :func:`~lightcraft_opt.linear.pulse_map_jacobian` (the Jacobian Function takes seconds
        to build at 32 substeps, each grid point then tens of milliseconds; figures:
        bench/README.md#mpcpy-the-nutation-mpcs-solve-time-against-ipopt-on-the-same-qp).
    options : to build Φ when ``pulse_map`` is None (its RCS profile must be
        PHASE_LOCKED).
    spins : grid of rotor spin [rad/s] (default :data:`DEFAULT_SPINS` times the craft's).
    altitudes : grid of altitudes [m] (increasing).
    speeds : vertical speed at each altitude [m/s] (default: the nominal flight's from
        the pad when it passes that altitude).
    cache : keep the model on disk as a cache entry (compiled/cache/entries.py: checksummed,
        verified before use, built again with a warning when damaged), in
        :func:`~lightcraft_opt.compiled.cache.cache_dir` (True) or the folder given, under the
        sha256 of Φ's expression graph, the model's parameter vector, the grid and the
        coordinates' Functions, and read it back instead of linearising again (a hit costs
        Φ's build and serialisation, a fraction of the whole build).

    Raises
    ------
    ParameterError when the craft does not spin (its spin sets the default grid), Φ's
    RCS profile is not PHASE_LOCKED or the grids are not increasing.
    """
    if spins is None and not model.craft.spin > 0:
        raise ParameterError(
            "craft.spin_rpm",
            "the MPC and LQR predict the coning of a spinning craft: need spin_rpm > 0, got "
            f"{model.craft.spin * 30 / math.pi:g}",
        )
    if isinstance(pulse_map, PulseMapJacobian):
        phi = pulse_map.pulse_map
    else:
        opts = options or PulseMapOptions(rcs_profile=RcsProfile.PHASE_LOCKED)
        phi = pulse_map or build_pulse_map(model, opts)
    lay = phi.inputs
    assert lay is not None  # build_pulse_map always records it
    coning_inputs(lay)  # a ParameterError unless PHASE_LOCKED
    s0 = model.craft.spin
    s_grid = np.asarray(s0 * np.asarray(DEFAULT_SPINS) if spins is None else spins, float)
    a_grid = np.asarray(altitudes, dtype=float)
    for name, grid in (("spins", s_grid), ("altitudes", a_grid)):
        if grid.ndim != 1 or grid.size < 1 or np.any(np.diff(grid) <= 0):
            raise ParameterError(name, f"must be an increasing 1-D grid, got {grid}")
    u_op = nominal_inputs(model, lay)
    v_grid = (
        nominal_climb_speeds(model, phi, a_grid, u_op)
        if speeds is None
        else np.asarray(speeds, dtype=float)
    )
    if v_grid.shape != a_grid.shape:
        raise ParameterError("speeds", f"needs one speed per altitude ({a_grid.size})")
    folder = (cache_dir() if cache is True else Path(cache)) if cache else None
    path = None if folder is None else folder / _cache_name(model, phi, s_grid, a_grid, v_grid)
    if path is not None:
        errors = (ValueError, KeyError, OSError, zipfile.BadZipFile)
        loaded = load_entry(path, lambda data: _decoded(data, lay, u_op, model.name), errors)
        if loaded is not None:
            return loaded
    jac = pulse_map if isinstance(pulse_map, PulseMapJacobian) else pulse_map_jacobian(phi)
    result = _linearise_grid(model, jac, s_grid, a_grid, v_grid, u_op)
    if path is not None:
        write_entry(path, _encoded(result))
    return result


def _linearise_grid(
    model: Model,
    jac: PulseMapJacobian,
    s_grid: np.ndarray,
    a_grid: np.ndarray,
    v_grid: np.ndarray,
    u_op: np.ndarray,
) -> ConingModel:
    phi = jac.pulse_map
    lay = phi.inputs
    assert lay is not None
    ns, na = s_grid.size, a_grid.size
    index = np.asarray(select_entries(lay, coning_inputs(lay), "inputs"))
    A = np.empty((ns, na, CONING.size, CONING.size))
    B = np.empty((ns, na, CONING.size, index.size))
    ratio = np.empty((ns, na))
    decay = np.empty((ns, na))
    ispin = STATE.slot("spin").start
    for i, s in enumerate(s_grid):
        for j, (alt, speed) in enumerate(zip(a_grid, v_grid, strict=True)):
            pt = climb_point(model, float(alt), float(speed), spin=float(s), pulse_map=jac)
            lin = coning_linear_model(model, pt, pulse_map=jac)
            Az, Bz = lin.A, lin.B
            back = turn(-lin.omega * phi.period)
            Az[_C] = back @ Az[_C]
            Bz[_C] = back @ Bz[_C]
            A[i, j], B[i, j] = Az, Bz
            ratio[i, j] = lin.omega / s
            decay[i, j] = pt.x_next[ispin] / pt.x[ispin]
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        raise ParameterError("model", "a grid point's linear model is not finite")
    return ConingModel(
        spins=s_grid,
        altitudes=a_grid,
        speeds=v_grid,
        A=A,
        B=B,
        omega_per_spin=ratio,
        spin_decay=decay,
        period=phi.period,
        inputs=tuple(entry_names(lay)[k] for k in index),
        input_index=index,
        map_inputs=lay,
        u_op=u_op,
        model_name=model.name,
    )


# --------------------------------------------------------------------------- disk cache
_ARRAYS = ("spins", "altitudes", "speeds", "A", "B", "omega_per_spin", "spin_decay")


def _cache_name(
    model: Model, phi: PulseMap, spins: np.ndarray, alts: np.ndarray, speeds: np.ndarray
) -> str:
    """The entry's file name: the structure key of what the tables are computed from."""
    numbers = (parameter_values(model), spins, alts, speeds)
    key = structure_key(
        "coning_model",
        phi.step,
        build_coning_coordinates(),
        coning_coordinate_jacobian(),
        *(np.ascontiguousarray(a, dtype=float).tobytes() for a in numbers),
    )
    return f"coning_model-{key}.npz"


def _encoded(cm: ConingModel) -> bytes:
    """The model's tables as the bytes of an .npz file (no pickles)."""
    out = io.BytesIO()
    np.savez(out, period=cm.period, **{k: getattr(cm, k) for k in _ARRAYS})
    return out.getvalue()


def _decoded(data: bytes, lay: VectorLayout, u_op: np.ndarray, name: str) -> ConingModel:
    """The model of the tables in ``data`` (:func:`_encoded`) for this input layout."""
    with np.load(io.BytesIO(data), allow_pickle=False) as tables:
        arrays = {k: np.array(tables[k]) for k in _ARRAYS}
        period = float(tables["period"])
    index = np.asarray(select_entries(lay, coning_inputs(lay), "inputs"))
    assert {f.name for f in fields(ConingModel)} >= set(_ARRAYS)
    return ConingModel(
        **arrays,
        period=period,
        inputs=tuple(entry_names(lay)[k] for k in index),
        input_index=index,
        map_inputs=lay,
        u_op=u_op,
        model_name=name,
    )
