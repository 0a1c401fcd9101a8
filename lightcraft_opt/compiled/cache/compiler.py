"""The C compiler: a casadi.Function compiled to a shared library, kept as a cache entry.

The generated C of a Function is compiled by the system C compiler (``$CC``, else gcc)
into a shared library and loaded back with ``casadi.external``; the result evaluates the
same expression graph to round-off (IEEE arithmetic, no ``-ffast-math``) and has the same
name, inputs and outputs, without derivatives of its own.

A library is a cache entry (entries.py) named by the Function and a key, the structure
key of the Function's serialised form (its whole expression graph: model structure and
options, not the numbers it takes through p) with the compiler's ``--version`` and the
flags. It is built in a temporary folder, moved into place and its checksum written, one
process at a time, so Monte Carlo workers that share a cache neither clobber nor
duplicate each other's work; it is verified before dlopen sees it, and a damaged one is
built again with a :class:`~.entries.CacheWarning`. Anything else that goes wrong (no
compiler, a failed compile, an unwritable cache) gives back the interpreted Function with
a :class:`CompilationWarning` that names the cause.
"""

from __future__ import annotations

import functools
import os
import subprocess
import time
import warnings
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import casadi as ca

from lightcraft_opt.compiled.cache.entries import (
    BuildReport,
    EntryStatus,
    cache_dir,
    check_entry,
    entry_file,
    reporter,
    structure_key,
)
from lightcraft_opt.compiled.cache.hpipm_source import (
    HPIPM_SOURCE_FIX,
    fixed_source,
    hpipm_flags,
    uses_hpipm,
)

__all__ = [
    "DEFAULT_FLAGS",
    "DERIVATIVE_FLAGS",
    "CompilationWarning",
    "CompileJob",
    "compile_all",
    "compile_function",
    "compiler_version",
    "library_path",
]

#: Optimisation flags of the default build. -O2 keeps IEEE semantics, so the library
#: agrees with the interpreter to round-off (checked to 1e-12 by tests/test_compiled.py).
#: -O3 is also exact but gains nothing measurable on this straight-line code and compiles
#: slower; -ffast-math reorders sums and assumes no NaN/inf, which changes results and
#: blinds simulate's non-finite check; -march=native may fuse multiply-adds (different
#: last bits) and ties the library to one CPU. Pass ``flags=`` to choose otherwise.
DEFAULT_FLAGS: tuple[str, ...] = ("-O2",)

#: Flags of derivative pieces (symbolic/maps/pulse_map_derivatives.py). Their SX is long
#: straight-line code (the jump's Hessian for a 4 x 16 optic: 106k instructions, 2.9 MB of
#: C) on which gcc -O2 spends minutes; -O1 compiles it far sooner and runs it several times
#: faster than casadi's interpreter (-O0 compiles sooner still but gains much less; figures:
#: bench/README.md#compile-cost-and-compiler-flags). Same IEEE semantics as -O2.
DERIVATIVE_FLAGS: tuple[str, ...] = ("-O1",)


#: A Function to compile and its flags.
CompileJob = tuple[ca.Function, tuple[str, ...]]

_BUILD = ("-fPIC", "-shared")  # always: a loadable shared library


class CompilationWarning(RuntimeWarning):
    """A Function could not be compiled; its interpreted form is used instead."""


class _CompileError(Exception):
    """Why compiling failed (turned into a :class:`CompilationWarning`)."""


def _compiler_command(compiler: str | None) -> str:
    return compiler or os.environ.get("CC") or "gcc"


def compiler_version(compiler: str | None = None) -> str | None:
    """First line of ``compiler --version`` (default ``$CC``, else gcc); None when there is
    no such compiler."""
    try:
        return _version(_compiler_command(compiler))
    except _CompileError:
        return None


@functools.lru_cache(maxsize=8)
def _version(cc: str) -> str:
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


def library_path(
    f: ca.Function,
    *,
    compiler: str | None = None,
    flags: Sequence[str] = DEFAULT_FLAGS,
    hpipm: bool = False,
) -> Path:
    """Where the compiled library of ``f`` is (or will be) cached (``hpipm``: as
    :func:`compile_function`).

    Raises
    ------
    FileNotFoundError : when ``compiler`` (default ``$CC``, else gcc) does not run: its
        version is part of the key.
    """
    try:
        return _library_path(f, _compiler_command(compiler), flags, hpipm)
    except _CompileError as err:
        raise FileNotFoundError(str(err)) from err


def _library_path(f: ca.Function, cc: str, flags: Sequence[str], hpipm: bool = False) -> Path:
    parts = [_version(cc), " ".join(flags)] + ([HPIPM_SOURCE_FIX] if hpipm else [])
    key = structure_key("library", f, *parts)
    return cache_dir() / f"{f.name()}-{key}.so"


