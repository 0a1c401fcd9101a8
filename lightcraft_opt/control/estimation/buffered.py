"""A casadi Function's first output called through its buffers, for the estimators'
numeric steps (psi_model.py, ekf.py)."""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["Evaluator"]


class Evaluator:
    """The first output of a casadi Function, called through its buffers
    (``Function.buffer``): the inputs copied into arrays it owns, the output (densified)
    read in place; the other outputs are not computed. A call costs about a microsecond
    beyond the Function's own work and its inputs' copies, against some 20 µs for a call
    from Python with its conversions to and from DM."""

    def __init__(self, f: ca.Function) -> None:
        rows, cols = f.size_out(0)
        ins = [ca.MX.sym(f.name_in(i), f.size_in(i)) for i in range(f.n_in())]
        first = f.call(ins)[0]
        self.function = ca.Function(
            f.name(), ins, [ca.densify(first)], f.name_in(), [f.name_out(0)]
        )
        self._buffer, self._trigger = self.function.buffer()
        self._args = [np.zeros(f.numel_in(i)) for i in range(f.n_in())]
        for i, a in enumerate(self._args):
            self._buffer.set_arg(i, a.data)
        self._out = np.zeros(rows * cols)
        self._buffer.set_res(0, self._out.data)
        self._shape = (cols, rows)

    def __call__(self, *args: np.ndarray | float) -> np.ndarray:
        """The output (rows, cols), a fresh array; each argument a number, a vector or a
        matrix of its input's shape."""
        for a, v in zip(self._args, args, strict=True):
            a[...] = np.ravel(v, order="F")  # casadi's column-major order
        self._trigger()
        return self._out.reshape(self._shape).T.copy()
