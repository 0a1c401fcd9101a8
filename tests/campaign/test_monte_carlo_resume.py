"""Resuming over a damaged run table: a damaged row is never trusted.

A row that is cut short, has the wrong number of fields, a value that does not read back
as written, a NaN or another value where the run's draw must be, or a run index found twice
is dropped (the other rows kept byte for byte), named in one warning, and its run flown
again: the resumed table is byte-identical to a clean campaign's. Three 0.3 s open-loop
runs keep this fast (the reference and the damaged copies share one flyer)."""

from __future__ import annotations

import json
import shutil

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.campaign.run_table import DamagedRowsWarning, RunTable, read_table
from lightcraft_opt.campaign.runner import run_campaign
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.campaign import load_campaign

OPEN = REPO_ROOT / "problems" / "montecarlo_open_loop.toml"
DURATION, RUNS, SEED = 0.3, 3, 7


@pytest.fixture(scope="module")
def campaign():
    return load_campaign(OPEN, duration=DURATION)


@pytest.fixture(scope="module")
def clean(campaign, tmp_path_factory):
    out = tmp_path_factory.mktemp("clean")
    return run_campaign(campaign, RUNS, SEED, out, workers=1, progress=False)


def _set(lines: list[str], row: int, column: str, value: str) -> None:
    fields = lines[row].split(",")
    fields[lines[0].split(",").index(column)] = value
    lines[row] = ",".join(fields)


def _garble(lines):  # a digit's stray neighbour in an output
    _set(lines, 2, "apogee_m", lines[2].split(",")[lines[0].split(",").index("apogee_m")] + "x")


def _nan_input(lines):
    _set(lines, 2, "mass_kg", "nan")


def _not_the_draw(lines):  # reads back, but is not what run 1 draws
    _set(lines, 2, "mass_kg", "0.0325")


def _short_row(lines):
    lines[2] = lines[2].rsplit(",", 1)[0]


def _twice(lines):
    lines.insert(-1, lines[2])


def _cut(lines):  # killed mid-write: the last line, cut, without its end of line
    lines[-2] = lines[-2][: len(lines[-2]) // 2]
    lines.pop()


@pytest.mark.parametrize(
    ("damage", "run", "why"),
    [
        (_garble, 1, "apogee_m: '"),
        (_nan_input, 1, "mass_kg: 'nan' is not a finite number"),
        (_not_the_draw, 1, "mass_kg: 0.0325 is not run 1's draw"),
        (_short_row, 1, " fields, not "),
        (_twice, 1, "run 1 is in the table 2 times"),
        (_cut, 2, "a cut line"),
    ],
)
def test_a_damaged_row_is_dropped_and_flown_again(campaign, clean, tmp_path, damage, run, why):
    out = tmp_path / "damaged"
    shutil.copytree(clean.out_dir, out)
    table = out / "runs.csv"
    lines = table.read_text().split("\n")  # header, rows 0-2, "" after the last end of line
    damage(lines)
    table.write_text("\n".join(lines))
    with pytest.warns(DamagedRowsWarning, match=r"dropped \d damaged rows?, flown again") as w:
        resumed = run_campaign(campaign, RUNS, SEED, out, workers=1, progress=False)
    (message,) = [str(x.message) for x in w if x.category is DamagedRowsWarning]
    assert f": run {run} (" in message and why in message and "\n" not in message
    assert resumed.made == 1 and resumed.skipped == RUNS - 1 and resumed.complete
    assert resumed.dropped == (2 if damage is _twice else 1)
    assert table.read_bytes() == (clean.out_dir / "runs.csv").read_bytes()
    assert list(read_table(out / "timings.csv")["run"]) == list(range(RUNS))
    assert resumed.summary["apogee_m"] == clean.summary["apogee_m"]


def test_reopening_keeps_the_good_rows_byte_for_byte(tmp_path):
    path = tmp_path / "t.csv"
    head, zero, two = "run,x\n", "0,0.1\n", "2,2.5\n"
    path.write_text(head + zero + "1,0.2,9\n" + two + "x,1.0\n3,nope\n4,0.")
    table = RunTable(path, ("run", "x"), lambda r: None if r["x"] != "nope" else "x: nope")
    assert table.done == {0, 2}
    assert table.dropped == ((1, "3 fields, not 2"), (None, "run: 'x' is not a run index"),
                             (3, "x: nope"), (4, "a cut line (no end of line)"))  # fmt: skip
    assert path.read_text() == head + zero + two
    assert RunTable(path, ("run", "x")).dropped == ()  # nothing left to drop


#: runs.csv columns before issue 19 named L components x/y/z (and the launch offset apart
#: from the optic's offset): new name -> old.
OLD_COLUMNS = {
    "launch_offset_x_m": "offset_east_m",
    "launch_offset_y_m": "offset_north_m",
    "final_x_m": "final_east_m",
    "final_y_m": "final_north_m",
    "final_z_m": "final_up_m",
    "landing_x_m": "landing_east_m",
    "landing_y_m": "landing_north_m",
}


@pytest.mark.parametrize("manifest", [True, False], ids=["with campaign.json", "runs.csv alone"])
def test_a_folder_with_the_old_column_names_is_refused_not_mixed(
    campaign, clean, tmp_path, manifest
):
    """A folder written before the rename (the same campaign otherwise): resuming into it
    is refused naming the columns, whether campaign.json (checked first) or runs.csv's
    header says so, and nothing there is touched (campaign.json is written only once
    the tables are known to be this campaign's)."""
    out = tmp_path / "old"
    shutil.copytree(clean.out_dir, out)
    header, rest = (out / "runs.csv").read_text().split("\n", 1)
    old = [OLD_COLUMNS.get(c, c) for c in header.split(",")]
    assert old != header.split(",")  # the campaign draws launch offsets: all seven renamed
    (out / "runs.csv").write_text(",".join(old) + "\n" + rest)
    path = out / "campaign.json"
    if manifest:
        data = json.loads(path.read_text())
        path.write_text(json.dumps({**data, "columns": old}))
    else:
        path.unlink()
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(ParameterError) as err:
        run_campaign(campaign, RUNS + 1, SEED, out, workers=1, progress=False)
    message = str(err.value)
    assert "other columns (there: offset_east_m, offset_north_m, final_east_m" in message
    assert "written now instead: launch_offset_x_m, launch_offset_y_m, final_x_m" in message
    assert "use another output folder" in message
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
