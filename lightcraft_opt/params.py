"""Physical parameters as frozen, validated dataclasses, all in SI units.

Every dataclass checks itself on creation and raises :class:`ParameterError`
naming the offending field, so a model that exists is a model that makes sense.
Frames are those of ``docs/frames.md``: vectors named ``*_B`` have components in
the despun body frame B, measured from the rotor reference point P (a point on
the spin axis, the rotor's dry mass centre).

Unit conversion never happens here: see :mod:`lightcraft_opt.files.model`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import Enum

from lightcraft_opt.errors import ParameterError

__all__ = [
    "AeroModel",
    "Aerodynamics",
    "BeamProfile",
    "BeamSizeModel",
    "Carrier",
    "Craft",
    "Engine",
    "Environment",
    "Flight",
    "FlightRecord",
    "ImpulseModel",
    "Laser",
    "Liner",
    "Model",
    "Propellant",
    "Rcs",
    "Site",
    "SpinDecay",
    "SpinDecayModel",
    "Thruster",
    "Wind",
]

Vec3 = tuple[float, float, float]


# --------------------------------------------------------------------------- checks
def _finite(name: str, value: float) -> float:
    if isinstance(value, bool):
        raise ParameterError(name, f"must be a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, f"must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ParameterError(name, f"must be finite, got {v}")
    return v


def _positive(name: str, value: float) -> float:
    v = _finite(name, value)
    if v <= 0.0:
        raise ParameterError(name, f"must be positive, got {v}")
    return v


def _non_negative(name: str, value: float) -> float:
    v = _finite(name, value)
    if v < 0.0:
        raise ParameterError(name, f"must not be negative, got {v}")
    return v


def _in_range(name: str, value: float, lo: float, hi: float) -> float:
    v = _finite(name, value)
    if not lo <= v <= hi:
        raise ParameterError(name, f"must lie in [{lo}, {hi}], got {v}")
    return v


def _vec3(name: str, value: Sequence[float]) -> Vec3:
    try:
        items = list(value)
    except TypeError:
        raise ParameterError(name, f"must be a list of 3 numbers, got {value!r}") from None
    if len(items) != 3:
        raise ParameterError(name, f"must have 3 components, got {len(items)}")
    x, y, z = (_finite(f"{name}[{i}]", c) for i, c in enumerate(items))
    return (x, y, z)


def _unit_vec3(name: str, value: Sequence[float]) -> Vec3:
    x, y, z = _vec3(name, value)
    n = math.sqrt(x * x + y * y + z * z)
    if n < 1e-12:
        raise ParameterError(name, "must be a non-zero direction")
    return (x / n, y / n, z / n)


def _series(name: str, value: Sequence[float], min_len: int = 1) -> tuple[float, ...]:
    try:
        items = tuple(_finite(f"{name}[{i}]", c) for i, c in enumerate(value))
    except TypeError:
        raise ParameterError(name, f"must be a list of numbers, got {value!r}") from None
    if len(items) < min_len:
        raise ParameterError(name, f"needs at least {min_len} values, got {len(items)}")
    return items


def _increasing(name: str, values: tuple[float, ...]) -> None:
    if any(b <= a for a, b in itertools.pairwise(values)):
        raise ParameterError(name, "must be strictly increasing")


def _triangle(name: str, a: float, b: float, c: float) -> None:
    """Principal moments of a real body obey a <= b + c (and permutations)."""
    tol = 1e-12 * (a + b + c)
    for x, y, z in ((a, b, c), (b, c, a), (c, a, b)):
        if x > y + z + tol:
            raise ParameterError(
                name,
                f"principal moments ({a:.6g}, {b:.6g}, {c:.6g}) kg m^2 violate the triangle "
                f"inequality: {x:.6g} > {y:.6g} + {z:.6g}, no real body has them",
            )


def _check_axisymmetric(name: str, axial: float, transverse: float) -> None:
    _triangle(name, axial, transverse, transverse)


def _set(obj: object, attr: str, value: object) -> None:
    object.__setattr__(obj, attr, value)


def _at_most(name: str, value: float, limit: float, unit: str, reason: str) -> float:
    """``value`` if it is at most ``limit``, else a ParameterError giving the physical
    ``reason`` of the bound (a finite number far outside it would load and then crash, or
    fly nonsense)."""
    if value > limit:
        raise ParameterError(name, f"{value:.6g} {unit} is above {limit:.6g} {unit}: {reason}")
    return value


#: Largest values the model is meant for, with the reason (docs/physics.md#validity).
MAX_CRAFT_MASS = 10.0  # kg
MAX_RIM_SPEED = 500.0  # m/s
MAX_WIND_SPEED = 100.0  # m/s
MAX_PULSE_RATE = 1000.0  # Hz
MAX_QUADRATURE = {"quadrature_radial": 64, "quadrature_azimuthal": 256}
_NO_LAUNCH_WIND = "stronger than any surface wind recorded (113 m/s); no launch flies in it"
_REFILL = (
    "the engine model is one blast per pulse in an optic refilled with air, which takes "
    "about a millisecond; the paper's craft flew at 10-28 Hz"
)


# --------------------------------------------------------------------------- craft parts
class Propellant(Enum):
    """What the engine heats: ambient air or an ablative Delrin liner."""

    AIR = "air"
    DELRIN = "delrin"


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
            _set(self, name, _series(f"aero.{name}", getattr(self, name)))
        _set(self, "table_alpha", _series("aero.table_alpha", self.table_alpha, 0))
        if self.model is AeroModel.TABLE:
            n = len(self.table_alpha)
            if n < 2:
                raise ParameterError("aero.table_alpha", "a table needs at least 2 angles")
            _increasing("aero.table_alpha", self.table_alpha)
            if self.table_alpha[0] < 0.0 or self.table_alpha[-1] > math.pi / 2 + 1e-12:
                raise ParameterError("aero.table_alpha", "angles must lie in [0, pi/2] rad")
            for name in ("cd", "cl", "cm"):
                if len(getattr(self, name)) != n:
                    raise ParameterError(f"aero.{name}", f"table needs {n} values (one per angle)")
        if self.reference_length is not None:
            _set(
                self, "reference_length", _positive("aero.reference_length", self.reference_length)
            )
        for name in ("cd_scale", "cl_scale", "cm_scale"):
            _set(self, name, _non_negative(f"aero.{name}", getattr(self, name)))
        for name in ("magnus_force_coefficient", "magnus_moment_coefficient"):
            _set(self, name, _finite(f"aero.{name}", getattr(self, name)))


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
        _set(self, "time_constant", _positive("spin_decay.time_constant", self.time_constant))
        _set(self, "disk_faces", _non_negative("spin_decay.disk_faces", self.disk_faces))


@dataclass(frozen=True)
class Liner:
    """Delrin ablative liner: a thin ring on the spin axis, part of the rotor.

    Attributes
    ----------
    mass : kg, at launch.
    radius : ring radius [m].
    axial_offset : ring centre along b1 from P [m].
    """

    mass: float
    radius: float
    axial_offset: float = 0.0

    def __post_init__(self) -> None:
        _set(self, "mass", _positive("liner.mass", self.mass))
        _set(self, "radius", _positive("liner.radius", self.radius))
        _set(self, "axial_offset", _finite("liner.axial_offset", self.axial_offset))


@dataclass(frozen=True)
class Carrier:
    """Despun carrier (platform) B of a gyrostat; absent for every craft flown.

    Attributes
    ----------
    mass : kg.
    inertia : (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) central inertia in B [kg m^2].
    position_B : carrier mass centre from P, B frame [m].
    """

    mass: float
    inertia: tuple[float, float, float, float, float, float]
    position_B: Vec3 = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        _set(self, "mass", _positive("carrier.mass", self.mass))
        vals = _series("carrier.inertia", self.inertia, 6)
        if len(vals) != 6:
            raise ParameterError("carrier.inertia", f"needs 6 values, got {len(vals)}")
        _set(self, "inertia", vals)
        _set(self, "position_B", _vec3("carrier.position_B", self.position_B))
        principal = _symmetric_eigenvalues(vals)
        if min(principal) <= 0.0:
            raise ParameterError(
                "carrier.inertia", f"must be positive definite, principal moments {principal}"
            )
        _triangle("carrier.inertia", *principal)


def _symmetric_eigenvalues(i6: Sequence[float]) -> tuple[float, float, float]:
    """Eigenvalues of a symmetric 3x3 matrix given as (xx, yy, zz, xy, xz, yz)."""
    import numpy as np

    xx, yy, zz, xy, xz, yz = i6
    m = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    a, b, c = np.linalg.eigvalsh(m)
    return (float(a), float(b), float(c))


@dataclass(frozen=True)
class Thruster:
    """One RCS thruster fixed in B.

    Attributes
    ----------
    position_B : point of action from P, B frame [m].
    direction_B : direction of the force on the craft, B frame (normalised on creation).
    max_thrust : N.
    """

    position_B: Vec3
    direction_B: Vec3
    max_thrust: float

    def __post_init__(self) -> None:
        _set(self, "position_B", _vec3("thruster.position_B", self.position_B))
        _set(self, "direction_B", _unit_vec3("thruster.direction_B", self.direction_B))
        _set(self, "max_thrust", _positive("thruster.max_thrust", self.max_thrust))


@dataclass(frozen=True)
class Rcs:
    """Reaction control system: thrusters fed from one tank.

    Attributes
    ----------
    isp : specific impulse [s].
    propellant_mass : kg at launch.
    tank_position_B : propellant mass centre from P, B frame [m].
    """

    thrusters: tuple[Thruster, ...]
    isp: float
    propellant_mass: float
    tank_position_B: Vec3 = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not self.thrusters:
            raise ParameterError("rcs.thrusters", "an RCS needs at least one thruster")
        for i, t in enumerate(self.thrusters):
            if not isinstance(t, Thruster):
                raise ParameterError(f"rcs.thrusters[{i}]", "must be a Thruster")
        _set(self, "thrusters", tuple(self.thrusters))
        _set(self, "isp", _positive("rcs.isp", self.isp))
        _set(self, "propellant_mass", _non_negative("rcs.propellant_mass", self.propellant_mass))
        _set(self, "tank_position_B", _vec3("rcs.tank_position_B", self.tank_position_B))


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
        _set(self, "capture_radius", _positive("engine.capture_radius", self.capture_radius))
        _set(self, "shadow_radius", _non_negative("engine.shadow_radius", self.shadow_radius))
        if self.shadow_radius >= self.capture_radius:
            raise ParameterError("engine.shadow_radius", "must be less than the capture radius")
        _set(self, "ring_radius", _positive("engine.ring_radius", self.ring_radius))
        _set(self, "ring_height", _finite("engine.ring_height", self.ring_height))
        _set(self, "blast_angle", _in_range("engine.blast_angle", self.blast_angle, -1.5, 1.5))
        _set(self, "lateral_gain", _finite("engine.lateral_gain", self.lateral_gain))
        _set(self, "tipping_gain", _finite("engine.tipping_gain", self.tipping_gain))
        _set(self, "kernel_offset", _positive("engine.kernel_offset", self.kernel_offset))
        _set(self, "health_floor", _in_range("engine.health_floor", self.health_floor, 0, 1))
        _set(self, "health_pulse", _positive("engine.health_pulse", self.health_pulse))
        _set(self, "health_width", _positive("engine.health_width", self.health_width))
        _set(self, "ablation", _non_negative("engine.ablation", self.ablation))
        if self.spent_coupling is not None:
            _set(
                self, "spent_coupling", _non_negative("engine.spent_coupling", self.spent_coupling)
            )
        for name in ("quadrature_radial", "quadrature_azimuthal"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 2:
                raise ParameterError(f"engine.{name}", f"must be an integer >= 2, got {v!r}")
            _at_most(
                f"engine.{name}",
                v,
                MAX_QUADRATURE[name],
                "points",
                "8 x 32 already gives the captured energy within 1e-3; a finer grid adds "
                "nothing measurable and the pulse map grows with the product of the two",
            )


@dataclass(frozen=True)
class Craft:
    """A lightcraft: the spinning rotor, optionally a despun carrier, liner and RCS.

    Attributes
    ----------
    name : label.
    diameter : m; S = pi diameter^2 / 4 is the aerodynamic reference area.
    mass : rotor mass at launch, liner included [kg] (paper Table 1 "launch mass",
        docs/references.md#paper-table-1).
    inertia_axial : J, rotor central moment about b1 at launch, liner included [kg m^2].
    inertia_transverse : I, rotor central moment about b2, b3 at launch [kg m^2].
    spin : rotor spin rate relative to B at launch [rad/s].
    propellant : air or Delrin.
    """

    name: str
    diameter: float
    mass: float
    inertia_axial: float
    inertia_transverse: float
    spin: float
    propellant: Propellant = Propellant.AIR
    liner: Liner | None = None
    carrier: Carrier | None = None
    rcs: Rcs | None = None
    aero: Aerodynamics = field(default_factory=Aerodynamics)
    spin_decay: SpinDecay = field(default_factory=SpinDecay)
    engine: Engine = field(default_factory=Engine)

    def __post_init__(self) -> None:
        _set(self, "diameter", _positive("craft.diameter", self.diameter))
        _set(self, "mass", _positive("craft.mass", self.mass))
        _set(self, "inertia_axial", _positive("craft.inertia_axial", self.inertia_axial))
        _set(
            self,
            "inertia_transverse",
            _positive("craft.inertia_transverse", self.inertia_transverse),
        )
        _set(self, "spin", _finite("craft.spin", self.spin))
        _at_most(
            "craft.mass",
            self.mass,
            MAX_CRAFT_MASS,
            "kg",
            "the engine model is fitted to craft of 10-100 g (docs/physics.md#validity)",
        )
        rim_speed = abs(self.spin) * self.diameter / 2
        if rim_speed > MAX_RIM_SPEED:
            raise ParameterError(
                "craft.spin",
                f"the rim would move at {rim_speed:.6g} m/s (above {MAX_RIM_SPEED:g} m/s): the "
                "hoop stress rho v^2 of a rim that fast exceeds the strength of any aluminium "
                "or composite rotor (about 430 m/s for 7075 aluminium)",
            )
        if not isinstance(self.propellant, Propellant):
            raise ParameterError(
                "craft.propellant",
                f"must be one of {[p.value for p in Propellant]}, got {self.propellant!r}",
            )
        _check_axisymmetric("craft.inertia", self.inertia_axial, self.inertia_transverse)
        rim = self.mass * (self.diameter / 2) ** 2
        if self.inertia_axial > rim * (1 + 1e-9):
            raise ParameterError(
                "craft.inertia_axial",
                f"{self.inertia_axial:.6g} kg m^2 exceeds mass x (diameter / 2)^2 = {rim:.6g} "
                "kg m^2, the moment with all the mass on the rim: no rotor inside the "
                "diameter has it",
            )
        if self.liner is not None:
            lm = self.liner.mass
            if lm >= self.mass:
                raise ParameterError("liner.mass", "must be less than the craft launch mass")
            j_dry, i_dry = self.dry_rotor_inertia()
            if j_dry <= 0.0 or i_dry <= 0.0:
                raise ParameterError(
                    "liner", "the liner ring alone has more inertia than the whole rotor"
                )
            _check_axisymmetric("craft.inertia (without liner)", j_dry, i_dry)
        if self.rcs is not None and self.carrier is None:
            _, ty, tz = self.rcs.tank_position_B
            if abs(ty) > 0.0 or abs(tz) > 0.0:
                raise ParameterError(
                    "rcs.tank_position_B",
                    "without a carrier the tank spins with the rotor and must sit on the "
                    "spin axis b1 (components 2 and 3 zero)",
                )

    @property
    def reference_area(self) -> float:
        """S = pi D^2 / 4 [m^2]."""
        return math.pi * self.diameter**2 / 4.0

    @property
    def reference_length(self) -> float:
        """Moment reference length c [m] (paper Eq. 4 corrected)."""
        return self.aero.reference_length or self.diameter

    def dry_rotor_inertia(self) -> tuple[float, float]:
        """(J, I) of the rotor without its liner, about the rotor dry mass centre P [kg m^2]."""
        if self.liner is None:
            return self.inertia_axial, self.inertia_transverse
        lm, r, z = self.liner.mass, self.liner.radius, self.liner.axial_offset
        # The launch inertia is about the launch rotor mass centre, at z_c = lm z / m.
        zc = lm * z / self.mass
        j_ring = lm * r**2
        i_ring_about_c = lm * r**2 / 2.0 + lm * (z - zc) ** 2
        m_dry = self.mass - lm
        return (
            self.inertia_axial - j_ring,
            self.inertia_transverse - i_ring_about_c - m_dry * zc**2,
        )

    @property
    def has_carrier(self) -> bool:
        """True for a gyrostat with a despun carrier; False for the spinning body flown."""
        return self.carrier is not None

    @property
    def thruster_count(self) -> int:
        """RCS thrusters of the craft (0 without an RCS): the n of the RCS input slots."""
        return len(self.rcs.thrusters) if self.rcs else 0


# --------------------------------------------------------------------------- laser, site, world
class BeamSizeModel(Enum):
    """How the beam's outer side grows along the beam."""

    LINEAR = "linear"  # a(z) = a0 + divergence z
    WAIST = "waist"  # a(z) = a_w sqrt(1 + ((z - z_focus) / z_R)^2), focus steerable


class BeamProfile(Enum):
    """Transverse fluence profile of the beam (used by the beam model)."""

    HOLLOW_SQUARE = "hollow_square"
    TOP_HAT = "top_hat"
    GAUSSIAN = "gaussian"


@dataclass(frozen=True)
class Laser:
    """A pulsed laser and its beam director.

    Attributes
    ----------
    pulse_energy_max : J per pulse the laser can deliver.
    pulse_rate : Hz.
    pulse_duration : s.
    wavelength : m.
    profile : transverse beam profile.
    hole_ratio : inner/outer side of a hollow square [-].
    edge_width : soft-edge width of the profile [m].
    divergence : full-angle growth of the beam side with range [rad] (LINEAR).
    size_model : linear divergence or a waist whose focus distance is an input.
    rayleigh_range : z_R of the waist form [m].
    pointing_limit : largest lateral beam-axis offset the director reaches [m].
    focus_range : (nearest, farthest) focus distance [m].
    """

    name: str
    pulse_energy_max: float
    pulse_rate: float
    pulse_duration: float
    wavelength: float
    profile: BeamProfile = BeamProfile.HOLLOW_SQUARE
    hole_ratio: float = 0.4
    edge_width: float = 0.003
    divergence: float = 0.0
    size_model: BeamSizeModel = BeamSizeModel.LINEAR
    rayleigh_range: float = 50.0
    pointing_limit: float = 0.1
    focus_range: tuple[float, float] = (1.0, 1000.0)

    def __post_init__(self) -> None:
        _set(self, "pulse_energy_max", _positive("laser.pulse_energy_max", self.pulse_energy_max))
        _set(self, "pulse_rate", _positive("laser.pulse_rate", self.pulse_rate))
        _at_most("laser.pulse_rate", self.pulse_rate, MAX_PULSE_RATE, "Hz", _REFILL)
        _set(self, "pulse_duration", _positive("laser.pulse_duration", self.pulse_duration))
        _set(self, "wavelength", _positive("laser.wavelength", self.wavelength))
        if not isinstance(self.profile, BeamProfile):
            raise ParameterError(
                "laser.profile",
                f"must be one of {[p.value for p in BeamProfile]}, got {self.profile!r}",
            )
        _set(self, "hole_ratio", _in_range("laser.hole_ratio", self.hole_ratio, 0.0, 0.99))
        _set(self, "edge_width", _positive("laser.edge_width", self.edge_width))
        _set(self, "divergence", _non_negative("laser.divergence", self.divergence))
        if not isinstance(self.size_model, BeamSizeModel):
            raise ParameterError(
                "laser.size_model",
                f"must be one of {[m.value for m in BeamSizeModel]}, got {self.size_model!r}",
            )
        _set(self, "rayleigh_range", _positive("laser.rayleigh_range", self.rayleigh_range))
        _set(self, "pointing_limit", _non_negative("laser.pointing_limit", self.pointing_limit))
        focus = _series("laser.focus_range", self.focus_range, 2)
        if len(focus) != 2:
            raise ParameterError("laser.focus_range", "must be (nearest, farthest)")
        lo, hi = (_positive("laser.focus_range", v) for v in focus)
        if hi < lo:
            raise ParameterError("laser.focus_range", "must be (nearest, farthest)")
        _set(self, "focus_range", (lo, hi))
        if self.pulse_duration * self.pulse_rate >= 1.0:
            raise ParameterError("laser.pulse_duration", "pulses would overlap at this rate")


@dataclass(frozen=True)
class FlightRecord:
    """A flight a model file flies, as its accounts give it (docs/physics.md#records):
    what plots mark beside the simulated flight. Not read by any simulation."""

    name: str
    apogee: float  # [m] above the pad
    air_time: float  # [s], launch to landing

    def __post_init__(self) -> None:
        _set(self, "apogee", _positive("record.apogee", self.apogee))
        _set(self, "air_time", _positive("record.air_time", self.air_time))


@dataclass(frozen=True)
class Site:
    """Launch site: origin of frame L (east-north-up) on the WGS-84 ellipsoid.

    Attributes
    ----------
    latitude, longitude : geodetic [rad].
    height : above the ellipsoid (taken as above sea level for the atmosphere) [m].
    """

    name: str
    latitude: float
    longitude: float
    height: float

    def __post_init__(self) -> None:
        _set(self, "latitude", _in_range("site.latitude", self.latitude, -math.pi / 2, math.pi / 2))
        _set(self, "longitude", _in_range("site.longitude", self.longitude, -math.pi, 2 * math.pi))
        _set(self, "height", _in_range("site.height", self.height, -500.0, 80_000.0))


@dataclass(frozen=True)
class Wind:
    """Wind relative to the ground, in L (docs/frames.md).

    Mean profile: speed(z) = speed_ref ((z + z0) / (height_ref + z0))^shear_exponent,
    blowing *from* azimuth ``direction_from + veer z`` (clockwise from north, as
    meteorologists say). If ``table_height`` is given, speed and direction are
    interpolated from ``table_speed`` / ``table_direction_from`` instead.
    Gust: a 1 - cos pulse of peak ``gust_L`` [m/s, L frame] from ``gust_start`` lasting
    ``gust_duration`` [s]; or, if ``gust_table_time`` is given, components
    interpolated in time from ``gust_table_L`` (one (east, north, up) row per time).
    """

    speed_ref: float = 0.0
    height_ref: float = 10.0
    roughness_height: float = 0.1
    shear_exponent: float = 1.0 / 7.0
    direction_from: float = 0.0
    veer: float = 0.0
    gust_L: Vec3 = (0.0, 0.0, 0.0)
    gust_start: float = 0.0
    gust_duration: float = 1.0
    table_height: tuple[float, ...] = ()
    table_speed: tuple[float, ...] = ()
    table_direction_from: tuple[float, ...] = ()
    gust_table_time: tuple[float, ...] = ()
    gust_table_L: tuple[Vec3, ...] = ()

    def __post_init__(self) -> None:
        _set(self, "speed_ref", _non_negative("wind.speed_ref", self.speed_ref))
        _at_most("wind.speed_ref", self.speed_ref, MAX_WIND_SPEED, "m/s", _NO_LAUNCH_WIND)
        _set(self, "height_ref", _positive("wind.height_ref", self.height_ref))
        _set(self, "roughness_height", _positive("wind.roughness_height", self.roughness_height))
        _set(self, "shear_exponent", _in_range("wind.shear_exponent", self.shear_exponent, 0, 1))
        _set(self, "direction_from", _finite("wind.direction_from", self.direction_from))
        _set(self, "veer", _finite("wind.veer", self.veer))
        _set(self, "gust_L", _vec3("wind.gust_L", self.gust_L))
        _at_most("wind.gust_L", math.hypot(*self.gust_L), MAX_WIND_SPEED, "m/s", _NO_LAUNCH_WIND)
        _set(self, "gust_start", _finite("wind.gust_start", self.gust_start))
        _set(self, "gust_duration", _positive("wind.gust_duration", self.gust_duration))
        h = _series("wind.table_height", self.table_height, 0)
        _set(self, "table_height", h)
        if h:
            if len(h) < 2:
                raise ParameterError("wind.table_height", "a table needs at least 2 heights")
            _increasing("wind.table_height", h)
            for name in ("table_speed", "table_direction_from"):
                vals = _series(f"wind.{name}", getattr(self, name), 0)
                if len(vals) != len(h):
                    raise ParameterError(f"wind.{name}", f"needs {len(h)} values (one per height)")
                _set(self, name, vals)
            if min(self.table_speed) < 0.0:
                raise ParameterError("wind.table_speed", "must not be negative")
            top = max(self.table_speed)
            _at_most("wind.table_speed", top, MAX_WIND_SPEED, "m/s", _NO_LAUNCH_WIND)
        elif self.table_speed or self.table_direction_from:
            raise ParameterError("wind.table_height", "speed/direction tables need heights")
        tt = _series("wind.gust_table_time", self.gust_table_time, 0)
        _set(self, "gust_table_time", tt)
        if tt:
            if len(tt) < 2:
                raise ParameterError("wind.gust_table_time", "a table needs at least 2 times")
            _increasing("wind.gust_table_time", tt)
            rows = tuple(
                _vec3(f"wind.gust_table_L[{i}]", r) for i, r in enumerate(self.gust_table_L)
            )
            if len(rows) != len(tt):
                raise ParameterError("wind.gust_table_L", f"needs {len(tt)} rows (one per time)")
            top = max(math.hypot(*r) for r in rows)
            _at_most("wind.gust_table_L", top, MAX_WIND_SPEED, "m/s", _NO_LAUNCH_WIND)
            _set(self, "gust_table_L", rows)
        elif self.gust_table_L:
            raise ParameterError("wind.gust_table_time", "a gust table needs times")


@dataclass(frozen=True)
class Environment:
    """Gravity, Earth rotation and wind settings.

    Attributes
    ----------
    gravity_j2 : include the J2 zonal term (default). With ``earth_rotation`` this is the
        WGS-84 normal gravity, plumb along L's up (the ellipsoid normal); False gives the
        paper's inverse-square gravity, 1.5 mrad off L's up at White Sands
        (docs/physics.md#gravity).
    earth_rotation : include Coriolis and centripetal terms of the rotating site frame.
    """

    wind: Wind = field(default_factory=Wind)
    gravity_j2: bool = True
    earth_rotation: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.wind, Wind):
            raise ParameterError("environment.wind", "must be a Wind")
        for name in ("gravity_j2", "earth_rotation"):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"environment.{name}", "must be true or false")


