"""Model expressions in casadi: pure builders from a model and its options to named
casadi Functions (docs/architecture.md#floors).

- :mod:`.terms`: the physics, term by term (aero, atmosphere, beam, engine, gravity,
  gyrostat, mass properties, rcs, rotation, spin decay, wind, invariants); terms import
  only each other.
- :mod:`.maps`: what sits on them: the coast's vector field and its integrators, the
  laser's jump, Φ's pieces, the pulse map Φ and the reduced map Ψ with their derivative
  chains, the error-state chart and coning coordinates, and the flat reference Φ the
  structured one is checked against. Maps import terms, never the other way
  (an import-linter contract).
"""
