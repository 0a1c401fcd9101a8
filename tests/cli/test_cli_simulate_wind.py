"""``lightcraft simulate --wind-mps --wind-from-deg``: the model file's craft in a wind the
command line gives. Reference: the craft and the beam are symmetric about the vertical, so
turning the wind turns the craft's drift with it; the drift has a downwind component (the
spinning craft's tilt response turns it some way off downwind)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.cli import main

FLIGHT5 = REPO_ROOT / "models" / "flight5.toml"


def _final_position(tmp_path, name: str, *flags: str) -> np.ndarray:
    out = tmp_path / name
    assert main(["simulate", str(FLIGHT5), "--duration", "0.6", "--out", str(out), *flags]) == 0
    summary = json.loads((out / "summary.json").read_text())
    return np.asarray(summary["final_position_m"])


@pytest.mark.slow
def test_the_craft_drifts_downwind_whichever_way_the_wind_blows(tmp_path, capsys):
    calm = _final_position(tmp_path, "calm", "--wind-mps", "0")
    east = _final_position(tmp_path, "east", "--wind-mps", "3", "--wind-from-deg", "90")
    north = _final_position(tmp_path, "north", "--wind-mps", "3", "--wind-from-deg", "0")
    capsys.readouterr()
    push_east, push_north = (east - calm)[:2], (north - calm)[:2]
    # from the east it blows west (-x), from the north south (-y): downwind components
    assert push_east[0] < -1e-3 and push_north[1] < -1e-3  # metres in 0.6 s
    # the wind turned by 90 degrees (east -> north) turns the drift by 90 degrees: (x, y) ->
    # (-y, x) takes west to south; Earth's rotation breaks the symmetry by far less
    turned = np.array([-push_east[1], push_east[0]])
    assert np.hypot(*(push_north - turned)) < 0.01 * np.hypot(*push_east)  # 0.13 % measured


@pytest.mark.parametrize("flags", [["--wind-mps", "-1"], ["--wind-mps", "200"]])
def test_a_wind_out_of_range_is_bad_input(flags, capsys):
    assert main(["simulate", str(FLIGHT5), *flags]) == 2
    assert "--wind-mps" in capsys.readouterr().err
