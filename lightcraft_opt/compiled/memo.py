"""The per-process memo: Φ, its derivative chains and Ψ's for a model, built once per
process.

:func:`pulse_map_for`, :func:`derivatives_for`, :func:`dense_sensitivity_for` and
:func:`reduced_derivatives_for` build once per process and model (the 16 latest kept, by
equal model and options) and compile once per structure (the disk cache, cache/).
``simulate``, the closed loop and Monte Carlo get Φ through :func:`pulse_map_for`,
compiled by default; ``LIGHTCRAFT_COMPILE=0`` in the environment, or ``compiled=False``,
keeps the interpreted map; without a C compiler the interpreted map comes with one
:class:`~lightcraft_opt.compiled.cache.CompilationWarning` per process.
"""

from __future__ import annotations

import contextlib
import os
import warnings
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator
from typing import TypeVar

import casadi as ca

from lightcraft_opt.compiled.cache import (
    DEFAULT_FLAGS,
    DERIVATIVE_FLAGS,
    BuildReport,
    CompilationWarning,
    compile_all,
)
from lightcraft_opt.compiled.pulse_map import (
    DERIVATIVE_INSTRUCTION_LIMIT,
    compile_pieces,
    compile_pulse_map,
    saved_derivative_pieces,
    saved_pulse_map_derivatives,
)
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap, build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import (
    PulseMapDerivatives,
    chain_derivatives,
    check_design,
)
from lightcraft_opt.symbolic.maps.pulse_map_sensitivities import (
    SensitivityPieces,
    build_dense_sensitivity,
    build_sensitivity_pieces,
)
from lightcraft_opt.symbolic.maps.reduced_map import ReducedMapOptions, build_reduced_map
from lightcraft_opt.symbolic.maps.reduced_map_derivatives import (
    ReducedMapDerivatives,
    build_reduced_map_derivatives,
)

__all__ = [
    "compile_by_default",
    "dense_sensitivity_for",
    "derivatives_for",
    "pulse_map_for",
    "reduced_derivatives_for",
]

_Key = tuple[Model, PulseMapOptions, bool]
_T = TypeVar("_T")
_K = TypeVar("_K", bound=Hashable)

#: Pulse maps built in this process, by (model, options, compiled); the oldest dropped first.
_MAPS: OrderedDict[_Key, PulseMap] = OrderedDict()
_MAPS_KEPT = 16
_warned_once = False


def compile_by_default() -> bool:
    """Whether Φ is compiled when the caller does not say: yes, unless the environment sets
    ``LIGHTCRAFT_COMPILE`` to 0, false, no or off."""
    flag = os.environ.get("LIGHTCRAFT_COMPILE", "1").strip().lower()
    return flag not in {"0", "false", "no", "off"}


def pulse_map_for(
    model: Model, options: PulseMapOptions | None = None, *, compiled: bool | None = None
) -> PulseMap:
    """The pulse map Φ of ``model``: built once per process for equal models and options
    (kept for the 16 latest), compiled to C where a compiler works (:func:`compile_pulse_map`,
    cached on disk by structure, so a model with other numbers compiles nothing).

    Parameters
    ----------
    model : the model; its numbers go in through p, so one map serves every p.
    options : Φ's options (default :class:`~lightcraft_opt.symbolic.maps.options.PulseMapOptions`).
    compiled : True or False to choose; None (default) for :func:`compile_by_default`.

    Returns
    -------
    PulseMap; the interpreted map, with one :class:`CompilationWarning` per process,
    when compiling fails. The compiled map evaluates values only: derivatives need the
    interpreted map (``compiled=False``).
    """
    opts = options or PulseMapOptions()
    want = compile_by_default() if compiled is None else bool(compiled)

    def build() -> PulseMap:
        interpreted = _MAPS.get((model, opts, False)) or build_pulse_map(model, opts)
        if not want:
            return interpreted
        with _compilation_warned_once():
            return compile_pulse_map(interpreted)

    return _remembered(_MAPS, (model, opts, want), build)


def _remembered(table: OrderedDict[_K, _T], key: _K, build: Callable[[], _T]) -> _T:
    """``table[key]``, built by ``build`` the first time; the oldest of more than
    :data:`_MAPS_KEPT` entries dropped."""
    if key in table:
        table.move_to_end(key)
        return table[key]
    value = table[key] = build()
    while len(table) > _MAPS_KEPT:
        table.popitem(last=False)
    return value


