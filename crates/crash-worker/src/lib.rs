//! crash-worker: The worker: owns groups of bodies and integrates them (tonic service over crash-core).
