//! The frame series written by a background thread, so that the step loop never waits
//! for encoding, compression or the disk.
//!
//! The run hands each frame over body by body (`begin_frame`, `frame_body`, `end_frame`)
//! and goes on; a writer thread owns the `SeriesWriter`. Memory stays bounded: at most
//! `MAX_FRAMES` frames are in flight (queued or being written) and at most
//! `MAX_QUEUED_ELEMENTS` elements' worth of bodies wait in the queue (one larger body is
//! let through alone). When the writer lags, the caller waits (`stalls` counts it, and
//! `take_stall_note` says so once).
//!
//! A writer error (disk full, read-only directory) stops the writing: the frame it hit
//! leaves no file, the frames before it stay listed in the .pvd, and the next call (or
//! `flush`/`finish`) returns the error, which names the file.

use crate::error::IoError;
use crate::frame::FrameBody;
use crate::series::{PvdEntry, SeriesWriter};
use crate::vtu::VtuFormat;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Frames handed over but not yet on disk (the one being written included).
pub const MAX_FRAMES: usize = 2;
/// Elements of the bodies waiting in the queue (about 140 bytes each).
pub const MAX_QUEUED_ELEMENTS: usize = 250_000;

enum Job {
    Begin {
        time: f64,
        step: u64,
        format: VtuFormat,
    },
    // boxed: a body is large beside the other jobs
    Body(Box<FrameBody>),
    End,
}

#[derive(Default)]
struct State {
    queue: VecDeque<Job>,
    queued_elements: usize,
    /// Frames begun by the caller and not yet written (or dropped) by the writer.
    frames_in_flight: usize,
    /// The writer's first error (handed to the caller once; later calls get `stopped`).
    error: Option<IoError>,
    stopped: Option<String>,
    closed: bool,
    /// Entries of the .pvd after the last written frame.
    entries: Vec<PvdEntry>,
    /// How often and how long the caller waited for the writer.
    stalls: u64,
    stall_time: Duration,
}

struct Shared {
    state: Mutex<State>,
    changed: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // a panic on the other side leaves a usable state (plain counters and a queue)
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// A `SeriesWriter` on its own thread.
pub struct BackgroundSeries {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    format: VtuFormat,
    dir: PathBuf,
    stall_noted: bool,
}

impl std::fmt::Debug for BackgroundSeries {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BackgroundSeries")
            .field("dir", &self.dir)
            .field("format", &self.format)
            .finish()
    }
}

/// The writer thread's nice value: its work is off the step loop's path, so the step
/// loop's threads (and on a cluster host the workers beside the master) take the CPU
/// first. With two workers and the master on two cores, a frame every 50 steps cost the
/// split showcase 2.81-2.88 s at nice 0 and 2.70 s at nice 10 (docs/performance.md,
/// session 25); one process with a core to spare is unchanged. The queue is bounded:
/// a writer that falls behind makes the step loop wait, and the log says so.
pub const WRITER_NICE: i32 = 10;

/// Lower the calling thread's priority to `WRITER_NICE`, or keep it where it is when it
/// is lower already (a run started under `nice`); Linux, nothing elsewhere.
#[cfg(target_os = "linux")]
#[allow(unsafe_code)]
fn lower_priority() {
    // SAFETY: gettid takes no arguments and returns the calling thread's id;
    // getpriority and setpriority with PRIO_PROCESS and a thread id read and set that
    // thread's nice value only. A refusal leaves the thread as it was, harmless.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        let now = libc::getpriority(libc::PRIO_PROCESS, tid);
        libc::setpriority(libc::PRIO_PROCESS, tid, now.max(WRITER_NICE));
    }
}

#[cfg(not(target_os = "linux"))]
fn lower_priority() {}

