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
/// Dropped without a successful commit (a write error, a full disk, an abandoned
/// frame), it removes its temporary file: no `*.tmp` is left behind.
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    w: BufWriter<File>,
    committed: bool,
}

impl AtomicFile {
    pub fn create(path: &Path) -> Result<Self, IoError> {
        let tmp = temp_path(path);
        let w = BufWriter::new(File::create(&tmp).at(&tmp)?);
        Ok(Self {
            path: path.to_path_buf(),
            tmp,
            w,
            committed: false,
        })
    }

    pub fn writer(&mut self) -> &mut dyn Write {
        &mut self.w
    }

    /// The temporary name (for errors while writing).
    pub fn temp(&self) -> &Path {
        &self.tmp
    }

    /// Flush, sync and rename to the final name (on failure the temporary file is
    /// removed when `self` drops).
    pub fn commit(mut self) -> Result<(), IoError> {
        self.w.flush().at(&self.tmp)?;
        self.w.get_ref().sync_all().at(&self.tmp)?;
        fs::rename(&self.tmp, &self.path).at(&self.path)?;
        self.committed = true;
        sync_dir(&self.path);
        Ok(())
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if !self.committed {
            // best effort: the error that got us here is the one worth reporting
            let _ = fs::remove_file(&self.tmp);
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("crash-atomic-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).expect("test dir");
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .expect("list")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// A writer that fails like a full disk after `left` bytes.
    struct FullAfter<'a> {
        inner: &'a mut dyn Write,
        left: usize,
    }

    impl Write for FullAfter<'_> {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.left == 0 {
                return Err(std::io::Error::from_raw_os_error(28)); // ENOSPC
            }
            let n = buf.len().min(self.left);
            self.left -= n;
            self.inner.write(&buf[..n])
        }
        fn flush(&mut self) -> std::io::Result<()> {
            self.inner.flush()
        }
    }

    #[test]
    fn a_write_error_leaves_neither_a_temp_file_nor_a_torn_file() {
        let d = dir("fail");
        let path = d.join("summary.json");
        write_atomic(&path, |w| w.write_all(b"old")).expect("first write");
        let e = write_atomic(&path, |w| {
            let mut full = FullAfter {
                inner: w,
                left: 10_000,
            };
            full.write_all(&[b'x'; 100_000])
        })
        .expect_err("the write must fail");
        assert!(e.to_string().contains("summary.json.tmp"), "{e}");
        assert_eq!(names(&d), ["summary.json"], "no *.tmp left");
        assert_eq!(
            fs::read(&path).expect("read"),
            b"old",
            "the old file stays whole"
        );
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn an_atomic_file_dropped_before_commit_removes_its_temp_file() {
        let d = dir("drop");
        let path = d.join("frame_0001.vtu");
        let mut f = AtomicFile::create(&path).expect("create");
        f.writer().write_all(b"half a frame").expect("write");
        assert_eq!(names(&d), ["frame_0001.vtu.tmp"]);
        drop(f);
        assert!(names(&d).is_empty(), "{:?}", names(&d));
        let mut f = AtomicFile::create(&path).expect("create");
        f.writer().write_all(b"a frame").expect("write");
        f.commit().expect("commit");
        assert_eq!(names(&d), ["frame_0001.vtu"]);
        let _ = fs::remove_dir_all(&d);
    }
}
