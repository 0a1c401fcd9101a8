"""The physics of the model, one term a module (docs/physics.md): forces, torques, the
beam and the engine's impulse, mass properties, rotations and the invariants that check
them. Pure casadi expressions of the state's parts; they import only each other."""
