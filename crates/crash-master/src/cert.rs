//! `crash-master cert`: a self-signed certificate and key for TLS between the master
//! and its workers (docs/reliability.md). The master serves with `--tls-cert
//! DIR/cert.pem --tls-key DIR/key.pem`; each worker trusts the same certificate with
//! `--tls-ca DIR/cert.pem` and dials `https://HOST:PORT`, HOST one of the names given.

use std::path::{Path, PathBuf};
use thiserror::Error;

pub const CERT_FILE: &str = "cert.pem";
pub const KEY_FILE: &str = "key.pem";

#[derive(Debug, Error)]
pub enum CertError {
    #[error("give at least one host name or IP address the workers dial (--host)")]
    NoHost,
    #[error("cannot make the certificate for {hosts:?}: {reason}")]
    Make { hosts: Vec<String>, reason: String },
    #[error("cannot write {path}: {reason}")]
    Write { path: PathBuf, reason: String },
}

/// A self-signed certificate (PEM) valid for `hosts` (DNS names or IP addresses), and
/// its private key (PEM).
pub fn self_signed(hosts: &[String]) -> Result<(String, String), CertError> {
    if hosts.is_empty() {
        return Err(CertError::NoHost);
    }
    let made = rcgen::generate_simple_self_signed(hosts.to_vec()).map_err(|e| CertError::Make {
        hosts: hosts.to_vec(),
        reason: e.to_string(),
    })?;
    Ok((made.cert.pem(), made.signing_key.serialize_pem()))
}

/// Write `DIR/cert.pem` and `DIR/key.pem` (the key readable by its owner only).
pub fn write_pair(dir: &Path, hosts: &[String]) -> Result<(PathBuf, PathBuf), CertError> {
    let (cert, key) = self_signed(hosts)?;
    let bad = |path: &Path, e: std::io::Error| CertError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    std::fs::create_dir_all(dir).map_err(|e| bad(dir, e))?;
    let (cp, kp) = (dir.join(CERT_FILE), dir.join(KEY_FILE));
    std::fs::write(&cp, cert).map_err(|e| bad(&cp, e))?;
    write_private(&kp, key.as_bytes()).map_err(|e| bad(&kp, e))?;
    Ok((cp, kp))
}

#[cfg(unix)]
fn write_private(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    use std::os::unix::fs::OpenOptionsExt;
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .mode(0o600)
        .open(path)?;
    f.write_all(bytes)
}

#[cfg(not(unix))]
fn write_private(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    std::fs::write(path, bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_self_signed_pair_is_pem_and_names_are_required() {
        let (c, k) = self_signed(&["localhost".into(), "127.0.0.1".into()]).expect("pair");
        assert!(c.starts_with("-----BEGIN CERTIFICATE-----"), "{c}");
        assert!(k.contains("PRIVATE KEY-----"));
        assert!(matches!(self_signed(&[]), Err(CertError::NoHost)));
    }
}
