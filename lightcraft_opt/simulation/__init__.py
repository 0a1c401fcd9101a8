"""Simulation: open-loop flights stepped by the pulse map Φ, their results, the end-of-flight
rule, and an independent variable-step reference for the coast.

- :mod:`.simulate`: :func:`simulate`, a flight pulse by pulse (or a second of pulses a call);
- :mod:`.flight_log`: :class:`FlightLog`, the record of a flight and the rule that ends it,
  shared with the closed loop;
- :mod:`.flight_measures`: :func:`flight_result`, derived measures (tilt, coning, H, energy);
- :mod:`.result`: :class:`SimulationResult`, :class:`SimulationStatus`, :class:`PulseRecord`;
- :mod:`.coast_reference`: the laser-off coast by CVODES (:func:`simulate_coast`) and how
  it integrates (:class:`SimulationOptions`).
"""

from lightcraft_opt.simulation.coast_reference import (
    SimulationOptions,
    coast_integrator,
    simulate_coast,
)
from lightcraft_opt.simulation.flight_log import LEFT_BEAM_PULSES, FlightLog, beam_gap
from lightcraft_opt.simulation.flight_measures import flight_result
from lightcraft_opt.simulation.result import PulseRecord, SimulationResult, SimulationStatus
from lightcraft_opt.simulation.simulate import InputPolicy, simulate

__all__ = [
    "LEFT_BEAM_PULSES",
    "FlightLog",
    "InputPolicy",
    "PulseRecord",
    "SimulationOptions",
    "SimulationResult",
    "SimulationStatus",
    "beam_gap",
    "coast_integrator",
    "flight_result",
    "simulate",
    "simulate_coast",
]
