"""Cache entries on disk: a file and its checksum, written atomically, verified before
use, built again with a warning when damaged (docs/architecture.md#rule-18).

An entry is one file in the cache folder (:func:`cache_dir`), named by what it holds and
a key, the sha256 of the structure that defines it (:func:`structure_key`), and beside it
its checksum ``<file>.sha256``: the sha256 of the file's bytes, in the format of
``sha256sum`` (so ``sha256sum -c *.sha256`` checks a cache folder by hand).

- Writing: under the entry's lock (``<file>.lock``, one process at a time), the file is
  written under a temporary name beside it and moved into place with ``os.replace``, then
  its checksum likewise. The checksum is written last, after the complete build: a file
  without one is a write that was interrupted.
- Reading: the file is read and hashed, and used only when the hash is its checksum. A
  file that does not match (cut short by an interrupted copy or a full disk, altered,
  emptied, or without its checksum) is read once more under the lock (a writer may have
  been between its two moves), then reported with a :class:`CacheWarning` that names the
  file and what is wrong with it, and removed; the caller builds the entry again
  (:func:`load_entry` returns None), once.
- A compiled library is handed to dlopen by path (:func:`entry_file`): it is verified
  first, so a damaged library is never loaded (a truncated one killed the process with
  SIGBUS before this check).

A cache that cannot be read or written costs a warning, never the run.
"""

from __future__ import annotations

import contextlib
import contextvars
import enum
import hashlib
import os
import shutil
import tempfile
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TypeVar

import casadi as ca

try:  # POSIX: one writer of an entry at a time, across processes
    import fcntl
except ImportError:  # pragma: no cover - Windows: atomic replace only
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "BuildReport",
    "CacheWarning",
    "EntryCheck",
    "EntryStatus",
    "cache_dir",
    "check_entry",
    "checksum_path",
    "discard_entry",
    "entry_file",
    "load_entry",
    "read_entry",
    "reported_builds",
    "reporter",
    "source_digest",
    "structure_key",
    "write_entry",
]

#: A build's progress report: called with one line saying what the build is doing.
BuildReport = Callable[[str], None]

#: The report of builds that were given none, set by :func:`reported_builds`.
_AMBIENT_REPORT: contextvars.ContextVar[BuildReport | None] = contextvars.ContextVar(
    "lightcraft_build_report", default=None
)


@contextlib.contextmanager
def reported_builds(report: BuildReport | None) -> Iterator[None]:
    """Inside, every compile that was given no ``report`` of its own tells ``report``
    what it builds (the CLI's progress lines: cli/progress.py).

    Scoped like :func:`warnings.catch_warnings`, not a global default: the CLI wraps a
    command in it, so a first ``lightcraft simulate`` or ``calibrate`` says what gcc is
    compiling without a ``report`` argument on every function between the command and
    the compiler (simulate, the closed loop, the controllers, the fit, the campaign).
    A report passed explicitly (the OCP's build) still wins."""
    token = _AMBIENT_REPORT.set(report)
    try:
        yield
    finally:
        _AMBIENT_REPORT.reset(token)


def reporter(report: BuildReport | None = None) -> BuildReport | None:
    """``report`` if given, else the one of the enclosing :func:`reported_builds`, else
    None (a build that says nothing)."""
    return report if report is not None else _AMBIENT_REPORT.get()


#: Format of the entries; part of every key, so entries of another format are never read.
_FORMAT = b"lightcraft_opt.compiled.cache 2"
_T = TypeVar("_T")


class CacheWarning(RuntimeWarning):
    """A cache entry was damaged (it is built again) or could not be read or written."""


class EntryStatus(enum.Enum):
    """What a cache entry is on disk."""

    WHOLE = "whole"  # the file matches its checksum
    ABSENT = "absent"  # no file: never built (a miss, no warning)
    DAMAGED = "damaged"  # a file that does not match its checksum, or has none


@dataclass(frozen=True)
class EntryCheck:
    """An entry's status and, when damaged, what is wrong with it."""

    status: EntryStatus
    fault: str = ""


def cache_dir() -> Path:
    """Folder of the cache: ``$LIGHTCRAFT_CACHE``, else ``$XDG_CACHE_HOME/lightcraft_opt``,
    else ``~/.cache/lightcraft_opt``."""
    if env := os.environ.get("LIGHTCRAFT_CACHE"):
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "lightcraft_opt"


def structure_key(*parts: str | bytes | ca.Function | ca.Sparsity) -> str:
    """sha256 (hex) of ``parts`` in order, with the entry format and casadi's version:
    Functions and sparsity patterns by their serialised form, strings and bytes as they
    are."""
    digest = hashlib.sha256(_FORMAT)
    digest.update(b"\0" + ca.__version__.encode())
    for part in parts:
        if isinstance(part, ca.Function | ca.Sparsity):
            part = part.serialize()
        digest.update(b"\0" + (part.encode() if isinstance(part, str) else part))
    return digest.hexdigest()


def source_digest(*modules: ModuleType) -> str:
    """sha256 (hex) of the source files of ``modules``: the code that builds a cached
    product is part of its structure."""
    digest = hashlib.sha256()
    for module in modules:
        assert module.__file__ is not None
        digest.update(b"\0" + Path(module.__file__).read_bytes())
    return digest.hexdigest()


def checksum_path(path: Path) -> Path:
    """Where the checksum of the entry ``path`` is kept: ``<file>.sha256`` beside it."""
    return path.with_name(path.name + ".sha256")


def check_entry(path: Path) -> EntryCheck:
    """Whether the entry ``path`` is whole, absent or damaged (and how); warns of nothing.

    Raises
    ------
    OSError when the file exists but cannot be read.
    """
    return _read(path)[1]


