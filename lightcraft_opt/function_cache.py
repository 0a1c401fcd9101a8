"""casadi Functions kept on disk by structure: written atomically, checksummed, rebuilt
when damaged (docs/architecture.md#rule-18).

Some products of a build are pure structure, the same for every run of a problem whose
structure is the same: Φ's explicit-chain derivatives over compiled pieces (compiled.py)
and the SX Functions of the NLP's surrogate (ocp/transcription.py). Building them takes
seconds (casadi's symbolic AD, CSE and expansion); loading their serialised form takes
milliseconds. :func:`load_functions` and :func:`save_functions` keep such Functions in
:func:`cache_dir`, one file per key:

- the key (:func:`structure_key`) is the sha256 of what defines the Functions: the
  serialised graphs they are built from (never run-time numbers), the source of the code
  that builds them (:func:`source_digest`, so an edited builder never reads a stale file)
  and casadi's version;
- a file is written under a temporary name and moved into place with ``os.replace``, with
  the sha256 of its payload (the Functions serialised, then zlib-compressed: a tenth of
  the size) in its header: a file is there complete or not at all, and a
  damaged one (truncated, altered, or naming a compiled library that is gone) is detected
  before use, reported with a :class:`CacheWarning` and built again. A cache that cannot
  be written costs a warning, never the run.

Compiled libraries (compiled.py) live in the same folder.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
import warnings
import zlib
from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType

import casadi as ca

__all__ = [
    "BuildReport",
    "CacheWarning",
    "cache_dir",
    "cache_path",
    "load_functions",
    "save_functions",
    "source_digest",
    "structure_key",
]

#: A build's progress report: called with one line saying what the build is doing.
BuildReport = Callable[[str], None]

_FORMAT = b"lightcraft_opt.functions 1"
_SUFFIX = ".casadi"


class CacheWarning(RuntimeWarning):
    """A cache file was damaged (it is built again) or could not be written."""


def cache_dir() -> Path:
    """Folder of the cache: ``$LIGHTCRAFT_CACHE``, else ``$XDG_CACHE_HOME/lightcraft_opt``,
    else ``~/.cache/lightcraft_opt``."""
    if env := os.environ.get("LIGHTCRAFT_CACHE"):
        return Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "lightcraft_opt"


def structure_key(*parts: str | bytes | ca.Function | ca.Sparsity) -> str:
    """sha256 (hex) of ``parts`` in order, with casadi's version: Functions and sparsity
    patterns by their serialised form, strings and bytes as they are."""
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


def cache_path(name: str, key: str) -> Path:
    """The file of the Functions ``name`` with ``key``."""
    return cache_dir() / f"{name}-{key}{_SUFFIX}"


def load_functions(name: str, key: str) -> list[ca.Function] | None:
    """The Functions saved under ``name`` and ``key``; None when there are none, or when
    the file is damaged (then with a :class:`CacheWarning`: the caller builds them again
    and :func:`save_functions` replaces the file)."""
    path = cache_path(name, key)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None
    except OSError as err:
        warnings.warn(f"cache file {path} unreadable ({err}): building again", CacheWarning, 2)
        return None
    header, _, rest = data.partition(b"\n")
    checksum, _, payload = rest.partition(b"\n")
    if header != _FORMAT or hashlib.sha256(payload).hexdigest().encode() != checksum:
        why = "not this format" if header != _FORMAT else "checksum mismatch"
        warnings.warn(f"cache file {path} is damaged ({why}): building again", CacheWarning, 2)
        return None
    try:
        functions = ca.StringDeserializer(zlib.decompress(payload).decode()).unpack()
    except (RuntimeError, UnicodeDecodeError, zlib.error) as err:  # e.g. a library gone
        lines = str(err).strip().splitlines() or [type(err).__name__]
        warnings.warn(
            f"cache file {path} cannot be loaded ({lines[-1][-300:]}): building again",
            CacheWarning,
            2,
        )
        return None
    return list(functions) if isinstance(functions, list | tuple) else [functions]


def save_functions(name: str, key: str, functions: Sequence[ca.Function]) -> None:
    """Save ``functions`` under ``name`` and ``key`` (atomically, with the checksum of
    their serialised form); a :class:`CacheWarning` when the cache cannot be written."""
    path = cache_path(name, key)
    serializer = ca.StringSerializer()
    serializer.pack(list(functions))
    payload = zlib.compress(serializer.encode().encode(), 1)  # a tenth, 0.1 s for 40 MB
    data = b"\n".join((_FORMAT, hashlib.sha256(payload).hexdigest().encode(), payload))
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, temporary = tempfile.mkstemp(prefix=f".{name}-", dir=path.parent)
        try:
            with os.fdopen(handle, "wb") as out:
                os.fchmod(out.fileno(), 0o644)  # readable like the libraries beside it
                out.write(data)
            os.replace(temporary, path)
        except BaseException:
            Path(temporary).unlink(missing_ok=True)
            raise
    except OSError as err:
        warnings.warn(f"could not write the cache file {path} ({err})", CacheWarning, 2)
