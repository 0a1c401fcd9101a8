"""Editing a model or laser file's values in place (edge): the calibration's fitted model
file (files/calibration_outputs.py) and a design's model file (files/design_outputs.py).

A value is written in SI with the unit in the key (``impulse_per_pulse_ns``,
``blast_angle_rad``, ``speed_ref_mps`` ...) so that it reloads to the very same float, on
the line of the key it replaces (any unit), with an end-of-line note and the old
``key = value``. A value the file did not give is added at the end of its table (or in a
new table). Should the edited text not read back to the same tables as the data with the
values put in (a layout the line editor does not know, e.g. an inline table), the file is
written from the tables instead, without the comments.
"""

from __future__ import annotations

import json
import os
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from dataclasses import field as dataclass_field
from pathlib import Path
from typing import Any

import numpy as np

from lightcraft_opt.errors import ModelFileError
from lightcraft_opt.files.model import QUANTITIES, SCHEMA

__all__ = ["Edit", "EditedModel", "put_value", "read_model_data", "write_edited"]

#: One value to write: (table path, SCHEMA table, field, SI value (a number, or a list of
#: numbers for a vector field), note).
Edit = tuple[tuple[str, ...], str, str, Any, str]


def read_model_data(path: Path) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise ModelFileError(
            str(path), None, f"cannot read it again to write the new model file: {err}"
        ) from err


def _is_key_of(key: str, table: str, field: str) -> bool:
    """Whether ``key`` gives ``field`` of the SCHEMA ``table`` (bare or with a unit)."""
    units = QUANTITIES.get(SCHEMA[table][field].kind)
    return key == field or bool(
        units and key.startswith(field + "_") and key[len(field) + 1 :] in units
    )


def _si_key(table: str, field: str) -> str:
    """The key of ``field`` in SI: ``blast_angle`` -> ``blast_angle_rad``."""
    units = QUANTITIES.get(SCHEMA[table][field].kind)
    si = next((u for u, f in units.items() if f == "1"), None) if units else None
    return f"{field}_{si}" if si else field


def put_value(
    data: dict[str, Any], where: tuple[str, ...], table: str, field: str, value: Any
) -> None:
    """Set ``field`` in the table at ``where`` to ``value`` [SI: a number or a list of
    numbers], the unit in the key."""
    node = data
    for name in where:
        node = node.setdefault(name, {})
    for key in list(node):
        if _is_key_of(key, table, field):
            del node[key]
    node[_si_key(table, field)] = _si_value(value)


