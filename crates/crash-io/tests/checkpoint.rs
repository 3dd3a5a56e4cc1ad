//! Checkpoints: a stepped group round-trips bit-exactly and continues identically;
//! damaged files are refused with errors that name the file.

mod common;

use common::{stepped_group, test_dir};
use crash_core::hash::state_hash;
use crash_core::{Clock, Group};
use crash_io::checkpoint::checkpoint_payload;
use crash_io::{read_checkpoint, write_checkpoint, IoError};

fn advance((clock, g): &mut (Clock, Group), n: usize) {
    let mut reports = g.start().expect("start");
    // start() recomputes forces at the current state without changing it.
    for _ in 0..n {
        let h = 0.9
            * reports
                .iter()
                .map(|r| r.stable_dt)
                .fold(f64::INFINITY, f64::min);
        reports = g.advance(clock, h).expect("step");
        *clock = clock.after(h);
    }
}

#[test]
fn group_round_trips_bit_exactly_and_continues_identically() {
    let dir = test_dir("checkpoint_group");
    let path = dir.join("checkpoint.bin");
    let mut original = stepped_group(25);
    write_checkpoint(&path, &original).expect("write");
    assert!(
        !dir.join("checkpoint.bin.tmp").exists(),
        "temp file renamed away"
    );
    let mut restored: (Clock, Group) = read_checkpoint(&path).expect("read");

    assert_eq!(
        state_hash(&restored.1.bodies),
        state_hash(&original.1.bodies)
    );
    assert_eq!(
        checkpoint_payload(&restored).expect("encode"),
        checkpoint_payload(&original).expect("encode"),
        "every serialized byte equal"
    );
    assert!(restored.0.same_as(&original.0), "the clock, bit for bit");

    advance(&mut original, 30);
    advance(&mut restored, 30);
    assert_eq!(
        state_hash(&restored.1.bodies),
        state_hash(&original.1.bodies)
    );
    assert_eq!(restored.0.step, 55);
    // The continued state is not the checkpointed one (the test can fail).
    let saved: (Clock, Group) = read_checkpoint(&path).expect("read");
    assert_ne!(state_hash(&saved.1.bodies), state_hash(&original.1.bodies));
}

#[test]
fn damaged_checkpoints_are_refused_with_the_file_named() {
    let dir = test_dir("checkpoint_damage");
    let path = dir.join("state.ckp");
    write_checkpoint(&path, &stepped_group(2)).expect("write");
    let good = std::fs::read(&path).expect("bytes");
    let named = |e: &IoError| e.to_string().contains("state.ckp");

    std::fs::write(&path, &good[..good.len() - 10]).expect("truncate");
    let e = read_checkpoint::<(Clock, Group)>(&path).expect_err("truncated");
    assert!(matches!(e, IoError::Truncated { .. }) && named(&e), "{e}");

    let mut bad = good.clone();
    bad[0] = b'X';
    std::fs::write(&path, &bad).expect("magic");
    let e = read_checkpoint::<(Clock, Group)>(&path).expect_err("magic");
    assert!(matches!(e, IoError::BadMagic { .. }) && named(&e), "{e}");

    let mut bad = good.clone();
    bad[8] = 99;
    std::fs::write(&path, &bad).expect("version");
    let e = read_checkpoint::<(Clock, Group)>(&path).expect_err("version");
    assert!(
        matches!(e, IoError::Version { found: 99, .. }) && named(&e),
        "{e}"
    );

    let mut bad = good.clone();
    let k = bad.len() / 2;
    bad[k] ^= 0x40;
    std::fs::write(&path, &bad).expect("flip");
    let e = read_checkpoint::<(Clock, Group)>(&path).expect_err("checksum");
    assert!(matches!(e, IoError::Checksum { .. }) && named(&e), "{e}");

    let e = read_checkpoint::<Group>(dir.join("missing.ckp")).expect_err("missing");
    assert!(e.to_string().contains("missing.ckp"), "{e}");

    std::fs::write(&path, &good).expect("restore");
    assert!(read_checkpoint::<(Clock, Group)>(&path).is_ok());
}

/// FNV-1a 64 as the checkpoint header holds it (what an editor would recompute).
fn fnv(b: &[u8]) -> u64 {
    let mut h = crash_core::hash::Fnv::default();
    h.bytes(b);
    h.finish()
}

#[test]
fn an_edited_keyed_checkpoint_with_its_checksum_recomputed_is_refused_by_its_mac() {
    use crash_io::{read_checkpoint_keyed, write_checkpoint_keyed, CheckpointKey};
    let dir = test_dir("checkpoint_keyed");
    let path = dir.join("keyed.ckp");
    let key = CheckpointKey([7; 32]);
    let value = stepped_group(2);
    write_checkpoint_keyed(&path, &value, Some(&key)).expect("write");
    let good = std::fs::read(&path).expect("bytes");
    let back: (Clock, Group) = read_checkpoint_keyed(&path, Some(&key)).expect("read");
    assert_eq!(
        checkpoint_payload(&back).expect("payload"),
        checkpoint_payload(&value).expect("payload")
    );
    let named = |e: &IoError| e.to_string().contains("keyed.ckp");

    // one payload byte changed and the plain checksum made to fit again
    let header = 8 + 4 + 8 + 8 + 32;
    let mut bad = good.clone();
    let k = header + (bad.len() - header) / 2;
    bad[k] ^= 0x01;
    let sum = fnv(&bad[header..]);
    bad[20..28].copy_from_slice(&sum.to_le_bytes());
    std::fs::write(&path, &bad).expect("edit");
    let e = read_checkpoint_keyed::<(Clock, Group)>(&path, Some(&key)).expect_err("edited");
    assert!(matches!(e, IoError::Mac { .. }) && named(&e), "{e}");

    // the right file under another secret's key: refused the same way
    std::fs::write(&path, &good).expect("restore");
    let other = CheckpointKey([8; 32]);
    let e = read_checkpoint_keyed::<(Clock, Group)>(&path, Some(&other)).expect_err("other");
    assert!(matches!(e, IoError::Mac { .. }), "{e}");

    // keyed, read without the secret: refused, saying what to give
    let e = read_checkpoint::<(Clock, Group)>(&path).expect_err("no key");
    assert!(
        matches!(e, IoError::Keyed { .. }) && named(&e) && e.to_string().contains("CRASH_SECRET"),
        "{e}"
    );

    // an unkeyed file while a secret is set: refused (else a stripped MAC would pass)
    let plain = dir.join("plain.ckp");
    write_checkpoint(&plain, &value).expect("write plain");
    let e = read_checkpoint_keyed::<(Clock, Group)>(&plain, Some(&key)).expect_err("unkeyed");
    assert!(matches!(e, IoError::Unkeyed { .. }), "{e}");
    // and it still reads without a secret
    assert!(read_checkpoint::<(Clock, Group)>(&plain).is_ok());
}
