"""What a closed loop's sensors see: the observability study of its estimator's model.

The estimator a closed-loop file builds (control/factory.py: Ψ with the wind, the coupling
and the rotor's moments as slow states, each sensor's reading and noise from the suite) is
flown along a nominal climb: the craft from ``altitude`` [m] at ``climb_speed`` [m/s] up,
coning slightly (w_B = (0, 0.3, -0.2) rad/s), under the model's nominal inputs, in calm
air (the wind is a state to find; the nominal inputs would lose the craft in a crosswind).
For each number of pulses N and each set of sensors, the Gramian of δ[0] from the readings
of the first N pulses (control/estimation/psi_observability.py) says how well each state
can be known: its Cramér-Rao bound, the condition number of the Gramian scaled by the
estimator's prior sigmas (like with like), and the directions no reading constrains
(docs/estimation.md#observability-on-ψ-with-the-wind-and-the-coupling).

The sets of sensors: the camera alone, then every sensor of the file together (when it has
more than the camera), so the table says what a gyro or a spin sensor buys.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

from lightcraft_opt.control.estimation import (
    ExtendedKalmanFilter,
    PsiEstimationModel,
    SensorOptions,
    SensorSuite,
    model_flight,
    model_observability,
)
from lightcraft_opt.control.estimation.psi_model import estimated_units
from lightcraft_opt.control.factory import build_estimator
from lightcraft_opt.control.options import PRIOR_SLOTS, EstimatorKind, EstimatorSpec
from lightcraft_opt.errors import ParameterError
from lightcraft_opt.layout import initial_state, nominal_inputs
from lightcraft_opt.model import Model

__all__ = ["BOOKKEEPING", "ObservabilityRow", "ObservabilityStudy", "observability_study"]

#: Entries of s the study takes as known: Ψ counts them (the liner, the RCS propellant, the
#: engine's load), no sensor is needed for them; and the rotor's moments over the model's,
#: which the estimator carries but which with the spin form one direction that neither a
#: camera nor a gyro sees (J ω is what the dynamics feel): left in, that direction would
#: hide every other bound.
BOOKKEEPING = (
    "liner_mass",
    "rcs_mass",
    "engine_load",
    "inertia[transverse]",
    "inertia[axial]",
)

#: The body rates of the nominal climb [rad/s] (frame B): a slight coning to see.
CLIMB_RATES_B = (0.0, 0.3, -0.2)


@dataclass(frozen=True)
class ObservabilityRow:
    """One N and one set of sensors.

    Attributes
    ----------
    pulses : N, the pulses read.
    sensors : the sensors read at every pulse.
    condition : the Gramian's condition number, scaled by the prior sigmas [-] (inf: a
        direction is unseen).
    bounds : {state: Cramér-Rao bound on its standard deviation [the state's SI unit]}
        (inf where the state leans on an unseen direction).
    unseen : the unseen directions, each {state: component of its unit vector}.
    """

    pulses: int
    sensors: tuple[str, ...]
    condition: float
    bounds: dict[str, float]
    unseen: list[dict[str, float]]


@dataclass(frozen=True)
class ObservabilityStudy:
    """The study of one model and sensor suite (module docstring).

    Attributes
    ----------
    model : the model's name.
    states : the entries of s studied (SI units: r_L [m], v_L [m/s] in L, H_L [kg m²/s]
        in L, the coning offset [-], wind_L [m/s] in L at the reference height, the
        coupling [N s/J], the moments over the model's [-]).
    prior : {state: the estimator's prior sigma [its SI unit]}.
    rows : one per (N, sensor set), N ascending, the camera alone first.
    climb : how the climb was flown, in words.
    units : {state: its SI unit} (``"m"``, ``"kg m^2/s"``, ``"-"`` ...).
    """

    model: str
    states: tuple[str, ...]
    prior: dict[str, float]
    rows: tuple[ObservabilityRow, ...]
    climb: str
    units: dict[str, str]

    def summary(self, shown: Sequence[str] | None = None) -> str:
        """A table: per row, the condition number and each shown state's bound [SI]."""
        names = [s for s in (shown or self.states) if s in self.states]
        head = f"{'N':>3s}  {'sensors':14s} {'condition':>9s}  " + "  ".join(
            f"{s:>12s}" for s in names
        )
        lines = [f"{self.model}: {self.climb}", head]
        prior = f"{'':3s}  {'(prior)':14s} {'':9s}  " + "  ".join(
            f"{self.prior[s]:12.3g}" for s in names
        )
        lines.append(prior)
        for row in self.rows:
            lines.append(
                f"{row.pulses:3d}  {'+'.join(row.sensors):14s} {row.condition:9.2g}  "
                + "  ".join(f"{row.bounds[s]:12.3g}" for s in names)
            )
        return "\n".join(lines)


def _calm(model: Model) -> Model:
    """``model`` in calm air: its wind's speed 0 (the rest of the wind as it was)."""
    env = model.environment
    return dataclasses.replace(
        model,
        environment=dataclasses.replace(env, wind=dataclasses.replace(env.wind, speed_ref=0.0)),
    )


def observability_study(
    model: Model,
    sensors: SensorOptions,
    *,
    pulses: Sequence[int] = (10, 20, 40),
    estimator: EstimatorSpec | None = None,
    altitude: float = 2.0,
    climb_speed: float = 4.0,
) -> ObservabilityStudy:
    """The observability study (module docstring) of ``model``'s estimator reading
    ``sensors``.

    Parameters
    ----------
    model : the controller's model (what the estimator believes).
    sensors : the suite the closed loop reads (at least a camera).
    pulses : the numbers N of pulses read, each >= 2.
    estimator : the file's ``[estimator]``, any kind: its prior sigmas scale the study
        (default the EKF's defaults); its other options do not enter.
    altitude : height of the climb's first pulse above the pad [m], > 0.
    climb_speed : vertical speed there [m/s], >= 0.
    """
    if not isinstance(sensors, SensorOptions) or sensors.camera is None:
        raise ParameterError("sensors", "the study needs a camera ([sensors.camera])")
    counts = sorted({int(n) for n in pulses})
    if not counts or counts[0] < 2:
        raise ParameterError("pulses", f"needs numbers of pulses >= 2, got {list(pulses)!r}")
    if not altitude > 0:
        raise ParameterError("altitude", f"needs a height above the pad > 0 m, got {altitude!r}")
    if not climb_speed >= 0:
        raise ParameterError("climb_speed", f"needs >= 0 m/s, got {climb_speed!r}")
    calm = _calm(model)
    given = {} if estimator is None else estimator.options
    priors = {k: v for k, v in given.items() if k in PRIOR_SLOTS}  # what scales the study
    spec = EstimatorSpec(EstimatorKind.EKF, priors)
    suite = SensorSuite(calm, sensors)
    ekf = build_estimator(spec, calm, suite)
    assert isinstance(ekf, ExtendedKalmanFilter)
    psi = ekf.model
    assert isinstance(psi, PsiEstimationModel)
    names = tuple(psi.names)
    prior = ekf.options.prior_sigmas(names)
    x0 = initial_state(
        psi.model, r_L=(0.0, 0.0, altitude), v_L=(0.0, 0.0, climb_speed), w_B=CLIMB_RATES_B
    )
    u = nominal_inputs(psi.model, psi.psi.inputs)
    S, F, _ = model_flight(psi, psi.start(x0), u, counts[-1])
    kept = [s for s in names if s not in BOOKKEEPING]
    read: list[tuple[str, ...]] = [("camera",)]
    every = tuple(suite.names)
    if len(every) > 1:
        read.append(("camera", *(s for s in every if s != "camera")))
    rows = []
    for n in counts:
        for names_read in read:
            seen = model_observability(psi, S[:n], F[: n - 1], names_read, states=kept, scale=prior)
            bounds = {s: seen.bound(s) * float(prior[names.index(s)]) for s in kept}
            rows.append(ObservabilityRow(n, names_read, seen.condition, bounds, seen.unseen()))
    climb = (
        f"from {altitude:g} m at {climb_speed:g} m/s up, w_B = {CLIMB_RATES_B} rad/s, "
        "nominal inputs, calm air"
    )
    sigma = {s: float(prior[names.index(s)]) for s in kept}
    units = estimated_units(psi.slow)
    unit = {s: units[s] for s in kept}
    return ObservabilityStudy(model.name, tuple(kept), sigma, tuple(rows), climb, unit)
