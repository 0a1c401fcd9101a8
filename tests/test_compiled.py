"""The fast paths of simulate against the interpreted pulse-by-pulse reference.

References: the interpreted Φ (casadi's SX virtual machine) for the C-compiled Φ, which
evaluates the same expression graph in IEEE double and so agrees to round-off (1e-12
relative, a thousand times the unit round-off for a few hundred thousand operations);
the per-pulse policy loop for the chunked mapaccum loop, which calls the same Function on
the same numbers and so agrees to the last bit.

C compilation uses a small Φ (4 substeps, a 2 x 8 optic quadrature): gcc takes about
10 s for it, once per test session, in a temporary cache.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from support.models import table1_flight5

from lightcraft_opt import compiled
from lightcraft_opt.compiled import (
    DERIVATIVES_CACHE,
    compile_pulse_map,
    compile_pulse_map_derivatives,
    derivatives_key,
    memo,
    saved_pulse_map_derivatives,
)
from lightcraft_opt.compiled import pulse_map as compiled_pulse_map
from lightcraft_opt.compiled.cache import (
    CacheWarning,
    CompilationWarning,
    cache_path,
    compile_function,
    library_path,
    load_functions,
)
from lightcraft_opt.compiled.cache import compiler as cache_compiler
from lightcraft_opt.compiled.pulse_map import DESIGN_INSTRUCTION_LIMIT
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import (
    PARAMETERS,
    STATE,
    initial_state,
    map_input_layout,
    nominal_inputs,
    parameter_values,
)
from lightcraft_opt.model import Engine
from lightcraft_opt.simulation.result import SimulationResult, SimulationStatus
from lightcraft_opt.simulation.simulate import simulate
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import (
    build_pulse_map_derivatives,
    chain_derivatives,
)

MODELS = Path(__file__).resolve().parents[1] / "models"
SMALL = PulseMapOptions(substeps=4, dense=2)
COARSE_OPTIC = Engine(quadrature_radial=2, quadrature_azimuthal=8)
ROUND_OFF = 1e-12


def _small_model(**engine_changes: object):
    return table1_flight5(engine=replace(COARSE_OPTIC, **engine_changes))


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """A cache folder of its own for this module (LIGHTCRAFT_CACHE)."""
    folder = tmp_path_factory.mktemp("lightcraft_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("LIGHTCRAFT_CACHE", str(folder))
        yield folder


@pytest.fixture(scope="module")
def small(cache):
    """(model, interpreted Φ, compiled Φ) of the small map; the compile happens here."""
    model = _small_model()
    phi = build_pulse_map(model, SMALL)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CompilationWarning)  # a broken gcc fails loudly here
        fast = compile_pulse_map(phi)
    return model, phi, fast


def _close(a, b, rtol=ROUND_OFF):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    assert np.all(np.abs(a - b) <= rtol * np.maximum(1.0, np.abs(a))), np.max(np.abs(a - b))


# --------------------------------------------------------------------------- compiled Φ
def test_compiled_pulse_map_equals_interpreted_on_random_inputs(small):
    model, phi, fast = small
    assert fast.dense is not phi.dense and fast.period == phi.period
    for f, g in ((phi.dense, fast.dense), (phi.step, fast.step)):
        assert (g.name(), g.name_in(), g.name_out()) == (f.name(), f.name_in(), f.name_out())
    rng = np.random.default_rng(1)
    p = parameter_values(model)
    u0 = nominal_inputs(model)
    for _ in range(5):
        x = initial_state(
            model,
            r_L=(*rng.uniform(-0.03, 0.03, 2), rng.uniform(0.0, 30.0)),
            v_L=rng.uniform(-3.0, 10.0, 3),
            w_B=rng.uniform(-2.0, 2.0, 3),
            tilt=rng.uniform(0.0, 0.5),
        )
        u = u0 * rng.uniform(0.5, 1.0, u0.size)
        t = rng.uniform(0.0, 5.0)
        for f, g in ((phi.dense, fast.dense), (phi.step, fast.step)):
            for a, b in zip(f(x, u, p, t), g(x, u, p, t), strict=True):
                _close(a, b)


def test_second_compile_is_a_cache_hit(small, monkeypatch):
    _, phi, _ = small
    path = library_path(phi.dense)
    assert path.exists() and path.parent == Path(os.environ["LIGHTCRAFT_CACHE"])
    before = path.stat().st_mtime_ns

    def no_build(*args, **kwargs):
        raise AssertionError("compiled again instead of loading the cached library")

    monkeypatch.setattr(cache_compiler, "_build", no_build)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CompilationWarning)
        again = compile_pulse_map(phi)
    assert again is not phi
    assert path.stat().st_mtime_ns == before
    assert not list(path.parent.glob(".pulse_map_dense-*"))  # no temporary left behind


def test_a_new_process_finds_the_same_library(small):
    """The key is a pure function of the model's structure: no addresses, no ordering."""
    code = (
        "import sys; sys.path.insert(0, sys.argv[1]);"
        "from test_compiled import SMALL, _small_model;"
        "from lightcraft_opt.compiled.cache import library_path;"
        "from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map;"
        "print(library_path(build_pulse_map(_small_model(), SMALL).dense))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(Path(__file__).parent)],
        capture_output=True,
        text=True,
        check=True,
        env=os.environ.copy(),
    )
    assert Path(out.stdout.strip()) == library_path(small[1].dense)


