"""Campaign files: a closed-loop file with the distributions of a Monte Carlo campaign.

A closed-loop file (files/closed_loop.py) with ``[campaign]`` and one ``[dispersions.<name>]``
table per dispersed quantity; every key, the quantities, their units, nominal values and
physical domains: docs/files/campaign.md. Problems raise
:class:`~lightcraft_opt.errors.ProblemFileError` naming the file and the key as written.
"""

from __future__ import annotations

import difflib
import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from lightcraft_opt.campaign.dispersions import (
    DISPERSED,
    DOMAINS,
    Dispersions,
    Distribution,
    Normal,
    Uniform,
    support,
)
from lightcraft_opt.campaign.spec import DISPERSED_PARAMETER, Campaign
from lightcraft_opt.control.options import ControllerKind
from lightcraft_opt.errors import OptionError, ParameterError, ProblemFileError
from lightcraft_opt.files import schema
from lightcraft_opt.files.closed_loop import ClosedLoopProblem, closed_loop_from_tables
from lightcraft_opt.files.problem import as_problem_file_errors, with_model_overrides
from lightcraft_opt.files.problem_tables import Table, read_table
from lightcraft_opt.files.schema import NUMBER, QUANTITIES, TEXT, Spec, quantity
from lightcraft_opt.layout import PARAMETERS, parameter_values

__all__ = ["DISPERSED_KIND", "TABLES", "distribution_keys", "load_campaign"]

_CAMPAIGN: dict[str, Spec] = {"compiled": Spec("switch")}
#: The tables of a campaign file beside a closed-loop file's (files/closed_loop.py TABLES):
#: ``[campaign]``; ``[dispersions.<name>]`` has :func:`distribution_keys` for the quantity
#: :data:`DISPERSED_KIND` gives each name. Every table and key: docs/files/campaign.md.
TABLES: dict[str, dict[str, Spec]] = {"campaign": _CAMPAIGN}
#: Quantity of each dispersed value's keys (None: bare numbers).
DISPERSED_KIND: dict[str, str | None] = {
    "mass": "mass",
    "inertia_axial": "inertia",
    "inertia_transverse": "inertia",
    "coupling": "impulse",
    "dropout_rate": None,
    "launch_offset_x": "length",
    "launch_offset_y": "length",
    "tilt": "angle",
    "tilt_azimuth": "angle",
    "wind_speed": "speed",
    "wind_direction_from": "angle",
}
#: Dispersion tables renamed: old -> new name, refused with the new one.
_FORMER = {"offset_east": "launch_offset_x", "offset_north": "launch_offset_y"}
_DISTRIBUTIONS = ("normal", "uniform")


def load_campaign(
    path: str | Path,
    *,
    duration: float | None = None,
    model_overrides: Mapping[str, Any] | None = None,
) -> Campaign:
    """Read a campaign file (docs/files/campaign.md) and the model file it names.

    Parameters
    ----------
    path : the file.
    duration : replaces the file's ``duration`` [s] of each flight.
    model_overrides : tables merged into the file's ``[model_overrides]``, keyed as in a
        file, units in the keys: ``{"craft": {"spin_rpm": 8200.0}}`` flies the campaign at
        another launch spin (a key replaces the file's key for the same field in any unit).
        The dispersions are drawn about the overridden values.

    Raises
    ------
    ProblemFileError naming the file and the key as written (an override's key as if it
    were written in the file's ``[model_overrides]``).
    """
    file = Path(path)
    with as_problem_file_errors():
        src, data = schema.read_toml(file)
        data = with_model_overrides(src, data, model_overrides)
        raw_campaign = data.pop("campaign", {})
        raw_dispersions = data.pop("dispersions", {})
        plant = data.get("plant", {})
        if isinstance(plant, dict) and "seed" in plant:
            raise ProblemFileError(
                src,
                "plant.seed",
                "a campaign seeds each run from its seed (--seed) and the run index: "
                "remove plant.seed",
            )
        if isinstance(raw_campaign, dict) and "controller" in raw_campaign:
            value = raw_campaign["controller"]
            raise ProblemFileError(
                src,
                "campaign.controller",
                f"{schema.renamed('campaign.controller', 'controller')}: write controller = "
                f"{json.dumps(value)} at the top of the file, before the first table (as in "
                "a closed-loop file)",
            )
        problem = closed_loop_from_tables(src, file, data, duration, absent=ControllerKind.NONE)
        table = read_table(src, raw_campaign, "campaign", _CAMPAIGN)
        dispersions = _dispersions(src, raw_dispersions, _nominal(problem))
        return Campaign(
            model=problem.model,
            duration=problem.duration,
            controller=problem.controller,
            x0=problem.x0,
            mpc=problem.mpc,
            director=problem.director,
            loop=problem.loop,
            plant_parameters=problem.plant_parameters,
            dispersions=dispersions,
            compiled=table.values.get("compiled"),
            title=problem.title,
            estimator=problem.estimator,
            sensors=problem.sensors,
        )


