//! Atomic file replacement: write a temp file in the same directory, fsync, rename.
//! A reader (or an interrupted run) sees either the old or the new file, never a torn one.

use crate::error::{AtPath, IoError};
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub(crate) fn temp_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Write `path` atomically with the bytes produced by `fill`.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let tmp = temp_path(path);
    let file = File::create(&tmp).at(&tmp)?;
    let mut w = BufWriter::new(file);
    fill(&mut w).at(&tmp)?;
    let file = w
        .into_inner()
        .map_err(|e| IoError::io(&tmp, e.into_error()))?;
    file.sync_all().at(&tmp)?;
    drop(file);
    fs::rename(&tmp, path).at(path)?;
    sync_dir(path);
    Ok(())
}

/// Make the rename durable. Best effort: not every platform can open a directory.
fn sync_dir(path: &Path) {
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
}
