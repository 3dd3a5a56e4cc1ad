//! crash-scene: Scene files (TOML), validation with precise locations, mesh generators and importers.
