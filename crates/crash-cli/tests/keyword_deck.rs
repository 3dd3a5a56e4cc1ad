//! `crash check`, `crash convert` and `crash run` on a keyword deck (the crash-scene
//! test deck): the deck runs as it is, and the converted scene runs to the same final
//! state hash.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn deck() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../crash-scene/tests/data/keyword/impact.k")
}

fn crash(args: &[&std::ffi::OsStr]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_crash"))
        .args(args)
        .output()
        .expect("crash starts");
    assert!(
        out.status.success(),
        "crash {args:?} failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The final state hash `crash run` reports.
fn final_hash(stderr: &[u8]) -> String {
    let s = String::from_utf8_lossy(stderr);
    s.split("final state hash ")
        .nth(1)
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|| panic!("no hash in {s}"))
}

#[test]
fn a_deck_checks_converts_and_runs_like_its_converted_scene() {
    let tmp = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-keyword-deck");
    let _ = std::fs::remove_dir_all(&tmp);
    let out = crash(&["check".as_ref(), deck().as_os_str()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("2 bodies, 34 nodes, 21 elements"), "{text}");

    let scene = tmp.join("impact.toml");
    let out = crash(&["convert".as_ref(), deck().as_os_str(), scene.as_os_str()]);
    let listed = String::from_utf8_lossy(&out.stdout);
    assert!(
        listed.contains("impact.part1.msh") && listed.contains("impact.part2.msh"),
        "{listed}"
    );

    let run = |input: &Path, dir: &str| {
        let o = tmp.join(dir);
        crash(&[
            "run".as_ref(),
            input.as_os_str(),
            "--quiet".as_ref(),
            "--no-pictures".as_ref(),
            "--out".as_ref(),
            o.as_os_str(),
        ])
    };
    let a = run(&deck(), "from-deck");
    let b = run(&scene, "from-scene");
    assert_eq!(final_hash(&a.stderr), final_hash(&b.stderr));
}
