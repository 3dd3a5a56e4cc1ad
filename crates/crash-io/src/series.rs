//! The ParaView series of a run: one .vtu per frame under `frames/` and a .pvd
//! collection that is rewritten atomically after every frame, so an interrupted run
//! still leaves a valid series. Restart keeps the frames up to the restart time and
//! continues the numbering.

use crate::atomic::{write_atomic, AtomicFile};
use crate::block_cache::BlockCache;
use crate::error::{AtPath, IoError};
use crate::frame::{Frame, FrameBody};
use crate::vtu::VtuFormat;
use crate::vtu_encode::{FrameEncoder, Spill};
use roxmltree::Document;
use std::mem::take;
use std::path::{Path, PathBuf};

/// Name of the collection file inside the output directory.
pub const PVD_FILE: &str = "frames.pvd";
/// Sub-directory (of the output directory) that holds the .vtu files.
pub const FRAMES_DIR: &str = "frames";

/// One frame listed in the .pvd.
#[derive(Debug, Clone, PartialEq)]
pub struct PvdEntry {
    pub time: f64,
    /// Path relative to the .pvd's directory, e.g. `frames/frame_000003.vtu`.
    pub file: String,
}

/// Writes the frame series of one run.
#[derive(Debug)]
pub struct SeriesWriter {
    dir: PathBuf,
    format: VtuFormat,
    entries: Vec<PvdEntry>,
    next_index: u64,
    /// The frame being written body by body.
    open: Option<OpenFrame>,
    /// Compressed blocks of the previous frame's steady arrays.
    cache: BlockCache,
}

#[derive(Debug)]
struct OpenFrame {
    time: f64,
    file: String,
    path: PathBuf,
    enc: FrameEncoder,
}

fn frame_file(index: u64) -> String {
    format!("{FRAMES_DIR}/frame_{index:06}.vtu")
}

fn index_of(file: &str) -> Option<u64> {
    file.strip_prefix(&format!("{FRAMES_DIR}/frame_"))?
        .strip_suffix(".vtu")?
        .parse()
        .ok()
}

/// Read the frames listed in a .pvd file.
pub fn read_pvd(path: &Path) -> Result<Vec<PvdEntry>, IoError> {
    let text = std::fs::read_to_string(path).at(path)?;
    let doc = Document::parse(&text).map_err(|e| IoError::format(path, format!("XML: {e}")))?;
    let mut out = Vec::new();
    for d in doc.descendants().filter(|n| n.has_tag_name("DataSet")) {
        let time = d
            .attribute("timestep")
            .and_then(|t| t.parse::<f64>().ok())
            .ok_or_else(|| IoError::format(path, "DataSet without a valid timestep"))?;
        let file = d
            .attribute("file")
            .ok_or_else(|| IoError::format(path, "DataSet without a file"))?;
        out.push(PvdEntry {
            time,
            file: file.to_string(),
        });
    }
    Ok(out)
}

