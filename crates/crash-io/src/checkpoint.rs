//! Checkpoints: any serde state in a compact binary form (postcard: f64 as its 8 raw
//! bytes, so values round-trip exactly), behind a header that names the format and
//! version and guards against truncation and corruption. Written atomically.
//!
//! Layout: magic "CRASHCKP" (8) | version u32 LE | payload length u64 LE |
//! FNV-1a 64 of the payload u64 LE | payload.
//!
//! Keyed (a shared secret is set): magic "CRASHCKM" and, between the checksum and the
//! payload, HMAC-SHA256 (32 bytes) of everything before it and of the payload, under a
//! key derived from the secret (`CheckpointKey`). The checksum finds accidents; the MAC
//! finds edits, since whoever edits must also know the secret. A keyed file is refused
//! without the key, an unkeyed one with it (else stripping the MAC would pass).

use crate::atomic::write_atomic;
use crate::error::{AtPath, IoError};
use crash_core::hash::Fnv;
use hmac::{Hmac, Mac};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;

pub const MAGIC: &[u8; 8] = b"CRASHCKP";
/// Magic of a keyed checkpoint (HMAC-SHA256 after the checksum).
pub const MAGIC_KEYED: &[u8; 8] = b"CRASHCKM";
const MAC_LEN: usize = 32;

type HmacSha256 = Hmac<sha2::Sha256>;

/// The key of checkpoint MACs (derived from the cluster's shared secret by crash-link:
/// `Secret::checkpoint_key`).
#[derive(Clone)]
pub struct CheckpointKey(pub [u8; 32]);

impl std::fmt::Debug for CheckpointKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("CheckpointKey(..)")
    }
}

impl CheckpointKey {
    fn mac(&self, head: &[u8], payload: &[u8]) -> HmacSha256 {
        let mut m = match HmacSha256::new_from_slice(&self.0) {
            Ok(m) => m,
            Err(_) => unreachable!("HMAC accepts any key length"),
        };
        m.update(head);
        m.update(payload);
        m
    }
}
/// Layout version of the payload. 2: body states apart from definitions, the run's
/// clock (`crash_core::Clock`). 3: the contact speed rule, the run's energy figure in
/// every record, the shortened last step apart, warnings raised so far. 5: velocity
/// programs say whether they prescribe a displacement. 6: quad reference data without
/// the gradients of nodes 1 and 2, with h.X, h.Y and bb in place of the hourglass shape
/// vector and stiffnesses (`crash_core::element::QuadElem`).
pub const VERSION: u32 = 6;
const HEADER: usize = 8 + 4 + 8 + 8;

fn checksum(b: &[u8]) -> u64 {
    let mut h = Fnv::default();
    h.bytes(b);
    h.finish()
}

/// The exact bytes a checkpoint of `value` holds after its header (for comparisons).
pub fn checkpoint_payload<T: Serialize>(value: &T) -> Result<Vec<u8>, postcard::Error> {
    postcard::to_stdvec(value)
}

/// Write `value` to `path` atomically (temp file in the same directory, fsync, rename).
pub fn write_checkpoint<T: Serialize>(path: impl AsRef<Path>, value: &T) -> Result<(), IoError> {
    write_checkpoint_keyed(path, value, None)
}

/// As `write_checkpoint`, with a MAC under `key` when one is given.
pub fn write_checkpoint_keyed<T: Serialize>(
    path: impl AsRef<Path>,
    value: &T,
    key: Option<&CheckpointKey>,
) -> Result<(), IoError> {
    let path = path.as_ref();
    let payload = checkpoint_payload(value).map_err(|e| IoError::Encode {
        path: path.to_path_buf(),
        source: e,
    })?;
    let mut head = Vec::with_capacity(HEADER + MAC_LEN);
    head.extend_from_slice(if key.is_some() { MAGIC_KEYED } else { MAGIC });
    head.extend_from_slice(&VERSION.to_le_bytes());
    head.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    head.extend_from_slice(&checksum(&payload).to_le_bytes());
    if let Some(k) = key {
        let tag = k.mac(&head, &payload).finalize().into_bytes();
        head.extend_from_slice(&tag);
    }
    write_atomic(path, |w| {
        w.write_all(&head)?;
        w.write_all(&payload)
    })
}

/// Read a checkpoint written by `write_checkpoint` (a keyed one is refused: it needs
/// `read_checkpoint_keyed` with the secret's key).
pub fn read_checkpoint<T: DeserializeOwned>(path: impl AsRef<Path>) -> Result<T, IoError> {
    read_checkpoint_keyed(path, None)
}

/// Read a checkpoint; with `key`, only a keyed one whose MAC holds.
pub fn read_checkpoint_keyed<T: DeserializeOwned>(
    path: impl AsRef<Path>,
    key: Option<&CheckpointKey>,
) -> Result<T, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).at(path)?;
    decode_checkpoint(path, &bytes, key)
}

/// The checks of `read_checkpoint_keyed` on bytes already read (`path` names them in
/// errors). Any bytes give a value or a typed error, never a panic (fuzzed:
/// crates/crash-io/tests/fuzz_checkpoint.rs).
pub fn decode_checkpoint<T: DeserializeOwned>(
    path: &Path,
    bytes: &[u8],
    key: Option<&CheckpointKey>,
) -> Result<T, IoError> {
    let truncated = |expected: u64| IoError::Truncated {
        path: path.to_path_buf(),
        found: bytes.len() as u64,
        expected,
    };
    let keyed = match bytes.get(..8) {
        Some(m) if m == MAGIC => false,
        Some(m) if m == MAGIC_KEYED => true,
        _ => {
            return Err(IoError::BadMagic {
                path: path.to_path_buf(),
            })
        }
    };
    match (keyed, key) {
        (true, None) => {
            return Err(IoError::Keyed {
                path: path.to_path_buf(),
            })
        }
        (false, Some(_)) => {
            return Err(IoError::Unkeyed {
                path: path.to_path_buf(),
            })
        }
        _ => {}
    }
    let header = HEADER + if keyed { MAC_LEN } else { 0 };
    if bytes.len() < header {
        return Err(truncated(header as u64));
    }
    let word = |at: usize| {
        let mut a = [0u8; 8];
        a.copy_from_slice(&bytes[at..at + 8]);
        u64::from_le_bytes(a)
    };
    let mut v = [0u8; 4];
    v.copy_from_slice(&bytes[8..12]);
    let version = u32::from_le_bytes(v);
    if version != VERSION {
        return Err(IoError::Version {
            path: path.to_path_buf(),
            found: version,
            expected: VERSION,
        });
    }
    let len = word(12);
    let sum = word(20);
    let expected = (header as u64).saturating_add(len);
    if (bytes.len() as u64) < expected {
        return Err(truncated(expected));
    }
    if bytes.len() as u64 > expected {
        return Err(IoError::format(
            path,
            format!(
                "checkpoint has {} bytes after its payload",
                bytes.len() as u64 - expected
            ),
        ));
    }
    let payload = &bytes[header..];
    if checksum(payload) != sum {
        return Err(IoError::Checksum {
            path: path.to_path_buf(),
        });
    }
    if let Some(k) = key {
        // constant-time comparison (verify_slice)
        if k.mac(&bytes[..HEADER], payload)
            .verify_slice(&bytes[HEADER..header])
            .is_err()
        {
            return Err(IoError::Mac {
                path: path.to_path_buf(),
            });
        }
    }
    postcard::from_bytes(payload).map_err(|e| IoError::Encode {
        path: path.to_path_buf(),
        source: e,
    })
}