impl BackgroundSeries {
    /// Start the writer thread for `series`.
    pub fn start(series: SeriesWriter) -> Result<Self, IoError> {
        let dir = series.dir().to_path_buf();
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                entries: series.entries().to_vec(),
                ..State::default()
            }),
            changed: Condvar::new(),
        });
        let s = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("crash-frames".into())
            .spawn(move || {
                lower_priority();
                write_loop(&s, series)
            })
            .map_err(|e| IoError::io(&dir, e))?;
        Ok(Self {
            shared,
            thread: Some(thread),
            format: VtuFormat::default(),
            dir,
            stall_noted: false,
        })
    }

    /// The format of the frames begun from now on.
    pub fn set_format(&mut self, format: VtuFormat) {
        self.format = format;
    }

    pub fn format(&self) -> VtuFormat {
        self.format
    }

    /// Hand over the start of a frame; waits while `MAX_FRAMES` frames are in flight.
    pub fn begin_frame(&mut self, time: f64, step: u64) -> Result<(), IoError> {
        let format = self.format;
        let mut st = self.wait_while(|st| st.frames_in_flight >= MAX_FRAMES)?;
        st.frames_in_flight += 1;
        st.queue.push_back(Job::Begin { time, step, format });
        drop(st);
        self.shared.changed.notify_all();
        Ok(())
    }

    /// Hand over one body of the frame begun last; waits while the queue is full.
    pub fn frame_body(&mut self, body: FrameBody) -> Result<(), IoError> {
        let n = body.element_count().max(1);
        let mut st = self.wait_while(|st| {
            st.queued_elements > 0 && st.queued_elements + n > MAX_QUEUED_ELEMENTS
        })?;
        st.queued_elements += n;
        st.queue.push_back(Job::Body(Box::new(body)));
        drop(st);
        self.shared.changed.notify_all();
        Ok(())
    }

    /// Hand over the end of the frame begun last (it is written in the background).
    pub fn end_frame(&mut self) -> Result<(), IoError> {
        let mut st = self.wait_while(|_| false)?;
        st.queue.push_back(Job::End);
        drop(st);
        self.shared.changed.notify_all();
        Ok(())
    }

    /// Wait until every frame handed over is on disk and listed in the .pvd.
    pub fn flush(&mut self) -> Result<(), IoError> {
        let st = self.wait_while(|st| st.frames_in_flight > 0 || !st.queue.is_empty())?;
        drop(st);
        Ok(())
    }

    /// Write what is queued, stop the thread and return the first error, if any.
    pub fn finish(&mut self) -> Result<(), IoError> {
        let Some(thread) = self.thread.take() else {
            return self.take_error();
        };
        self.shared.lock().closed = true;
        self.shared.changed.notify_all();
        if thread.join().is_err() {
            let mut st = self.shared.lock();
            if st.error.is_none() && st.stopped.is_none() {
                st.error = Some(IoError::Invalid(format!(
                    "the frame writer of {} panicked",
                    self.dir.display()
                )));
            }
        }
        self.take_error()
    }

    /// The frames listed in the .pvd so far.
    pub fn entries(&self) -> Vec<PvdEntry> {
        self.shared.lock().entries.clone()
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// How often and how long the caller waited for the writer.
    pub fn stalls(&self) -> (u64, Duration) {
        let st = self.shared.lock();
        (st.stalls, st.stall_time)
    }

    /// A note for the log, once, the first time the caller had to wait.
    pub fn take_stall_note(&mut self) -> Option<String> {
        if self.stalls().0 == 0 || self.stall_noted {
            return None;
        }
        self.stall_noted = true;
        Some(format!(
            "the frame writer lags behind the run (frames are large or {} is slow): the step loop waits for it",
            self.dir.display()
        ))
    }

    fn take_error(&self) -> Result<(), IoError> {
        let mut st = self.shared.lock();
        if let Some(e) = st.error.take() {
            st.stopped = Some(e.to_string());
            return Err(e);
        }
        match &st.stopped {
            Some(m) => Err(IoError::Invalid(format!(
                "frames are no longer written after an earlier error: {m}"
            ))),
            None => Ok(()),
        }
    }

    /// Lock the state once `busy` is false (or the writer failed: then the error).
    fn wait_while(&self, busy: impl Fn(&State) -> bool) -> Result<MutexGuard<'_, State>, IoError> {
        self.take_error()?;
        let mut st = self.shared.lock();
        let mut waited = None;
        while busy(&st) && st.error.is_none() && st.stopped.is_none() && self.thread.is_some() {
            waited.get_or_insert_with(Instant::now);
            st = self
                .shared
                .changed
                .wait(st)
                .unwrap_or_else(|p| p.into_inner());
        }
        if let Some(t) = waited {
            st.stalls += 1;
            st.stall_time += t.elapsed();
        }
        if st.error.is_some() || st.stopped.is_some() {
            drop(st);
            return Err(self
                .take_error()
                .err()
                .unwrap_or_else(|| IoError::Invalid("the frame writer stopped".into())));
        }
        Ok(st)
    }
}

impl Drop for BackgroundSeries {
    fn drop(&mut self) {
        let _ = self.finish();
    }
}

/// The writer thread: take jobs in order until closed and drained.
fn write_loop(shared: &Shared, mut series: SeriesWriter) {
    loop {
        let job = {
            let mut st = shared.lock();
            loop {
                if let Some(j) = st.queue.pop_front() {
                    break j;
                }
                if st.closed {
                    return;
                }
                st = shared.changed.wait(st).unwrap_or_else(|p| p.into_inner());
            }
        };
        let failed = shared.lock().error.is_some();
        let (elements, ended) = match &job {
            Job::Body(b) => (b.element_count().max(1), false),
            Job::End => (0, true),
            Job::Begin { .. } => (0, false),
        };
        // after an error nothing more is written; jobs are only counted off
        let result = if failed {
            Ok(())
        } else {
            match job {
                Job::Begin { time, step, format } => {
                    series.set_format(format);
                    series.begin_frame(time, step)
                }
                Job::Body(mut b) => {
                    // what the step loop left of a deferred capture, on this thread
                    b.complete();
                    let r = series.frame_body(&b);
                    crate::frame::recycle(*b);
                    r
                }
                Job::End => series.end_frame().map(|_| ()),
            }
        };
        let mut st = shared.lock();
        st.queued_elements -= elements;
        if ended {
            st.frames_in_flight = st.frames_in_flight.saturating_sub(1);
            st.entries = series.entries().to_vec();
        }
        if let Err(e) = result {
            series.abort_frame();
            if st.error.is_none() && st.stopped.is_none() {
                st.error = Some(e);
            }
        }
        drop(st);
        shared.changed.notify_all();
    }
}
