"""Compiled libraries as cache entries (compiled/cache/compiler.py, docs/architecture.md#rule-18).

Reference: the interpreted Function, and the process that loads a library. Before the
check, a library cut to half in the cache (an interrupted copy, a full disk) killed every
later run in dlopen with SIGBUS (exit 135, no message) until the cache was deleted by
hand. Now a later run verifies the library against its checksum before dlopen sees it:
each damage (cut to half, bytes flipped, emptied, its checksum missing) is reported with a
CacheWarning that names the file and the fault, the library is built again, once, and the
run goes on with the same numbers. Each load of a damaged library happens in a new
process, so a regression shows as its exit status instead of killing the test session.
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
from support.damage import DAMAGES
from support.paths import REPO_ROOT

from lightcraft_opt.compiled.cache import (
    CacheWarning,
    CompilationWarning,
    EntryStatus,
    check_entry,
    checksum_path,
    compile_function,
    library_path,
)

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="needs a C compiler")

#: Compiles the Function of _square() from the cache and prints its value at (1, 2, 3).
LOAD = """
import casadi as ca
from lightcraft_opt.compiled.cache import compile_function
x = ca.SX.sym("x", 3)
f = ca.Function("square", [x], [ca.sin(x) * ca.dot(x, x)], ["x"], ["s"])
g = compile_function(f)
print(g.is_a("External"), *(float(v).hex() for v in g([1.0, 2.0, 3.0]).full().ravel()))
"""


def _square() -> ca.Function:
    x = ca.SX.sym("x", 3)
    return ca.Function("square", [x], [ca.sin(x) * ca.dot(x, x)], ["x"], ["s"])


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(folder))
    return folder


def _load_in_a_new_process() -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-W", "always", "-c", LOAD],
        capture_output=True,
        text=True,
        env=os.environ.copy(),
        cwd=REPO_ROOT,
        timeout=300,
    )


def test_a_library_is_written_with_its_checksum_and_loaded_from_the_cache(cache):
    f = _square()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fast = compile_function(f)
    path = library_path(f)
    assert fast.is_a("External") and path.parent == cache
    assert check_entry(path).status is EntryStatus.WHOLE
    digest, name = checksum_path(path).read_text().split()
    assert name == path.name and len(digest) == 64  # sha256sum's format
    assert not [p.name for p in cache.iterdir() if p.name.startswith(".")]  # no temporary
    x = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(fast(x), f(x), rtol=1e-12)
    run = _load_in_a_new_process()  # a hit: no gcc, no warning
    assert run.returncode == 0 and "Warning" not in run.stderr, run.stderr
    assert run.stdout.split()[0] == "True"


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_library_is_built_again_never_loaded(cache, damage):
    f = _square()
    compile_function(f)
    path = library_path(f)
    whole = path.read_bytes()
    spoil, fault = DAMAGES[damage]
    spoil(path)
    run = _load_in_a_new_process()
    assert run.returncode == 0, f"exit {run.returncode}: {run.stderr}"  # SIGBUS was 135
    warned = [line for line in run.stderr.splitlines() if "CacheWarning" in line]
    assert len(warned) == 1, run.stderr
    assert f"cache file {path} is damaged" in warned[0] and fault in warned[0]
    assert "building again" in warned[0]
    assert "CompilationWarning" not in run.stderr
    compiled, *values = run.stdout.split()
    assert compiled == "True"
    reference = f([1.0, 2.0, 3.0]).full().ravel()  # the interpreter, to round-off
    np.testing.assert_allclose([float.fromhex(v) for v in values], reference, rtol=1e-12)
    assert check_entry(path).status is EntryStatus.WHOLE
    assert len(path.read_bytes()) == len(whole)  # the same library, built again
    again = _load_in_a_new_process()  # rebuilt once: the next run is a plain hit
    assert again.returncode == 0 and "Warning" not in again.stderr, again.stderr


def test_a_damaged_library_that_cannot_be_built_again_is_never_loaded(cache, monkeypatch):
    """Without a compiler the damaged library stays unused: the interpreted Function, with
    the warning that the library is damaged and the one that compiling failed."""
    f = _square()
    compile_function(f)
    path = library_path(f)
    DAMAGES["half"][0](path)
    monkeypatch.setattr("lightcraft_opt.compiled.cache.compiler._build", _no_compiler)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        out = compile_function(f)
    assert out is f
    said = [(w.category, str(w.message)) for w in record]
    assert len(said) == 2, said
    assert said[0][0] is CacheWarning and f"{path} is damaged" in said[0][1]
    assert said[1][0] is CompilationWarning and "no C compiler here" in said[1][1]
    assert not path.exists()  # removed: a later run does not warn of it again


def _no_compiler(*args: object) -> None:
    raise OSError("no C compiler here")
