//! Inputs for the proptest targets (tests/tests/fuzz_*.rs): mutations of a valid
//! input, which reach deeper than random bytes (a valid header, then one wrong field),
//! and the number of cases a target tries.

use proptest::prelude::*;

/// Cases per target: `CRASH_FUZZ_CASES`, else 10 000 (the CI figure).
pub fn cases() -> u32 {
    std::env::var("CRASH_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000)
}

/// The proptest configuration of every target: `cases()`, no failure files written
/// into the source tree (a failure prints its minimal input; it becomes a regression
/// test by hand).
pub fn config() -> ProptestConfig {
    ProptestConfig {
        cases: cases(),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// One edit of a byte string.
#[derive(Debug, Clone)]
pub enum Edit {
    Flip {
        at: usize,
        bit: u8,
    },
    Set {
        at: usize,
        byte: u8,
    },
    Insert {
        at: usize,
        bytes: Vec<u8>,
    },
    Delete {
        at: usize,
        len: usize,
    },
    Truncate {
        at: usize,
    },
    /// Copy a span to another place (repeats a line, a field, a record).
    Duplicate {
        from: usize,
        len: usize,
        to: usize,
    },
}

/// Interesting bytes for text formats: digits, signs, separators, line ends.
const SPECIAL: &[u8] = b"0123456789-+.eE \t\n\r,=[]\"*$#{}xX\0\xff";

fn edit() -> impl Strategy<Value = Edit> {
    let pos = any::<usize>();
    prop_oneof![
        (pos, 0u8..8).prop_map(|(at, bit)| Edit::Flip { at, bit }),
        (pos, any::<u8>()).prop_map(|(at, byte)| Edit::Set { at, byte }),
        (pos, proptest::sample::select(SPECIAL)).prop_map(|(at, byte)| Edit::Set { at, byte }),
        (pos, proptest::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(at, bytes)| Edit::Insert { at, bytes }),
        (pos, 1usize..64).prop_map(|(at, len)| Edit::Delete { at, len }),
        pos.prop_map(|at| Edit::Truncate { at }),
        (pos, 1usize..200, pos).prop_map(|(from, len, to)| Edit::Duplicate { from, len, to }),
    ]
}

/// Apply edits (positions taken modulo the current length); the result stays below
/// `limit` bytes.
pub fn apply(mut b: Vec<u8>, edits: &[Edit], limit: usize) -> Vec<u8> {
    for e in edits {
        let n = b.len().max(1);
        match e {
            Edit::Flip { at, bit } => {
                if let Some(x) = b.get_mut(at % n) {
                    *x ^= 1 << bit;
                }
            }
            Edit::Set { at, byte } => {
                if let Some(x) = b.get_mut(at % n) {
                    *x = *byte;
                }
            }
            Edit::Insert { at, bytes } => {
                let at = at % (b.len() + 1);
                b.splice(at..at, bytes.iter().copied());
            }
            Edit::Delete { at, len } => {
                let at = at % n;
                let end = (at + len).min(b.len());
                if at < end {
                    b.drain(at..end);
                }
            }
            Edit::Truncate { at } => b.truncate(at % n),
            Edit::Duplicate { from, len, to } => {
                let from = from % n;
                let end = (from + len).min(b.len());
                if from < end {
                    let span: Vec<u8> = b[from..end].to_vec();
                    let to = to % (b.len() + 1);
                    b.splice(to..to, span);
                }
            }
        }
    }
    b.truncate(limit);
    b
}

/// A valid input with 1 to 8 edits.
pub fn mutated(valid: Vec<u8>, limit: usize) -> impl Strategy<Value = Vec<u8>> {
    proptest::collection::vec(edit(), 1..8).prop_map(move |e| apply(valid.clone(), &e, limit))
}

/// Random bytes below `limit` (half of them printable text).
pub fn random(limit: usize) -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        proptest::collection::vec(any::<u8>(), 0..limit),
        proptest::collection::vec(proptest::sample::select(SPECIAL), 0..limit),
        "[ -~\n]{0,512}".prop_map(String::into_bytes),
    ]
}
