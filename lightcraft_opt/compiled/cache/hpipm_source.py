"""casadi's generated C for an HPIPM ``conic``, made to build and to solve as the interpreter does.

A Function that calls HPIPM (the controllers' QPs, control/director_qp.py, control/mpc_qp.py)
generates C that includes HPIPM's headers and calls its library. Both ship inside the casadi
wheel (``casadi/include``, ``casadi/libhpipm.so``, ``casadi/libblasfeo.so``): the library is
compiled against them and finds them at run time by its rpath, with nothing installed by hand.

casadi 3.8's generated solver fills HPIPM's options (``struct d_ocp_qp_ipm_arg``) field by
field from the interpreted plugin's values, copies them whole into the solver's argument, and
leaves five fields it does not know unset (``dual_gap_max``, ``lam0_min``, ``t0_min``,
``t0_init``, ``update_fact_exit``): stack garbage. With ``dual_gap_max`` garbage, the director's
QP that the interpreter solves in 11 iterations hit the 30-iteration cap in C every time.
:func:`fixed_source` sets HPIPM's own defaults of the mode for those five before the copy
keeps the rest, which is what the interpreted plugin does (HPIPM's ``arg_set_default``, then
the options); the C then gives the interpreter's solution to the last bit (the director's
QP: tests/compiled/test_hpipm_source.py).
"""

from __future__ import annotations

from pathlib import Path

import casadi as ca

__all__ = ["HPIPM_SOURCE_FIX", "fixed_source", "hpipm_flags", "uses_hpipm"]

#: Part of the cache key of a library whose source calls HPIPM: a change of the fix below
#: builds it again.
HPIPM_SOURCE_FIX = "hpipm-arg-defaults-1"

_COPY = "memcpy(&myarg, &p->hpipm_options, sizeof(struct d_ocp_qp_ipm_arg));"
_FIXED_COPY = """d_ocp_qp_ipm_arg_set_default((enum hpipm_mode) p->hpipm_options.mode, &myarg);
    { /* lightcraft_opt: casadi leaves these unset (compiled/cache/hpipm_source.py) */
      double dual_gap_max = myarg.dual_gap_max, lam0_min = myarg.lam0_min;
      double t0_min = myarg.t0_min;
      int t0_init = myarg.t0_init, update_fact_exit = myarg.update_fact_exit;
      memcpy(&myarg, &p->hpipm_options, sizeof(struct d_ocp_qp_ipm_arg));
      myarg.dual_gap_max = dual_gap_max; myarg.lam0_min = lam0_min; myarg.t0_min = t0_min;
      myarg.t0_init = t0_init; myarg.update_fact_exit = update_fact_exit; }"""


def uses_hpipm(source: str) -> bool:
    """Whether generated C ``source`` calls HPIPM."""
    return "#include <hpipm_" in source


def fixed_source(source: str) -> str:
    """``source`` (generated C that calls HPIPM) with the options' copy fixed (module
    docstring). Raises ValueError when the copy is not there once per solver call site
    (another casadi: the fix must be looked at again)."""
    count = source.count(_COPY)
    if count == 0:
        raise ValueError(
            "casadi's generated HPIPM solver no longer copies its options as casadi 3.8 did; "
            "compiled/cache/hpipm_source.py must be checked against this casadi"
        )
    return source.replace(_COPY, _FIXED_COPY)


def hpipm_flags() -> tuple[list[str], list[str]]:
    """(compile flags, link flags) for generated C that calls HPIPM: the casadi wheel's
    headers, its HPIPM and BLASFEO libraries, and an rpath to find them at run time."""
    root = Path(ca.__file__).resolve().parent
    include = root / "include"
    return [f"-I{include}"], [f"-L{root}", "-lhpipm", "-lblasfeo", f"-Wl,-rpath,{root}"]
