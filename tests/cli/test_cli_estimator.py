"""``lightcraft closed-loop`` with an ``[estimator]`` table: the truth flies as before (no
estimate columns, no estimate.png); an estimator this build cannot make exits 2 with one
line naming it, before any flight."""

from __future__ import annotations

from pathlib import Path

from support.paths import REPO_ROOT

from lightcraft_opt.cli import main
from lightcraft_opt.files.closed_loop_outputs import STEP_COLUMNS

FILE = f'''title = "estimator in the CLI"
model = "{REPO_ROOT / "models" / "flight5.toml"}"
duration_s = 0.2
controller = "none"

[sensors.camera]
noise_mm = 5.0

[estimator]
'''


def test_the_truth_flies_as_before_and_a_missing_estimator_exits_2(tmp_path: Path, capsys):
    path = tmp_path / "loop.toml"
    path.write_text(FILE + 'kind = "truth"\n', encoding="utf-8")
    out = tmp_path / "truth"
    assert main(["closed-loop", str(path), "--out", str(out)]) == 0
    assert (out / "steps.csv").read_text().splitlines()[0].split(",") == list(STEP_COLUMNS)
    assert not (out / "estimate.png").exists() and (out / "closed_loop.png").is_file()
    assert "told the true state" in capsys.readouterr().out

    path.write_text(FILE + 'kind = "mhe"\nhorizon_pulses = 8\n', encoding="utf-8")
    assert main(["closed-loop", str(path), "--out", str(tmp_path / "mhe")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.splitlines()) == 1
    assert "'mhe' estimator is not available in this build" in err
    assert not (tmp_path / "mhe" / "steps.csv").exists()
