"""Maps built on the physics terms: the coast's right-hand side and integrators, the laser
pulse's jump, Φ's named pieces and the pulse map Φ, the coning-aware reduced map Ψ, their
explicit-chain derivatives and sensitivities, the error-state chart, coning coordinates,
and ``reference_pulse_map``, the flat single-graph Φ the structured one is checked
against."""