@dataclass(frozen=True)
class Flight:
    """Conditions of one flight (Table 1): what the laser did that day.

    Attributes
    ----------
    pulse_energy : J per pulse at launch.
    pulse_rate : Hz.
    beam_side : outer side of the beam at launch [m].
    impulse_per_pulse : axial impulse of the first pulse [N s] (Table 1).
    """

    pulse_energy: float
    pulse_rate: float
    beam_side: float
    impulse_per_pulse: float

    def __post_init__(self) -> None:
        _set(self, "pulse_energy", _positive("flight.pulse_energy", self.pulse_energy))
        _set(self, "pulse_rate", _positive("flight.pulse_rate", self.pulse_rate))
        _at_most("flight.pulse_rate", self.pulse_rate, MAX_PULSE_RATE, "Hz", _REFILL)
        _set(self, "beam_side", _positive("flight.beam_side", self.beam_side))
        _set(
            self, "impulse_per_pulse", _positive("flight.impulse_per_pulse", self.impulse_per_pulse)
        )

    @property
    def coupling_coefficient(self) -> float:
        """C_m = impulse / pulse energy [N s / J] (docs/physics.md#table-1)."""
        return self.impulse_per_pulse / self.pulse_energy


@dataclass(frozen=True)
class Model:
    """Everything a simulation needs: craft, laser, site, environment, flight."""

    name: str
    craft: Craft
    site: Site
    laser: Laser
    flight: Flight
    environment: Environment = field(default_factory=Environment)

    def __post_init__(self) -> None:
        if self.flight.pulse_energy > self.laser.pulse_energy_max * (1 + 1e-12):
            raise ParameterError(
                "flight.pulse_energy",
                f"{self.flight.pulse_energy} J exceeds the laser's {self.laser.pulse_energy_max} J",
            )