def test_cache_key_follows_structure_not_parameter_values(small):
    """Numbers read through p (mass, spin, blast angle, optic size) share one library;
    structure (the optic quadrature, the substeps) gets its own."""
    model, phi, _ = small
    key = library_path(phi.dense)
    for same in (
        table1_flight5(engine=COARSE_OPTIC, mass=0.04, spin=500.0),
        _small_model(blast_angle=0.3, capture_radius=0.05),
    ):
        assert library_path(build_pulse_map(same, SMALL).dense) == key
    for other, opts in (
        (_small_model(quadrature_azimuthal=12), SMALL),
        (model, PulseMapOptions(substeps=8, dense=2)),
        (model, replace(SMALL, dense=4)),
    ):
        assert library_path(build_pulse_map(other, opts).dense) != key
    assert library_path(phi.dense, flags=("-O3",)) != key


def test_missing_compiler_falls_back_to_the_interpreter_with_a_warning(small, monkeypatch):
    _, phi, _ = small
    monkeypatch.setenv("CC", "/nonexistent/cc")
    with pytest.warns(CompilationWarning, match="nonexistent"):
        assert compile_pulse_map(phi) is phi
    with pytest.warns(CompilationWarning, match="no-such-cc"):
        assert compile_function(phi.step, compiler="no-such-cc") is phi.step


def test_failing_compile_falls_back_and_leaves_no_library(small):
    _, phi, _ = small
    flags = ("-O2", "--no-such-flag-for-lightcraft")
    with pytest.warns(CompilationWarning, match="no-such-flag"):
        assert compile_pulse_map(phi, flags=flags) is phi
    assert not library_path(phi.dense, flags=flags).exists()
    assert not list(library_path(phi.dense).parent.glob(".pulse_map_dense-*"))


def test_unwritable_cache_falls_back_with_a_warning(small, tmp_path, monkeypatch):
    _, phi, _ = small
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(blocker / "cache"))
    with pytest.warns(CompilationWarning, match="could not compile"):
        assert compile_pulse_map(phi) is phi


def test_simulate_compiled_flies_the_interpreted_flight(small):
    model, phi, fast = small
    with warnings.catch_warnings():
        warnings.simplefilter("error", CompilationWarning)
        flag = simulate(model, 1.0, pulse_map=phi, compiled=True)  # cache hit
    reference = simulate(model, 1.0, pulse_map=phi)
    prebuilt = simulate(model, 1.0, pulse_map=fast)
    for result in (flag, prebuilt):
        assert result.status is reference.status
        np.testing.assert_array_equal(result.t, reference.t)
        _close(reference.x, result.x)
        _close(reference.pulses.engine, result.pulses.engine)


# --------------------------------------------------------------------------- mapaccum
@pytest.fixture(scope="module")
def flight5():
    model = load_model(MODELS / "flight5.toml")
    return model, build_pulse_map(model)


