"""A small design problem file (tests/ocp/test_design.py, its Python and command-line tests):
Flight 5 on a 4 x 16 optic, 10 pulses at 420 J straight up, the impulse per pulse, the
transverse moment and the launch spin free, the altitude after the 10 pulses rewarded.
Written into a ``problems/`` folder beside a copy of the repository's ``models/``
(:func:`write_design_problem`)."""

from __future__ import annotations

import shutil
from pathlib import Path

from support.paths import MODELS

DESIGN_PROBLEM = """
title = "most altitude in 10 pulses, spin, moments and impulse free"
model = "../models/flight5.toml"
horizon_pulses = 10

[model_overrides.craft.engine]
quadrature_radial = 4
quadrature_azimuthal = 16

[[objective]]
term = "final_altitude"

[[control]]
input = "pointing_L"
lower_m = [0.0, 0.0]
upper_m = [0.0, 0.0]
[[control]]
input = "energy"
lower_j = 420.0
upper_j = 420.0

[[design]]
parameter = "impulse_per_pulse"
lower_ns = 0.05
upper_ns = 0.07
[[design]]
parameter = "rotor_transverse_inertia_dry"
lower_g_cm2 = 400.0
upper_g_cm2 = 500.0
[[design]]
parameter = "launch_spin"
lower_rpm = 6000.0
upper_rpm = 12000.0

[solver]
tol = 1e-8

[pulse_map]
scheme = "split"
substeps = 1
dense = 1
"""


def write_design_problem(folder: Path, text: str = DESIGN_PROBLEM, name: str = "design") -> Path:
    """``folder``/problems/``name``.toml holding ``text``, beside a copy of models/ (the
    file's ``../models/flight5.toml``); returns its path."""
    shutil.copytree(MODELS, folder / "models")
    (folder / "problems").mkdir()
    source = folder / "problems" / f"{name}.toml"
    source.write_text(text)
    return source
