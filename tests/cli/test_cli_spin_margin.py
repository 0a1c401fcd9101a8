"""``lightcraft spin-margin``: the table it writes is the Python API's sweep, the unit in
every column's key; bad input exits 2 naming the flag (docs/design.md#stability-constrained-spin).

Reference: :func:`lightcraft_opt.linearize.spin_margin_sweep` on the same options, the
same numbers to the last bit (the CLI only converts RPM and cm to SI on the way in).
"""

from __future__ import annotations

import csv
import math

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.cli import main
from lightcraft_opt.files.model import load_model
from lightcraft_opt.linearize import SpinMarginOptions, spin_margin_sweep
from lightcraft_opt.symbolic.maps.options import PulseMapOptions

MODEL = REPO_ROOT / "models" / "flight5.toml"
RPM = 2 * math.pi / 60
#: A short sweep: two positions, one climb node, a coarse grid.
FLAGS = [
    "--positions-cm=-6,-4",
    "--limit", "1.03",
    "--spin-min-rpm", "6000",
    "--spin-max-rpm", "18000",
    "--grid-step-rpm", "3000",
    "--altitudes-m", "30",
    "--offsets-cm", "1",
    "--quiet",
]  # fmt: skip


def test_the_csv_is_the_python_sweep_with_units_in_the_keys(tmp_path, capsys):
    assert main(["spin-margin", str(MODEL), *FLAGS, "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "2/2 positions reach the limit" in out
    with open(tmp_path / "spin_margin.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert (tmp_path / "spin_margin.png").stat().st_size > 10_000
    options = SpinMarginOptions(
        limit=1.03,
        spin_range=(6000 * RPM, 18000 * RPM),
        grid_step=3000 * RPM,
        altitudes=(30.0,),
        offsets=(0.01,),
        pulse_map_options=PulseMapOptions(substeps=8, dense=8),
    )
    sweep = spin_margin_sweep(load_model(MODEL), [-0.06, -0.04], options)
    expected = sweep.rows()
    assert [r["status"] for r in rows] == ["found", "found"]
    for row, want in zip(rows, expected, strict=True):
        assert set(row) == set(want)
        for key in ("mass_centre_b1_m", "least_spin_rad_per_s", "multiplier_at_10000_rpm"):
            assert float(row[key]) == want[key]  # the float's repr, read back exactly
    assert float(rows[0]["least_spin_rpm"]) < float(rows[1]["least_spin_rpm"])


@pytest.mark.parametrize(
    ("flags", "named"),
    [
        (["--limit", "0"], "--limit"),
        (["--spin-max-rpm", "70000"], "--spin-max-rpm"),
        (["--spin-min-rpm", "9000", "--spin-max-rpm", "8000"], "--spin-min-rpm"),
        (["--positions-cm", ","], "--positions-cm"),
        (["--altitudes-m", "10,-5"], "--altitudes-m"),
        (["--handle", "carrier"], "--handle"),  # Flight 5 has no carrier
    ],
)
def test_bad_input_exits_2_naming_the_flag(flags, named, tmp_path, capsys):
    status = main(["spin-margin", str(MODEL), *flags, "--out", str(tmp_path / "out")])
    assert status == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err
    assert not (tmp_path / "out" / "spin_margin.csv").exists()
