"""Functions kept on disk by structure (compiled/cache/functions.py, docs/architecture.md#rule-18).

Reference: the Functions that were saved. A loaded Function is the same graph, so it gives
the same numbers to the last bit; an entry that is not exactly what was written (cut to
half, bytes flipped, emptied, its checksum missing, a compiled library it calls gone or
damaged) is refused with a CacheWarning that names the file, never used and never a
crash, and built again.
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
from support.damage import DAMAGES, half
from support.paths import REPO_ROOT

from lightcraft_opt.compiled.cache import (
    CacheWarning,
    cache_path,
    checksum_path,
    compile_function,
    library_path,
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


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_entry_is_refused_with_a_warning_and_built_again(cache, damage):
    save_functions("pair", "k1", _functions())
    path = cache_path("pair", "k1")
    spoil, fault = DAMAGES[damage]
    spoil(path)
    with pytest.warns(CacheWarning, match=f"{path.name} is damaged \\(.*{fault}") as record:
        assert load_functions("pair", "k1") is None
    assert len(record) == 1 and str(path) in str(record[0].message)
    assert not path.exists() and not checksum_path(path).exists()  # removed: no warning again
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        assert load_functions("pair", "k1") is None  # a plain miss now
    save_functions("pair", "k1", _functions())  # rebuilt: the entry is whole again
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        loaded = load_functions("pair", "k1")
    assert loaded is not None
    _same_numbers(_functions()[0], loaded[0])


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs a C compiler")
@pytest.mark.parametrize("damage", ["gone", "half"])
def test_an_entry_whose_compiled_library_is_not_whole_is_refused_before_loading(cache, damage):
    """A saved Function that calls a compiled library names it, and unpacking it loads the
    library: with the library gone or cut to half (which dlopen answers with SIGBUS), the
    entry is refused before unpacking, in a new process (this one keeps the library
    loaded), which exits normally and builds the Functions again."""
    square = _functions()[0]
    compiled = compile_function(square)
    assert compiled.is_a("External")
    library = library_path(square)
    x = ca.MX.sym("x", 3)
    twice = ca.Function("twice", [x], [2 * compiled(x)])
    save_functions("uses_library", "k1", [twice], [library])
    if damage == "gone":
        library.unlink()
    else:
        half(library)
    code = (
        "from lightcraft_opt.compiled.cache import load_functions\n"
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
    fault = "gone" if damage == "gone" else "do not match the checksum"
    assert "CacheWarning" in run.stderr and f"{library}, which is" in run.stderr, run.stderr
    assert fault in run.stderr, run.stderr
    assert not cache_path("uses_library", "k1").exists()


def test_an_unwritable_cache_warns_and_the_run_goes_on(tmp_path, monkeypatch):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(blocker / "cache"))
    with pytest.warns(CacheWarning, match="could not write"):
        save_functions("pair", "k1", _functions())
    with pytest.warns(CacheWarning, match="is unreadable"):
        assert load_functions("pair", "k1") is None


def test_the_key_is_the_graph_not_the_objects():
    """Equal graphs built twice give one key; another graph, sparsity or text another."""
    a, b = _functions(), _functions()
    assert structure_key(*a) == structure_key(*b)
    assert structure_key(a[0]) != structure_key(a[1])
    assert structure_key(a[0], "n=3") != structure_key(a[0], "n=4")
    assert structure_key(ca.Sparsity.dense(2, 2)) != structure_key(ca.Sparsity.diag(2))
