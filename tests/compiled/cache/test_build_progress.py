"""A first compile says what it builds and counts gcc's libraries as they finish
(compiled/cache/compiler.py, cli/progress.py; issue 29, item 5).

Reference: the cache folder itself. With an empty folder (LIGHTCRAFT_CACHE) every library
is missing, so the report names what is compiled and counts 1/n ... n/n, one line each;
with the same folder again every library is whole and the report hears nothing. Two
tiny Functions keep gcc's part to a fraction of a second.
"""

from __future__ import annotations

import re
import shutil

import casadi as ca
import numpy as np
import pytest
from support.paths import REPO_ROOT

import lightcraft_opt.cli.simulate as simulate_command
from lightcraft_opt.cli import main
from lightcraft_opt.compiled.cache import (
    DEFAULT_FLAGS,
    compile_all,
    compile_function,
    reported_builds,
)

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")

FLIGHT5 = REPO_ROOT / "models" / "flight5.toml"
COUNT = re.compile(r"^\s+compiled (\d+)/(\d+): (\w+) \(\d+\.\d s\)$")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(folder))
    return folder


def _tiny(name: str) -> ca.Function:
    x = ca.SX.sym("x", 2)
    return ca.Function(name, [x], [ca.sin(x) * x[0]], ["x"], ["y"])


def test_a_first_compile_names_what_it_builds_and_counts_k_of_n(cache):
    said: list[str] = []
    jobs = [(_tiny("tiny_a"), DEFAULT_FLAGS), (_tiny("tiny_b"), DEFAULT_FLAGS)]
    done, libraries = compile_all(jobs, report=said.append, what="two tiny maps", workers=1)
    assert said[0].startswith("compiling two tiny maps: 2 libraries with ")
    counts = [COUNT.match(line) for line in said[1:]]
    assert all(counts) and len(counts) == 2, said
    assert [(m[1], m[2]) for m in counts if m] == [("1", "2"), ("2", "2")]
    assert {m[3] for m in counts if m} == {"tiny_a", "tiny_b"}
    assert len(libraries) == 2 and all(f.is_a("External") for f in done)
    assert np.allclose(np.asarray(done[0]([0.3, 0.4])).ravel(), np.sin([0.3, 0.4]) * 0.3)

    said.clear()  # warm: every library whole, nothing to say
    compile_all(jobs, report=said.append, what="two tiny maps")
    assert said == []


def test_a_compile_inside_reported_builds_reports_without_being_asked(cache):
    said: list[str] = []
    with reported_builds(said.append):
        compile_function(_tiny("tiny_c"), what="a tiny map")
    assert said[0].startswith("compiling a tiny map: 1 library with ")
    assert len(said) == 2 and COUNT.match(said[1])
    said.clear()
    compile_function(_tiny("tiny_d"))  # outside: says nothing
    assert said == []


def test_every_command_prints_its_first_compiles_on_stderr(cache, monkeypatch, capsys):
    """cli/main.py wraps a command in reported_builds(build_line): a compile anywhere
    below the command prints its lines on stderr, stdout stays the command's own."""

    def run(args):
        compile_function(_tiny("tiny_e"), what="a tiny map")
        return 0

    monkeypatch.setattr(simulate_command, "run", run)
    assert main(["simulate", str(FLIGHT5)]) == 0
    printed = capsys.readouterr()
    lines = printed.err.splitlines()
    assert lines[0].startswith("  compiling a tiny map: 1 library with ")
    assert COUNT.match(lines[1]) and lines[1].startswith("    compiled 1/1: tiny_e")
    assert "compil" not in printed.out
    assert main(["simulate", str(FLIGHT5)]) == 0  # warm: quiet
    assert capsys.readouterr().err == ""
