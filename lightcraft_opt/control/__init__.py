"""Control at pulse rate: controllers, the nutation MPC and its QP, their prediction model,
and the closed loop that flies them on the full pulse map Φ.

- :mod:`.options`: :class:`ControllerKind` (which controller), :class:`MpcOptions`,
  :class:`ControlWeights`, :class:`DirectorOptions` (with :class:`FocusSchedule`,
  :class:`DirectorRcs`), :class:`ClosedLoopOptions` (noise, plant dispersion, drop-outs,
  injected faults), :class:`EstimatorSpec` (which :class:`EstimatorKind` tells the
  controller the state);
- :mod:`.factory`: :func:`build_controller`, every controller from a :class:`ControllerKind`,
  and :func:`build_estimator`;
- :mod:`.prediction_model`: linear models in coning coordinates scheduled on spin and
  altitude (:func:`coning_model`), the MPC's and the LQR controller's prediction;
- :mod:`.controllers`: the ``step(x)`` interface (:class:`Controller`, a Protocol a
  user's own controller meets: docs/mpc.md#your-own-controller),
  :class:`OpenLoopController`, :class:`LqrController`, and the coning frame
  (:class:`ConingFrame`: coning coordinates of a state, Φ's saturated input of the
  model's inputs) and phase tracker they share;
- :mod:`.mpc_qp`: the stage-structured QP (HPIPM, ...); :mod:`.mpc_step`: the MPC's whole
  pulse as casadi Functions of (state, memory); :mod:`.mpc`: :class:`MpcController`, the
  shell around them;
- :mod:`.director_qp`, :mod:`.director`: :class:`DirectorController`, beam tracking by a
  real-time iteration on the reduced map Ψ (beam pointing, focus, pulse energy);
- :mod:`.estimation`: readings, estimates, the estimators' interface, and the output
  feedback a closed loop flies with them;
- :mod:`.closed_loop`: :func:`closed_loop`, ``u = controller.step(x); x = Φ(x, u, p)``;
- :mod:`.result`: :class:`ClosedLoopResult` with the controller's log and step statistics,
  and an estimator's :class:`EstimationLog`.

The what (options, result) never imports the how (an import-linter contract). Nothing
here imports python-control: the linear models, the Riccati gain and the focus schedule
come from :mod:`lightcraft_opt.linear` (docs/architecture.md#contracts).
"""

from __future__ import annotations

from lightcraft_opt.control.closed_loop import closed_loop, disperse, measured
from lightcraft_opt.control.controllers import (
    ConingFrame,
    Controller,
    LqrController,
    Measurement,
    OpenLoopController,
    StageWeights,
    stage_weights,
)
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.factory import build_controller, build_estimator
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.mpc_qp import NutationQp, QpStatus
from lightcraft_opt.control.options import (
    ClosedLoopOptions,
    ControllerFault,
    ControllerKind,
    ControlWeights,
    DirectorOptions,
    DirectorRcs,
    DirectorWeights,
    EstimatorKind,
    EstimatorSpec,
    FocusSchedule,
    MeasurementNoise,
    MpcOptions,
    MpcSolver,
    PlantDispersion,
)
from lightcraft_opt.control.prediction_model import ConingModel, coning_model, turn
from lightcraft_opt.control.result import (
    ClosedLoopResult,
    ControllerLog,
    ControllerStatus,
    EstimationLog,
    StepStats,
)

__all__ = [
    "ClosedLoopOptions",
    "ClosedLoopResult",
    "ConingFrame",
    "ConingModel",
    "ControlWeights",
    "Controller",
    "ControllerFault",
    "ControllerKind",
    "ControllerLog",
    "ControllerStatus",
    "DirectorController",
    "DirectorOptions",
    "DirectorRcs",
    "DirectorWeights",
    "EstimationLog",
    "EstimatorKind",
    "EstimatorSpec",
    "FocusSchedule",
    "LqrController",
    "Measurement",
    "MeasurementNoise",
    "MpcController",
    "MpcOptions",
    "MpcSolver",
    "NutationQp",
    "OpenLoopController",
    "PlantDispersion",
    "QpStatus",
    "StageWeights",
    "StepStats",
    "build_controller",
    "build_estimator",
    "closed_loop",
    "coning_model",
    "disperse",
    "measured",
    "stage_weights",
    "turn",
]
