"""casadi Functions kept on disk by structure, as cache entries (entries.py).

Some products of a build are pure structure, the same for every run of a problem whose
structure is the same: Φ's explicit-chain derivatives over compiled pieces (compiled/pulse_map.py)
and the SX Functions of the NLP's surrogate (ocp/transcription.py). Building them takes
seconds (casadi's symbolic AD, CSE and expansion); loading their serialised form takes
milliseconds. :func:`save_functions` keeps such Functions as one entry, serialised and
zlib-compressed (a tenth of the size), under a key (:func:`~.entries.structure_key`: the
graphs they are built from, never run-time numbers, and the source of the code that builds
them, :func:`~.entries.source_digest`, so an edited builder never reads a stale file).

A Function that calls a compiled library names the library by its path, and casadi
loads it (dlopen) while unpacking: the entry lists those libraries, and
:func:`load_functions` verifies each one (compiler.py's entries) before unpacking, so a
damaged or missing library makes the entry unusable (a :class:`~.entries.CacheWarning`,
built again) instead of crashing the process.
"""

from __future__ import annotations

import json
import zlib
from collections.abc import Sequence
from pathlib import Path

import casadi as ca

from lightcraft_opt.compiled.cache.entries import (
    EntryStatus,
    cache_dir,
    check_entry,
    load_entry,
    write_entry,
)

__all__ = ["cache_path", "load_functions", "save_functions"]

_SUFFIX = ".casadi"


def cache_path(name: str, key: str) -> Path:
    """The file of the Functions ``name`` with ``key``."""
    return cache_dir() / f"{name}-{key}{_SUFFIX}"


def save_functions(
    name: str, key: str, functions: Sequence[ca.Function], libraries: Sequence[Path] = ()
) -> None:
    """Save ``functions`` as the entry ``name`` with ``key`` (entries.py: atomically, then
    its checksum); ``libraries`` are the compiled libraries they call. A
    :class:`~.entries.CacheWarning` when the cache cannot be written."""
    serializer = ca.StringSerializer()
    serializer.pack(list(functions))
    header = json.dumps({"libraries": [str(p) for p in libraries]}).encode()
    # level 1: a tenth of the size, and quick (figures:
    # bench/README.md#build-time-a-new-structure-and-the-same-structure-again)
    payload = zlib.compress(serializer.encode().encode(), 1)
    write_entry(cache_path(name, key), header + b"\n" + payload)


def load_functions(name: str, key: str) -> list[ca.Function] | None:
    """The Functions saved as ``name`` with ``key``; None when there are none, or when the
    entry is damaged, calls a library that is not whole, or cannot be unpacked (then with
    a :class:`~.entries.CacheWarning`: the caller builds them again and
    :func:`save_functions` writes the entry anew)."""
    errors = (ValueError, KeyError, zlib.error, OSError, RuntimeError, _LibraryNotWhole)
    return load_entry(cache_path(name, key), _unpack, errors)


class _LibraryNotWhole(Exception):
    """A library the Functions call is missing or damaged."""


def _unpack(data: bytes) -> list[ca.Function]:
    """The Functions of an entry, once every library they call is verified whole."""
    header, _, payload = data.partition(b"\n")
    for library in map(Path, json.loads(header)["libraries"]):
        check = check_entry(library)
        if check.status is not EntryStatus.WHOLE:
            fault = check.fault or "gone"
            raise _LibraryNotWhole(f"it calls the compiled library {library}, which is {fault}")
    functions = ca.StringDeserializer(zlib.decompress(payload).decode()).unpack()
    return list(functions) if isinstance(functions, list | tuple) else [functions]
