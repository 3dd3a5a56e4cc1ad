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

/// The text of tests/scenes/two-spheres-tiny.toml with the spheres in contact from the
/// start (centres 0.101 m apart, closing at 1 m/s each, a 10 um contact margin), then
/// `extra` (TOML appended: its first table applies to the last body, the right sphere).
/// The scene of the split fault tests.
pub fn spheres_in_contact(extra: &str) -> String {
    std::fs::read_to_string(test_scene("two-spheres-tiny.toml"))
        .unwrap_or_default()
        .replace(
            "penalty_scale = 0.1",
            "penalty_scale = 0.1\nmargin = 1.0e-5",
        )
        .replace("velocity = [5.0, 0.0, 0.0]", "velocity = [1.0, 0.0, 0.0]")
        .replace("velocity = [-5.0, 0.0, 0.0]", "velocity = [-1.0, 0.0, 0.0]")
        .replace(
            "position = [-0.0625, 0.0, 0.0]",
            "position = [-0.0505, 0.0, 0.0]",
        )
        .replace(
            "position = [0.0625, 0.0, 0.0]",
            "position = [0.0505, 0.0, 0.0]",
        )
        + extra
}

/// A load of `force` newtons along x on every node of the last body from 0.1 ms.
pub fn pull_last(force: &str) -> String {
    format!("\n[[bodies.load]]\nselect = \"all\"\nforce = [{force}, 0.0, 0.0]\nstart = 1.0e-4\n")
}

/// The material of the showcase scenes and of most tests.
pub fn steel() -> Material {
    Material::steel()
}
