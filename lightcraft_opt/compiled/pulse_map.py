"""Φ compiled: its dense Function, and its derivative chains over compiled pieces, kept
on disk by structure.

What runs often is compiled to C (compiled/cache/compiler.py: one library per Function, a cache
entry by structure, verified before it is loaded); this module knows Φ's structure.
:func:`compile_pulse_map` compiles Φ's dense Function and takes its step from it;
:func:`compile_pulse_map_derivatives` compiles Φ's pieces and their derivatives, each its
own library, and chains them (symbolic/maps/pulse_map_derivatives.py), never casadi's AD through
the whole graph (docs/architecture.md#rule-17); :func:`saved_pulse_map_derivatives` keeps
that chain on disk (compiled/cache/functions.py), so a later build of the same structure loads it in
milliseconds instead of redoing casadi's AD of every piece (seconds; figures:
bench/README.md#build-time-a-new-structure-and-the-same-structure-again);
:func:`saved_derivative_pieces` keeps the pieces' interpreted derivatives likewise, for
processes that compile nothing.

Cost, for Flight 5 with the default options (Φ composed of named pieces,
symbolic/maps/pulse_map.py; 0.65 MB of C): gcc -O2 compiles it in seconds, once per model
structure; a cache hit costs milliseconds (serialising and hashing the Function, verifying
the library); a pulse then runs several times faster than interpreted, with results
identical here to the last bit (promised: to round-off). The flat SX construction of before
(symbolic/maps/reference_pulse_map.py) took minutes and gigabytes to compile and gained
far less. -O0 compiles faster but runs slower than casadi's interpreter; -O1 took longer and
more memory than -O2 on straight-line code. Figures: bench/README.md#compile-cost-and-compiler-flags
and the table of the `pulse_map.py` section there.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path

import casadi as ca

from lightcraft_opt.compiled.cache import (
    DEFAULT_FLAGS,
    DERIVATIVE_FLAGS,
    BuildReport,
    compile_all,
    compile_function,
    compiler_version,
    load_functions,
    save_functions,
    source_digest,
    structure_key,
)
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.symbolic.maps import jump_derivatives
from lightcraft_opt.symbolic.maps import pulse_map_derivatives as derivative_chain
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import (
    DerivativePieces,
    PulseMapDerivatives,
    build_derivative_pieces,
    chain_derivatives,
    check_design,
)
from lightcraft_opt.symbolic.maps.pulse_map_pieces import PulseMapPieces

__all__ = [
    "BUILDING_PIECES",
    "DERIVATIVES_CACHE",
    "DERIVATIVE_INSTRUCTION_LIMIT",
    "DESIGN_INSTRUCTION_LIMIT",
    "PIECES_CACHE",
    "compile_pieces",
    "compile_pulse_map",
    "compile_pulse_map_derivatives",
    "derivatives_key",
    "instruction_limit",
    "saved_derivative_pieces",
    "saved_pulse_map_derivatives",
]

#: Derivative pieces above this many SX instructions stay interpreted: gcc's time and memory
#: grow faster than the code (the Hessian of one Yoshida substep, 553k instructions, is 13 MB
#: of C that takes 3.3 GB and over a minute even at -O0). The OCP's Strang map (2 substeps,
#: 4 x 16 optic; substep Hessian 241k) compiles whole, and so does the jump's Hessian at the
#: model files' 8 x 32 optic, taken through the quadrature (symbolic/maps/jump_derivatives.py:
#: 231k instructions under the waist beam, where casadi's AD of the whole jump gives 542k).
DERIVATIVE_INSTRUCTION_LIMIT = 250_000

#: The limit for the pieces of a chain also in designed entries of p (a design, ocp/design.py):
#: each designed entry adds a few per cent to the substep's Hessian (the OCP's Strang map: 241k
#: instructions, 255k with two entries, which gcc compiled in 100 s under load 5, the run's
#: largest process 2.2 GB), and a design problem is solved offline over hundreds of
#: iterations, where one longer gcc run per structure pays for itself: with that Hessian
#: interpreted a chain-NLP iteration at 130 pulses took 831 ms instead of 101-191 ms (bench/
#: README.md#design_chainpy-a-chain-nlp-iteration-with-and-without-a-design).
DESIGN_INSTRUCTION_LIMIT = 300_000

#: What a build reports when it starts casadi's AD of Φ's pieces.
BUILDING_PIECES = "building Φ's derivative pieces (casadi's AD of each piece, seconds) ..."

_THIS_MODULE = sys.modules[__name__]


def compile_pulse_map(
    phi: PulseMap, *, compiler: str | None = None, flags: Sequence[str] = DEFAULT_FLAGS
) -> PulseMap:
    """The pulse map with its dense Function compiled
    (:func:`~lightcraft_opt.compiled.cache.compile_function`).

    ``step`` is taken from the compiled ``dense`` (its last column is ``x_next``, the
    same expression), so one library serves both and gcc runs once. If compiling fails,
    ``phi`` comes back unchanged (with the warning).
    """
    dense = compile_function(phi.dense, compiler=compiler, flags=flags, what="Φ, the pulse map")
    if dense is phi.dense:
        return phi
    x, u, p, t = (ca.MX.sym(dense.name_in(i), dense.sparsity_in(i)) for i in range(4))
    X, engine = dense(x, u, p, t)
    step = ca.Function(
        phi.step.name(),
        [x, u, p, t],
        [X[:, -1], engine],
        phi.step.name_in(),
        phi.step.name_out(),
    )
    return dataclasses.replace(phi, step=step, dense=dense)


def compile_pulse_map_derivatives(
    phi: PulseMap,
    derivatives: DerivativePieces | None = None,
    *,
    compiler: str | None = None,
    workers: int | None = None,
    max_instructions: int | None = None,
    report: BuildReport | None = None,
    design: tuple[int, ...] = (),
) -> PulseMapDerivatives:
    """Φ's explicit-chain derivatives (symbolic/maps/pulse_map_derivatives.py) in v = (x, u,
    p[design]) over compiled pieces: each value piece (``DEFAULT_FLAGS``) and derivative
    piece (``DERIVATIVE_FLAGS``, compiled/cache/compiler.py) of at most ``max_instructions``
    SX instructions (default :func:`instruction_limit`) is its own library, cached like
    any other, compiled ``workers`` at a time (default: the cores); bigger pieces stay
    interpreted. A piece that does not compile
    stays interpreted (with the warning of ``compile_function``). ``report`` is told what is
    being built and how many libraries are compiled so far. ``derivatives``, if given, must
    have been built with the same ``design`` (sorted indices into PARAMETERS)."""
    limit = instruction_limit(design, max_instructions)
    return _compiled_derivatives(phi, derivatives, compiler, workers, limit, report, design)[0]


def _compiled_derivatives(
    phi: PulseMap,
    derivatives: DerivativePieces | None,
    compiler: str | None,
    workers: int | None,
    max_instructions: int,
    report: BuildReport | None,
    design: tuple[int, ...] = (),
) -> tuple[PulseMapDerivatives, list[Path]]:
    """(:func:`compile_pulse_map_derivatives`, the libraries its chain loads)."""
    if phi.pieces is None:
        raise ParameterError("phi", "needs a Φ from build_pulse_map, with its pieces")
    if derivatives is None:
        if report is not None:
            report(BUILDING_PIECES)
        derivatives = build_derivative_pieces(phi.pieces, design=design)
    built = [f for f in derivatives.functions() if f is not None]
    fast, done, libraries = compile_pieces(
        phi.pieces, built, compiler, workers, max_instructions, report, "Φ's derivative pieces"
    )
    compiled_derivatives = iter(done)
    replaced = tuple(
        None if f is None else next(compiled_derivatives) for f in derivatives.functions()
    )
    return chain_derivatives(phi, DerivativePieces.of(replaced), fast, design=design), libraries


def compile_pieces(
    pieces: PulseMapPieces,
    derivatives: Sequence[ca.Function],
    compiler: str | None = None,
    workers: int | None = None,
    max_instructions: int = DERIVATIVE_INSTRUCTION_LIMIT,
    report: BuildReport | None = None,
    what: str = "Φ's pieces",
) -> tuple[PulseMapPieces, list[ca.Function], list[Path]]:
    """Φ's value pieces (``DEFAULT_FLAGS``) and the given derivative pieces
    (``DERIVATIVE_FLAGS``) compiled, each its own library, ``workers`` at a time (default:
    the cores); pieces over ``max_instructions`` SX instructions, or that do not compile,
    stay interpreted. Returns the pieces, the derivative pieces and the libraries loaded.
    ``report`` and ``what`` as in :func:`~lightcraft_opt.compiled.cache.compile_all`."""
    values = (pieces.normalise, pieces.jump, pieces.substep, pieces.coning_rate)
    jobs = [(f, DEFAULT_FLAGS) for f in values] + [(f, DERIVATIVE_FLAGS) for f in derivatives]
    done, libraries = compile_all(
        jobs,
        compiler=compiler,
        workers=workers,
        max_instructions=max_instructions,
        report=report,
        what=what,
    )
    normalise, jump, substep, coning_rate = done[:4]
    fast = dataclasses.replace(
        pieces, normalise=normalise, jump=jump, substep=substep, coning_rate=coning_rate
    )
    return fast, done[4:], libraries


#: Name of the cache entries of Φ's compiled derivatives (compiled/cache/functions.py).
DERIVATIVES_CACHE = "pulse_map_derivatives"


def saved_pulse_map_derivatives(
    phi: PulseMap,
    *,
    max_instructions: int | None = None,
    report: BuildReport | None = None,
    design: tuple[int, ...] = (),
) -> PulseMapDerivatives:
    """:func:`compile_pulse_map_derivatives` of ``phi`` in v = (x, u, p[design])
    (``design``: sorted indices into PARAMETERS, the OCP's designed entries of p), kept on
    disk by structure (compiled/cache/functions.py): the chain's Functions over the compiled
    pieces, serialised with the libraries they call (verified before loading), under the key
    :func:`derivatives_key`. A hit loads in milliseconds instead of seconds of casadi's AD
    on each piece; a damaged entry, or one whose library is damaged, is built again with a
    :class:`~lightcraft_opt.compiled.cache.CacheWarning`. Derivatives with a piece that failed to
    compile (no compiler ...) are used, never saved.
    ``max_instructions`` as in :func:`compile_pulse_map_derivatives`."""
    design = check_design(design)
    max_instructions = instruction_limit(design, max_instructions)
    start = time.perf_counter()
    key = derivatives_key(phi, max_instructions, design)
    loaded = None if key is None else load_functions(DERIVATIVES_CACHE, key)
    chain = PulseMapDerivatives.CHAIN_FUNCTIONS  # then the pieces
    if loaded is not None and len(loaded) == chain + len(fields(DerivativePieces)):
        if report is not None:
            report(f"Φ's derivatives: loaded from the cache in {time.perf_counter() - start:.1f} s")
        pieces_of = DerivativePieces.of(tuple(loaded[chain:]))
        return PulseMapDerivatives.of_functions(loaded[:chain], pieces_of, design)
    derivatives, libraries = _compiled_derivatives(
        phi, None, None, None, max_instructions, report, design
    )
    pieces = derivatives.pieces.functions()
    complete = derivatives.hessian is not None and _all_compiled(pieces, max_instructions)
    if key is not None and complete:
        saved = [*derivatives.functions(), *(f for f in pieces if f)]
        save_functions(DERIVATIVES_CACHE, key, saved, libraries)
    return derivatives


def _all_compiled(derivative_pieces: Sequence[ca.Function | None], limit: int) -> bool:
    """Whether every derivative piece of at most ``limit`` instructions came back
    compiled (not: a compile failed)."""
    return all(
        f is not None and (f.is_a("External") or f.n_instructions() > limit)
        for f in derivative_pieces
    )


def instruction_limit(design: tuple[int, ...], max_instructions: int | None = None) -> int:
    """``max_instructions`` if given, else the limit for a chain in ``design``:
    :data:`DESIGN_INSTRUCTION_LIMIT` with designed entries of p, else
    :data:`DERIVATIVE_INSTRUCTION_LIMIT`."""
    if max_instructions is not None:
        return max_instructions
    return DESIGN_INSTRUCTION_LIMIT if design else DERIVATIVE_INSTRUCTION_LIMIT


def derivatives_key(
    phi: PulseMap,
    max_instructions: int | None = None,
    design: tuple[int, ...] = (),
) -> str | None:
    """The structure key of ``phi``'s compiled derivatives in v = (x, u, p[design]): Φ's
    graph (its dense Function and pieces, which hold the model's structure and the options;
    the model's numbers go in through p), the options and input layout, the designed
    entries of p (a key of its own per design; none: the key of the chain without them),
    the compiler's version, flags and instruction limit (default :func:`instruction_limit`),
    and the source of the chain and of this module; None without a C compiler."""
    version = compiler_version()
    if version is None:
        return None
    max_instructions = instruction_limit(design, max_instructions)
    compiled = repr((DEFAULT_FLAGS, DERIVATIVE_FLAGS, max_instructions))
    return _structure_key("pulse_map_derivatives", phi, design, version, compiled)


def _structure_key(name: str, phi: PulseMap, design: tuple[int, ...], *more: str) -> str:
    """The key of an entry ``name`` built from ``phi``'s structure in v = (x, u,
    p[design]) (:func:`derivatives_key`), with ``more`` (how it was built) after it."""
    pieces = phi.pieces
    assert pieces is not None
    numbers = (pieces.substeps, pieces.step_length, pieces.n_thrusters, pieces.has_carrier)
    designed = (repr(("design", check_design(design))),) if design else ()
    return structure_key(
        name,
        phi.dense,
        pieces.normalise,
        pieces.jump,
        pieces.substep,
        pieces.coning_rate,
        repr((numbers, pieces.substep_inputs, phi.options, phi.inputs, phi.period)),
        *more,
        source_digest(derivative_chain, jump_derivatives, _THIS_MODULE),
        *designed,
    )


#: Name of the cache entries of Φ's interpreted derivative pieces (:func:`saved_derivative_pieces`).
PIECES_CACHE = "pulse_map_derivative_pieces"

#: What an entry of :data:`PIECES_CACHE` holds in place of a Hessian that was not built.
_ABSENT = "absent_piece"


def saved_derivative_pieces(
    phi: PulseMap, *, design: tuple[int, ...] = (), report: BuildReport | None = None
) -> DerivativePieces:
    """``phi``'s derivative pieces in v = (x, u, p[design]), interpreted (casadi's AD of
    each piece, :func:`build_derivative_pieces`), kept on disk by structure like the
    compiled chain (compiled/cache/functions.py): where nothing is compiled
    (``LIGHTCRAFT_COMPILE=0``, no C compiler) a later process loads them in a second or
    two instead of redoing the AD (4-20 s for the problem files' maps). ``report`` hears
    which it was; a damaged entry is built again with a
    :class:`~lightcraft_opt.compiled.cache.CacheWarning`."""
    if phi.pieces is None:
        raise ParameterError("phi", "needs a Φ from build_pulse_map, with its pieces")
    design = check_design(design)
    start = time.perf_counter()
    key = _structure_key(PIECES_CACHE, phi, design, "interpreted")
    loaded = load_functions(PIECES_CACHE, key)
    if loaded is not None and len(loaded) == len(fields(DerivativePieces)):
        if report is not None:
            seconds = time.perf_counter() - start
            report(f"Φ's derivative pieces: loaded from the cache in {seconds:.1f} s")
        return DerivativePieces.of(tuple(None if f.name() == _ABSENT else f for f in loaded))
    if report is not None:
        report(BUILDING_PIECES)
    pieces = build_derivative_pieces(phi.pieces, design=design)
    absent = ca.Function(_ABSENT, [], [])
    save_functions(PIECES_CACHE, key, [absent if f is None else f for f in pieces.functions()])
    return pieces
