//! Atomic file replacement: write a temp file in the same directory, fsync, rename.
//! A reader (or an interrupted run) sees either the old or the new file, never a torn one.

use crate::error::{AtPath, IoError};
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

fn temp_path(path: &Path) -> PathBuf {
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
    let mut f = AtomicFile::create(path)?;
    if let Err(e) = fill(f.writer()) {
        let tmp = f.temp().to_path_buf();
        drop(f);
        let _ = fs::remove_file(&tmp);
        return Err(IoError::io(&tmp, e));
    }
    f.commit()
}

/// A file written under a temporary name that takes its own name only when complete
/// (`commit`): for files written piece by piece, e.g. a frame as its bodies arrive.
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    w: BufWriter<File>,
}

impl AtomicFile {
    pub fn create(path: &Path) -> Result<Self, IoError> {
        let tmp = temp_path(path);
        let w = BufWriter::new(File::create(&tmp).at(&tmp)?);
        Ok(Self {
            path: path.to_path_buf(),
            tmp,
            w,
        })
    }

    pub fn writer(&mut self) -> &mut dyn Write {
        &mut self.w
    }

    /// The temporary name (for errors while writing).
    pub fn temp(&self) -> &Path {
        &self.tmp
    }

    /// Flush, sync and rename to the final name. On failure the temporary file is
    /// removed (a full disk leaves no partial file behind).
    pub fn commit(self) -> Result<(), IoError> {
        let Self { path, tmp, w } = self;
        let done = (|| {
            let file = w
                .into_inner()
                .map_err(|e| IoError::io(&tmp, e.into_error()))?;
            file.sync_all().at(&tmp)?;
            drop(file);
            fs::rename(&tmp, &path).at(&path)
        })();
        if done.is_err() {
            let _ = fs::remove_file(&tmp);
        }
        done?;
        sync_dir(&path);
        Ok(())
    }
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
