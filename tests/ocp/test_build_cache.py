"""The OCP's build cache (docs/ocp.md#the-build-cache): the NLP's surrogate Functions
(MultipleShooting.surrogate) kept on disk by structure.

References: the freshly built Functions and the solve of a fresh build. A loaded
Function is the same graph, so it gives the same numbers to the last bit, and a solve
built from the cache is the fresh build's solve bit for bit (the same arithmetic in the
same order). A damaged file is refused with a CacheWarning and built again, and the key
is the structure: another horizon gets a file of its own, other run-time values (initial
state, wind) do not.

The lateral problem of test_ocp.py on its cheap Φ (one Strang substep, 4 x 16 optic),
interpreted (the suite's LIGHTCRAFT_COMPILE=0), in a cache folder of each test's own.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from ocp.test_ocp import CHEAP_MAP, QUADRATURE, TOL, lateral_problem
from support.models import table1_flight5

from lightcraft_opt.compiled.cache import CacheWarning
from lightcraft_opt.layout import initial_state
from lightcraft_opt.model import Engine
from lightcraft_opt.ocp.chain import SURROGATE_CACHE, Surrogate, build_surrogate
from lightcraft_opt.ocp.options import OcpOptions
from lightcraft_opt.ocp.result import OcpStatus
from lightcraft_opt.ocp.solve import CompiledOcp
from lightcraft_opt.ocp.transcription import MultipleShooting
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import build_pulse_map_derivatives

BUILT = "building the NLP's derivatives"
LOADED = "the NLP's derivatives: loaded from the cache"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(folder))
    return folder


@pytest.fixture(scope="module")
def lateral():
    base = table1_flight5()
    model = replace(base, craft=replace(base.craft, engine=Engine(**QUADRATURE)))  # type: ignore[arg-type]
    phi = build_pulse_map(model, CHEAP_MAP)
    return lateral_problem(model), phi, build_pulse_map_derivatives(phi)


def _surrogate(lateral, problem=None) -> tuple[Surrogate, list[str]]:
    base, phi, derivatives = lateral
    said: list[str] = []
    tr = MultipleShooting(problem or base, phi, derivatives=derivatives)
    return build_surrogate(tr, report=said.append), said


def _files(cache) -> list:
    return sorted(cache.glob(f"{SURROGATE_CACHE}-*.casadi"))  # not their checksums, locks


def test_loaded_surrogate_evaluates_like_the_fresh_one(cache, lateral):
    fresh, said = _surrogate(lateral)
    assert any(BUILT in line for line in said) and len(_files(cache)) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        loaded, said = _surrogate(lateral)
    assert any(LOADED in line for line in said)
    rng = np.random.default_rng(4)
    for name in Surrogate.__dataclass_fields__:
        a, b = getattr(fresh, name), getattr(loaded, name)
        assert a is not b and a.name() == b.name()
        args = [ca.DM(a.sparsity_in(i), rng.normal(size=a.nnz_in(i))) for i in range(a.n_in())]
        for u, v in zip(a.call(args), b.call(args), strict=True):
            assert np.array_equal(np.asarray(u), np.asarray(v)), name


def test_a_second_build_solves_bit_for_bit(cache, lateral):
    problem, phi, _ = lateral
    first_said: list[str] = []
    first = CompiledOcp(
        problem, OcpOptions(tol=TOL), pulse_map=phi, build_progress=first_said.append
    )
    second_said: list[str] = []
    second = CompiledOcp(
        problem, OcpOptions(tol=TOL), pulse_map=phi, build_progress=second_said.append
    )
    assert any(BUILT in line for line in first_said)
    assert any(LOADED in line for line in second_said)
    a, b = first.solve(), second.solve()
    assert a.status is OcpStatus.SOLVED and b.status is OcpStatus.SOLVED
    assert a.iterations == b.iterations
    assert np.array_equal(a.w, b.w) and np.array_equal(a.lam_g, b.lam_g)


@pytest.mark.parametrize("damage", ["truncated", "flipped"])
def test_a_damaged_cache_file_is_rebuilt_with_a_warning(cache, lateral, damage):
    problem, phi, _ = lateral
    reference = CompiledOcp(problem, OcpOptions(tol=TOL), pulse_map=phi).solve()
    (path,) = _files(cache)
    data = path.read_bytes()
    path.write_bytes(
        data[: len(data) // 2] if damage == "truncated" else data[:-8] + bytes(8 * [0x20])
    )
    said: list[str] = []
    with pytest.warns(CacheWarning, match="damaged"):
        again = CompiledOcp(problem, OcpOptions(tol=TOL), pulse_map=phi, build_progress=said.append)
    assert any(BUILT in line for line in said)
    result = again.solve()
    assert result.status is OcpStatus.SOLVED and np.array_equal(result.w, reference.w)
    with warnings.catch_warnings():  # the file was written again, whole
        warnings.simplefilter("error", CacheWarning)
        _, said = _surrogate(lateral)
    assert any(LOADED in line for line in said)


def test_the_key_is_the_structure_not_the_values(cache, lateral):
    problem, _, _ = lateral
    _surrogate(lateral)
    moved = replace(
        problem,
        x0=initial_state(problem.model, r_L=(-0.02, 0.01, 3.0), v_L=(0.1, 0.0, 5.0)),
        parameters={"wind_speed_ref": 1.0, "wind_direction_from": 0.3},
    )
    _, said = _surrogate(lateral, moved)
    assert any(LOADED in line for line in said) and len(_files(cache)) == 1
    _, said = _surrogate(lateral, replace(problem, horizon=5))
    assert any(BUILT in line for line in said) and len(_files(cache)) == 2
