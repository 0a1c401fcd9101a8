"""The one factory of the closed loop's controllers: one function builds them from an Enum
(docs/architecture.md#rule-7).

``lightcraft closed-loop``, the campaign runner and Python build every controller with
:func:`build_controller` from a :class:`~lightcraft_opt.control.options.ControllerKind`;
the callers choose the kind and the options (a campaign passes them without a wall-clock
budget), the factory how each kind is put together:

- ``NONE``: :class:`~.controllers.OpenLoopController`, the nominal input every pulse;
- ``MPC``: :class:`~.mpc.MpcController` on the linear prediction model in coning
  coordinates (:func:`~.prediction_model.coning_model`, linearised from ``plant`` once
  per model and cached on disk: tens of seconds the first time,
  bench/README.md#mpcpy-the-nutation-mpcs-solve-time-against-ipopt-on-the-same-qp);
- ``LQR``: :class:`~.controllers.LqrController` on the same model, with the MPC's weights;
- ``DIRECTOR``: :class:`~.director.DirectorController`; on a craft with RCS whose
  ``DirectorOptions.rcs`` is ``NUTATION``, with the nutation MPC alongside.

:func:`build_estimator` likewise builds what tells the controller the state from an
:class:`~lightcraft_opt.control.options.EstimatorSpec`, and :func:`build_tracker` the sensor
suite with it, as the CLI and the campaigns fly them (docs/estimation.md#output-feedback).
"""

from __future__ import annotations

from lightcraft_opt.control.controllers import Controller, LqrController, OpenLoopController
from lightcraft_opt.control.director import DirectorController
from lightcraft_opt.control.estimation import (
    BEAM_OFFSET,
    EkfOptions,
    Estimator,
    ExtendedKalmanFilter,
    MheOptions,
    MovingHorizonEstimator,
    PsiEstimationModel,
    SensorOptions,
    SensorSuite,
    UkfOptions,
    UnscentedKalmanFilter,
    estimation_model,
)
from lightcraft_opt.control.mpc import MpcController
from lightcraft_opt.control.options import (
    ControllerKind,
    DirectorOptions,
    DirectorRcs,
    EstimatorKind,
    EstimatorSpec,
    MpcOptions,
)
from lightcraft_opt.control.prediction_model import coning_model
from lightcraft_opt.errors import OptionError
from lightcraft_opt.model import Model
from lightcraft_opt.symbolic.maps.pulse_map import PulseMap

__all__ = ["build_controller", "build_estimator", "build_tracker", "controller_kind"]


def controller_kind(kind: ControllerKind | str, name: str = "kind") -> ControllerKind:
    """``kind`` as a :class:`ControllerKind` (a member, or its value: "mpc", "lqr",
    "director", "none"); else an OptionError naming ``name`` and the allowed values."""
    if isinstance(kind, ControllerKind):
        return kind
    try:
        return ControllerKind(kind)
    except ValueError:
        allowed = [k.value for k in ControllerKind]
        raise OptionError(f"{name} must be one of {allowed}, got {kind!r}") from None


def build_controller(
    kind: ControllerKind | str,
    model: Model,
    plant: PulseMap,
    *,
    mpc: MpcOptions | None = None,
    director: DirectorOptions | None = None,
    compiled: bool | None = None,
) -> Controller:
    """The controller ``kind`` of ``model`` for the plant Φ ``plant`` (module docstring).

    Parameters
    ----------
    kind : which controller (:class:`ControllerKind`, or its value).
    model : the controller's model (what it believes; the plant may differ).
    plant : the closed loop's Φ: its input layout is the controller's output, and the MPC's
        and LQR's prediction model is linearised from it.
    mpc : the MPC's options (default :class:`MpcOptions`); the LQR takes their weights, the
        director its nutation MPC's.
    director : the director's options (default :class:`DirectorOptions`).
    compiled : compile the director's Ψ pieces and the controllers' steps (None:
        ``compiled.compile_by_default``).

    Raises
    ------
    OptionError naming ``build_controller.kind`` when ``kind`` is not a controller.
    """
    kind = controller_kind(kind, "build_controller.kind")
    mpc = MpcOptions() if mpc is None else mpc
    director = DirectorOptions() if director is None else director
    assert plant.inputs is not None  # build_pulse_map always records it
    if kind is ControllerKind.NONE:
        return OpenLoopController(model, plant.inputs)
    if kind is ControllerKind.DIRECTOR:
        nutation = None
        if model.craft.rcs is not None and director.rcs is DirectorRcs.NUTATION:
            prediction = coning_model(model, pulse_map=plant, cache=True)
            nutation = MpcController(model, mpc, prediction=prediction, compiled=compiled)
        return DirectorController(
            model, plant.inputs, director, nutation=nutation, compiled=compiled
        )
    # linearised once per model structure and numbers, then read from the disk cache
    prediction = coning_model(model, pulse_map=plant, cache=True)
    if kind is ControllerKind.MPC:
        return MpcController(model, mpc, prediction=prediction, compiled=compiled)
    return LqrController(model, prediction, mpc.weights)


