//! Proptest targets of the input readers (issue 14 point 6): the TOML scene parser
//! (with its plan), the Gmsh reader, the keyword deck reader and the checkpoint reader
//! (plain and keyed) take random bytes and mutations of a valid input and answer with a
//! value or a typed error, never a panic; inputs are bounded (64 KiB), so none can hang.
//! `CRASH_FUZZ_CASES` cases per target (default 10 000).
#![allow(clippy::unwrap_used)] // a test panics on failure

use crash_core::{Clock, Group};
use crash_io::CheckpointKey;
use crash_tests::fixtures::{root, test_scene};
use crash_tests::mutate::{config, mutated, random};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

const LIMIT: usize = 64 << 10;

fn valid_scene() -> Vec<u8> {
    std::fs::read(test_scene("two-spheres-tiny.toml")).unwrap()
}

fn valid_msh() -> Vec<u8> {
    std::fs::read(root().join("scenes/meshes/bracket.msh")).unwrap()
}

fn valid_deck() -> Vec<u8> {
    std::fs::read(root().join("crates/crash-scene/tests/data/keyword/impact.k")).unwrap()
}

/// A checkpoint of two stepped spheres (plain and keyed).
fn valid_checkpoints() -> &'static (Vec<u8>, Vec<u8>) {
    static CK: OnceLock<(Vec<u8>, Vec<u8>)> = OnceLock::new();
    CK.get_or_init(|| {
        let built = crash_scene::load(&test_scene("two-spheres-tiny.toml"))
            .unwrap()
            .build()
            .unwrap();
        let mut g = Group::new(built.bodies, built.gravity);
        let r = g.start().unwrap();
        let h = 0.9 * r.iter().map(|r| r.stable_dt).fold(f64::INFINITY, f64::min);
        g.advance(&Clock::default(), h).unwrap();
        let value = (Clock::default().after(h), g);
        let dir = scratch_dir();
        let (p, k) = (dir.join("plain.ckp"), dir.join("keyed.ckp"));
        crash_io::write_checkpoint(&p, &value).unwrap();
        crash_io::write_checkpoint_keyed(&k, &value, Some(&key())).unwrap();
        (std::fs::read(p).unwrap(), std::fs::read(k).unwrap())
    })
}

fn key() -> CheckpointKey {
    CheckpointKey([42; 32])
}

/// A directory of this test process under target/tmp.
fn scratch() -> PathBuf {
    let d = crash_tests::procs::out_dir("fuzz-inputs");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn scratch_dir() -> &'static Path {
    static D: OnceLock<PathBuf> = OnceLock::new();
    D.get_or_init(scratch)
}

fn scene(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let file = test_scene("fuzzed.toml");
    if let Ok(s) = crash_scene::parse(&text, file.to_str().unwrap()) {
        let _ = s.plan();
    }
}

fn msh(bytes: &[u8]) {
    let _ = crash_scene::msh::read_msh(&String::from_utf8_lossy(bytes));
}

fn deck(bytes: &[u8]) {
    // the reader takes a path (decks include others): one file per test thread
    let path = scratch_dir().join(format!("{:?}.k", std::thread::current().id()));
    std::fs::write(&path, bytes).unwrap();
    let _ = crash_scene::keyword::load(&path, &crash_scene::keyword::DeckOptions::default());
}

fn checkpoint(bytes: &[u8], keyed: bool) {
    let k = key();
    let key = keyed.then_some(&k);
    let at = Path::new("fuzzed.ckp");
    let _ = crash_io::decode_checkpoint::<(Clock, Group)>(at, bytes, key);
    let _ = crash_io::decode_checkpoint::<crash_master::RestartFile>(at, bytes, key);
    // the header made to fit the edited payload (length, checksum): the payload
    // decoder itself sees the mutation
    if !keyed && bytes.len() >= 28 {
        let mut b = bytes.to_vec();
        b[..8].copy_from_slice(b"CRASHCKP");
        b[8..12].copy_from_slice(&crash_io::checkpoint::VERSION.to_le_bytes());
        let len = (b.len() - 28) as u64;
        b[12..20].copy_from_slice(&len.to_le_bytes());
        let mut h = crash_core::hash::Fnv::default();
        h.bytes(&b[28..]);
        b[20..28].copy_from_slice(&h.finish().to_le_bytes());
        let _ = crash_io::decode_checkpoint::<(Clock, Group)>(at, &b, None);
        let _ = crash_io::decode_checkpoint::<crash_master::RestartFile>(at, &b, None);
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn scene_parser_never_panics_on_mutated_scenes(b in mutated(valid_scene(), LIMIT)) {
        scene(&b);
    }

    #[test]
    fn scene_parser_never_panics_on_random_text(b in random(4096)) {
        scene(&b);
    }

    #[test]
    fn gmsh_reader_never_panics_on_mutated_meshes(b in mutated(valid_msh(), LIMIT)) {
        msh(&b);
    }

    #[test]
    fn gmsh_reader_never_panics_on_random_text(b in random(4096)) {
        msh(&b);
    }

    #[test]
    fn deck_reader_never_panics_on_mutated_decks(b in mutated(valid_deck(), LIMIT)) {
        deck(&b);
    }

    #[test]
    fn deck_reader_never_panics_on_random_text(b in random(4096)) {
        deck(&b);
    }

    #[test]
    fn checkpoint_reader_never_panics_on_mutated_checkpoints(
        b in mutated(valid_checkpoints().0.clone(), LIMIT),
        k in mutated(valid_checkpoints().1.clone(), LIMIT),
    ) {
        checkpoint(&b, false);
        checkpoint(&k, true);
    }

    #[test]
    fn checkpoint_reader_never_panics_on_random_bytes(b in random(4096), keyed: bool) {
        checkpoint(&b, keyed);
    }
}
