"""Functions kept on disk by structure (function_cache.py, docs/architecture.md#rule-18).

Reference: the Functions that were saved. A loaded Function is the same graph, so it gives
the same numbers to the last bit; a file that is not exactly what was written (an altered
byte, a truncation, a compiled library it names that is gone) is refused with a
CacheWarning, never used and never a crash.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import warnings

import casadi as ca
import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.compiled import compile_function
from lightcraft_opt.function_cache import (
    CacheWarning,
    cache_path,
    load_functions,
    save_functions,
    structure_key,
)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(folder))
    return folder


def _functions() -> list[ca.Function]:
    x = ca.SX.sym("x", 3)
    y = ca.MX.sym("y", 2)
    square = ca.Function("square", [x], [ca.sin(x) * ca.dot(x, x)], ["x"], ["s"], {"cse": True})
    shifted = ca.Function("shifted", [y], [ca.exp(y) - 1], ["y"], ["e"])
    return [square, shifted]


def _same_numbers(a: ca.Function, b: ca.Function) -> None:
    assert (a.name(), a.name_in(), a.name_out()) == (b.name(), b.name_in(), b.name_out())
    rng = np.random.default_rng(3)
    args = [rng.normal(size=a.sparsity_in(i).shape) for i in range(a.n_in())]
    for u, v in zip(a.call(args), b.call(args), strict=True):
        assert np.array_equal(np.asarray(u), np.asarray(v))


def test_saved_functions_load_back_to_the_last_bit(cache):
    functions = _functions()
    assert load_functions("pair", "k1") is None  # nothing saved yet: a miss, no warning
    save_functions("pair", "k1", functions)
    assert cache_path("pair", "k1").parent == cache
    assert not [p for p in cache.iterdir() if p.name.startswith(".")]  # no temporary left
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        loaded = load_functions("pair", "k1")
    assert loaded is not None and len(loaded) == 2
    for a, b in zip(functions, loaded, strict=True):
        _same_numbers(a, b)


@pytest.mark.parametrize(
    "damage",
    [
        lambda data: data[: len(data) // 2],  # truncated
        lambda data: data[:-10] + bytes(b ^ 1 for b in data[-10:]),  # bits flipped
        lambda data: b"another format 1" + data[data.index(b"\n") :],  # not this format
        lambda data: b"",  # empty
    ],
    ids=["truncated", "flipped", "format", "empty"],
)
def test_a_damaged_file_is_refused_with_a_warning(cache, damage):
    save_functions("pair", "k1", _functions())
    path = cache_path("pair", "k1")
    path.write_bytes(damage(path.read_bytes()))
    with pytest.warns(CacheWarning, match="damaged"):
        assert load_functions("pair", "k1") is None
    save_functions("pair", "k1", _functions())  # rebuilt: the file is whole again
    assert load_functions("pair", "k1") is not None


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs a C compiler")
def test_a_file_whose_compiled_library_is_gone_is_refused_with_a_warning(cache):
    """A saved Function that calls a compiled library names it: with the library gone, a
    new process (this one keeps the library loaded) cannot load the file and builds it
    again."""
    compiled = compile_function(_functions()[0])
    assert compiled.is_a("External")
    x = ca.MX.sym("x", 3)
    save_functions("uses_library", "k1", [ca.Function("twice", [x], [2 * compiled(x)])])
    for library in cache.glob("square-*.so"):
        library.unlink()
    code = (
        "from lightcraft_opt.function_cache import load_functions\n"
        "print(load_functions('uses_library', 'k1'))"
    )
    run = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=os.environ.copy(),
        cwd=REPO_ROOT,
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "None"
    assert "CacheWarning" in run.stderr and "cannot be loaded" in run.stderr


def test_an_unwritable_cache_warns_and_the_run_goes_on(tmp_path, monkeypatch):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(blocker / "cache"))
    with pytest.warns(CacheWarning, match="could not write"):
        save_functions("pair", "k1", _functions())
    with pytest.warns(CacheWarning, match="unreadable"):
        assert load_functions("pair", "k1") is None


def test_the_key_is_the_graph_not_the_objects():
    """Equal graphs built twice give one key; another graph, sparsity or text another."""
    a, b = _functions(), _functions()
    assert structure_key(*a) == structure_key(*b)
    assert structure_key(a[0]) != structure_key(a[1])
    assert structure_key(a[0], "n=3") != structure_key(a[0], "n=4")
    assert structure_key(ca.Sparsity.dense(2, 2)) != structure_key(ca.Sparsity.diag(2))