fn write_pvd(path: &Path, entries: &[PvdEntry]) -> Result<(), IoError> {
    write_atomic(path, |w| {
        writeln!(w, r#"<?xml version="1.0"?>"#)?;
        writeln!(
            w,
            r#"<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">"#
        )?;
        writeln!(w, "  <Collection>")?;
        for e in entries {
            writeln!(
                w,
                r#"    <DataSet timestep="{:e}" group="" part="0" file="{}"/>"#,
                e.time, e.file
            )?;
        }
        writeln!(w, "  </Collection>")?;
        writeln!(w, "</VTKFile>")
    })
}

impl SeriesWriter {
    /// Start a new series in `dir` (created if needed). Frames of an earlier series that
    /// its .pvd listed are removed so stale frames cannot mix in.
    pub fn create(dir: impl AsRef<Path>) -> Result<Self, IoError> {
        let dir = dir.as_ref().to_path_buf();
        let frames = dir.join(FRAMES_DIR);
        std::fs::create_dir_all(&frames).at(&frames)?;
        let pvd = dir.join(PVD_FILE);
        let old = if pvd.exists() {
            read_pvd(&pvd).unwrap_or_default()
        } else {
            Vec::new()
        };
        // The .pvd first, then the files: it never lists a missing frame.
        write_pvd(&pvd, &[])?;
        remove_frames(&dir, &old)?;
        Ok(Self {
            dir,
            format: VtuFormat::default(),
            entries: Vec::new(),
            next_index: 0,
            open: None,
            cache: BlockCache::default(),
        })
    }

    /// Continue the series in `dir` after a restart from `up_to_time`: frames with
    /// time <= up_to_time are kept, later ones are dropped (and their files removed),
    /// and numbering continues after the last kept frame.
    pub fn reopen(dir: impl AsRef<Path>, up_to_time: f64) -> Result<Self, IoError> {
        let dir = dir.as_ref().to_path_buf();
        let frames = dir.join(FRAMES_DIR);
        std::fs::create_dir_all(&frames).at(&frames)?;
        let pvd = dir.join(PVD_FILE);
        let all = if pvd.exists() {
            read_pvd(&pvd)?
        } else {
            Vec::new()
        };
        let (keep, drop): (Vec<_>, Vec<_>) = all.into_iter().partition(|e| e.time <= up_to_time);
        let next_index = keep
            .iter()
            .filter_map(|e| index_of(&e.file))
            .max()
            .map_or(0, |i| i + 1);
        write_pvd(&pvd, &keep)?;
        remove_frames(&dir, &drop)?;
        Ok(Self {
            dir,
            format: VtuFormat::default(),
            entries: keep,
            next_index,
            open: None,
            cache: BlockCache::default(),
        })
    }

    /// Choose how data arrays are stored (default: Float64, zlib-compressed).
    pub fn with_format(mut self, format: VtuFormat) -> Self {
        self.format = format;
        self
    }

    /// The format of the frames begun from now on.
    pub fn set_format(&mut self, format: VtuFormat) {
        self.format = format;
    }

    /// Write one frame and rewrite the .pvd. A frame at or before the last listed time
    /// replaces the listed frames from that time on. Returns the .vtu path.
    pub fn write(&mut self, frame: &Frame) -> Result<PathBuf, IoError> {
        self.begin_frame(frame.time, frame.step)?;
        for b in &frame.bodies {
            self.frame_body(b)?;
        }
        self.end_frame()
    }

    /// Start a frame that arrives body by body (`frame_body`, then `end_frame`): the
    /// data is staged (memory, then `NAME.vtu.spill` for a large frame) and the .vtu is
    /// written as a temporary file that takes its name only when complete.
    pub fn begin_frame(&mut self, time: f64, step: u64) -> Result<(), IoError> {
        if !time.is_finite() {
            return Err(IoError::Invalid(format!(
                "frame at step {step} has a non-finite time {time}"
            )));
        }
        let file = frame_file(self.next_index);
        let path = self.dir.join(&file);
        let mut spill_name = path.clone().into_os_string();
        spill_name.push(".spill");
        let spill = Spill::with_file(PathBuf::from(spill_name));
        self.open = Some(OpenFrame {
            time,
            file,
            path,
            enc: FrameEncoder::new(time, step, self.format, spill, take(&mut self.cache)),
        });
        Ok(())
    }

    /// One body of the frame begun last (bodies in id order).
    pub fn frame_body(&mut self, body: &FrameBody) -> Result<(), IoError> {
        let f = self
            .open
            .as_mut()
            .ok_or_else(|| IoError::Invalid("a frame body arrived outside a frame".into()))?;
        // a deferred capture handed straight here (not through the background writer)
        let r = f.enc.body(&body.completed()).at(&f.path);
        if r.is_err() {
            self.open = None;
        }
        r
    }

    /// Drop the frame begun last (after an error): its staged data is removed and
    /// no .vtu of it appears.
    pub fn abort_frame(&mut self) {
        self.open = None;
    }

    /// Finish the frame begun last: write and rename its .vtu, list it in the .pvd.
    pub fn end_frame(&mut self) -> Result<PathBuf, IoError> {
        let OpenFrame {
            time,
            file,
            path,
            enc,
        } = self
            .open
            .take()
            .ok_or_else(|| IoError::Invalid("end of a frame that was not begun".into()))?;
        let mut out = AtomicFile::create(&path)?;
        match enc.finish(out.writer()) {
            Ok(cache) => self.cache = cache,
            Err(e) => {
                let temp = out.temp().to_path_buf();
                drop(out);
                let _ = std::fs::remove_file(&temp);
                return Err(IoError::io(&path, e));
            }
        }
        out.commit()?;
        let mut replaced = Vec::new();
        if self.entries.last().is_some_and(|e| e.time >= time) {
            let (keep, drop): (Vec<_>, Vec<_>) =
                self.entries.drain(..).partition(|e| e.time < time);
            self.entries = keep;
            replaced = drop;
        }
        self.next_index += 1;
        self.entries.push(PvdEntry { time, file });
        write_pvd(&self.pvd_path(), &self.entries)?;
        remove_frames(&self.dir, &replaced)?;
        Ok(path)
    }

    pub fn entries(&self) -> &[PvdEntry] {
        &self.entries
    }

    pub fn pvd_path(&self) -> PathBuf {
        self.dir.join(PVD_FILE)
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

/// Remove the .vtu files of `entries` (only our own `frames/frame_N.vtu` names).
fn remove_frames(dir: &Path, entries: &[PvdEntry]) -> Result<(), IoError> {
    for e in entries.iter().filter(|e| index_of(&e.file).is_some()) {
        let p = dir.join(&e.file);
        match std::fs::remove_file(&p) {
            Ok(()) => {}
            Err(err) if err.kind() == std::io::ErrorKind::NotFound => {}
            Err(err) => return Err(IoError::io(&p, err)),
        }
    }
    Ok(())
}
