"""The map an OCP predicts with and where its derivatives come from (CompiledOcp's build).

Φ interpreted, as the NLP differentiates it: the problem's full map
(:func:`~lightcraft_opt.compiled.memo.pulse_map_for` with the problem's options over
``OcpOptions.pulse_map``), the reduced map Ψ (``OcpOptions.prediction`` "reduced"), or the
caller's. Its derivatives: Φ's explicit chain (also in the designed entries of p) over
compiled pieces from the disk cache where a compiler works, interpreted otherwise; None
when casadi's AD differentiates the NLP (``OcpOptions.chain_derivatives`` off, or a map
without pieces).
"""

from __future__ import annotations

from lightcraft_opt.compiled import (
    compile_by_default,
    derivatives_for,
    pulse_map_for,
    saved_derivative_pieces,
    saved_pulse_map_derivatives,
)
from lightcraft_opt.compiled.cache import BuildReport
from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.layout import RcsProfile
from lightcraft_opt.ocp.nlp_solver import uses_chain
from lightcraft_opt.ocp.options import OcpOptions, PredictionMap
from lightcraft_opt.ocp.problem import OcpProblem
from lightcraft_opt.symbolic.maps.options import PulseMapOptions
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap
from lightcraft_opt.symbolic.maps.pulse_map_derivatives import (
    PulseMapDerivatives,
    chain_derivatives,
)
from lightcraft_opt.symbolic.maps.reduced_map import ReducedMapOptions, reduced_pulse_map

__all__ = ["prediction_derivatives", "prediction_map"]


def prediction_map(
    problem: OcpProblem, opts: OcpOptions, pulse_map: PulseMap | None
) -> tuple[PulseMap, PulseMapOptions | None]:
    """(Φ the NLP predicts with, the options this built it with: None when the caller gave
    ``pulse_map`` or the prediction is the reduced map). A given map must take the
    problem's inputs (a ParameterError naming ``pulse_map``)."""
    map_options = problem.pulse_map_options(opts.pulse_map)
    if pulse_map is not None:
        phi = pulse_map
    elif opts.prediction is PredictionMap.REDUCED:
        if map_options.rcs_profile is not RcsProfile.HOLD:
            raise OptionError(
                "OcpOptions.prediction 'reduced' takes held RCS levels only; this problem's "
                f"RCS profile is {map_options.rcs_profile.value!r}"
            )
        reduced = ReducedMapOptions(substeps=map_options.substeps, dense=map_options.dense)
        phi = reduced_pulse_map(problem.model, reduced)
    else:
        phi = pulse_map_for(problem.model, map_options, compiled=False)
    built = pulse_map is None and opts.prediction is PredictionMap.FULL
    if phi.step.size1_in(1) != problem.inputs.size or (
        phi.inputs is not None and phi.inputs != problem.inputs
    ):
        raise ParameterError(
            "pulse_map",
            f"takes inputs {phi.inputs or phi.step.size1_in(1)}, the problem "
            f"{problem.inputs}: build it from the problem's model with "
            "problem.pulse_map_options(...)",
        )
    return phi, map_options if built else None


def prediction_derivatives(
    problem: OcpProblem,
    opts: OcpOptions,
    phi: PulseMap,
    built_with: PulseMapOptions | None,
    report: BuildReport | None = None,
) -> PulseMapDerivatives | None:
    """Φ's chain derivatives for the NLP of ``problem`` (module docstring), in v = (x, u,
    p[design]) (the launch spin is an entry of x0, not of p); ``built_with`` the options
    :func:`prediction_map` built ``phi`` with (then the per-process memo serves them)."""
    if not uses_chain(opts) or phi.pieces is None:
        return None
    design = tuple(sorted(int(i) for i in problem.design_layout.p_index))
    if built_with is not None:
        return derivatives_for(problem.model, built_with, design=design, report=report)
    if compile_by_default():
        return saved_pulse_map_derivatives(phi, report=report, design=design)
    pieces = saved_derivative_pieces(phi, design=design, report=report)
    return chain_derivatives(phi, pieces, design=design)