def compile_function(
    f: ca.Function,
    *,
    compiler: str | None = None,
    flags: Sequence[str] = DEFAULT_FLAGS,
    report: BuildReport | None = None,
    what: str | None = None,
    hpipm: bool = False,
) -> ca.Function:
    """``f`` compiled to C and loaded back, from the cache when it is there and whole.

    Parameters
    ----------
    f : an SX or MX Function (e.g. ``PulseMap.dense``).
    compiler : C compiler command; default ``$CC``, else ``gcc``.
    flags : optimisation flags (see :data:`DEFAULT_FLAGS` for why -O2).
    report : told, when the library is not in the cache, what is compiled and when it is
        done (as :func:`compile_all` does); default: the enclosing
        :func:`~.entries.reported_builds`, else nothing.
    what : what ``f`` is, for the report (default: its name).
    hpipm : ``f`` calls an HPIPM conic: its key carries the version of the source's fix
        (hpipm_source.py). Generated C that calls HPIPM is always fixed and linked against
        the casadi wheel's HPIPM and BLASFEO.

    Returns
    -------
    casadi.Function with the name, inputs and outputs of ``f`` that evaluates the same
    expressions natively (no derivatives); ``f`` itself, with a
    :class:`CompilationWarning` naming the cause, when compiling is not possible.
    """
    cc = _compiler_command(compiler)
    report = reporter(report)
    if report is None or not _missing_libraries([(f, tuple(flags))], cc, hpipm):
        return _compiled(f, cc, flags, hpipm)[0]
    report(_compiling_line(what or f.name(), 1, cc))
    start = time.perf_counter()
    out = _compiled(f, cc, flags, hpipm)[0]
    report(_compiled_line(1, 1, f.name(), start))
    return out


def _compiling_line(what: str, n: int, cc: str) -> str:
    """The report's first line of a build that compiles ``n`` libraries of ``what``."""
    libraries = "1 library" if n == 1 else f"{n} libraries"
    return f"compiling {what}: {libraries} with {cc} (once per structure, then the disk cache) ..."


def _compiled_line(k: int, n: int, name: str, start: float) -> str:
    """The report's line when the ``k``-th of ``n`` libraries, ``name``'s, is compiled
    (the time since ``start``, a :func:`time.perf_counter`)."""
    return f"  compiled {k}/{n}: {name} ({time.perf_counter() - start:.1f} s)"


def _compiled(
    f: ca.Function, cc: str, flags: Sequence[str], hpipm: bool = False
) -> tuple[ca.Function, Path | None]:
    """(:func:`compile_function` of ``f``, the library it loads or None when it is ``f``)."""
    try:
        path = entry_file(
            _library_path(f, cc, flags, hpipm), lambda target: _build(f, target, cc, flags)
        )
        return ca.external(f.name(), str(path)), path
    except (_CompileError, OSError, RuntimeError, ValueError) as err:
        warnings.warn(
            f"could not compile {f.name()!r}, using the interpreted Function: {err}",
            CompilationWarning,
            stacklevel=3,
        )
        return f, None


def _build(f: ca.Function, target: Path, cc: str, flags: Sequence[str]) -> None:
    """Generate C for ``f`` beside ``target`` and compile it into ``target`` (C that calls
    HPIPM fixed and linked as hpipm_source.py says)."""
    source = target.with_name(f"{f.name()}.c")
    generator = ca.CodeGenerator(source.name, {"with_header": False})
    generator.add(f)
    text = generator.dump()
    include: list[str] = []
    link: list[str] = []
    if uses_hpipm(text):
        text = fixed_source(text)
        include, link = hpipm_flags()
    source.write_text(text)
    cmd = [cc, *flags, *_BUILD, *include, str(source), "-o", str(target), *link, "-lm"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    except OSError as err:
        raise _CompileError(f"{cc} did not run ({err})") from err
    if proc.returncode != 0:
        raise _CompileError(
            f"{' '.join(cmd[: 1 + len(flags)])} ... exited {proc.returncode}: "
            f"{proc.stderr.strip()[-500:]}"
        )


def compile_all(
    jobs: Sequence[CompileJob],
    *,
    compiler: str | None = None,
    workers: int | None = None,
    max_instructions: int | None = None,
    report: BuildReport | None = None,
    what: str = "casadi Functions",
    hpipm: bool = False,
) -> tuple[list[ca.Function], list[Path]]:
    """Each (Function, flags) compiled, its own library, ``workers`` at a time (default: the
    cores), in order; a Function over ``max_instructions`` SX instructions, or one that
    does not compile, stays interpreted. ``report`` (default: the enclosing
    :func:`~.entries.reported_builds`, else none) hears how many libraries of ``what``
    are not in the cache, then each one compiled, as ``compiled k/n``; nothing when all
    are. ``hpipm``: as :func:`compile_function`, for every job.

    Returns
    -------
    The Functions, compiled or not, in the order of ``jobs``, and the libraries the
    compiled ones load.
    """
    cc = _compiler_command(compiler)
    limit = max_instructions

    def small(f: ca.Function) -> bool:
        return limit is None or f.n_instructions() <= limit

    report = reporter(report)
    missing = _missing_libraries([j for j in jobs if small(j[0])], cc, hpipm) if report else set()
    if report is not None and missing:
        report(_compiling_line(what, len(missing), cc))
    count = iter(range(1, len(missing) + 1))  # next() is atomic under the GIL
    start = time.perf_counter()

    def compiled_or_not(job: CompileJob) -> tuple[ca.Function, Path | None]:
        f, flags = job
        if not small(f):
            return f, None
        out = _compiled(f, cc, flags, hpipm)
        if report is not None and id(f) in missing:
            report(_compiled_line(next(count), len(missing), f.name(), start))
        return out

    n = workers or os.cpu_count() or 1
    with ThreadPoolExecutor(max_workers=max(1, n)) as pool:
        done = list(pool.map(compiled_or_not, jobs))
    return [f for f, _ in done], [path for _, path in done if path is not None]


def _missing_libraries(jobs: Sequence[CompileJob], cc: str, hpipm: bool = False) -> set[int]:
    """ids of the Functions of ``jobs`` whose library is not whole in the cache (none when
    there is no compiler: nothing will be compiled)."""
    try:
        return {
            id(f)
            for f, flags in jobs
            if check_entry(_library_path(f, cc, flags, hpipm)).status is not EntryStatus.WHOLE
        }
    except (_CompileError, OSError):
        return set()