def _assert_same_flight(a: SimulationResult, b: SimulationResult) -> None:
    assert (a.status, a.message) == (b.status, b.message)
    for name in ("t", "x"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    for name in ("t", "u", "engine", "beam_gap"):
        np.testing.assert_array_equal(getattr(a.pulses, name), getattr(b.pulses, name))


@pytest.mark.parametrize(
    ("case", "status", "pulses"),
    [
        ("nominal", SimulationStatus.DURATION_REACHED, 52),
        ("laser_off_lands_in_second_chunk", SimulationStatus.LANDED, None),
        ("tilted_leaves_beam_in_second_chunk", SimulationStatus.LEFT_BEAM, None),
        ("ramped_energy_with_dropouts", SimulationStatus.DURATION_REACHED, 52),
        ("two_pulses_beside_the_craft_inside_a_chunk", SimulationStatus.DURATION_REACHED, 52),
    ],
)
def test_mapaccum_chunks_fly_the_per_pulse_policy_flight(flight5, case, status, pulses):
    """A 2 s Flight 5 flight from open-loop inputs (chunks of 26 pulses through
    Φ.mapaccum) and from the same inputs as a policy (one call per pulse): identical,
    including where a landing or leaving the beam cuts the flight inside a chunk."""
    model, phi = flight5
    u0 = nominal_inputs(model)
    energy = map_input_layout(0, False).slot("energy").start
    x0, dropout_rate, rows = initial_state(model), 0.0, u0[None, :]
    if case == "laser_off_lands_in_second_chunk":
        rows = np.where(np.arange(u0.size) == energy, 0.0, u0)[None, :]
        x0 = initial_state(model, v_L=(0.0, 0.0, 8.0))  # back on the pad after 1.6 s
    elif case == "tilted_leaves_beam_in_second_chunk":
        x0 = initial_state(model, tilt=math.radians(10.0))
    elif case == "ramped_energy_with_dropouts":
        rows = np.tile(u0, (40, 1))
        rows[:, energy] *= np.linspace(1.0, 0.7, 40)  # the last row held after pulse 40
        dropout_rate = 0.3
    elif case == "two_pulses_beside_the_craft_inside_a_chunk":
        rows = np.tile(u0, (52, 1))
        pointing = map_input_layout(0, False).slot("pointing_L").start
        rows[30:32, pointing] = 0.3  # the beam 30 cm east for two pulses: outside, not out

    def policy(k, t, x):
        return rows[min(k, len(rows) - 1)]

    common = dict(x0=x0, pulse_map=phi, dropout_rate=dropout_rate, seed=5)
    chunked = simulate(model, 2.0, inputs=rows, **common)
    per_pulse = simulate(model, 2.0, inputs=policy, **common)
    _assert_same_flight(chunked, per_pulse)
    assert chunked.status is status
    n = len(chunked.pulses.t)
    if pulses is None:
        assert 26 < n < 52  # ended inside the second chunk
    else:
        assert n == pulses
    if dropout_rate:
        assert 0 < np.sum(chunked.pulses.u[:, energy] == 0.0) < n
    if case == "two_pulses_beside_the_craft_inside_a_chunk":
        outside = np.flatnonzero(chunked.pulses.beam_gap > 0.0)
        assert outside.tolist() == [30, 31]


# --------------------------------------------------------------------------- Φ by default
@pytest.fixture
def fresh_memo(monkeypatch):
    """pulse_map_for's in-process memo and one-warning flag, emptied for one test."""
    monkeypatch.setattr(memo, "_MAPS", type(memo._MAPS)())
    monkeypatch.setattr(memo, "_warned_once", False)


def test_pulse_map_for_builds_once_and_compiles_by_default(small, fresh_memo, monkeypatch):
    model, phi, _ = small
    monkeypatch.delenv("LIGHTCRAFT_COMPILE", raising=False)
    assert compiled.compile_by_default()
    with warnings.catch_warnings():
        warnings.simplefilter("error", CompilationWarning)
        first = compiled.pulse_map_for(model, SMALL)  # a cache hit on disk: no gcc
    assert first.dense.is_a("External") and not phi.dense.is_a("External")
    assert first.dense.name() == phi.dense.name() and first.pieces is not None

    def no_build(*args, **kwargs):
        raise AssertionError("built Φ again for an equal model")

    monkeypatch.setattr(memo, "build_pulse_map", no_build)
    assert compiled.pulse_map_for(model, SMALL) is first
    assert compiled.pulse_map_for(_small_model(), SMALL) is first  # equal, not the same object
    again = simulate(model, 0.5, options=SMALL)  # simulate asks pulse_map_for
    reference = simulate(model, 0.5, pulse_map=phi)
    np.testing.assert_array_equal(again.t, reference.t)
    _close(reference.x, again.x)


@pytest.mark.parametrize("flag", ["0", "false", "off"])
def test_environment_turns_compiling_off(small, fresh_memo, monkeypatch, flag):
    model, _, _ = small
    monkeypatch.setenv("LIGHTCRAFT_COMPILE", flag)
    assert not compiled.compile_by_default()
    assert not compiled.pulse_map_for(model, SMALL).dense.is_a("External")
    assert compiled.pulse_map_for(model, SMALL, compiled=True).dense.is_a("External")


def test_without_a_compiler_one_warning_per_process(small, fresh_memo, monkeypatch):
    model, _, _ = small
    monkeypatch.setenv("CC", "/nonexistent/cc")
    with pytest.warns(CompilationWarning, match="nonexistent") as record:
        a = compiled.pulse_map_for(model, SMALL, compiled=True)
        b = compiled.pulse_map_for(model, replace(SMALL, dense=4), compiled=True)
    assert len([w for w in record if issubclass(w.category, CompilationWarning)]) == 1
    assert not a.dense.is_a("External") and not b.dense.is_a("External")
    x, u, p = initial_state(model), nominal_inputs(model), parameter_values(model)
    _close(a.step(x, u, p, 0.0)[0], b.step(x, u, p, 0.0)[0])


# --------------------------------------------------------------------------- derivatives
@pytest.mark.slow
def test_compiled_chain_derivatives_equal_the_interpreted_chain(small):
    """Φ's explicit-chain Jacobian and Hessian over compiled pieces (each piece its own
    library, the derivative pieces at DERIVATIVE_FLAGS) against the same chain interpreted.
    Pieces above 40k instructions (here the Yoshida substep's) stay interpreted, as the
    big ones do by default: the chain mixes both (gcc takes ~20 s for the rest)."""
    model, phi, _ = small
    interpreted = build_pulse_map_derivatives(phi)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CompilationWarning)
        fast = compile_pulse_map_derivatives(phi, interpreted.pieces, max_instructions=40_000)
    kinds = {f.name(): f.is_a("External") for f in fast.pieces.functions() if f is not None}
    assert kinds["pulse_jump_hessian"] and kinds["normalise_attitude_jacobian"]
    assert not kinds["coast_substep_hessian"]
    assert fast.hessian is not None and interpreted.hessian is not None
    rng = np.random.default_rng(2)
    x = initial_state(model, r_L=(0.01, -0.02, 4.0), v_L=(0.2, 0.1, 8.0), w_B=(0.0, 2.0, -1.0))
    u, p = nominal_inputs(model), parameter_values(model)
    lam_x, lam_e = rng.normal(size=x.size), rng.normal(size=11)
    for a, b in zip(fast.jacobian(x, u, p, 0.4), interpreted.jacobian(x, u, p, 0.4), strict=True):
        _close(a, b)
    _close(
        fast.hessian(x, u, p, 0.4, lam_x, lam_e), interpreted.hessian(x, u, p, 0.4, lam_x, lam_e)
    )


