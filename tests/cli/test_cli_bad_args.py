"""The command line's edge: bad arguments and output folders, and the internal-error backstop.

Reference: the CLI contract (docs/architecture.md#rule-9): bad input exits with status 2
and one message on stderr naming the argument, never a traceback; a number out of its flag's
range is argparse's usage error, before any file is read; anything else that escapes a
command is one ``lightcraft: internal error:`` line and status 1.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.cli import build_parser, main, montecarlo, optimize, simulate

MODEL = REPO_ROOT / "models" / "flight5.toml"
PROBLEMS = REPO_ROOT / "problems"

# (command and arguments, the flag named, a fragment of the reason); the input files need
# not exist: the flags are checked first.
BAD_NUMBERS = [
    (["simulate", "m.toml", "--tilt-deg", "inf"], "--tilt-deg", "must be a finite number; got inf"),
    (["simulate", "m.toml", "--tilt-deg", "90"], "--tilt-deg", "must lie in [0, 90) deg"),
    (["simulate", "m.toml", "--tilt-deg", "-5"], "--tilt-deg", "from the vertical"),
    (["simulate", "m.toml", "--tilt-azimuth-deg", "nan"], "--tilt-azimuth-deg", "finite"),
    (["simulate", "m.toml", "--dropout-rate", "0.1", "--seed", "-1"], "--seed", "got -1"),
    (["simulate", "m.toml", "--seed", "1.5"], "--seed", "must be an integer >= 0"),
    (["simulate", "m.toml", "--dropout-rate", "1.5"], "--dropout-rate", "must lie in [0, 1]"),
    (["simulate", "m.toml", "--dropout-rate", "-0.1"], "--dropout-rate", "a probability"),
    (["simulate", "m.toml", "--duration", "0"], "--duration", "must lie in (0, 3600] s"),
    (["simulate", "m.toml", "--duration", "1e300"], "--duration", "an hour at most"),
    (["simulate", "m.toml", "--duration", "ten"], "--duration", "must be a number; got 'ten'"),
    (["simulate", "m.toml", "--launch-speed", "nan"], "--launch-speed", "finite"),
    (["simulate", "m.toml", "--launch-speed", "400"], "--launch-speed", "speed of sound"),
    (["simulate", "m.toml", "--launch-offset-x-cm", "1001"], "--launch-offset-x-cm",
     "10 m from the"),
    (["simulate", "m.toml", "--launch-offset-y-cm=-2e3"], "--launch-offset-y-cm",
     "[-1000, 1000]"),
    (["optimize", "p.toml", "--horizon", "0"], "--horizon", "in [1, 5200]"),
    (["optimize", "p.toml", "--horizon", "1e11"], "--horizon", "must be an integer"),
    (["optimize", "p.toml", "--max-iter", "0"], "--max-iter", "must be an integer >= 1; got 0"),
    (["closed-loop", "p.toml", "--duration", "-1"], "--duration", "must lie in (0, 3600] s"),
    (["montecarlo", "p.toml", "--runs", "0"], "--runs", "must be an integer in [1, 1000000]"),
    (["montecarlo", "p.toml", "--seed", "-1"], "--seed", "non-negative"),
    (["montecarlo", "p.toml", "--workers", "0"], "--workers", ">= 1; got 0"),
    (["montecarlo", "p.toml", "--duration", "inf"], "--duration", "finite"),
    (["montecarlo", "p.toml", "--model-override", "spin=3"], "--model-override",
     "needs TABLE.KEY=VALUE with the unit in the key"),
    (["montecarlo", "p.toml", "--model-override", "craft.spin_rpm="], "--model-override",
     "needs TABLE.KEY=VALUE"),
    (["montecarlo", "p.toml", "--model-override", "craft.spin_rpm=fast"], "--model-override",
     "craft.spin_rpm: 'fast' is not a TOML value"),
    (["calibrate", "m.toml", "--track", "t.csv", "--fit", "cm", "--max-iter", "-3"], "--max-iter",
     "got -3"),
    (["calibrate", "m.toml", "--track", "t.csv", "--fit", "cm", "--substeps", "4"], "--substeps",
     "must be a multiple of 8 (the dense output samples per pulse); got 4"),
    (["calibrate", "m.toml", "--track", "t.csv", "--fit", "cm", "--substeps", "2048"],
     "--substeps", "in [1, 1024]"),
    (["calibrate", "m.toml", "--track", "t.csv", "--fit", "cm", "--initial", "cm=nan"],
     "--initial", "cm: must be a finite number; got nan"),
    (["calibrate", "m.toml", "--track", "t.csv", "--fit", "cm", "--initial", "=1"], "--initial",
     "needs NAME=VALUE in SI, got '=1'"),
]  # fmt: skip


# issue 19: L components are x, y, z (docs/outputs.md); the former spellings are refused
# with the new name, before any file is read (m.toml and t.csv do not exist)
RENAMED = [
    (["simulate", "m.toml", "--offset-east-cm", "3"], "--offset-east-cm",
     "'--offset-east-cm' was renamed '--launch-offset-x-cm': write --launch-offset-x-cm=3"),
    (["simulate", "m.toml", "--offset-north-cm=-2"], "--offset-north-cm",
     "'--offset-north-cm' was renamed '--launch-offset-y-cm': write --launch-offset-y-cm=-2"),
    (["simulate", "m.toml", "--offset-north-cm"], "--offset-north-cm",
     "'--offset-north-cm' was renamed '--launch-offset-y-cm'"),
    (["calibrate", "m.toml", "--track", "t.csv", "--fit", "offset", "--initial",
      "offset_east=0.01"], "--initial",
     "'offset_east' was renamed 'launch_offset_x': write launch_offset_x=0.01"),
    (["calibrate", "m.toml", "--track", "t.csv", "--fit", "tilt", "--initial",
      "tilt_north=-0.02"], "--initial",
     "'tilt_north' was renamed 'launch_tilt_y': write launch_tilt_y_rad=-0.02"),
    (["calibrate", "m.toml", "--track", "t.csv", "--fit", "tilt", "--initial",
      "launch_tilt_y=0.5"], "--initial",
     "launch_tilt_y is an angle and needs its unit: write launch_tilt_y_deg=0.5 (degrees, "
     "as calibrate prints it) or launch_tilt_y_rad=0.5"),
]  # fmt: skip


@pytest.mark.parametrize(("argv", "flag", "reason"), BAD_NUMBERS + RENAMED)
def test_a_bad_number_or_a_former_name_is_a_usage_error_naming_the_flag(argv, flag, reason, capsys):
    """An out-of-range number says its range; a former flag or name gives the new one."""
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert f"error: argument {flag}: " in captured.err
    assert reason in captured.err
    assert "Traceback" not in captured.err and captured.out == ""
    assert "m.toml" not in captured.err.splitlines()[-1]  # refused before reading any file


# issue 29: one spelling per unit; a file written with a former one exits 2 naming the key
# in the new spelling (one line, no traceback), for every command that reads a file
FORMER_UNITS = [
    ("simulate", "models/flight5.toml", "impulse_per_pulse_ns", "impulse_per_pulse_n_s"),
    ("optimize", "problems/crosswind_launch.toml", "slew_rate_mps", "slew_rate_m_per_s"),
    ("closed-loop", "problems/nutation_suppression.toml", "rate_rad_per_s", "rate_rad_s"),
    ("montecarlo", "problems/montecarlo_gust_mpc.toml", "rate_rad_per_s", "rate_rad_s"),
]


@pytest.mark.parametrize(("command", "file", "key", "former"), FORMER_UNITS)
def test_a_former_unit_spelling_in_a_file_exits_2_naming_the_new_key(
    command, file, key, former, tmp_path, capsys
):
    for folder in ("models", "problems"):
        (tmp_path / folder).mkdir()
        for source in (REPO_ROOT / folder).glob("*.toml"):
            (tmp_path / folder / source.name).write_text(source.read_text())
    path = tmp_path / file
    text = path.read_text()
    assert f"{key} = " in text
    path.write_text(text.replace(f"{key} = ", f"{former} = ", 1))
    assert main([command, str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.splitlines()) == 1
    assert f"'{former}' was renamed '{key}'" in err and err.rstrip().endswith(f"write {key}")


def test_values_at_the_ends_of_the_ranges_are_taken():
    parse = build_parser().parse_args
    args = parse(["simulate", "m.toml", "--tilt-deg", "89.9", "--dropout-rate", "0",
                  "--launch-offset-x-cm", "-1000", "--launch-offset-y-cm", "1e3", "--seed", "0",
                  "--duration", "3600", "--launch-speed", "-340",
                  "--tilt-azimuth-deg", "-400"])  # fmt: skip
    assert (args.tilt_deg, args.dropout_rate, args.seed) == (89.9, 0.0, 0)
    assert (args.launch_offset_x_cm, args.launch_offset_y_cm) == (-1000.0, 1000.0)
    assert (args.duration, args.launch_speed, args.tilt_azimuth_deg) == (3600.0, -340.0, -400.0)
    args = parse(["calibrate", "m.toml", "--track", "t.csv", "--fit", "cm", "--substeps", "1024",
                  "--initial", "cm=1.5e-4", "--initial", " tilt = 0.01"])  # fmt: skip
    assert args.substeps == 1024 and dict(args.initial) == {"cm": 1.5e-4, "tilt": 0.01}
    args = parse(["montecarlo", "p.toml", "--runs", "1", "--seed", "0", "--workers", "1"])
    assert (args.runs, args.seed, args.workers) == (1, 0, 1)


def _commands(tmp_path: Path) -> dict[str, list[str]]:
    """Each command with inputs that load, but for its --out."""
    track = tmp_path / "track.csv"
    track.write_text("t_s,x_m,y_m,z_m\n0.1,0,0,0.1\n0.2,0,0,0.3\n")
    return {
        "simulate": ["simulate", str(MODEL), "--duration", "0.1"],
        "optimize": ["optimize", str(PROBLEMS / "crosswind_launch.toml"), "--horizon", "2"],
        "closed-loop": ["closed-loop", str(PROBLEMS / "nutation_suppression.toml")],
        "montecarlo": ["montecarlo", str(PROBLEMS / "montecarlo_open_loop.toml"), "--runs", "1"],
        "calibrate": ["calibrate", str(MODEL), "--track", str(track), "--fit", "cm"],
        "spin-margin": ["spin-margin", str(MODEL)],
    }


@pytest.mark.parametrize("command", ["simulate", "optimize", "closed-loop", "montecarlo",
                                     "calibrate", "spin-margin"])  # fmt: skip
def test_an_out_that_cannot_be_made_names_out_before_the_work(command, tmp_path, capsys):
    argv = _commands(tmp_path)[command]
    a_file = tmp_path / "a_file"
    a_file.write_text("not a folder\n")
    under = a_file / "sub" / "out"
    cases = [
        (a_file, f"--out: {a_file} is a file, not a folder"),
        (under, f"--out: cannot make {under}: {a_file} is a file"),
    ]
    if Path("/proc/self").is_dir():  # procfs: no folder can be made or written there
        cases += [(Path("/proc/lightcraft-out"), "--out: cannot make /proc/lightcraft-out: ")]
        cases += [(Path("/proc"), "--out: cannot write in /proc: ")]
    for out, message in cases:
        assert main([*argv, "--out", str(out)]) == 2, out
        captured = capsys.readouterr()
        assert captured.err.startswith("lightcraft: error: ") and message in captured.err
        assert "Traceback" not in captured.err and len(captured.err.splitlines()) == 1
        assert captured.out == ""  # nothing started
    assert a_file.read_text() == "not a folder\n"


def _raise(exc: BaseException):
    def run(args):
        raise exc

    return run


def test_an_unexpected_exception_is_one_line_and_exit_1(monkeypatch, capsys):
    monkeypatch.delenv("LIGHTCRAFT_DEBUG", raising=False)
    monkeypatch.setattr(simulate, "run", _raise(RuntimeError("boom\n  in two lines")))
    assert main(["simulate", "m.toml"]) == 1
    err = capsys.readouterr().err
    assert err == (
        "lightcraft: internal error: RuntimeError: boom in two lines (please report; run with "
        "LIGHTCRAFT_DEBUG=1 for the traceback)\n"
    )
    monkeypatch.setenv("LIGHTCRAFT_DEBUG", "1")
    assert main(["simulate", "m.toml"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("Traceback (most recent call last):")
    assert err.endswith(
        "lightcraft: internal error: RuntimeError: boom in two lines (please report)\n"
    )


def test_ctrl_c_exits_130_with_one_line(monkeypatch, capsys):
    monkeypatch.setattr(optimize, "run", _raise(KeyboardInterrupt()))
    assert main(["optimize", "p.toml"]) == 130
    assert capsys.readouterr().err == "lightcraft: interrupted\n"


def test_status_counts_print_as_words():
    assert (
        montecarlo._counts({"duration_reached": 12, "left_beam": 3})
        == "12 duration_reached, 3 left_beam"
    )
    assert montecarlo._counts({}) == "no runs"