_HEADER = re.compile(r"^\s*\[\[?\s*([^\[\]#]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(r"^(\s*)([A-Za-z0-9_-]+)\s*=\s*(.*)$")


def _sections(lines: list[str]) -> list[tuple[tuple[str, ...] | None, int, int]]:
    """(table path, first line, end line) of each table of a TOML text: the root table
    first (path ()), arrays of tables with path None (never edited)."""
    out: list[tuple[tuple[str, ...] | None, int, int]] = []
    path: tuple[str, ...] | None = ()
    start = 0
    for i, line in enumerate(lines):
        m = _HEADER.match(line)
        if m:
            out.append((path, start, i))
            array = line.lstrip().startswith("[[")
            name = tuple(part.strip().strip('"') for part in m.group(1).split("."))
            path, start = (None if array else name), i + 1
    out.append((path, start, len(lines)))
    return out


def _set_line(
    lines: list[str], where: tuple[str, ...], match: Any, key: str, value: str, note: str
) -> None:
    """Replace the line of table ``where`` whose key ``match(key)`` accepts by
    ``key = value  # note`` (``note`` given the old ``key = value``), in place; add it at
    the end of the table (or in a new table at the end of the text) when there is none."""
    for path, start, end in _sections(lines):
        if path != where:
            continue
        for i in range(start, end):
            m = _KEY.match(lines[i])
            if m and match(m.group(2)):
                old = m.group(3).split("#", 1)[0].strip()
                was = f"; was {m.group(2)} = {old}" if note else ""
                comment = f"  # {note}{was}" if note else ""
                lines[i] = f"{m.group(1)}{key} = {value}{comment}"
                return
        last = max((i for i in range(start, end) if lines[i].strip()), default=start - 1)
        lines.insert(last + 1, f"{key} = {value}" + (f"  # {note}" if note else ""))
        return
    lines += ["", f"[{'.'.join(where)}]", f"{key} = {value}" + (f"  # {note}" if note else "")]


def _edited(
    text: str,
    edits: list[Edit],
    paths: Mapping[str, str],
) -> str:
    """``text`` with each (table path, SCHEMA table, field, SI value, note) of ``edits``
    and each root key -> string of ``paths`` set by :func:`_set_line`."""
    lines = text.splitlines()
    for where, table, field, value, note in edits:
        match = lambda k, t=table, f=field: _is_key_of(k, t, f)  # noqa: E731
        _set_line(lines, where, match, _si_key(table, field), _toml_value(_si_value(value)), note)
    for key, where_to in paths.items():
        _set_line(lines, (), lambda k, key=key: k == key, key, json.dumps(where_to), "")
    return "\n".join(lines) + "\n"


@dataclass
class EditedModel:
    """A model file and the laser file it names, with values put in: what the calibration's
    fitted model and a design's model write (module docstring).

    Attributes
    ----------
    source : the model file edited.
    data : its tables (with any overrides already in), edited in place.
    edits, laser_edits : the values put in the model file and in its laser file.
    laser : the laser file's tables, read on the first laser edit; None without one.
    """

    source: Path
    data: dict[str, Any]
    edits: list[Edit] = dataclass_field(default_factory=list)
    laser_edits: list[Edit] = dataclass_field(default_factory=list)
    laser: dict[str, Any] | None = None

    @property
    def laser_path(self) -> Path:
        return self.source.parent / self.data["laser"]

    def put(
        self, file: str, where: tuple[str, ...], table: str, name: str, value: Any, note: str
    ) -> None:
        """Put SI ``value`` at ``where`` (SCHEMA ``table``, field ``name``) of the model file
        (``file`` "model") or of its laser file ("laser"), with an end-of-line ``note``."""
        if file == "laser":
            self.laser = self.laser if self.laser is not None else read_model_data(self.laser_path)
            put_value(self.laser, where, table, name, value)
            self.laser_edits.append((where, table, name, value, note))
        else:
            put_value(self.data, where, table, name, value)
            self.edits.append((where, table, name, value, note))

    def write(self, path: Path, header: list[str], suffix: str) -> Path:
        """Write the edited model file ``path`` under ``header`` and, after a laser edit,
        the edited laser file beside it as ``<laser>-<suffix>.toml``; the site and laser
        paths are made relative to ``path``'s folder. Returns ``path``."""
        out_dir, laser_path = path.parent, self.laser_path
        if self.laser is not None:
            edited_laser = out_dir / f"{laser_path.stem}-{suffix}.toml"
            laser_text = laser_path.read_text(encoding="utf-8")
            write_edited(edited_laser, header, laser_text, self.laser_edits, {}, self.laser)
            laser_path = edited_laser
        site = self.source.parent / self.data["site"]
        self.data["site"] = Path(os.path.relpath(site, out_dir)).as_posix()
        self.data["laser"] = Path(os.path.relpath(laser_path, out_dir)).as_posix()
        paths = {"site": self.data["site"], "laser": self.data["laser"]}
        text = self.source.read_text(encoding="utf-8")
        write_edited(path, header, text, self.edits, paths, self.data)
        return path


def write_edited(
    path: Path,
    header: list[str],
    source_text: str,
    edits: list[Edit],
    paths: Mapping[str, str],
    data: dict[str, Any],
) -> None:
    """Write ``source_text`` edited (:func:`_edited`) to ``path`` under ``header`` if it
    reads back to ``data``; else ``data`` itself as TOML (module docstring)."""
    text = "\n".join(header) + "\n" + _edited(source_text, edits, paths)
    try:
        same = tomllib.loads(text) == data
    except tomllib.TOMLDecodeError:
        same = False
    if not same:
        text = "\n".join([*header, *_toml(data)]) + "\n"
    path.write_text(text, encoding="utf-8")


def _si_value(value: Any) -> float | list[float]:
    """A number as a float, a vector as a list of floats."""
    if isinstance(value, list | tuple) or np.ndim(value) > 0:
        return [float(v) for v in value]
    return float(value)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} to TOML")


def _toml(data: Mapping[str, Any], prefix: str = "") -> list[str]:
    """TOML lines of ``data``: its plain keys, then its tables and arrays of tables."""
    lines = [
        f"{k} = {_toml_value(v)}"
        for k, v in data.items()
        if not isinstance(v, dict) and not _table_array(v)
    ]
    for k, v in data.items():
        name = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict):
            lines += ["", f"[{name}]", *_toml(v, name)]
        elif _table_array(v):
            for row in v:
                lines += ["", f"[[{name}]]", *_toml(row, name)]
    return lines


def _table_array(v: Any) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)
