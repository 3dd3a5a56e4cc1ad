//! Files a scene names (meshes, keyword includes): checked before anything is read,
//! and read with a size cap, so that `/dev/zero`, a FIFO or a mistyped multi-gigabyte
//! path cannot exhaust memory.

use std::io::Read;
use std::path::Path;

/// Largest mesh or keyword file read [bytes]: 4 GiB holds a Gmsh file of some 40
/// million elements, more than `shape::MAX_ELEMENTS` per body.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// Why a file cannot be used.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FileProblem {
    /// It does not exist, or cannot be opened or read (the OS's message).
    Unreadable(String),
    /// It is a directory, a device, a FIFO...: only regular files are read.
    NotRegular(&'static str),
    /// It is larger than the cap (its size in bytes, or None for "more than the cap").
    TooLarge(Option<u64>),
}

impl FileProblem {
    /// What to tell the user (`path` as they wrote it, or resolved).
    pub fn describe(&self, path: &Path, cap: u64) -> String {
        match self {
            FileProblem::Unreadable(e) => format!("cannot read {}: {e}", path.display()),
            FileProblem::NotRegular(kind) => {
                format!("{} is {kind}, not a regular file", path.display())
            }
            FileProblem::TooLarge(Some(n)) => format!(
                "{} is {n} bytes, more than the {cap} bytes a mesh or deck file may have",
                path.display()
            ),
            FileProblem::TooLarge(None) => format!(
                "{} holds more than the {cap} bytes a mesh or deck file may have",
                path.display()
            ),
        }
    }
}

fn kind(ft: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
        if ft.is_fifo() {
            return "a FIFO";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    if ft.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}

/// Exists, is a regular file (symlinks followed) and is at most `cap` bytes.
pub fn check(path: &Path, cap: u64) -> Result<u64, FileProblem> {
    let meta = std::fs::metadata(path).map_err(|e| FileProblem::Unreadable(e.to_string()))?;
    if !meta.is_file() {
        return Err(FileProblem::NotRegular(kind(meta.file_type())));
    }
    if meta.len() > cap {
        return Err(FileProblem::TooLarge(Some(meta.len())));
    }
    Ok(meta.len())
}

/// Read a file checked by `check`, never more than `cap` bytes (it may have grown).
pub fn read(path: &Path, cap: u64) -> Result<Vec<u8>, FileProblem> {
    let len = check(path, cap)?;
    let f = std::fs::File::open(path).map_err(|e| FileProblem::Unreadable(e.to_string()))?;
    let mut bytes = Vec::with_capacity(len as usize);
    f.take(cap.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| FileProblem::Unreadable(e.to_string()))?;
    if bytes.len() as u64 > cap {
        return Err(FileProblem::TooLarge(None));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_large_files_are_refused_before_reading() {
        if Path::new("/dev/zero").exists() {
            assert_eq!(
                read(Path::new("/dev/zero"), 1 << 20),
                Err(FileProblem::NotRegular("a character device"))
            );
        }
        assert_eq!(
            check(Path::new("/"), 10),
            Err(FileProblem::NotRegular("a directory"))
        );
        let me = Path::new(file!());
        let me = if me.exists() {
            me.to_path_buf()
        } else {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("src/files.rs")
        };
        assert!(matches!(
            check(&me, 10),
            Err(FileProblem::TooLarge(Some(_)))
        ));
        assert!(read(&me, MAX_FILE_BYTES).is_ok());
        assert!(matches!(
            read(Path::new("/no/such/file"), 10),
            Err(FileProblem::Unreadable(_))
        ));
    }
}