#: The slow states the built estimators carry beside Ψ's state: the wind, the coupling,
#: and the rotor's moments, whose 1 % errors put the cone's phase half a radian off a pulse
#: (docs/estimation.md#what-the-director-needs).
SLOW_STATES = ("wind", "coupling", "inertia")


def build_estimator(
    spec: EstimatorSpec, model: Model, sensors: SensorSuite | None
) -> Estimator | None:
    """The estimator ``spec`` names for ``model``, reading ``sensors``; None for
    ``TRUTH`` (the controller is told the true state with the loop's noise).

    Parameters
    ----------
    spec : which estimator and its options, SI (:class:`EstimatorSpec`).
    model : the estimator's model (what it believes: the controller's).
    sensors : the sensor suite the closed loop reads and the estimator models.

    Raises
    ------
    OptionError naming ``build_estimator.spec`` for a spec that is not an EstimatorSpec,
    ``build_estimator.sensors`` when an estimator has no suite to read.
    """
    if not isinstance(spec, EstimatorSpec):
        raise OptionError(f"build_estimator.spec must be an EstimatorSpec, got {spec!r}")
    if spec.kind is EstimatorKind.TRUTH:
        return None
    if sensors is None:
        raise OptionError(
            f"build_estimator.sensors: the {spec.kind.value!r} estimator needs a suite"
        )
    # Ψ on the director's optic (one compiled Ψ for both), each sensor's h and R from the suite
    psi = PsiEstimationModel(
        estimation_model(model),
        {name: (sensors.measurement(name), sensors.covariance(name)) for name in sensors.names},
        slow=SLOW_STATES,
    )
    ekf = EkfOptions()
    prior = ekf.prior + spec.prior_sigmas()  # later pairs override earlier ones
    scale = float(spec.options.get("noise_scale", ekf.noise_scale))
    chosen = spec.options.get("second_order", False)
    curved = chosen if isinstance(chosen, tuple) else BEAM_OFFSET if chosen else ()
    if spec.kind is EstimatorKind.EKF:
        options = EkfOptions(prior=prior, noise_scale=scale, second_order=curved)
        return ExtendedKalmanFilter(psi, options)
    if spec.kind is EstimatorKind.UKF:
        return UnscentedKalmanFilter(psi, UkfOptions(prior=prior, noise_scale=scale))
    # the MHE starts from the filter's priors: one belief about the launch
    mhe = MheOptions()
    horizon = int(spec.options.get("horizon", mhe.horizon))
    return MovingHorizonEstimator(
        psi,
        MheOptions(
            horizon=horizon,
            max_iter=int(spec.options.get("max_iter", mhe.max_iter)),
            relinearize=int(spec.options.get("relinearize", mhe.relinearize or horizon)),
            prior_sigma=ekf.prior_default,
            prior_sigmas=prior,
            second_order=curved,
        ),
    )


def build_tracker(
    spec: EstimatorSpec, model: Model, sensors: SensorOptions | None
) -> tuple[SensorSuite | None, Estimator | None]:
    """The sensor suite and the estimator a closed loop flies with (its ``sensors=`` and
    ``estimator=``): (None, None) for ``TRUTH``, whose controller is told the true state
    (the sensors, if any, are read by no one); else the suite of ``sensors`` (None: the
    default camera, :class:`SensorOptions`) on ``model`` and :func:`build_estimator`'s
    estimator reading it."""
    if not isinstance(spec, EstimatorSpec):
        raise OptionError(f"build_tracker.spec must be an EstimatorSpec, got {spec!r}")
    if spec.kind is EstimatorKind.TRUTH:
        return None, None
    suite = SensorSuite(model, sensors)
    return suite, build_estimator(spec, model, suite)
