//! Every scene shipped in scenes/ parses and builds.

use std::path::PathBuf;

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

#[test]
fn every_scene_in_scenes_dir_parses_and_builds() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .expect("scenes/ exists")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 8,
        "expected the showcase and verification scenes, found {files:?}"
    );
    for f in &files {
        let scene = crash_scene::load(f).unwrap_or_else(|e| panic!("{e}"));
        let built = scene.build().unwrap_or_else(|e| panic!("{e}"));
        let s = built.summary();
        println!("{s}\n");
        assert_eq!(built.bodies.len(), scene.spec.bodies.len());
        for (i, b) in built.bodies.iter().enumerate() {
            assert_eq!(
                b.def.id as usize,
                i,
                "{}: ids follow file order",
                f.display()
            );
        }
        assert!(s.elements > 0 && built.end_time > 0.0);
    }
}
