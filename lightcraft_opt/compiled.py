"""Compile a casadi.Function to C, cached on disk, for faster evaluation.

The generated C of a Function is compiled by the system C compiler into a shared library
and loaded back with ``casadi.external``; the result evaluates the same expression graph
to round-off (IEEE arithmetic, no ``-ffast-math``) and has the same name, inputs and
outputs. A compiled Function has no derivatives of its own: Φ's derivatives are compiled
as Functions in their own right (:func:`compile_pulse_map_derivatives`, the explicit chain
of symbolic/pulse_map_derivatives.py over compiled pieces).

Cache: the libraries live in ``$LIGHTCRAFT_CACHE``, else ``$XDG_CACHE_HOME/lightcraft_opt``,
else ``~/.cache/lightcraft_opt`` (:func:`cache_dir`), one file per key, the sha256 of the
Function's serialized form (its whole expression graph: model structure and options, not the
numbers it takes through p) with the casadi version, the compiler's ``--version`` and the
flags. A library is compiled under a temporary name and moved into place with
``os.replace``, one process at a time per key (a lock file), so Monte Carlo workers that
share a cache neither clobber nor duplicate each other's work. Anything that goes wrong
(no compiler, a failed compile, an unwritable cache) gives back the interpreted Function
with a :class:`CompilationWarning` that names the cause.

Φ's chain derivatives over compiled pieces are kept on disk too, as serialised Functions
that name their libraries (:func:`saved_pulse_map_derivatives`, function_cache.py): a
later build of the same structure loads them in milliseconds instead of redoing casadi's
AD of every piece (4 s for the OCP's map of problem (a), 10 s for problem (b)'s).

Φ is compiled by default (:func:`pulse_map_for`): ``simulate``, the closed loop and Monte
Carlo ask for the pulse map of a model through it and get the compiled map, built once per
process and model (an in-process memo) and compiled once per structure (the disk cache).
``LIGHTCRAFT_COMPILE=0`` in the environment, or ``compiled=False``, keeps the interpreted
map; without a C compiler the interpreted map comes with one warning.

Cost, measured for Flight 5 with the default options (Φ composed of named pieces,
symbolic/pulse_map.py; 0.65 MB of C; gcc 12 on 2 cores): gcc -O2 takes 5-14 s (idle to
loaded) and under 0.3 GB once per model structure; a cache hit costs a few ms (serialising
and hashing the Function); a pulse then takes 0.15-0.4 ms instead of 0.9-2 ms, with results
identical here to the last bit (promised: to round-off). The flat SX construction of
before (flat_pulse_map.py) took 3 min and 2.8 GB to compile and gained 1.6x. -O0 compiles
faster but runs slower than casadi's interpreter; -O1 took longer and more memory than -O2
on straight-line code.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import fields
from pathlib import Path
from typing import TypeVar

import casadi as ca

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.function_cache import (
    BuildReport,
    cache_dir,
    load_functions,
    save_functions,
    source_digest,
    structure_key,
)
from lightcraft_opt.model import Model
from lightcraft_opt.options import PulseMapOptions
from lightcraft_opt.symbolic import pulse_map_derivatives as derivative_chain
from lightcraft_opt.symbolic.pulse_map import PulseMap, build_pulse_map
from lightcraft_opt.symbolic.pulse_map_derivatives import (
    DerivativePieces,
    PulseMapDerivatives,
    build_derivative_pieces,
    chain_derivatives,
)
from lightcraft_opt.symbolic.pulse_map_pieces import PulseMapPieces
from lightcraft_opt.symbolic.pulse_map_sensitivities import (
    SensitivityPieces,
    build_dense_sensitivity,
    build_sensitivity_pieces,
)
from lightcraft_opt.symbolic.reduced_map import ReducedMapOptions, build_reduced_map
from lightcraft_opt.symbolic.reduced_map_derivatives import (
    ReducedMapDerivatives,
    build_reduced_map_derivatives,
)

try:  # POSIX: serialise compilations of one key across processes
    import fcntl
except ImportError:  # pragma: no cover - Windows: atomic replace only
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "DEFAULT_FLAGS",
    "DERIVATIVES_CACHE",
    "DERIVATIVE_FLAGS",
    "DERIVATIVE_INSTRUCTION_LIMIT",
    "CompilationWarning",
    "cache_dir",
    "compile_by_default",
    "compile_function",
    "compile_pulse_map",
    "compile_pulse_map_derivatives",
    "dense_sensitivity_for",
    "derivatives_for",
    "derivatives_key",
    "library_path",
    "pulse_map_for",
    "reduced_derivatives_for",
    "saved_pulse_map_derivatives",
]

#: Optimisation flags of the default build. -O2 keeps IEEE semantics, so the library
#: agrees with the interpreter to round-off (checked to 1e-12 by tests/test_compiled.py).
#: -O3 is also exact but gains nothing measurable on this straight-line code and compiles
#: slower; -ffast-math reorders sums and assumes no NaN/inf, which changes results and
#: blinds simulate's non-finite check; -march=native may fuse multiply-adds (different
#: last bits) and ties the library to one CPU. Pass ``flags=`` to choose otherwise.
DEFAULT_FLAGS: tuple[str, ...] = ("-O2",)

#: Flags of the derivative pieces (symbolic/pulse_map_derivatives.py). Their SX is long
#: straight-line code (the jump's Hessian for a 4 x 16 optic: 106k instructions, 2.9 MB of
#: C) on which gcc -O2 spends minutes; -O1 compiles it in 27 s and runs it 9x faster than
#: casadi's interpreter (-O0: 9 s, 2.6x). Same IEEE semantics as -O2.
DERIVATIVE_FLAGS: tuple[str, ...] = ("-O1",)

#: Derivative pieces above this many SX instructions stay interpreted: gcc's time and memory
#: grow faster than the code (the Hessian of one Yoshida substep, 553k instructions, is 13 MB
#: of C that takes 3.3 GB and over a minute even at -O0). The OCP's Strang map (2 substeps,
#: 4 x 16 optic; substep Hessian 229k) compiles whole.
DERIVATIVE_INSTRUCTION_LIMIT = 250_000

_BUILD = ("-fPIC", "-shared")  # always: a loadable shared library
_THIS_MODULE = sys.modules[__name__]
_BUILDING_PIECES = "building Φ's derivative pieces (casadi's AD of each piece, seconds) ..."
_CACHE_FORMAT = b"lightcraft_opt.compiled 1"


class CompilationWarning(RuntimeWarning):
    """A Function could not be compiled; its interpreted form is used instead."""


class _CompileError(Exception):
    """Why compiling failed (turned into a :class:`CompilationWarning`)."""


def _compiler_command(compiler: str | None) -> str:
    return compiler or os.environ.get("CC") or "gcc"


@functools.lru_cache(maxsize=8)
def _compiler_version(cc: str) -> str:
    """First line of ``cc --version``; raises _CompileError when there is no such compiler.
    Asked once per process and compiler (a failure is not cached: a later call asks again)."""
    try:
        proc = subprocess.run(
            [cc, "--version"], capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=60
        )
    except (OSError, subprocess.SubprocessError) as err:
        raise _CompileError(f"no C compiler {cc!r} ({err})") from err
    if proc.returncode != 0:
        raise _CompileError(f"{cc} --version failed: {proc.stderr.strip()[-500:]}")
    return proc.stdout.splitlines()[0] if proc.stdout else cc


def _key(f: ca.Function, compiler_version: str, flags: Sequence[str]) -> str:
    digest = hashlib.sha256(_CACHE_FORMAT)
    for part in (ca.__version__, compiler_version, " ".join(flags)):
        digest.update(b"\0" + part.encode())
    digest.update(b"\0" + f.serialize().encode())
    return digest.hexdigest()


def library_path(
    f: ca.Function, *, compiler: str | None = None, flags: Sequence[str] = DEFAULT_FLAGS
) -> Path:
    """Where the compiled library of ``f`` is (or will be) cached.

    Raises
    ------
    FileNotFoundError : when ``compiler`` (default ``$CC``, else gcc) does not run: its
        version is part of the key.
    """
    try:
        return _library_path(f, _compiler_command(compiler), flags)
    except _CompileError as err:
        raise FileNotFoundError(str(err)) from err


def _library_path(f: ca.Function, cc: str, flags: Sequence[str]) -> Path:
    return cache_dir() / f"{f.name()}-{_key(f, _compiler_version(cc), flags)}.so"


def compile_function(
    f: ca.Function, *, compiler: str | None = None, flags: Sequence[str] = DEFAULT_FLAGS
) -> ca.Function:
    """``f`` compiled to C and loaded back, from the cache when it is there.

    Parameters
    ----------
    f : an SX or MX Function (e.g. ``PulseMap.dense``).
    compiler : C compiler command; default ``$CC``, else ``gcc``.
    flags : optimisation flags (see :data:`DEFAULT_FLAGS` for why -O2).

    Returns
    -------
    casadi.Function with the name, inputs and outputs of ``f`` that evaluates the same
    expressions natively (no derivatives); ``f`` itself, with a
    :class:`CompilationWarning` naming the cause, when compiling is not possible.
    """
    cc = _compiler_command(compiler)
    try:
        path = _library_path(f, cc, flags)
        if not path.exists():
            path.parent.mkdir(parents=True, exist_ok=True)
            with _locked(path.with_suffix(".lock")):
                if not path.exists():  # another process may have built it meanwhile
                    _build(f, path, cc, flags)
        return ca.external(f.name(), str(path))
    except (_CompileError, OSError, RuntimeError) as err:
        warnings.warn(
            f"could not compile {f.name()!r}, using the interpreted Function: {err}",
            CompilationWarning,
            stacklevel=2,
        )
        return f


def compile_pulse_map(
    phi: PulseMap, *, compiler: str | None = None, flags: Sequence[str] = DEFAULT_FLAGS
) -> PulseMap:
    """The pulse map with its dense Function compiled (:func:`compile_function`).

    ``step`` is taken from the compiled ``dense`` (its last column is ``x_next``, the
    same expression), so one library serves both and gcc runs once. If compiling fails,
    ``phi`` comes back unchanged (with the warning).
    """
    dense = compile_function(phi.dense, compiler=compiler, flags=flags)
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


def _build(f: ca.Function, path: Path, cc: str, flags: Sequence[str]) -> None:
    """Generate C for ``f``, compile it beside ``path`` and move it into place."""
    work = Path(tempfile.mkdtemp(prefix=f".{f.name()}-", dir=path.parent))
    try:
        source = work / f"{f.name()}.c"
        generator = ca.CodeGenerator(source.name, {"with_header": False})
        generator.add(f)
        source.write_text(generator.dump())
        target = work / path.name
        cmd = [cc, *flags, *_BUILD, str(source), "-o", str(target), "-lm"]
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
        except OSError as err:
            raise _CompileError(f"{cc} did not run ({err})") from err
        if proc.returncode != 0:
            raise _CompileError(
                f"{' '.join(cmd[: 1 + len(flags)])} ... exited {proc.returncode}: "
                f"{proc.stderr.strip()[-500:]}"
            )
        os.replace(target, path)
    finally:
        shutil.rmtree(work, ignore_errors=True)


@contextlib.contextmanager
def _locked(lock_path: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``lock_path`` (a no-op without fcntl)."""
    if fcntl is None:  # pragma: no cover
        yield
        return
    with open(lock_path, "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


# --------------------------------------------------------------------------- Φ by default

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
    options : Φ's options (default :class:`~lightcraft_opt.options.PulseMapOptions`).
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


# --------------------------------------------------------------------------- derivatives

#: Φ's chain derivatives built in this process, likewise.
_DERIVATIVES: OrderedDict[_Key, PulseMapDerivatives] = OrderedDict()


def compile_pulse_map_derivatives(
    phi: PulseMap,
    derivatives: DerivativePieces | None = None,
    *,
    compiler: str | None = None,
    workers: int | None = None,
    max_instructions: int = DERIVATIVE_INSTRUCTION_LIMIT,
    report: BuildReport | None = None,
) -> PulseMapDerivatives:
    """Φ's explicit-chain derivatives (symbolic/pulse_map_derivatives.py) over compiled
    pieces: each value piece (:data:`DEFAULT_FLAGS`) and derivative piece
    (:data:`DERIVATIVE_FLAGS`) of at most ``max_instructions`` SX instructions is its own
    library, cached like any other, compiled ``workers`` at a time (default: the cores);
    bigger pieces stay interpreted. A piece that does not compile stays interpreted (with
    the warning of :func:`compile_function`). ``report`` is told what is being built and
    how many libraries are compiled so far."""
    if phi.pieces is None:
        raise ParameterError("phi", "needs a Φ from build_pulse_map, with its pieces")
    if derivatives is None:
        if report is not None:
            report(_BUILDING_PIECES)
        derivatives = build_derivative_pieces(phi.pieces)
    built = [f for f in derivatives.functions() if f is not None]
    fast, done = _compiled_with_pieces(
        phi.pieces, built, compiler, workers, max_instructions, report
    )
    compiled_derivatives = iter(done)
    replaced = tuple(
        None if f is None else next(compiled_derivatives) for f in derivatives.functions()
    )
    return chain_derivatives(phi, DerivativePieces.of(replaced), fast)


def _compiled_with_pieces(
    pieces: PulseMapPieces,
    derivatives: Sequence[ca.Function],
    compiler: str | None,
    workers: int | None,
    max_instructions: int,
    report: BuildReport | None = None,
) -> tuple[PulseMapPieces, list[ca.Function]]:
    """Φ's value pieces (:data:`DEFAULT_FLAGS`) and the given derivative pieces
    (:data:`DERIVATIVE_FLAGS`) compiled, each its own library, ``workers`` at a time (default:
    the cores); pieces over ``max_instructions`` SX instructions, or that do not compile,
    stay interpreted."""
    values = (pieces.normalise, pieces.jump, pieces.substep, pieces.coning_rate)
    jobs = [(f, DEFAULT_FLAGS) for f in values] + [(f, DERIVATIVE_FLAGS) for f in derivatives]
    done = _compile_all(jobs, compiler, workers, max_instructions, report)
    normalise, jump, substep, coning_rate = done[:4]
    fast = dataclasses.replace(
        pieces, normalise=normalise, jump=jump, substep=substep, coning_rate=coning_rate
    )
    return fast, done[4:]


def _compile_all(
    jobs: Sequence[tuple[ca.Function, tuple[str, ...]]],
    compiler: str | None,
    workers: int | None,
    max_instructions: int,
    report: BuildReport | None = None,
) -> list[ca.Function]:
    """Each (Function, flags) compiled, its own library, ``workers`` at a time (default: the
    cores), in order; a Function over ``max_instructions`` SX instructions, or one that does
    not compile, stays interpreted. ``report`` (if any) hears how many libraries are not in
    the cache, then each one compiled."""
    small = [job for job in jobs if job[0].n_instructions() <= max_instructions]
    missing = _missing_libraries(small, compiler) if report is not None else set()
    if report is not None and missing:
        report(
            f"compiling {len(missing)} libraries with {_compiler_command(compiler)} "
            "(a minute or more, once per structure) ..."
        )
    count = iter(range(1, len(missing) + 1))  # next() is atomic under the GIL

    def compiled_or_not(job: tuple[ca.Function, tuple[str, ...]]) -> ca.Function:
        f, flags = job
        if f.n_instructions() > max_instructions:
            return f
        out = compile_function(f, compiler=compiler, flags=flags)
        if report is not None and id(f) in missing:
            report(f"  compiled {next(count)}/{len(missing)}: {f.name()}")
        return out

    n = workers or os.cpu_count() or 1
    with ThreadPoolExecutor(max_workers=max(1, n)) as pool:
        return list(pool.map(compiled_or_not, jobs))


def _missing_libraries(
    jobs: Sequence[tuple[ca.Function, tuple[str, ...]]], compiler: str | None
) -> set[int]:
    """ids of the Functions of ``jobs`` whose library is not in the cache (none when
    there is no compiler: nothing will be compiled)."""
    cc = _compiler_command(compiler)
    try:
        return {id(f) for f, flags in jobs if not _library_path(f, cc, flags).exists()}
    except _CompileError:
        return set()


def derivatives_for(
    model: Model,
    options: PulseMapOptions | None = None,
    *,
    compiled: bool | None = None,
    report: BuildReport | None = None,
) -> PulseMapDerivatives:
    """Φ's explicit-chain derivatives for ``model``: built once per process for equal
    models and options, over compiled pieces unless ``compiled`` is False or
    :func:`compile_by_default` says no; those come from the disk cache
    (:func:`saved_pulse_map_derivatives`: the first build of the OCP's map takes about a
    minute on 2 cores, a later one milliseconds). ``report`` hears what a build does."""
    opts = options or PulseMapOptions()
    want = compile_by_default() if compiled is None else bool(compiled)

    def build() -> PulseMapDerivatives:
        phi = pulse_map_for(model, opts, compiled=False)
        assert phi.pieces is not None  # build_pulse_map always records its pieces
        if not want:
            if report is not None:
                report(_BUILDING_PIECES)
            return chain_derivatives(phi, build_derivative_pieces(phi.pieces))
        with _compilation_warned_once():
            return saved_pulse_map_derivatives(phi, report=report)

    return _remembered(_DERIVATIVES, (model, opts, want), build)


#: Name of the cache files of Φ's compiled derivatives (function_cache.py).
DERIVATIVES_CACHE = "pulse_map_derivatives"


def saved_pulse_map_derivatives(
    phi: PulseMap,
    *,
    max_instructions: int = DERIVATIVE_INSTRUCTION_LIMIT,
    report: BuildReport | None = None,
) -> PulseMapDerivatives:
    """:func:`compile_pulse_map_derivatives` of ``phi``, kept on disk by structure
    (function_cache.py): the chain's Functions over the compiled pieces, serialised (they
    name the libraries), under the key :func:`derivatives_key`. A hit loads in
    milliseconds instead of seconds of casadi's AD on each piece; a damaged file is built
    again with a :class:`~lightcraft_opt.function_cache.CacheWarning`. Derivatives with a
    piece that failed to compile (no compiler ...) are used, never saved.
    ``max_instructions`` as in :func:`compile_pulse_map_derivatives`."""
    start = time.perf_counter()
    key = derivatives_key(phi, max_instructions)
    loaded = None if key is None else load_functions(DERIVATIVES_CACHE, key)
    if loaded is not None and len(loaded) == 3 + len(fields(DerivativePieces)):
        if report is not None:
            report(f"Φ's derivatives: loaded from the cache in {time.perf_counter() - start:.1f} s")
        pieces_of = DerivativePieces.of(tuple(loaded[3:]))
        return PulseMapDerivatives(loaded[0], loaded[1], loaded[2], pieces_of)
    derivatives = compile_pulse_map_derivatives(
        phi, max_instructions=max_instructions, report=report
    )
    pieces = derivatives.pieces.functions()
    complete = derivatives.hessian is not None and _all_compiled(pieces, max_instructions)
    if key is not None and complete:
        functions = [derivatives.values, derivatives.jacobian, derivatives.hessian]
        save_functions(DERIVATIVES_CACHE, key, [*functions, *(f for f in pieces if f)])
    return derivatives


def _all_compiled(derivative_pieces: Sequence[ca.Function | None], limit: int) -> bool:
    """Whether every derivative piece of at most ``limit`` instructions came back
    compiled (not: a compile failed)."""
    return all(
        f is not None and (f.is_a("External") or f.n_instructions() > limit)
        for f in derivative_pieces
    )


def derivatives_key(
    phi: PulseMap, max_instructions: int = DERIVATIVE_INSTRUCTION_LIMIT
) -> str | None:
    """The structure key of ``phi``'s compiled derivatives: Φ's graph (its dense Function
    and pieces, which hold the model's structure and the options; the model's numbers go
    in through p), the options and input layout, the compiler's version, flags and
    instruction limit, and the source of the chain and of this module; None without a C
    compiler."""
    try:
        version = _compiler_version(_compiler_command(None))
    except _CompileError:
        return None
    pieces = phi.pieces
    assert pieces is not None
    numbers = (pieces.substeps, pieces.step_length, pieces.n_thrusters, pieces.has_carrier)
    return structure_key(
        "pulse_map_derivatives",
        phi.dense,
        pieces.normalise,
        pieces.jump,
        pieces.substep,
        pieces.coning_rate,
        repr((numbers, pieces.substep_inputs, phi.options, phi.inputs, phi.period)),
        version,
        repr((DEFAULT_FLAGS, DERIVATIVE_FLAGS, max_instructions)),
        source_digest(derivative_chain, _THIS_MODULE),
    )


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
    (:func:`~lightcraft_opt.symbolic.pulse_map_sensitivities.build_dense_sensitivity`) in
    ``n_directions`` directions, chained over pieces compiled (:data:`DERIVATIVE_FLAGS`)
    unless ``compiled`` is False or :func:`compile_by_default` says no. The pieces are built
    once per process for equal models, options and directions and compiled once per
    structure (the disk cache); the chain itself, a short MX graph, is assembled on each
    call."""
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
            _, done = _compiled_with_pieces(
                own, interpreted.functions(), None, None, DERIVATIVE_INSTRUCTION_LIMIT
            )
        return interpreted.replaced(tuple(done))

    key = (model, opts, want, n_directions)
    return build_dense_sensitivity(phi, n_directions, _remembered(_SENSITIVITIES, key, build))


#: Ψ's Jacobian chains built in this process, by (model, options, compiled), likewise.
_REDUCED: OrderedDict[tuple[Model, ReducedMapOptions, bool], ReducedMapDerivatives] = OrderedDict()


def reduced_derivatives_for(
    model: Model, options: ReducedMapOptions | None = None, *, compiled: bool | None = None
) -> ReducedMapDerivatives:
    """The reduced map Ψ's value and Jacobian chains for ``model``
    (:func:`~lightcraft_opt.symbolic.reduced_map_derivatives.build_reduced_map_derivatives`),
    over pieces compiled (values with :data:`DEFAULT_FLAGS`, Jacobians with
    :data:`DERIVATIVE_FLAGS`) unless ``compiled`` is False or :func:`compile_by_default` says
    no; built once per process for equal models and options, compiled once per structure
    (Flight 5 with a 4 x 16 optic: about a minute on 2 cores, then the disk cache)."""
    opts = options or ReducedMapOptions()
    want = compile_by_default() if compiled is None else bool(compiled)

    def build() -> ReducedMapDerivatives:
        interpreted = build_reduced_map_derivatives(build_reduced_map(model, opts))
        if not want:
            return interpreted
        flags = (DERIVATIVE_FLAGS, DERIVATIVE_FLAGS, DEFAULT_FLAGS, DEFAULT_FLAGS)
        jobs = list(zip(interpreted.pieces(), flags, strict=True))
        with _compilation_warned_once():
            done = _compile_all(jobs, None, None, DERIVATIVE_INSTRUCTION_LIMIT)
        return interpreted.replaced((done[0], done[1], done[2], done[3]))

    return _remembered(_REDUCED, (model, opts, want), build)
