"""docs/files.md, the reference of the files users write: its examples are files the readers
accept as written (the model path made absolute), so the page cannot drift from the readers
without a test failing."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.files.campaign import load_campaign
from lightcraft_opt.files.closed_loop import load_closed_loop
from lightcraft_opt.files.problem import load_problem

PAGE = REPO_ROOT / "docs" / "files.md"


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", PAGE.read_text(encoding="utf-8"), re.S)


def _example(start: str) -> str:
    (block,) = [b for b in _blocks("toml") if b.startswith(start)]
    return re.sub(r'model = "\.\./models/', f'model = "{REPO_ROOT}/models/', block)


def test_every_toml_example_parses():
    blocks = _blocks("toml")
    assert len(blocks) == 4  # model, problem, closed loop, campaign
    for block in blocks:
        tomllib.loads(block)


def test_the_problem_example_loads(tmp_path: Path):
    path = tmp_path / "problem.toml"
    path.write_text(_example('title = "hold Flight 5'), encoding="utf-8")
    loaded = load_problem(path)
    assert loaded.problem.horizon == 260 and loaded.options.max_iter == 200


def test_the_closed_loop_and_campaign_examples_load(tmp_path: Path):
    closed = _example('title = "nutation suppression')
    path = tmp_path / "closed_loop.toml"
    path.write_text(closed, encoding="utf-8")
    assert load_closed_loop(path).duration == pytest.approx(1.0)
    campaign = _example('controller = "mpc"').replace('controller = "mpc"', "", 1)
    path = tmp_path / "campaign.toml"
    # a campaign seeds each run itself: the page says [plant] seed is refused there
    closed = re.sub(r"\nseed = \d+\n", "\n", closed)
    path.write_text(closed + "\n" + campaign, encoding="utf-8")
    spec = load_campaign(path)
    assert [name for name, _ in spec.dispersions.items] == ["mass", "wind_speed"]