def _nominal(problem: ClosedLoopProblem) -> dict[str, float]:
    """Each dispersed quantity's value without the campaign (SI)."""
    p = parameter_values(problem.model, problem.plant_parameters)
    out = {name: float(p[PARAMETERS.index(slot)][0]) for name, slot in DISPERSED_PARAMETER.items()}
    out["dropout_rate"] = problem.loop.dropout_rate
    for name in ("launch_offset_x", "launch_offset_y", "tilt", "tilt_azimuth"):
        out[name] = 0.0
    return out


def _dispersions(src: str, raw: Any, nominal: dict[str, float]) -> Dispersions:
    if not isinstance(raw, dict):
        raise ProblemFileError(src, "dispersions", f"must be a table [dispersions], got {raw!r}")
    items: list[tuple[str, Normal | Uniform]] = []
    for name, table in raw.items():
        where = f"dispersions.{name}"
        if name in _FORMER:
            new = _FORMER[name]
            raise ProblemFileError(
                src,
                where,
                f"{schema.renamed(name, new)}: write [dispersions.{new}], its keys unchanged",
            )
        if name not in DISPERSED:
            close = difflib.get_close_matches(name, list(DISPERSED), n=1, cutoff=0.6)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise ProblemFileError(
                src, where, f"unknown dispersion; {hint}allowed: {', '.join(DISPERSED)}"
            )
        dist = _distribution(src, where, table, DISPERSED_KIND[name], nominal[name])
        _check_domain(src, name, where, table, dist)
        items.append((name, dist))
    if "tilt" in raw and "tilt_azimuth" not in raw:
        items.append(("tilt_azimuth", Uniform(0.0, 2.0 * math.pi)))
    return Dispersions(tuple(items))


def distribution_keys(kind: str | None) -> dict[str, Spec]:
    """The keys of a ``[dispersions.<name>]`` table for a quantity of ``kind`` (a key of
    schema.QUANTITIES, None for a bare number)."""
    value = quantity(kind) if kind else NUMBER
    return {
        "distribution": TEXT,
        "mean": value,
        "sigma": value,
        "relative_sigma": NUMBER,
        "truncate_sigmas": NUMBER,
        "low": value,
        "high": value,
    }


