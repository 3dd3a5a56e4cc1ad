//! Scenes and materials shared by the tests.

use crash_core::Material;
use std::path::{Path, PathBuf};

/// The repository's root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// A scene of the test suite (`tests/scenes/`).
pub fn test_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// A scene of the repository (`scenes/`).
pub fn scene(name: &str) -> PathBuf {
    root().join("scenes").join(name)
}

/// The material of the showcase scenes and of most tests.
pub fn steel() -> Material {
    Material::steel()
}