def read_entry(path: Path) -> bytes | None:
    """The bytes of the entry ``path`` when it is whole; None when it is absent, and when
    it is damaged or unreadable (then with a :class:`CacheWarning`, and the damaged entry
    removed: the caller builds it again)."""
    try:
        data, check = _read(path)
        if check.status is EntryStatus.DAMAGED:
            data, check = _read_again(path, data, check)
    except OSError as err:
        _warn(f"cache file {path} is unreadable ({err}): building again")
        return None
    if check.status is EntryStatus.DAMAGED:
        _warn(f"cache file {path} is damaged ({check.fault}): building again")
    return data if check.status is EntryStatus.WHOLE else None


def load_entry(
    path: Path,
    decode: Callable[[bytes], _T],
    errors: tuple[type[Exception], ...],
) -> _T | None:
    """``decode`` of the whole entry ``path`` (:func:`read_entry`); None when there is none
    to decode, or when ``decode`` raises one of ``errors`` on it (then with a
    :class:`CacheWarning` and the entry removed, :func:`discard_entry`)."""
    data = read_entry(path)
    if data is None:
        return None
    try:
        return decode(data)
    except errors as err:
        lines = str(err).strip().splitlines() or [type(err).__name__]
        discard_entry(path, f"cannot be loaded ({lines[-1][-300:]})")
        return None


def discard_entry(path: Path, fault: str) -> None:
    """Remove the entry ``path``, with a :class:`CacheWarning` that says ``fault`` (why it
    cannot be used); the caller builds it again."""
    _warn(f"cache file {path} {fault}: building again")
    with contextlib.suppress(OSError), _locked(path):
        _remove(path)


def write_entry(path: Path, data: bytes) -> None:
    """Write ``data`` as the entry ``path``: the file, then its checksum, each atomically;
    a :class:`CacheWarning` when the cache cannot be written."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with _locked(path):
            checksum = _checksum_line(path, hashlib.sha256(data).hexdigest())
            _replace(path, data)
            _replace(checksum_path(path), checksum)
    except OSError as err:
        _warn(f"could not write the cache file {path} ({err})")


def entry_file(path: Path, build: Callable[[Path], None]) -> Path:
    """``path``, verified whole on disk: as it is when it is whole, else built by
    ``build(target)`` (which writes the file ``target``, in a new temporary folder beside
    ``path`` that is removed afterwards), moved into place and its checksum written, one
    process at a time. A damaged file is reported with a :class:`CacheWarning`, removed and
    built again; it is never returned. For files used by path (a library for dlopen).

    Raises
    ------
    OSError when the cache cannot be read or written, and whatever ``build`` raises.
    """
    if check_entry(path).status is EntryStatus.WHOLE:
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    with _locked(path):
        check = check_entry(path)  # another process may have built it meanwhile
        if check.status is EntryStatus.WHOLE:
            return path
        if check.status is EntryStatus.DAMAGED:
            _warn(f"cache file {path} is damaged ({check.fault}): building again")
            _remove(path)
        work = Path(tempfile.mkdtemp(prefix=f".{path.name}-", dir=path.parent))
        try:
            target = work / path.name
            build(target)
            with target.open("rb") as built:
                digest = hashlib.file_digest(built, "sha256").hexdigest()
            os.replace(target, path)
            _replace(checksum_path(path), _checksum_line(path, digest))
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return path


# --------------------------------------------------------------------------- the files


def _read(path: Path) -> tuple[bytes | None, EntryCheck]:
    """The file's bytes and what they are against the checksum."""
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None, EntryCheck(EntryStatus.ABSENT)
    try:
        recorded = checksum_path(path).read_text(encoding="ascii").split()
    except FileNotFoundError:
        return data, _damaged("no checksum: the write that made it was interrupted")
    except (OSError, UnicodeDecodeError) as err:
        return data, _damaged(f"its checksum is unreadable: {err}")
    if not data:
        return data, _damaged("empty")
    if not recorded or recorded[0] != hashlib.sha256(data).hexdigest():
        fault = f"{len(data)} bytes that do not match the checksum: cut short or altered"
        return data, _damaged(fault)
    return data, EntryCheck(EntryStatus.WHOLE)


def _read_again(
    path: Path, data: bytes | None, check: EntryCheck
) -> tuple[bytes | None, EntryCheck]:
    """The entry read once more under its lock, after a writer's two moves; still damaged,
    removed. In a cache that cannot be locked (read-only) the first reading stands."""
    try:
        with _locked(path):
            data, check = _read(path)
            if check.status is EntryStatus.DAMAGED:
                _remove(path)
    except OSError:
        pass
    return data, check


def _damaged(fault: str) -> EntryCheck:
    return EntryCheck(EntryStatus.DAMAGED, fault)


def _checksum_line(path: Path, hexdigest: str) -> bytes:
    """The checksum file's line, as sha256sum writes it."""
    return f"{hexdigest}  {path.name}\n".encode("ascii")


def _replace(path: Path, data: bytes) -> None:
    """Write ``data`` under a temporary name beside ``path``, then move it into place."""
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}-", dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as out:
            os.fchmod(out.fileno(), 0o644)
            out.write(data)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def _remove(path: Path) -> None:
    """Remove the entry: its file, then its checksum."""
    path.unlink(missing_ok=True)
    checksum_path(path).unlink(missing_ok=True)


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """Hold the exclusive lock of the entry ``path`` (a no-op without fcntl)."""
    if fcntl is None:  # pragma: no cover
        yield
        return
    with open(path.with_name(path.name + ".lock"), "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _warn(message: str) -> None:
    warnings.warn(message, CacheWarning, stacklevel=3)