def _distribution(
    src: str, where: str, raw: Any, kind: str | None, nominal: float
) -> Normal | Uniform:
    table = read_table(src, raw, where, distribution_keys(kind), required=("distribution",))
    v = table.values
    name = v["distribution"]
    if name not in _DISTRIBUTIONS:
        close = difflib.get_close_matches(str(name), _DISTRIBUTIONS, n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ProblemFileError(
            src,
            table.key("distribution"),
            f"unknown distribution {name!r}; {hint}allowed: {', '.join(_DISTRIBUTIONS)}",
        )
    allowed = {"normal": ("mean", "sigma", "relative_sigma", "truncate_sigmas"),
               "uniform": ("low", "high")}[name]  # fmt: skip
    for field in v:
        if field != "distribution" and field not in allowed:
            raise ProblemFileError(
                src, table.key(field), f"not a key of a {name} distribution: {', '.join(allowed)}"
            )
    try:
        if name == "uniform":
            for field in ("low", "high"):
                if field not in v:
                    raise ProblemFileError(src, table.key(field), "missing required key")
            if v["low"] > v["high"]:
                raise ProblemFileError(
                    src, table.key("low"), f"must be <= high, got {v['low']!r} > {v['high']!r} (SI)"
                )
            return Uniform(v["low"], v["high"])
        if ("sigma" in v) == ("relative_sigma" in v):
            raise ProblemFileError(
                src, table.key("sigma"), "give one of sigma (absolute) or relative_sigma"
            )
        field = "sigma" if "sigma" in v else "relative_sigma"
        if v[field] < 0:
            raise ProblemFileError(src, table.key(field), f"must be >= 0, got {v[field]!r}")
        if field == "relative_sigma" and nominal == 0.0:
            raise ProblemFileError(
                src,
                table.key(field),
                "the nominal value is 0: give an absolute sigma (with its unit in the key)",
            )
        sigma = v["sigma"] if field == "sigma" else v["relative_sigma"] * abs(nominal)
        truncate = v.get("truncate_sigmas")
        if truncate is not None and not truncate > 0:
            raise ProblemFileError(
                src, table.key("truncate_sigmas"), f"must be > 0, got {truncate!r}"
            )
        return Normal(v.get("mean", nominal), sigma, truncate)
    except (OptionError, ParameterError) as err:
        raise ProblemFileError(src, where, str(err)) from err


def _check_domain(src: str, name: str, where: str, raw: dict[str, Any], dist: Distribution) -> None:
    """Refuse ``dist`` if it draws values outside quantity ``name``'s physical domain,
    naming the key and the value in the file's units."""
    domain, kind = DOMAINS[name], DISPERSED_KIND[name]
    keys = {_field(key): key for key in raw}
    table = Table(where, {}, keys)

    def shown(si: float, *fields: str) -> str:
        """``si`` in the unit of the first of ``fields`` written with one (else SI)."""
        units = QUANTITIES[kind] if kind else {"": "1"}
        written = [keys[f].split("_", 1)[1] for f in fields if "_" in keys.get(f, "")]
        unit = next((u for u in written if u in units), "")
        unit = unit or next(u for u, factor in units.items() if factor == "1")
        return f"{si / float(units[unit]):g} {schema.unit_symbol(unit)}".rstrip()

    def refuse(key: str, what: str, si: float, *fields: str) -> None:
        if domain.below(si):
            bound = domain.low_text()
        elif domain.above(si):
            bound = f"above {domain.high:g}"
        else:
            return
        raise ProblemFileError(src, key, f"{what}{shown(si, *fields)} is {bound}: {domain.why}")

    low, high = support(dist)
    if isinstance(dist, Uniform):
        refuse(table.key("low"), "", low, "low")
        refuse(table.key("high"), "", high, "high")
        return
    if not (math.isfinite(low) and math.isfinite(high)):
        if domain.bounded:
            raise ProblemFileError(
                src,
                table.key("truncate_sigmas"),
                f"missing: an untruncated normal draws any value, and {domain.why}; give "
                "truncate_sigmas so that mean ± truncate_sigmas·sigma stays inside",
            )
        return
    refuse(table.key("mean"), "mean ", dist.mean, "mean", "sigma")
    sides = (("-", low), ("+", high))
    for sign, si in sides:
        what = f"mean {sign} truncate_sigmas·sigma = "
        refuse(table.key("truncate_sigmas"), what, si, "sigma", "mean")


def _field(key: str) -> str:
    """The field a key of a dispersion table gives (``low_mps`` -> ``low``)."""
    for field in ("relative_sigma", "truncate_sigmas", "distribution", "mean", "sigma", "low",
                  "high"):  # fmt: skip
        if key == field or key.startswith(field + "_"):
            return field
    return key