def test_compiled_dense_sensitivity_equals_the_interpreted_chain(small, monkeypatch):
    """The dense-output sensitivities calibration uses (forward-mode pieces, each its own
    library at DERIVATIVE_FLAGS) against the same chain interpreted, in 2 random directions
    of the state and every parameter."""
    model, _, _ = small
    monkeypatch.setattr(memo, "_SENSITIVITIES", type(memo._SENSITIVITIES)())
    with warnings.catch_warnings():
        warnings.simplefilter("error", CompilationWarning)
        fast = compiled.dense_sensitivity_for(model, SMALL, 2, compiled=True)
    slow = compiled.dense_sensitivity_for(model, SMALL, 2, compiled=False)
    assert compiled.dense_sensitivity_for(model, SMALL, 2, compiled=True) is not fast  # MX anew
    assert len(memo._SENSITIVITIES) == 2  # ... over the pieces built once
    rng = np.random.default_rng(4)
    x = initial_state(model, r_L=(0.01, -0.02, 4.0), v_L=(0.2, 0.1, 8.0), w_B=(0.0, 2.0, -1.0))
    u, p = nominal_inputs(model), parameter_values(model)
    S = rng.normal(size=(x.size, 2))
    Q = 1e-2 * rng.normal(size=(p.size, 2)) * np.maximum(np.abs(p), 1e-3)[:, None]
    for a, b in zip(fast(x, u, p, 0.4, S, Q), slow(x, u, p, 0.4, S, Q), strict=True):
        _close(a, b)


