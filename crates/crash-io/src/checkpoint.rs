//! Checkpoints: any serde state in a compact binary form (postcard: f64 as its 8 raw
//! bytes, so values round-trip exactly), behind a header that names the format and
//! version and guards against truncation and corruption. Written atomically.
//!
//! Layout: magic "CRASHCKP" (8) | version u32 LE | payload length u64 LE |
//! FNV-1a 64 of the payload u64 LE | payload.

use crate::atomic::write_atomic;
use crate::error::{AtPath, IoError};
use crash_core::hash::Fnv;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;

pub const MAGIC: &[u8; 8] = b"CRASHCKP";
/// Layout version of the payload. 2: body states apart from definitions, the run's
/// clock (`crash_core::Clock`). 3: the contact speed rule, the run's energy figure in
/// every record, the shortened last step apart, warnings raised so far.
pub const VERSION: u32 = 4;
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
    let path = path.as_ref();
    let payload = checkpoint_payload(value).map_err(|e| IoError::Encode {
        path: path.to_path_buf(),
        source: e,
    })?;
    write_atomic(path, |w| {
        w.write_all(MAGIC)?;
        w.write_all(&VERSION.to_le_bytes())?;
        w.write_all(&(payload.len() as u64).to_le_bytes())?;
        w.write_all(&checksum(&payload).to_le_bytes())?;
        w.write_all(&payload)
    })
}

/// Read a checkpoint written by `write_checkpoint`.
pub fn read_checkpoint<T: DeserializeOwned>(path: impl AsRef<Path>) -> Result<T, IoError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).at(path)?;
    let truncated = |expected: u64| IoError::Truncated {
        path: path.to_path_buf(),
        found: bytes.len() as u64,
        expected,
    };
    if bytes.len() < MAGIC.len() || &bytes[..8] != MAGIC {
        return Err(IoError::BadMagic {
            path: path.to_path_buf(),
        });
    }
    if bytes.len() < HEADER {
        return Err(truncated(HEADER as u64));
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
    let expected = (HEADER as u64).saturating_add(len);
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
    let payload = &bytes[HEADER..];
    if checksum(payload) != sum {
        return Err(IoError::Checksum {
            path: path.to_path_buf(),
        });
    }
    postcard::from_bytes(payload).map_err(|e| IoError::Encode {
        path: path.to_path_buf(),
        source: e,
    })
}
