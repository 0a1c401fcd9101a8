"""The lightcraft engine: optic, blast ring, impulse model, health and ablation
(docs/physics.md#engine-parameters)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.checks import (
    at_most,
    finite,
    in_range,
    non_negative,
    positive,
    set_frozen,
)
from lightcraft_opt.model.limits import MAX_QUADRATURE

__all__ = ["Engine", "ImpulseModel"]


class ImpulseModel(Enum):
    """How the captured energy's asymmetry becomes lateral and angular impulse."""

    SECTOR = "sector"
    KERNEL = "kernel"


@dataclass(frozen=True)
class Engine:
    """The lightcraft engine: optic, blast ring, impulse model, health and ablation.

    Geometry is in B from P (docs/frames.md); values are guesses to calibrate
    (docs/physics.md#engine-parameters) unless a model file says otherwise.

    Attributes
    ----------
    capture_radius : outer radius of the optic that collects the beam [m].
    shadow_radius : radius of the central shadow (nose, no capture) [m].
    ring_radius : radius of the focal (blast) ring [m].
    ring_height : axial position of the ring along b1 from P [m].
    impulse_model : sector model or kernel form.
    blast_angle : effective radial tilt beta of each sector's reaction [rad]; its sign
        decides whether the lateral push restores (sector model), its size the ratio
        tipping / lateral = R_f / tan(beta): the default 0.5 lets the craft ride the beam
        (models/flight5.toml says why).
    lateral_gain, tipping_gain : k_L, k_M of the kernel form [-] (signed).
    kernel_offset : d0, offset of peak lateral impulse in the kernel form [m].
    health_floor : air-mode thrust fraction left after overheating, g_inf [-].
    health_pulse : pulse number of the overheating step, n_f [-].
    health_width : width of the step in pulses, w_n [-].
    ablation : liner mass lost per captured joule [kg/J] (Delrin).
    spent_coupling : axial impulse per captured joule once the liner is spent [N s/J];
        ``None`` means the flight's own coupling (air mode).
    quadrature_radial, quadrature_azimuthal : points of the optic quadrature.
    """

    capture_radius: float = 0.055
    shadow_radius: float = 0.0075
    ring_radius: float = 0.05
    ring_height: float = 0.0
    impulse_model: ImpulseModel = ImpulseModel.SECTOR
    blast_angle: float = 0.5
    lateral_gain: float = 0.1
    tipping_gain: float = 0.1
    kernel_offset: float = 0.045
    health_floor: float = 0.3
    health_pulse: float = 100.0
    health_width: float = 8.0
    ablation: float = 30e-9
    spent_coupling: float | None = None
    quadrature_radial: int = 8
    quadrature_azimuthal: int = 32

    def __post_init__(self) -> None:
        if not isinstance(self.impulse_model, ImpulseModel):
            raise ParameterError(
                "engine.impulse_model",
                f"must be one of {[m.value for m in ImpulseModel]}, got {self.impulse_model!r}",
            )
        set_frozen(self, "capture_radius", positive("engine.capture_radius", self.capture_radius))
        set_frozen(self, "shadow_radius", non_negative("engine.shadow_radius", self.shadow_radius))
        if self.shadow_radius >= self.capture_radius:
            raise ParameterError("engine.shadow_radius", "must be less than the capture radius")
        set_frozen(self, "ring_radius", positive("engine.ring_radius", self.ring_radius))
        set_frozen(self, "ring_height", finite("engine.ring_height", self.ring_height))
        set_frozen(self, "blast_angle", in_range("engine.blast_angle", self.blast_angle, -1.5, 1.5))
        set_frozen(self, "lateral_gain", finite("engine.lateral_gain", self.lateral_gain))
        set_frozen(self, "tipping_gain", finite("engine.tipping_gain", self.tipping_gain))
        set_frozen(self, "kernel_offset", positive("engine.kernel_offset", self.kernel_offset))
        set_frozen(self, "health_floor", in_range("engine.health_floor", self.health_floor, 0, 1))
        set_frozen(self, "health_pulse", positive("engine.health_pulse", self.health_pulse))
        set_frozen(self, "health_width", positive("engine.health_width", self.health_width))
        set_frozen(self, "ablation", non_negative("engine.ablation", self.ablation))
        if self.spent_coupling is not None:
            set_frozen(
                self, "spent_coupling", non_negative("engine.spent_coupling", self.spent_coupling)
            )
        for name in ("quadrature_radial", "quadrature_azimuthal"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 2:
                raise ParameterError(f"engine.{name}", f"must be an integer >= 2, got {v!r}")
            at_most(
                f"engine.{name}",
                v,
                MAX_QUADRATURE[name],
                "points",
                "8 x 32 already gives the captured energy within 1e-3; a finer grid adds "
                "nothing measurable and the pulse map grows with the product of the two",
            )
