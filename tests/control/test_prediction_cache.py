"""The MPC's scheduled model kept on disk (control/prediction_model.py as a cache entry,
docs/architecture.md#rule-18).

Reference: the model linearised afresh. A model read from the cache is the tables that
were written, so it equals the fresh one to the last bit. Before the check, a
``coning_model-*.npz`` cut to half made every later closed loop fail with "internal
error: BadZipFile" until the cache was deleted by hand; now each damage (cut to half,
bytes flipped, emptied, its checksum missing) and a whole file of another layout are
reported with a CacheWarning that names the file, and the model is linearised again,
once, and written whole.

A small model keeps it quick: Flight 5 with RCS on a 2 x 8 optic and 4 substeps, a
2 x 2 grid of spin and altitude (2 s to linearise).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest
from support.damage import DAMAGES
from support.paths import MODELS

from lightcraft_opt.compiled.cache import CacheWarning, EntryStatus, check_entry, write_entry
from lightcraft_opt.control import prediction_model
from lightcraft_opt.control.prediction_model import ConingModel, coning_model
from lightcraft_opt.files.model import load_model
from lightcraft_opt.layout import RcsProfile
from lightcraft_opt.linear.operating_points import pulse_map_jacobian
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import build_pulse_map

TABLES = ("spins", "altitudes", "speeds", "A", "B", "omega_per_spin", "spin_decay")


@pytest.fixture(scope="module")
def small():
    """(model, Φ's Jacobian, grid keywords, the model linearised without a cache)."""
    base = load_model(MODELS / "flight5-rcs.toml")
    engine = replace(base.craft.engine, quadrature_radial=2, quadrature_azimuthal=8)
    model = replace(base, craft=replace(base.craft, engine=engine))
    options = PulseMapOptions(rcs_profile=RcsProfile.PHASE_LOCKED, substeps=4, dense=2)
    jac = pulse_map_jacobian(build_pulse_map(model, options))
    spin = model.craft.spin
    grid = dict(spins=[0.95 * spin, spin], altitudes=[0.0, 2.0], speeds=[0.0, 5.0])
    return model, jac, grid, coning_model(model, pulse_map=jac, **grid)


def _same(a: ConingModel, b: ConingModel) -> None:
    for name in TABLES:
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.period == b.period and a.inputs == b.inputs


def _entry(folder):
    (path,) = folder.glob("coning_model-*.npz")
    return path


def _no_linearising(*args, **kwargs):
    raise AssertionError("linearised again instead of reading the cache")


def test_a_cached_model_reads_back_to_the_last_bit(small, tmp_path, monkeypatch):
    model, jac, grid, fresh = small
    first = coning_model(model, pulse_map=jac, cache=tmp_path, **grid)
    _same(first, fresh)
    assert check_entry(_entry(tmp_path)).status is EntryStatus.WHOLE
    monkeypatch.setattr(prediction_model, "_linearise_grid", _no_linearising)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        _same(coning_model(model, pulse_map=jac, cache=tmp_path, **grid), fresh)


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_damaged_model_is_linearised_again_with_a_warning(small, tmp_path, monkeypatch, damage):
    model, jac, grid, fresh = small
    coning_model(model, pulse_map=jac, cache=tmp_path, **grid)
    path = _entry(tmp_path)
    spoil, fault = DAMAGES[damage]
    spoil(path)
    with pytest.warns(CacheWarning, match="is damaged") as record:
        again = coning_model(model, pulse_map=jac, cache=tmp_path, **grid)
    message = str(record[0].message)
    assert len(record) == 1 and str(path) in message and fault in message
    _same(again, fresh)
    assert check_entry(path).status is EntryStatus.WHOLE  # written whole again
    monkeypatch.setattr(prediction_model, "_linearise_grid", _no_linearising)
    with warnings.catch_warnings():  # built again once: the next run reads it
        warnings.simplefilter("error", CacheWarning)
        _same(coning_model(model, pulse_map=jac, cache=tmp_path, **grid), fresh)


def test_a_whole_file_that_is_not_the_tables_is_linearised_again(small, tmp_path):
    """A file whose checksum is right but which is no .npz of the tables (another layout
    under the same name) cannot be read: the warning says why, and the model is built."""
    model, jac, grid, fresh = small
    coning_model(model, pulse_map=jac, cache=tmp_path, **grid)
    path = _entry(tmp_path)
    write_entry(path, b"not a zip file")
    with pytest.warns(CacheWarning, match="cannot be loaded"):
        _same(coning_model(model, pulse_map=jac, cache=tmp_path, **grid), fresh)
    assert check_entry(path).status is EntryStatus.WHOLE
