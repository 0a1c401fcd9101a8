"""The physical description of a flight, by part, as frozen, validated dataclasses in SI units.

Every dataclass checks itself on creation and raises
:class:`~lightcraft_opt.errors.ParameterError` naming the offending field, so a model that
exists is a model that makes sense. Frames are those of ``docs/frames.md``: vectors named
``*_B`` have components in the despun body frame B, measured from the rotor reference point
P (a point on the spin axis, the rotor's dry mass centre).

- :mod:`.craft`: :class:`Craft`, the spinning rotor, and its :class:`Propellant`; its parts:
  :mod:`.aero` (:class:`Aerodynamics`, :class:`SpinDecay`), :mod:`.engine`
  (:class:`Engine`), :mod:`.mass` (:class:`Liner`, :class:`Carrier`, their mass properties)
  and :mod:`.rcs` (:class:`Rcs`, :class:`Thruster`);
- :mod:`.laser`: :class:`Laser`, the beam's profile and size, the :class:`FocusSchedule`;
- :mod:`.site`: :class:`Site`, :class:`Environment` and its :class:`Wind`;
- :mod:`.flight`: :class:`Flight` (the conditions of one flight), :class:`FlightRecord`;
- :mod:`.model`: :class:`Model`, the whole;
- :mod:`.checks`: the checks every value passes, each naming its field; :mod:`.limits`: the
  largest values the model is meant for, with their reasons.

Import from here: ``from lightcraft_opt.model import Model, Craft``. This is the physical
description; the run-time parameter vector p is a layout (``lightcraft_opt.layout``,
``PARAMETERS``, ``parameter_values``). Unit conversion never happens here: see
:mod:`lightcraft_opt.files.model`.
"""

from lightcraft_opt.model.aero import Aerodynamics, AeroModel, SpinDecay, SpinDecayModel
from lightcraft_opt.model.craft import Craft, Propellant
from lightcraft_opt.model.engine import Engine, ImpulseModel
from lightcraft_opt.model.flight import Flight, FlightRecord
from lightcraft_opt.model.laser import BeamProfile, BeamSizeModel, FocusSchedule, Laser
from lightcraft_opt.model.mass import Carrier, Liner
from lightcraft_opt.model.model import Model
from lightcraft_opt.model.rcs import Rcs, Thruster
from lightcraft_opt.model.site import Environment, Site, Wind

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
    "FocusSchedule",
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
