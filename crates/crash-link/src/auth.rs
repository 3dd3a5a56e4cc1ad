//! Who may attach: a shared secret that a worker proves in its Hello without sending
//! it. The master's first message (`Challenge`) carries a fresh random nonce; the
//! worker answers `HMAC-SHA256(secret, DOMAIN || nonce || its Hello fields)`, which the
//! master checks in constant time. The secret is read from a file or an environment
//! variable, never from the command line (where `ps` shows it to every user).

use hmac::{Hmac, Mac};
use sha2::Sha256;
use std::path::Path;
use thiserror::Error;

/// Environment variable that holds the shared secret (when no `--secret-file`).
pub const SECRET_ENV: &str = "CRASH_SECRET";
/// Bytes of the master's nonce.
pub const NONCE_LEN: usize = 32;
/// Bytes of a proof (HMAC-SHA256).
pub const PROOF_LEN: usize = 32;
/// Shortest secret accepted [bytes].
pub const MIN_SECRET_LEN: usize = 16;
/// Separates this use of the secret from any other.
const DOMAIN: &[u8] = b"crash-hello-v3\0";
/// Separates the checkpoint key from the handshake's use of the secret.
const CHECKPOINT_DOMAIN: &[u8] = b"crash-checkpoint-key-v1\0";

type HmacSha256 = Hmac<Sha256>;

#[derive(Debug, Error)]
pub enum SecretError {
    #[error("cannot read the secret file {path}: {reason}")]
    Read { path: String, reason: String },
    #[error("the secret from {from} is {len} bytes long; use at least {MIN_SECRET_LEN} (e.g. `head -c 32 /dev/urandom | base64 > secret`)")]
    TooShort { from: String, len: usize },
    #[error("cannot draw a random nonce: {0}")]
    Random(String),
}

/// The shared secret of one cluster. Its Debug output never shows it.
#[derive(Clone)]
pub struct Secret(Vec<u8>);

impl std::fmt::Debug for Secret {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Secret({} bytes)", self.0.len())
    }
}

/// The Hello fields a proof covers (all of them but the proof).
#[derive(Debug, Clone, Copy)]
pub struct HelloFields<'a> {
    pub protocol_version: u32,
    pub threads: u32,
    pub host: &'a str,
    pub pid: u32,
}

impl Secret {
    /// A secret from bytes (trailing whitespace and newlines dropped).
    pub fn new(bytes: &[u8], from: &str) -> Result<Self, SecretError> {
        let end = bytes
            .iter()
            .rposition(|b| !b.is_ascii_whitespace())
            .map_or(0, |i| i + 1);
        let s = &bytes[..end];
        if s.len() < MIN_SECRET_LEN {
            return Err(SecretError::TooShort {
                from: from.to_string(),
                len: s.len(),
            });
        }
        Ok(Self(s.to_vec()))
    }

    /// The secret in a file (its whole content, trailing newline dropped).
    pub fn from_file(path: &Path) -> Result<Self, SecretError> {
        let bytes = std::fs::read(path).map_err(|e| SecretError::Read {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Self::new(&bytes, &path.display().to_string())
    }

    /// `--secret-file` if given, else `CRASH_SECRET` if set and not empty, else none.
    pub fn configured(file: Option<&Path>) -> Result<Option<Self>, SecretError> {
        if let Some(p) = file {
            return Self::from_file(p).map(Some);
        }
        match std::env::var_os(SECRET_ENV) {
            Some(v) if !v.is_empty() => {
                Self::new(v.as_encoded_bytes(), &format!("${SECRET_ENV}")).map(Some)
            }
            _ => Ok(None),
        }
    }

    /// The key of checkpoint MACs: HMAC-SHA256(secret, CHECKPOINT_DOMAIN), so a
    /// checkpoint's MAC and a Hello proof are never computed under the same key.
    pub fn checkpoint_key(&self) -> crash_io::CheckpointKey {
        let mut m = match HmacSha256::new_from_slice(&self.0) {
            Ok(m) => m,
            Err(_) => unreachable!("HMAC accepts any key length"),
        };
        m.update(CHECKPOINT_DOMAIN);
        crash_io::CheckpointKey(m.finalize().into_bytes().into())
    }

    fn mac(&self, nonce: &[u8], h: &HelloFields<'_>) -> HmacSha256 {
        // HMAC takes keys of any length: new_from_slice cannot fail
        let mut m = match HmacSha256::new_from_slice(&self.0) {
            Ok(m) => m,
            Err(_) => unreachable!("HMAC accepts any key length"),
        };
        m.update(DOMAIN);
        m.update(&(nonce.len() as u32).to_le_bytes());
        m.update(nonce);
        m.update(&h.protocol_version.to_le_bytes());
        m.update(&h.threads.to_le_bytes());
        m.update(&h.pid.to_le_bytes());
        m.update(&(h.host.len() as u32).to_le_bytes());
        m.update(h.host.as_bytes());
        m
    }

    /// The worker's proof for the master's nonce and its own Hello fields.
    pub fn prove(&self, nonce: &[u8], hello: &HelloFields<'_>) -> Vec<u8> {
        self.mac(nonce, hello).finalize().into_bytes().to_vec()
    }

    /// Check a proof in constant time.
    pub fn verify(&self, nonce: &[u8], hello: &HelloFields<'_>, proof: &[u8]) -> bool {
        self.mac(nonce, hello).verify_slice(proof).is_ok()
    }
}

/// Whether a secret file may be read by other users (group or others have any
/// permission); callers warn. Always false where permissions are not Unix modes.
pub fn readable_by_others(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::metadata(path).is_ok_and(|m| m.permissions().mode() & 0o077 != 0)
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        false
    }
}

/// A fresh random nonce from the operating system.
pub fn nonce() -> Result<[u8; NONCE_LEN], SecretError> {
    let mut n = [0u8; NONCE_LEN];
    getrandom::fill(&mut n).map_err(|e| SecretError::Random(e.to_string()))?;
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields(host: &str) -> HelloFields<'_> {
        HelloFields {
            protocol_version: 3,
            threads: 2,
            host,
            pid: 7,
        }
    }

    #[test]
    fn a_proof_holds_only_for_its_secret_nonce_and_fields() {
        let s = Secret::new(b"0123456789abcdef\n", "test").expect("secret");
        let other = Secret::new(b"0123456789abcdeX", "test").expect("secret");
        let n = nonce().expect("nonce");
        let p = s.prove(&n, &fields("a"));
        assert_eq!(p.len(), PROOF_LEN);
        assert!(s.verify(&n, &fields("a"), &p));
        assert!(!other.verify(&n, &fields("a"), &p));
        assert!(!s.verify(&n, &fields("b"), &p));
        assert!(!s.verify(&[0; NONCE_LEN], &fields("a"), &p));
        assert!(!s.verify(&n, &fields("a"), &[]));
        assert!(!s.verify(&n, &fields("a"), &p[..31]));
    }

    #[test]
    fn short_secrets_are_refused_and_debug_hides_it() {
        assert!(Secret::new(b"short\n", "x").is_err());
        let s = Secret::new(b"0123456789abcdef", "x").expect("secret");
        assert!(!format!("{s:?}").contains("0123"));
    }
}
