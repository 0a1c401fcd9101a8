"""Monte Carlo on a Dask cluster: a LocalCluster on the loopback (two worker processes,
one thread each) gives the byte-identical run table of the campaign made serially in this
process (tests/campaign/test_monte_carlo.py has the other engines)."""

from __future__ import annotations

from pathlib import Path

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.campaign import engines as monte_carlo_engines
from lightcraft_opt.campaign.runner import run_campaign
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.files.campaign import load_campaign

ROOT = REPO_ROOT
OPEN = ROOT / "problems" / "montecarlo_open_loop.toml"
DURATION = 0.3  # s: 8 pulses
RUNS, SEED = 6, 11


@pytest.fixture(scope="module")
def campaign():
    return load_campaign(OPEN, duration=DURATION)


@pytest.fixture(scope="module")
def serial(campaign, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    return run_campaign(campaign, RUNS, SEED, out, workers=1, progress=False)


def _bytes(out: Path) -> bytes:
    return (out / "runs.csv").read_bytes()


def test_dask_cluster_gives_the_identical_table(serial, campaign, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        host="127.0.0.1",
        processes=True,
        n_workers=2,
        threads_per_worker=1,
        dashboard_address=None,
    ) as cluster:
        result = run_campaign(
            campaign, RUNS, SEED, tmp_path, scheduler=cluster.scheduler_address, progress=False
        )
    assert result.engine.startswith("dask tcp://127.0.0.1")
    assert _bytes(tmp_path) == _bytes(serial.out_dir)


def test_unreachable_scheduler_is_named(campaign, tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(monte_carlo_engines, "CONNECT_TIMEOUT", 1.0)
    with pytest.raises(ParameterError, match=r"tcp://127\.0\.0\.1:9"):
        run_campaign(campaign, 2, 0, tmp_path, scheduler="tcp://127.0.0.1:9", progress=False)
