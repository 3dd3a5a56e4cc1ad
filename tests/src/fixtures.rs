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

/// A third sphere, 0.3 m off the two of `spheres_in_contact`, pushed down beyond any
/// finite acceleration from 0.1 ms.
pub fn third_sphere() -> String {
    "\n[[bodies]]\nname = \"third\"\nmaterial = \"steel\"\nthickness = 1.0e-3\n\
     sphere = { radius = 0.05, level = 2 }\nposition = [0.0, 0.3, 0.0]\n\
     [[bodies.load]]\nselect = \"all\"\nforce = [0.0, 0.0, -1.0e308]\nstart = 1.0e-4\n"
        .to_string()
}

/// `third_sphere` resting on a fixed plate 1.005 mm below it (close enough to pair them
/// from the start, so its group holds the plate's read-only copy and is never split):
/// a fault in a whole group.
pub fn third_sphere_on_a_plate() -> String {
    third_sphere()
        + "[[bodies]]\nname = \"floor\"\nmaterial = \"steel\"\nthickness = 1.0e-3\n\
           plate = { size = [0.2, 0.2], cells = [4, 4] }\nposition = [0.0, 0.3, -0.051005]\n\
           [[bodies.fix]]\nselect = \"all\"\n"
}

/// The material of the showcase scenes and of most tests.
pub fn steel() -> Material {
    Material::steel()
}
