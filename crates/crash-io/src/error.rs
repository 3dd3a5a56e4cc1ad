//! Typed errors of result writing and reading; every variant names the file.

use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum IoError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {what}")]
    Format { path: PathBuf, what: String },
    #[error("{path}: checkpoint is not a crash checkpoint (bad magic)")]
    BadMagic { path: PathBuf },
    #[error("{path}: checkpoint format version {found}, this build reads version {expected}")]
    Version {
        path: PathBuf,
        found: u32,
        expected: u32,
    },
    #[error("{path}: checkpoint is truncated ({found} bytes, {expected} expected)")]
    Truncated {
        path: PathBuf,
        found: u64,
        expected: u64,
    },
    #[error("{path}: checkpoint is corrupt (checksum mismatch)")]
    Checksum { path: PathBuf },
    /// The keyed MAC does not hold: edited, or written under another secret.
    #[error("{path}: checkpoint was edited or written under another shared secret (its keyed MAC does not match this secret); refusing to use it")]
    Mac { path: PathBuf },
    #[error("{path}: checkpoint is keyed (written with a shared secret): give the same secret (--secret-file or CRASH_SECRET) to read it")]
    Keyed { path: PathBuf },
    #[error("{path}: checkpoint carries no keyed MAC but a shared secret is set: it cannot be told from an edited one; read it without the secret if you trust the file")]
    Unkeyed { path: PathBuf },
    #[error("{path}: {source}")]
    Encode {
        path: PathBuf,
        #[source]
        source: postcard::Error,
    },
    #[error("{path}: {source}")]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    #[error("{path}: PNG: {what}")]
    Png { path: PathBuf, what: String },
    #[error("{0}")]
    Invalid(String),
}

impl IoError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    pub(crate) fn format(path: &Path, what: impl Into<String>) -> Self {
        Self::Format {
            path: path.to_path_buf(),
            what: what.into(),
        }
    }
}

/// Attach a path to an `std::io::Result`.
pub(crate) trait AtPath<T> {
    fn at(self, path: &Path) -> Result<T, IoError>;
}

impl<T> AtPath<T> for std::io::Result<T> {
    fn at(self, path: &Path) -> Result<T, IoError> {
        self.map_err(|e| IoError::io(path, e))
    }
}
