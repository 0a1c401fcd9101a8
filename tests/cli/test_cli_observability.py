"""``lightcraft observability``: the observability study of a closed-loop file's estimator
reading its sensors (control/observability.py, docs/estimation.md).

References, invariants of the Fisher information W_N = Σ_{k<N} M_kᵀ Hᵀ R⁻¹ H M_k:

- a sensor added only adds information (W grows by a positive semidefinite term), so no
  state's Cramér-Rao bound is larger with the camera and the gyro than with the camera
  alone;
- more pulses only add terms, so no bound is larger at N = 40 than at N = 10;
- the camera alone does not see the spin (H_L along up): its bound stays far above its
  prior after 40 pulses, where the gyro brings it below (docs/estimation.md's table).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.cli import main

GYRO = REPO_ROOT / "problems" / "director_tracked_gyro.toml"


def _rows(path: Path) -> dict[tuple[int, str], dict[str, float]]:
    with path.open(encoding="utf-8") as f:
        return {
            (int(r["pulses"]), r["sensors"]): {k: float(v) for k, v in r.items() if k != "sensors"}
            for r in csv.DictReader(f)
        }


def test_the_study_adds_information_with_sensors_and_pulses(tmp_path: Path, capsys):
    out = tmp_path / "obs"
    assert main(["observability", str(GYRO), "--pulses", "10,40", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "camera+gyro" in printed and "Cramér-Rao bounds" in printed
    assert (out / "observability.png").stat().st_size > 10_000
    rows = _rows(out / "observability.csv")
    assert set(rows) == {(10, "camera"), (10, "camera+gyro"), (40, "camera"), (40, "camera+gyro")}
    keys = [k for k in rows[10, "camera"] if k.startswith("bound_")]
    assert "bound_coupling_ns_per_j" in keys and "bound_r_L_east_m" in keys
    assert "bound_liner_mass_kg" not in keys  # bookkeeping: known
    for key in keys:
        for n in (10, 40):
            assert rows[n, "camera+gyro"][key] <= rows[n, "camera"][key] * (1 + 1e-6), (n, key)
        for read in ("camera", "camera+gyro"):
            assert rows[40, read][key] <= rows[10, read][key] * (1 + 1e-6), (read, key)
    spin = "bound_H_L_up_kg_m2_per_s"
    prior = 1e-5  # the EKF's prior sigma of H_L along up [kg m²/s]
    assert rows[40, "camera"][spin] > 100 * prior  # unseen by the camera
    assert rows[40, "camera+gyro"][spin] < prior  # the gyro sees it
    assert all(math.isfinite(v) for v in rows[40, "camera+gyro"].values())


def test_a_file_without_sensors_or_bad_pulses_exit_2(tmp_path: Path, capsys):
    plain = REPO_ROOT / "problems" / "director_crosswind.toml"
    assert main(["observability", str(plain), "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "sensors" in err and "Traceback" not in err and len(err.splitlines()) == 1
    assert main(["observability", str(GYRO), "--pulses", "1", "--out", str(tmp_path / "b")]) == 2
    assert "--pulses" in capsys.readouterr().err


def test_a_moving_horizon_files_priors_scale_the_condition_not_the_bounds(tmp_path: Path):
    """The gyro file with the MHE (its horizon an MHE-only option) and a prior position
    sigma of 50 mm instead of 5: the study reads the file's priors alone. They scale the
    Gramian (D W D), which moves its condition number, while each bound, √(W⁻¹)ᵢᵢ of the
    readings' information alone, stays the same (1e-6 relative)."""
    text = GYRO.read_text(encoding="utf-8").replace('"../models/', f'"{REPO_ROOT / "models"}/')
    assert 'kind = "ekf"' in text
    mhe = 'kind = "mhe"\nhorizon_pulses = 12\nprior_position_mm = 50.0'
    path = tmp_path / "mhe.toml"
    path.write_text(text.replace('kind = "ekf"', mhe), encoding="utf-8")
    assert main(["observability", str(path), "--pulses", "10", "--out", str(tmp_path / "m")]) == 0
    assert main(["observability", str(GYRO), "--pulses", "10", "--out", str(tmp_path / "e")]) == 0
    looser = _rows(tmp_path / "m" / "observability.csv")
    default = _rows(tmp_path / "e" / "observability.csv")
    for key in default:
        assert looser[key]["condition"] != pytest.approx(default[key]["condition"], rel=0.01)
        for column, value in default[key].items():
            if column.startswith("bound_"):
                assert looser[key][column] == pytest.approx(value, rel=1e-6), (key, column)
