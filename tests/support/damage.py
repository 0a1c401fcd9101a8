"""Ways a cache entry is damaged (docs/architecture.md#rule-18), for the cache tests.

Each damage writes a new file in place of the entry, as an interrupted copy leaves it: a
library this process has loaded is mapped, and changing that file in place would kill
the process (SIGBUS) whatever the cache does.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from lightcraft_opt.compiled.cache import checksum_path


def _rewritten(path: Path, data: bytes) -> None:
    new = path.with_name(path.name + ".new")
    new.write_bytes(data)
    os.replace(new, path)


def half(path: Path) -> None:
    """Cut to half its size: an interrupted copy, a full disk."""
    data = path.read_bytes()
    _rewritten(path, data[: len(data) // 2])


def flipped(path: Path) -> None:
    """Eight bytes inverted a third of the way in: an altered file."""
    data = bytearray(path.read_bytes())
    for i in range(len(data) // 3, len(data) // 3 + 8):
        data[i] ^= 0xFF
    _rewritten(path, bytes(data))


def emptied(path: Path) -> None:
    """Empty: a file created and never written."""
    _rewritten(path, b"")


def unchecked(path: Path) -> None:
    """Its checksum missing: a write interrupted before the checksum."""
    checksum_path(path).unlink()


#: Each damage and the words of the fault the warning names.
DAMAGES: dict[str, tuple[Callable[[Path], None], str]] = {
    "half": (half, "do not match the checksum"),
    "flipped": (flipped, "do not match the checksum"),
    "empty": (emptied, "empty"),
    "no-checksum": (unchecked, "no checksum"),
}
