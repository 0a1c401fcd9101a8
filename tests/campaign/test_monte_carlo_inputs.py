"""What a campaign draws: the distributions' moments, the streams, and the campaign files.

Moments are checked against the distributions' analytic values with tolerances from the
sampling error of N draws (4 standard errors); the truncated normal's standard deviation
at ±3σ is σ √(1 − 2·3·φ(3) / (2Φ(3) − 1)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.paths import REPO_ROOT

from lightcraft_opt.campaign.dispersions import (
    DISPERSED,
    Dispersions,
    Normal,
    Uniform,
    draw,
    draw_many,
    loop_seed,
)
from lightcraft_opt.control.options import ControllerKind
from lightcraft_opt.errors import OptionError, ParameterError, ProblemFileError
from lightcraft_opt.files.campaign import load_campaign

ROOT = REPO_ROOT
N = 4000


def _truncated_std(k: float) -> float:
    phi = math.exp(-0.5 * k * k) / math.sqrt(2 * math.pi)
    mass = math.erf(k / math.sqrt(2))
    return math.sqrt(1 - 2 * k * phi / mass)


def test_normal_and_uniform_moments():
    d = Dispersions(
        (
            ("launch_offset_x", Normal(0.0325, 0.002)),
            ("tilt", Normal(0.0, 0.01, truncate=3.0)),
            ("wind_speed", Uniform(1.0, 4.0)),
        )
    )
    v = draw_many(d, 123, N)
    m = v["launch_offset_x"]
    assert abs(m.mean() - 0.0325) < 4 * 0.002 / math.sqrt(N)
    assert abs(m.std(ddof=1) / 0.002 - 1) < 4 / math.sqrt(2 * N)
    t = v["tilt"]
    assert np.max(np.abs(t)) <= 3 * 0.01
    assert abs(t.std(ddof=1) / (0.01 * _truncated_std(3.0)) - 1) < 4 / math.sqrt(2 * N)
    w = v["wind_speed"]
    assert np.all((w >= 1.0) & (w < 4.0))
    assert abs(w.mean() - 2.5) < 4 * (3 / math.sqrt(12)) / math.sqrt(N)
    assert abs(w.var(ddof=1) / (9 / 12) - 1) < 4 * math.sqrt(0.8 / N)  # Var(s²)/σ⁴ = 0.8/N


def test_draws_depend_on_seed_and_index_only():
    a = Dispersions((("mass", Normal(1.0, 0.1, 3.0)), ("coupling", Uniform(0.5, 1.0))))
    b = Dispersions((("coupling", Uniform(0.5, 1.0)), ("mass", Normal(1.0, 0.1, 3.0))))
    alone = Dispersions((("coupling", Uniform(0.5, 1.0)),))
    assert a == b  # the order given does not matter: kept in DISPERSED order
    assert draw(a, 5, 7) == draw(b, 5, 7)
    # each quantity has its own stream: adding the mass leaves the coupling's draws alone
    assert draw(a, 5, 7)["coupling"] == draw(alone, 5, 7)["coupling"]
    assert draw(a, 5, 7) != draw(a, 5, 8) != draw(a, 6, 7)
    seeds = {loop_seed(5, i) for i in range(100)}
    assert len(seeds) == 100 and all(0 <= s < 2**63 for s in seeds)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: Normal(0.0, -1.0), "sigma"),
        (lambda: Normal(0.0, 1.0, truncate=0.0), "truncate"),
        (lambda: Uniform(2.0, 1.0), "low"),
        (lambda: Dispersions((("spin", Normal(0.0, 1.0)),)), "unknown quantity"),
        (lambda: Dispersions((("tilt", Normal(0, 1)), ("tilt", Normal(0, 2)))), "twice"),
    ],
)
def test_bad_distributions_raise_option_errors(make, match):
    with pytest.raises(OptionError, match=match):
        make()


def test_campaign_files_read_units_and_nominals():
    c = load_campaign(ROOT / "problems" / "montecarlo_open_loop.toml")
    items = dict(c.dispersions.items)
    assert c.controller is ControllerKind.NONE and c.duration == 3.0
    assert items["mass"] == Normal(0.0325, 0.02 * 0.0325, 3.0)
    assert items["launch_offset_x"] == Normal(0.0, 0.003, 3.0)  # sigma_mm = 3
    assert items["launch_offset_y"] == Normal(0.0, 0.003, 3.0)
    assert items["tilt"].sigma == pytest.approx(math.radians(1.0), rel=1e-15)
    assert items["tilt_azimuth"] == Uniform(0.0, 2 * math.pi)  # added: uniform azimuth
    assert items["wind_direction_from"].high == pytest.approx(2 * math.pi, rel=1e-15)
    assert c.columns[: len(DISPERSED) + 2] == ("run", *(col for col, _ in DISPERSED.values()),
                                                "loop_seed")  # fmt: skip
    mpc = load_campaign(ROOT / "problems" / "montecarlo_gust_mpc.toml")
    assert mpc.controller is ControllerKind.MPC
    assert mpc.plant_parameters["gust_L"] == (2.0, 0.0, 0.0)
    assert mpc.loop.faults == (20, 21)


BASE = f"""title = "bad"
model = "{(ROOT / "models" / "flight5.toml").as_posix()}"
duration_s = 0.3
"""


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ('[dispersions.mass]\ndistribution = "gaussian"\nsigma_g = 1\n',
         "dispersions.mass.distribution"),
        ('[dispersions.tilt]\ndistribution = "normal"\nsigma_deg = -1\n',
         "dispersions.tilt.sigma_deg"),
        ('[dispersions.wind_speed]\ndistribution = "uniform"\nlow_mps = 3\nhigh_mps = 1\n',
         "dispersions.wind_speed.low_mps"),
        ('[dispersions.spin]\ndistribution = "normal"\nsigma = 1\n', "dispersions.spin"),
        ('[dispersions.tilt]\ndistribution = "normal"\nsigma_kg = 1\n',
         "dispersions.tilt.sigma_kg"),
        ('[dispersions.mass]\ndistribution = "uniform"\nlow_g = 1\nhigh_g = 2\nsigma_g = 1\n',
         "dispersions.mass.sigma_g"),
        ('[dispersions.launch_offset_x]\ndistribution = "normal"\nrelative_sigma = 0.1\n',
         "dispersions.launch_offset_x.relative_sigma"),
        ('[dispersions.mass]\ndistribution = "normal"\n', "dispersions.mass.sigma"),
        ('[plant]\nseed = 3\n', "plant.seed"),
        ('controller = "pid"\n', "controller"),
        ('[campaign]\ncontroller = "mpc"\n', "campaign.controller"),  # moved to the top
        ("[mpc]\n[director]\n", "controller"),  # both tables: name the one
    ],
)  # fmt: skip
def test_bad_campaign_files_name_the_key(tmp_path, text, key):
    path = tmp_path / "bad.toml"
    path.write_text(BASE + text)
    with pytest.raises(ProblemFileError) as err:
        load_campaign(path)
    assert err.value.field == key, str(err.value)
    assert str(path) in str(err.value)


@pytest.mark.parametrize(
    ("text", "key", "message"),
    [
        # a uniform's bounds: below a bound that may be reached, at an excluded one, above
        ('[dispersions.wind_speed]\ndistribution = "uniform"\nlow_mps = -5\nhigh_mps = 1\n',
         "dispersions.wind_speed.low_mps", "-5 m/s is below 0: a wind speed cannot be negative"),
        ('[dispersions.mass]\ndistribution = "uniform"\nlow_g = 0\nhigh_g = 30\n',
         "dispersions.mass.low_g", "0 g is not above 0: a mass must be positive"),
        ('[dispersions.dropout_rate]\ndistribution = "uniform"\nlow = 0.5\nhigh = 1.5\n',
         "dispersions.dropout_rate.high", "1.5 is above 1: a drop-out rate is a probability"),
        # a truncated normal's mean ± truncate_sigmas·sigma, in the file's unit
        ('[dispersions.mass]\ndistribution = "normal"\nsigma_g = 10\ntruncate_sigmas = 4\n',
         "dispersions.mass.truncate_sigmas",
         "mean - truncate_sigmas·sigma = -7.5 g is not above 0"),
        ('[dispersions.dropout_rate]\ndistribution = "normal"\nmean = 0.97\nsigma = 0.01\n'
         'truncate_sigmas = 4\n', "dispersions.dropout_rate.truncate_sigmas",
         "mean + truncate_sigmas·sigma = 1.01 is above 1"),
        ('[dispersions.inertia_axial]\ndistribution = "normal"\nmean_g_cm2 = -3\n'
         'sigma_g_cm2 = 0\n', "dispersions.inertia_axial.mean_g_cm2",
         "mean -3 g cm^2 is not above 0: an inertia must be positive"),
        ('[dispersions.coupling]\ndistribution = "normal"\nrelative_sigma = 0.5\n'
         'truncate_sigmas = 3\n', "dispersions.coupling.truncate_sigmas",
         "an impulse per pulse must be positive"),
        # an untruncated normal on a bounded quantity reaches past the bound
        ('[dispersions.wind_speed]\ndistribution = "normal"\nmean_mps = 3\nsigma_mps = 0.1\n',
         "dispersions.wind_speed.truncate_sigmas", "missing: an untruncated normal"),
    ],
)  # fmt: skip
def test_a_distribution_outside_its_quantity_s_domain_is_refused(tmp_path, text, key, message):
    path = tmp_path / "bad.toml"
    path.write_text(BASE + text)
    with pytest.raises(ProblemFileError) as err:
        load_campaign(path)
    assert err.value.field == key, str(err.value)
    assert message in str(err.value)


@pytest.mark.parametrize(("old", "new"), [("offset_east", "x"), ("offset_north", "y")])
def test_a_dispersion_under_its_former_name_says_what_it_was_renamed(tmp_path, old, new):
    """The launch offsets were offset_east / offset_north before issue 19 (runs.csv says
    x and y for L components): the old table is refused with its new name."""
    path = tmp_path / "old.toml"
    path.write_text(BASE + f'[dispersions.{old}]\ndistribution = "normal"\nsigma_mm = 2\n')
    with pytest.raises(ProblemFileError) as err:
        load_campaign(path)
    assert str(err.value) == (
        f"{path}: dispersions.{old}: '{old}' was renamed 'launch_offset_{new}': write "
        f"[dispersions.launch_offset_{new}], its keys unchanged"
    )


def test_distributions_inside_their_domains_are_taken(tmp_path):
    """Reaching a closed bound, a point mass, and an untruncated normal where any value is
    physical (an offset) are all fine."""
    path = tmp_path / "good.toml"
    path.write_text(BASE + '[dispersions.wind_speed]\ndistribution = "uniform"\nlow_mps = 0\n'
                    'high_mps = 2\n[dispersions.dropout_rate]\ndistribution = "uniform"\n'
                    'low = 0\nhigh = 1\n[dispersions.mass]\ndistribution = "normal"\n'
                    'sigma_g = 0\n[dispersions.launch_offset_x]\ndistribution = "normal"\n'
                    'sigma_mm = 2\n')  # fmt: skip
    items = dict(load_campaign(path).dispersions.items)
    assert items["wind_speed"] == Uniform(0.0, 2.0) and items["dropout_rate"] == Uniform(0, 1)
    assert items["mass"].sigma == 0 and items["launch_offset_x"] == Normal(0.0, 0.002)


@pytest.mark.parametrize(
    ("name", "dist", "match"),
    [
        ("wind_speed", Uniform(-5.0, 1.0), r"low = -5 is below 0: a wind speed"),
        ("mass", Normal(0.03, 0.01, 4.0), r"mean - truncate·sigma = -0.01 is not above 0"),
        ("dropout_rate", Normal(0.5, 0.1), r"untruncated normal"),
        ("coupling", Uniform(0.0, 0.1), r"not above 0: an impulse per pulse"),
    ],
)
def test_dispersions_refuse_a_support_outside_the_domain(name, dist, match):
    with pytest.raises(OptionError, match=rf"Dispersions\.{name}: .*{match}"):
        Dispersions(((name, dist),))


@pytest.mark.parametrize(
    ("text", "kind"),
    [
        ('controller = "lqr"\n[mpc]\n', ControllerKind.LQR),
        ("[director]\n", ControllerKind.DIRECTOR),
        ("[mpc]\n", ControllerKind.MPC),
        ("[campaign]\ncompiled = false\n", ControllerKind.NONE),  # neither: the open loop
    ],
)
def test_a_campaign_names_its_controller_as_a_closed_loop_file_does(tmp_path, text, kind):
    """The closed-loop file's rule (files/closed_loop.py), with the open loop for a file
    without controller tables; the shipped campaign files name theirs."""
    path = tmp_path / "c.toml"
    path.write_text(BASE + text)
    assert load_campaign(path).controller is kind
    for name, shipped in [
        ("montecarlo_open_loop", ControllerKind.NONE),
        ("montecarlo_gust_mpc", ControllerKind.MPC),
        ("montecarlo_director", ControllerKind.DIRECTOR),
    ]:
        assert load_campaign(ROOT / "problems" / f"{name}.toml").controller is shipped


def test_the_former_campaign_controller_says_where_it_went(tmp_path):
    path = tmp_path / "old.toml"
    path.write_text(BASE + '[campaign]\ncontroller = "director"\n')
    with pytest.raises(ProblemFileError) as err:
        load_campaign(path)
    assert str(err.value) == (
        f"{path}: campaign.controller: 'campaign.controller' was renamed 'controller': write "
        'controller = "director" at the top of the file, before the first table (as in a '
        "closed-loop file)"
    )


# --------------------------------------------------------------------------- model overrides
DESIGN = ROOT / "problems" / "montecarlo_design.toml"
RPM = 2 * math.pi / 60


def _design_with_craft_table(tmp_path, craft_table: str):
    """montecarlo_design.toml written again with a [model_overrides.craft] table."""
    text = DESIGN.read_text(encoding="utf-8")
    model = (ROOT / "models" / "flight5.toml").as_posix()
    text = text.replace('model = "../models/flight5.toml"', f'model = "{model}"', 1)
    laser = (ROOT / "models" / "plvts-waist.toml").as_posix()
    text = text.replace('laser = "plvts-waist.toml"', f'laser = "{laser}"', 1)
    wind = "[model_overrides.environment.wind]"
    text = text.replace(wind, f"[model_overrides.craft]\n{craft_table}\n\n{wind}", 1)
    path = tmp_path / "design.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_model_overrides_fly_the_campaign_a_table_would(tmp_path):
    from lightcraft_opt.campaign.runner import campaign_fingerprint

    craft = {"inertia_transverse_g_cm2": 400.0, "spin_rpm": 8200.0}
    given = load_campaign(DESIGN, duration=0.5, model_overrides={"craft": craft})
    path = _design_with_craft_table(tmp_path, "inertia_transverse_g_cm2 = 400.0\nspin_rpm = 8200.0")
    written = load_campaign(path, duration=0.5)
    assert campaign_fingerprint(given, 7) == campaign_fingerprint(written, 7)
    assert given.model.craft.spin == pytest.approx(8200 * RPM, rel=1e-15)
    assert given.model.craft.inertia_transverse == pytest.approx(4.0e-5, rel=1e-15)
    # the file's own overrides stay: its waist laser and its crosswind
    plain = load_campaign(DESIGN, duration=0.5)
    assert given.model.laser == plain.model.laser
    assert given.model.environment == plain.model.environment
    # the dispersions are drawn about the overridden moment (1 % relative in the file)
    dist = dict(given.dispersions.items)["inertia_transverse"]
    assert dist.mean == pytest.approx(4.0e-5, rel=1e-12)
    assert dist.sigma == pytest.approx(4.0e-7, rel=1e-12)


def test_a_model_override_replaces_the_file_s_key_in_any_unit(tmp_path):
    path = _design_with_craft_table(tmp_path, "spin_rpm = 8200.0")
    c = load_campaign(path, duration=0.5, model_overrides={"craft": {"spin_rad_per_s": 900.0}})
    assert c.model.craft.spin == 900.0


def test_a_bad_model_override_is_named(tmp_path):
    with pytest.raises(ProblemFileError) as err:
        load_campaign(DESIGN, model_overrides={"craft": {"spin_rmp": 8200.0}})
    assert err.value.field == "model_overrides.craft.spin_rmp", str(err.value)
    with pytest.raises(ParameterError) as err:
        load_campaign(DESIGN, model_overrides=[("craft", {})])  # type: ignore[arg-type]
    assert err.value.field == "model_overrides"
    # a file whose [model_overrides] is not a table is refused, with overrides or without
    path = tmp_path / "flat.toml"
    path.write_text(BASE + "model_overrides = 3\n")
    for extra in (None, {"craft": {"spin_rpm": 8200.0}}):
        with pytest.raises(ProblemFileError) as err:
            load_campaign(path, model_overrides=extra)
        assert err.value.field == "model_overrides" and "must be a table" in str(err.value)
