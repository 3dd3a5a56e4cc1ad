//! A small valid scene and helpers to break it one key at a time.
#![allow(dead_code)]

use crash_scene::{ErrorKind, SceneError};
use std::path::PathBuf;

/// Line numbers are part of the tests: keep this text's layout.
pub const BASE: &str = r#"end_time = 1.0e-3

[materials.steel]
density = 7800.0
young = 200.0e9
poisson = 0.3

[[bodies]]
name = "plate"
material = "steel"
thickness = 2.0e-3
plate = { size = [0.4, 0.4], cells = [4, 4] }

[[bodies.fix]]
select = "x-"
dofs = "all"

[[bodies]]
name = "ball"
material = "steel"
thickness = 1.0e-3
sphere = { radius = 0.1, level = 1 }
position = [0.0, 0.0, 0.2]
velocity = [0.0, 0.0, -5.0]
"#;

/// BASE with one exact substring replaced (which must occur).
pub fn with(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "BASE has no {from:?}");
    BASE.replacen(from, to, 1)
}

/// Parse and build `text` as "scene.toml"; the error it must give.
pub fn error(text: &str) -> SceneError {
    match crash_scene::parse(text, "scene.toml").and_then(|s| s.build()) {
        Ok(_) => panic!("scene was accepted:\n{text}"),
        Err(e) => e,
    }
}

/// Assert kind, location and that the message says each of `parts`.
pub fn check(
    e: &SceneError,
    kind: ErrorKind,
    line: usize,
    column: usize,
    key: &str,
    parts: &[&str],
) {
    let shown = e.to_string();
    assert_eq!(e.kind, kind, "{shown}");
    assert_eq!((e.line, e.column), (line, column), "{shown}");
    assert_eq!(e.key, key, "{shown}");
    assert!(
        shown.starts_with(&format!("{}:{line}:{column}: ", e.file)),
        "{shown}"
    );
    for p in parts {
        assert!(shown.contains(p), "message lacks {p:?}: {shown}");
    }
}

/// A fresh directory for files a test writes (scene + mesh), in cargo's scratch space
/// for integration tests.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("crash-scene-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}
