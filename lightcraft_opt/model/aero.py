"""The craft's aerodynamics: the coefficients C_D, C_L, C_M (paper Eqs. 2-5, corrected) and
the friction torque that slows the rotor's spin (docs/physics.md#aero-coefficients,
docs/physics.md#spin-decay)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from lightcraft_opt.errors import ParameterError
from lightcraft_opt.model.checks import (
    finite,
    increasing,
    non_negative,
    positive,
    series,
    set_frozen,
)

__all__ = [
    "PAPER_CD",
    "PAPER_CL",
    "PAPER_CM",
    "AeroModel",
    "Aerodynamics",
    "SpinDecay",
    "SpinDecayModel",
]


class AeroModel(Enum):
    """How the aerodynamic coefficients C_D, C_L, C_M depend on angle of attack."""

    POLYNOMIAL = "polynomial"
    TABLE = "table"


class SpinDecayModel(Enum):
    """Aerodynamic friction torque on the rotor about b1."""

    NONE = "none"
    EXPONENTIAL = "exponential"
    ROTATING_DISK = "rotating_disk"


# Paper Eq. 5 (the seed paper, docs/references.md#paper-eq-5) with the C_M typo corrected
# (docs/physics.md#aero-coefficients); ascending powers of alpha [rad].
PAPER_CD = (0.731, 0.0398, -0.8463, 0.3928)
PAPER_CL = (0.0, 0.5531, 0.5531, -0.2724, -0.3317, 0.1993)
PAPER_CM = (0.0, 0.080, -0.0583, -0.3585, 0.8794, -0.6619, 0.1598)


@dataclass(frozen=True)
class Aerodynamics:
    """Aerodynamic coefficients of the craft (paper Eqs. 2-5, corrected).

    Polynomials hold ascending powers of the angle of attack alpha [rad] on 0..pi/2;
    a table holds values at ``table_alpha`` [rad] (0..pi/2, increasing). Coefficients
    beyond pi/2 mirror those below: C(alpha) = C(pi - alpha) (docs/frames.md).

    Attributes
    ----------
    reference_length
        c in M = q S c C_M [m]; ``None`` means the craft diameter.
    cd_scale, cl_scale, cm_scale
        Multipliers on C_D, C_L, C_M (calibration handles) [-].
    magnus_force_coefficient, magnus_moment_coefficient
        Magnus force and moment coefficients per unit spin ratio [-] (default 0: off).
    """

    model: AeroModel = AeroModel.POLYNOMIAL
    cd: tuple[float, ...] = PAPER_CD
    cl: tuple[float, ...] = PAPER_CL
    cm: tuple[float, ...] = PAPER_CM
    table_alpha: tuple[float, ...] = ()
    reference_length: float | None = None
    cd_scale: float = 1.0
    cl_scale: float = 1.0
    cm_scale: float = 1.0
    magnus_force_coefficient: float = 0.0
    magnus_moment_coefficient: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.model, AeroModel):
            raise ParameterError(
                "aero.model", f"must be one of {[m.value for m in AeroModel]}, got {self.model!r}"
            )
        for name in ("cd", "cl", "cm"):
            set_frozen(self, name, series(f"aero.{name}", getattr(self, name)))
        set_frozen(self, "table_alpha", series("aero.table_alpha", self.table_alpha, 0))
        if self.model is AeroModel.TABLE:
            n = len(self.table_alpha)
            if n < 2:
                raise ParameterError("aero.table_alpha", "a table needs at least 2 angles")
            increasing("aero.table_alpha", self.table_alpha)
            if self.table_alpha[0] < 0.0 or self.table_alpha[-1] > math.pi / 2 + 1e-12:
                raise ParameterError("aero.table_alpha", "angles must lie in [0, pi/2] rad")
            for name in ("cd", "cl", "cm"):
                if len(getattr(self, name)) != n:
                    raise ParameterError(f"aero.{name}", f"table needs {n} values (one per angle)")
        if self.reference_length is not None:
            set_frozen(
                self, "reference_length", positive("aero.reference_length", self.reference_length)
            )
        for name in ("cd_scale", "cl_scale", "cm_scale"):
            set_frozen(self, name, non_negative(f"aero.{name}", getattr(self, name)))
        for name in ("magnus_force_coefficient", "magnus_moment_coefficient"):
            set_frozen(self, name, finite(f"aero.{name}", getattr(self, name)))


@dataclass(frozen=True)
class SpinDecay:
    """Friction torque on the rotor about b1.

    ``EXPONENTIAL``: T = -J w_R / time_constant (paper Eq. 6, docs/references.md#paper-eq-6).
    ``ROTATING_DISK``: von Karman disk friction (docs/references.md#von-karman-1921), laminar
    or turbulent, whichever is larger, times ``disk_faces`` (docs/physics.md#spin-decay).
    The formulas are the two-sided (both faces wetted) results of Schlichting
    (docs/references.md#schlichting), so 1 means a whole disk.
    """

    model: SpinDecayModel = SpinDecayModel.NONE
    time_constant: float = 15.0
    disk_faces: float = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.model, SpinDecayModel):
            raise ParameterError(
                "spin_decay.model",
                f"must be one of {[m.value for m in SpinDecayModel]}, got {self.model!r}",
            )
        set_frozen(self, "time_constant", positive("spin_decay.time_constant", self.time_constant))
        set_frozen(self, "disk_faces", non_negative("spin_decay.disk_faces", self.disk_faces))