@contextlib.contextmanager
def _compilation_warned_once() -> Iterator[None]:
    """Warnings raised inside are shown as they were, except that a CompilationWarning is
    shown only the first time in this process."""
    global _warned_once
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", CompilationWarning)
        yield
    for w in caught:
        if not issubclass(w.category, CompilationWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        elif not _warned_once:
            _warned_once = True
            warnings.warn(w.message, CompilationWarning, stacklevel=4)


#: Φ's chain derivatives built in this process, by (model, options, compiled, design),
#: likewise.
_DERIVATIVES: OrderedDict[
    tuple[Model, PulseMapOptions, bool, tuple[int, ...]], PulseMapDerivatives
] = OrderedDict()


def derivatives_for(
    model: Model,
    options: PulseMapOptions | None = None,
    *,
    design: tuple[int, ...] = (),
    compiled: bool | None = None,
    report: BuildReport | None = None,
) -> PulseMapDerivatives:
    """Φ's explicit-chain derivatives for ``model`` in v = (x, u, p[design]) (``design``:
    sorted indices into PARAMETERS, the OCP's designed entries of p): built once per
    process for equal models, options and designs, over compiled pieces unless
    ``compiled`` is False or :func:`compile_by_default` says no; those come from the disk
    cache (:func:`saved_pulse_map_derivatives`: the first build of the OCP's map takes
    about a minute on 2 cores, a later one milliseconds). ``report`` hears what a build
    does."""
    opts = options or PulseMapOptions()
    want = compile_by_default() if compiled is None else bool(compiled)
    design = check_design(design)

    def build() -> PulseMapDerivatives:
        phi = pulse_map_for(model, opts, compiled=False)
        assert phi.pieces is not None  # build_pulse_map always records its pieces
        if not want:  # interpreted, the pieces' AD kept on disk
            pieces = saved_derivative_pieces(phi, design=design, report=report)
            return chain_derivatives(phi, pieces, design=design)
        with _compilation_warned_once():
            return saved_pulse_map_derivatives(phi, report=report, design=design)

    return _remembered(_DERIVATIVES, (model, opts, want, design), build)


#: Φ's pieces in forward mode built in this process, by (model, options, compiled,
#: directions), likewise.
_SENSITIVITIES: OrderedDict[tuple[Model, PulseMapOptions, bool, int], SensitivityPieces] = (
    OrderedDict()
)


def dense_sensitivity_for(
    model: Model,
    options: PulseMapOptions | None = None,
    n_directions: int = 1,
    *,
    compiled: bool | None = None,
) -> ca.Function:
    """``pulse_map_dense_sensitivity(x, u, p, t, dx, dp) -> (X, dX)`` of ``model``'s Φ
    (:func:`~lightcraft_opt.symbolic.maps.pulse_map_sensitivities.build_dense_sensitivity`) in
    ``n_directions`` directions, chained over pieces compiled
    (:data:`~lightcraft_opt.compiled.cache.DERIVATIVE_FLAGS`) unless ``compiled`` is False or
    :func:`compile_by_default` says no. The pieces are built once per process for equal
    models, options and directions and compiled once per structure (the disk cache); the
    chain itself, a short MX graph, is assembled on each call."""
    opts = options or PulseMapOptions()
    want = compile_by_default() if compiled is None else bool(compiled)
    phi = pulse_map_for(model, opts, compiled=False)
    assert phi.pieces is not None  # build_pulse_map always records its pieces
    own = phi.pieces

    def build() -> SensitivityPieces:
        interpreted = build_sensitivity_pieces(own, n_directions)
        if not want:
            return interpreted
        with _compilation_warned_once():
            what = "Φ's pieces and their sensitivities"
            _, done, _ = compile_pieces(own, interpreted.functions(), what=what)
        return interpreted.replaced(tuple(done))

    key = (model, opts, want, n_directions)
    return build_dense_sensitivity(phi, n_directions, _remembered(_SENSITIVITIES, key, build))


#: Ψ's Jacobian chains built in this process, by (model, options, compiled), likewise.
_REDUCED: OrderedDict[tuple[Model, ReducedMapOptions, bool], ReducedMapDerivatives] = OrderedDict()


def reduced_derivatives_for(
    model: Model, options: ReducedMapOptions | None = None, *, compiled: bool | None = None
) -> ReducedMapDerivatives:
    """The reduced map Ψ's value and Jacobian chains for ``model``
    (:func:`~lightcraft_opt.symbolic.maps.reduced_map_derivatives.build_reduced_map_derivatives`),
    over pieces compiled (values with :data:`~lightcraft_opt.compiled.cache.DEFAULT_FLAGS`,
    Jacobians with :data:`~lightcraft_opt.compiled.cache.DERIVATIVE_FLAGS`) unless ``compiled`` is
    False or :func:`compile_by_default` says no; built once per process for equal models
    and options, compiled once per structure (Flight 5 with a 4 x 16 optic: about a minute
    on 2 cores, then the disk cache)."""
    opts = options or ReducedMapOptions()
    want = compile_by_default() if compiled is None else bool(compiled)

    def build() -> ReducedMapDerivatives:
        interpreted = build_reduced_map_derivatives(build_reduced_map(model, opts))
        if not want:
            return interpreted
        flags = (DERIVATIVE_FLAGS, DERIVATIVE_FLAGS, DEFAULT_FLAGS, DEFAULT_FLAGS)
        jobs = list(zip(interpreted.pieces(), flags, strict=True))
        with _compilation_warned_once():
            done, _ = compile_all(
                jobs, max_instructions=DERIVATIVE_INSTRUCTION_LIMIT, what="Ψ's Jacobian pieces"
            )
        return interpreted.replaced((done[0], done[1], done[2], done[3]))

    return _remembered(_REDUCED, (model, opts, want), build)
