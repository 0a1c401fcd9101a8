"""Problem (b) of problems/least_energy_flight16.toml with the pulse energy capped: the
infeasible problem of issue 27 and its feasible twin, as problem files."""

from __future__ import annotations

from pathlib import Path

from support.paths import MODELS, PROBLEMS

#: The shipped problem (b): least laser energy for Flight 16 to reach a height.
SOURCE = PROBLEMS / "least_energy_flight16.toml"


def capped_flight16(path: Path, *, energy_cap_J: float, minimum_m: float) -> Path:
    """Write problem (b) to ``path`` with each pulse's energy in [0, energy_cap_J] J and
    the terminal altitude at least ``minimum_m`` m (its model read from models/; the
    file's solver options, Strang map and initial guess kept). Returns ``path``."""
    text = SOURCE.read_text()
    model = 'model = "../models/flight16.toml"'
    minimum = "minimum_m = 30.0"
    assert model in text and minimum in text, "problems/least_energy_flight16.toml changed"
    text = text.replace(model, f'model = "{(MODELS / "flight16.toml").as_posix()}"')
    text = text.replace(minimum, f"minimum_m = {minimum_m!r}")
    cap = f'[[control]]\ninput = "energy"\nlower_j = 0.0\nupper_j = {energy_cap_J!r}\n\n[solver]'
    path.write_text(text.replace("[solver]", cap, 1))
    return path