def test_cli_without_a_compiler_warns_in_one_line_and_flies(tmp_path):
    """`lightcraft simulate` where gcc is missing: the interpreted Φ, one warning line that
    names the cause (no source location, no traceback), exit 0 and the usual files."""
    env = {k: v for k, v in os.environ.items() if k != "LIGHTCRAFT_COMPILE"}
    env.update(CC="/nonexistent/cc", LIGHTCRAFT_CACHE=str(tmp_path / "cache"))
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "lightcraft_opt.cli", "simulate", str(MODELS / "flight5.toml")]
    proc = subprocess.run(
        [*cmd, "--duration", "0.2", "--out", str(out)],
        capture_output=True,
        text=True,
        env=env,
    )
    assert proc.returncode == 0, proc.stderr
    warning_lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(warning_lines) == 1, proc.stderr
    assert warning_lines[0].startswith("lightcraft: warning: could not compile")
    assert "/nonexistent/cc" in warning_lines[0]
    assert (out / "summary.json").exists()


def test_compiled_chain_derivatives_are_saved_and_loaded_by_structure(small, monkeypatch):
    """saved_pulse_map_derivatives: the first call compiles (here: reuses the libraries of
    the test above) and saves the chain's Functions; the next loads them without building
    anything and gives the same numbers to the last bit. Other numbers through p share the
    key, other substeps do not; a damaged file is built again with a CacheWarning."""
    model, phi, _ = small
    limit = 40_000
    first = saved_pulse_map_derivatives(phi, max_instructions=limit)
    key = derivatives_key(phi, limit)
    assert key is not None and cache_path(DERIVATIVES_CACHE, key).exists()
    same = table1_flight5(engine=COARSE_OPTIC, mass=0.04, spin=500.0)
    assert derivatives_key(build_pulse_map(same, SMALL), limit) == key
    other = build_pulse_map(model, PulseMapOptions(substeps=2, dense=2))
    assert derivatives_key(other, limit) not in (key, None)
    assert derivatives_key(phi) != key  # another instruction limit
    # a chain also in designed entries of p: a key per design, none the plain chain's
    i, j = PARAMETERS.slot("rotor_mass_dry").start, PARAMETERS.slot("impulse_per_pulse").start
    designed = {derivatives_key(phi, limit, design) for design in ((i,), (j,), (i, j))}
    assert len(designed) == 3 and not designed & {key, None}
    assert derivatives_key(phi, limit, ()) == key
    assert derivatives_key(phi, None, (i,)) == derivatives_key(phi, DESIGN_INSTRUCTION_LIMIT, (i,))

    def no_build(*args, **kwargs):
        raise AssertionError("built again instead of loading the saved derivatives")

    with monkeypatch.context() as patch:
        patch.setattr(compiled_pulse_map, "_compiled_derivatives", no_build)
        with warnings.catch_warnings():
            warnings.simplefilter("error", CacheWarning)
            loaded = saved_pulse_map_derivatives(phi, max_instructions=limit)
    assert loaded.hessian is not None and first.hessian is not None
    rng = np.random.default_rng(5)
    x = initial_state(model, r_L=(0.01, -0.02, 4.0), v_L=(0.2, 0.1, 8.0), w_B=(0.0, 2.0, -1.0))
    u, p = nominal_inputs(model), parameter_values(model)
    lam_x, lam_e = rng.normal(size=x.size), rng.normal(size=11)
    for f, g in ((first.jacobian, loaded.jacobian), (first.values, loaded.values)):
        for a, b in zip(f(x, u, p, 0.4), g(x, u, p, 0.4), strict=True):
            assert np.array_equal(np.asarray(a), np.asarray(b))
    hess = (first.hessian(x, u, p, 0.4, lam_x, lam_e), loaded.hessian(x, u, p, 0.4, lam_x, lam_e))
    assert np.array_equal(*(np.asarray(h) for h in hess))

    path = cache_path(DERIVATIVES_CACHE, key)
    path.write_bytes(path.read_bytes()[:-100])
    with pytest.warns(CacheWarning, match="damaged"):
        rebuilt = saved_pulse_map_derivatives(phi, max_instructions=limit)
    assert rebuilt.hessian is not None
    again = rebuilt.hessian(x, u, p, 0.4, lam_x, lam_e)
    assert np.array_equal(np.asarray(again), np.asarray(hess[0]))
    assert load_functions(DERIVATIVES_CACHE, key) is not None  # whole again


