"""Monte Carlo on a Dask cluster: a LocalCluster on the loopback (two worker processes,
one thread each) gives the byte-identical run table of the campaign made serially in this
process (tests/campaign/test_monte_carlo.py has the other engines). A malformed scheduler
address fails before any file is written, an address where nothing listens in well under
the connect timeout, and a client that could not connect leaves nothing to close at exit."""

from __future__ import annotations

import gc
import json
import socket
import sys
import time
from pathlib import Path

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.campaign import engines as monte_carlo_engines
from lightcraft_opt.campaign.runner import run_campaign
from lightcraft_opt.cli import main
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


@pytest.mark.slow
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


@pytest.mark.parametrize(
    ("address", "problem"),
    [
        ("not-an-address", "no port number"),
        ("tcp://:8786", "no host"),
        ("tcp://127.0.0.1:99999", "port 99999 is not in 1..65535"),
        ("tcp://127.0.0.1:port", "no port number"),
        ("udp://127.0.0.1:8786", "unknown scheme 'udp'"),
    ],
)
def test_a_malformed_scheduler_address_fails_before_any_file(campaign, tmp_path, address, problem):
    out = tmp_path / "never"
    with pytest.raises(ParameterError, match="is not a Dask scheduler address") as err:
        run_campaign(campaign, 2, 0, out, scheduler=address, progress=False)
    assert err.value.field == "scheduler" and problem in str(err.value)
    assert not out.exists()


def test_scheduler_addresses_and_files(tmp_path):
    assert monte_carlo_engines.scheduler_address("127.0.0.1:8786") == "tcp://127.0.0.1:8786"
    assert monte_carlo_engines.scheduler_address("tls://[::1]:8786") == "tls://[::1]:8786"
    good, bad = tmp_path / "scheduler.json", tmp_path / "other.json"
    good.write_text(json.dumps({"type": "Scheduler", "address": "tcp://10.0.0.5:8786"}))
    bad.write_text(json.dumps({"type": "Scheduler"}))
    assert monte_carlo_engines.scheduler_address(str(good)) == "tcp://10.0.0.5:8786"
    with pytest.raises(ParameterError, match="not a scheduler file holding an address"):
        monte_carlo_engines.scheduler_address(str(bad))


def test_cli_malformed_scheduler_exits_2_at_once(tmp_path, capsys):
    argv = ["montecarlo", str(OPEN), "--runs", "2", "--scheduler", "not-an-address",
            "--out", str(tmp_path / "o"), "--quiet"]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "lightcraft: error: scheduler: 'not-an-address' is not a Dask scheduler" in err


def test_nothing_listening_fails_in_seconds(campaign, tmp_path):
    """Port 1 on the loopback: refused at once by the plain TCP probe, well before the
    10 s the client would wait."""
    pytest.importorskip("distributed")
    start = time.monotonic()
    with pytest.raises(ParameterError, match=r"cannot reach the Dask scheduler at 'tcp://127\.0"):
        run_campaign(campaign, 2, 0, tmp_path, scheduler="tcp://127.0.0.1:1", progress=False)
    assert time.monotonic() - start < monte_carlo_engines.CONNECT_TIMEOUT / 2


def test_a_server_that_never_answers_fails_in_seconds(campaign, tmp_path, monkeypatch):
    """Something listens but never speaks (a socket nobody accepts on): Dask's handshake
    gives up at the probe's deadline (the client alone would wait for ever)."""
    pytest.importorskip("distributed")
    monkeypatch.setattr(monte_carlo_engines, "PROBE_TIMEOUT", 1.0)
    with socket.socket() as mute:
        mute.bind(("127.0.0.1", 0))
        mute.listen(8)
        address = f"tcp://127.0.0.1:{mute.getsockname()[1]}"
        start = time.monotonic()
        with pytest.raises(ParameterError, match="nothing answered as a Dask scheduler"):
            run_campaign(campaign, 2, 0, tmp_path, scheduler=address, progress=False)
        assert time.monotonic() - start < monte_carlo_engines.PROBE_TIMEOUT + 2


def test_a_client_that_cannot_connect_is_closed(campaign, tmp_path, monkeypatch):
    """A client whose start fails (here: the address unchecked, so the client's own
    parser refuses it) is closed before the error is raised, so its ``__del__`` has
    nothing left to do (unclosed, it waits twice the timeout and prints an "Exception
    ignored" traceback at exit)."""
    pytest.importorskip("distributed")
    monkeypatch.setattr(monte_carlo_engines, "scheduler_address", lambda text: text)
    monkeypatch.setattr(monte_carlo_engines, "_probe", lambda address: None)
    unraisable: list[object] = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    start = time.monotonic()
    with pytest.raises(ParameterError, match="cannot reach the Dask scheduler"):
        run_campaign(campaign, 2, 0, tmp_path, scheduler="not-an-address", progress=False)
    gc.collect()  # the half-made client's __del__ runs here
    assert unraisable == []
    assert time.monotonic() - start < 5
