"""Named slots of a flat vector: :class:`Slot`, :class:`VectorLayout`. (The check of a flat
numeric vector is :func:`lightcraft_opt.model.checks.checked_vector`.)

Physics code reads ``STATE.get("w_B", x)``, never ``x[10:13]`` (docs/architecture.md#rule-8).
Every slot has a unit and a frame (docs/frames.md), and :meth:`VectorLayout.labels` turns
them into plot and CSV labels. Slicing works alike on numpy arrays and casadi SX/MX column
vectors. A :class:`Slot` indexes numpy arrays itself: ``X[:, STATE.slot("w_B")]`` is the
(n, 3) block of a trajectory (a copy, by integer indices; ``STATE.index("w_B")``, a slice,
gives a view and also indexes casadi). The layouts themselves are in
:mod:`lightcraft_opt.layout.vectors`.
"""

from __future__ import annotations

import builtins
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from lightcraft_opt.errors import ParameterError

__all__ = ["Slot", "VectorLayout"]

T = TypeVar("T")


@dataclass(frozen=True)
class Slot:
    """A named block of a vector: ``size`` entries from ``start``, with unit and frame.

    It indexes numpy arrays as its entries' indices (``__array__``): ``x[slot]``,
    ``X[..., slot]`` (a copy, always ``size`` long, even for one entry) and ``x[slot] =
    value``; :attr:`slice` is the same entries as a slice (a view, and casadi takes it).
    """

    name: str
    start: int
    size: int
    unit: str
    frame: str = ""
    components: tuple[str, ...] = ()

    @property
    def stop(self) -> int:
        return self.start + self.size

    @property
    def slice(self) -> builtins.slice:
        """``slice(start, stop)``."""
        return slice(self.start, self.stop)

    def __array__(self, dtype: Any = None, copy: bool | None = None) -> np.ndarray:
        """The entries' indices, ``start`` to ``stop`` (numpy's array protocol), so that a
        slot indexes numpy arrays."""
        return np.arange(self.start, self.stop, dtype=dtype or np.intp)


class VectorLayout:
    """Named contiguous slots of a flat vector.

    Parameters
    ----------
    name : what the vector is ("state", "input", "parameters").
    spec : (name, size, unit, frame, component names) per slot, in order.
    """

    def __init__(
        self, name: str, spec: Sequence[tuple[str, int, str, str, tuple[str, ...]]]
    ) -> None:
        slots: list[Slot] = []
        start = 0
        for slot_name, size, unit, frame, comps in spec:
            if comps and len(comps) != size:
                raise ValueError(f"{name}.{slot_name}: {len(comps)} component names for {size}")
            slots.append(Slot(slot_name, start, size, unit, frame, comps))
            start += size
        self.name = name
        self.slots: tuple[Slot, ...] = tuple(slots)
        self.size = start
        self._by_name = {s.name: s for s in slots}
        if len(self._by_name) != len(slots):
            raise ValueError(f"{name}: duplicate slot names")

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __repr__(self) -> str:
        return f"VectorLayout({self.name!r}, {[s.name for s in self.slots]}, size={self.size})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, VectorLayout):
            return NotImplemented
        return (self.name, self.slots) == (other.name, other.slots)

    def __hash__(self) -> int:
        return hash((self.name, self.slots))

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.slots)

    def slot(self, name: str) -> Slot:
        try:
            return self._by_name[name]
        except KeyError:
            raise ParameterError(
                f"{self.name}.{name}", f"no such slot; the {self.name} holds {list(self.names)}"
            ) from None

    def index(self, name: str) -> slice:
        """The slice of slot ``name``."""
        s = self.slot(name)
        return slice(s.start, s.stop)

    def get(self, name: str, vector: T) -> T:
        """Slot ``name`` of ``vector`` (numpy array or casadi column); scalars come as 1-vectors
        for casadi and as floats for 1-D numpy."""
        s = self.slot(name)
        if s.size == 1:
            return vector[s.start]  # type: ignore[index]
        return vector[s.start : s.stop]  # type: ignore[index]

    def pack(
        self, values: Mapping[str, Any], default: Mapping[str, Any] | None = None
    ) -> np.ndarray:
        """Flat float vector from ``{slot: value}``; every slot given here or in ``default``."""
        out = np.empty(self.size)
        merged = dict(default or {})
        merged.update(values)
        unknown = set(merged) - set(self._by_name)
        if unknown:
            raise ParameterError(
                f"{self.name}.{sorted(unknown)[0]}",
                f"no such slot; the {self.name} holds {list(self.names)}",
            )
        for s in self.slots:
            if s.name not in merged:
                raise ParameterError(f"{self.name}.{s.name}", "missing")
            v = np.asarray(merged[s.name], dtype=float).reshape(-1)
            if v.size != s.size:
                raise ParameterError(
                    f"{self.name}.{s.name}", f"needs {s.size} values, got {v.size}"
                )
            if not np.all(np.isfinite(v)):
                raise ParameterError(f"{self.name}.{s.name}", "must be finite (got NaN or inf)")
            out[s.start : s.stop] = v
        return out

    def unpack(self, vector: Sequence[float] | np.ndarray) -> dict[str, np.ndarray | float]:
        """``{slot: value}`` from a flat numeric vector (floats for size-1 slots)."""
        v = np.asarray(vector, dtype=float).reshape(-1)
        if v.size != self.size:
            raise ParameterError(self.name, f"needs {self.size} values, got {v.size}")
        return {
            s.name: float(v[s.start]) if s.size == 1 else v[s.start : s.stop].copy()
            for s in self.slots
        }

    def labels(self) -> list[str]:
        """One label per entry, with unit: ``"r_L[east] [m]"``; for plots and CSV headers."""
        out: list[str] = []
        for s in self.slots:
            unit = f" [{s.unit}]" if s.unit else ""
            if s.size == 1:
                out.append(f"{s.name}{unit}")
            else:
                comps = s.components or tuple(str(i + 1) for i in range(s.size))
                out.extend(f"{s.name}[{c}]{unit}" for c in comps)
        return out