def test_interpreted_derivative_pieces_are_kept_by_structure(tmp_path, monkeypatch):
    """saved_derivative_pieces (what a process that compiles nothing uses): the first call
    builds the pieces by casadi's AD and saves them, the next loads them without any AD and
    they give the same numbers to the last bit; other numbers through p share the entry;
    a damaged entry is dropped with a CacheWarning (so the next call builds it again)."""
    monkeypatch.setenv("LIGHTCRAFT_CACHE", str(tmp_path))
    model = _small_model()
    phi = build_pulse_map(model, PulseMapOptions(substeps=2, dense=1))
    said: list[str] = []
    first = compiled_pulse_map.saved_derivative_pieces(phi, report=said.append)
    assert said == [compiled_pulse_map.BUILDING_PIECES]
    (entry,) = tmp_path.glob(f"{compiled_pulse_map.PIECES_CACHE}-*.casadi")

    def no_build(*args, **kwargs):
        raise AssertionError("built again instead of loading the saved pieces")

    same = build_pulse_map(table1_flight5(engine=COARSE_OPTIC, mass=0.04), phi.options)
    with monkeypatch.context() as patch:
        patch.setattr(compiled_pulse_map, "build_derivative_pieces", no_build)
        with warnings.catch_warnings():
            warnings.simplefilter("error", CacheWarning)
            loaded = compiled_pulse_map.saved_derivative_pieces(same, report=said.append)
    assert said[-1].startswith("Φ's derivative pieces: loaded from the cache")
    x = initial_state(model, r_L=(0.01, -0.02, 4.0), v_L=(0.2, 0.1, 8.0), w_B=(0.0, 2.0, -1.0))
    u, p = nominal_inputs(model), parameter_values(model)
    lam = np.random.default_rng(3).normal(size=STATE.size)
    chains = [chain_derivatives(phi, d) for d in (first, loaded)]
    assert all(c.hessian is not None for c in chains)
    for f, g in ((chains[0].jacobian, chains[1].jacobian), (chains[0].values, chains[1].values)):
        for a, b in zip(f(x, u, p, 0.4), g(x, u, p, 0.4), strict=True):
            assert np.array_equal(np.asarray(a), np.asarray(b))
    lam_e = np.zeros(chains[0].values.size1_out(1))
    hess = [np.asarray(c.hessian(x, u, p, 0.4, lam, lam_e)) for c in chains]  # type: ignore[misc]
    assert np.array_equal(*hess) and np.any(hess[0])

    entry.write_bytes(entry.read_bytes()[:-100])  # damaged: dropped, so built again
    key = entry.name.removeprefix(f"{compiled_pulse_map.PIECES_CACHE}-").removesuffix(".casadi")
    with pytest.warns(CacheWarning, match="damaged"):
        assert load_functions(compiled_pulse_map.PIECES_CACHE, key) is None
    assert not entry.exists()
