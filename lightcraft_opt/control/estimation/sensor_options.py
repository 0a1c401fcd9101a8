"""The tracker's sensors as options: what a closed-loop file's ``[sensors]`` describes
(docs/estimation.md#sensors, docs/files/closed_loop.md#keys-sensors-camera). Numbers only:
the suite that draws their readings is :mod:`.sensors`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum

from lightcraft_opt.errors import OptionError, ParameterError
from lightcraft_opt.model.checks import checked_choice, checked_int, checked_number, checked_vector

__all__ = [
    "MIN_SITE_DISTANCE",
    "SENSORS",
    "CameraKind",
    "CameraOptions",
    "GyroOptions",
    "SensorOptions",
    "SpinSensorOptions",
]

#: The sensors a suite may hold, in the order their seeds are drawn.
SENSORS = ("camera", "gyro", "spin")
#: The least horizontal distance [m] of a tracking mount from the pad's vertical: its azimuth
#: is measured from the line to the pad, which a mount under the craft's path lacks.
MIN_SITE_DISTANCE = 1.0


class CameraKind(Enum):
    """What a camera gives: the position in L (``position``, noise in m), or the
    (azimuth, elevation) of the craft from each of two or more tracking mounts
    (``stereo``, noise in rad; symbolic/maps/measurements.py bearings_from)."""

    POSITION = "position"
    STEREO = "stereo"


def _checked_latency(owner: str, value: object) -> None:
    checked_int(owner, "latency_pulses", value, 0)


@dataclass(frozen=True)
class CameraOptions:
    """The tracking camera.

    Attributes
    ----------
    kind : :class:`CameraKind`.
    noise : 1-sigma of each coordinate, > 0: [m] for ``position``, [rad] for ``stereo``.
    sites : ((east, north, up), ...) [m, L frame]: the mounts of a ``stereo`` camera, two or
        more, each at least 1 m off the pad's vertical; empty for ``position``.
    frame_rate : frames per second [Hz], > 0; None (the default): one frame at each pulse
        node (dt = 0).
    latency_pulses : whole pulses from the node a frame belongs to until it arrives, >= 0.
    lost_rate : probability that a frame is lost, in [0, 1).
    """

    kind: CameraKind = CameraKind.POSITION
    noise: float = 0.005
    sites: tuple[tuple[float, float, float], ...] = ()
    frame_rate: float | None = None
    latency_pulses: int = 0
    lost_rate: float = 0.0

    def __post_init__(self) -> None:
        checked_choice("CameraOptions", "kind", self.kind, CameraKind)
        checked_number("CameraOptions", "noise", self.noise, 0.0)
        if self.frame_rate is not None:
            checked_number("CameraOptions", "frame_rate", self.frame_rate, 0.0)
        _checked_latency("CameraOptions", self.latency_pulses)
        if not (
            isinstance(self.lost_rate, int | float)
            and not isinstance(self.lost_rate, bool)
            and 0.0 <= self.lost_rate < 1.0
        ):
            raise OptionError(f"CameraOptions.lost_rate must lie in [0, 1), got {self.lost_rate!r}")
        self._check_sites()

    def _check_sites(self) -> None:
        sites = self.sites
        if self.kind is CameraKind.POSITION:
            if sites:
                raise OptionError(
                    "CameraOptions.sites are the mounts of a stereo camera; a position camera "
                    f"takes none, got {sites!r}"
                )
            return
        if not isinstance(sites, tuple) or len(sites) < 2:
            raise OptionError(
                f"CameraOptions.sites: a stereo camera needs two or more mounts, got {sites!r}"
            )
        for i, site in enumerate(sites):
            try:
                s = checked_vector(f"CameraOptions.sites[{i}]", site, 3)
            except ParameterError as err:
                raise OptionError(str(err)) from err
            if math.hypot(s[0], s[1]) < MIN_SITE_DISTANCE:
                raise OptionError(
                    f"CameraOptions.sites[{i}] must stand at least {MIN_SITE_DISTANCE:g} m off "
                    f"the pad's vertical (its azimuth is measured from the line to it), got "
                    f"{list(site)}"
                )

    @property
    def size(self) -> int:
        """Entries of one frame: 3, or 2 per mount."""
        return 3 if self.kind is CameraKind.POSITION else 2 * len(self.sites)


@dataclass(frozen=True)
class GyroOptions:
    """Rate gyros on the craft, w_B (3,) in B, one sample at each node.

    Attributes
    ----------
    noise : 1-sigma of each axis [rad/s], > 0.
    latency_pulses : whole pulses until a sample arrives, >= 0.
    """

    noise: float = 0.01
    latency_pulses: int = 0

    def __post_init__(self) -> None:
        checked_number("GyroOptions", "noise", self.noise, 0.0)
        _checked_latency("GyroOptions", self.latency_pulses)


@dataclass(frozen=True)
class SpinSensorOptions:
    """A spin counter: the rotor spin relative to B [rad/s] (the state's ``spin``), one
    sample at each node.

    Attributes
    ----------
    noise : 1-sigma [rad/s], > 0 (default 10 RPM).
    latency_pulses : whole pulses until a sample arrives, >= 0.
    """

    noise: float = 10.0 * 2.0 * math.pi / 60.0
    latency_pulses: int = 0

    def __post_init__(self) -> None:
        checked_number("SpinSensorOptions", "noise", self.noise, 0.0)
        _checked_latency("SpinSensorOptions", self.latency_pulses)


@dataclass(frozen=True)
class SensorOptions:
    """What the tracker has: a camera, and optionally gyros and a spin counter.

    Attributes
    ----------
    camera : :class:`CameraOptions` (default: positions in L at 5 mm, at each node, no
        latency, nothing lost).
    gyro : :class:`GyroOptions`, or None: no gyros.
    spin : :class:`SpinSensorOptions`, or None: no spin counter.
    """

    camera: CameraOptions = field(default_factory=CameraOptions)
    gyro: GyroOptions | None = None
    spin: SpinSensorOptions | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.camera, CameraOptions):
            raise OptionError(f"SensorOptions.camera must be a CameraOptions, got {self.camera!r}")
        for name, cls in (("gyro", GyroOptions), ("spin", SpinSensorOptions)):
            value = getattr(self, name)
            if value is not None and not isinstance(value, cls):
                raise OptionError(
                    f"SensorOptions.{name} must be a {cls.__name__} or None, got {value!r}"
                )
