//! The master's end of the step lane (`crash_link::lane`): a listener beside the gRPC
//! one, the admission of lanes, and a link's blocking I/O on its lane.
//!
//! Admission: a lane is taken only for a worker the master welcomed and is waiting for
//! (`Desk::expect`), only with that worker's index and session token (compared in
//! constant time) in its opening, read within the handshake deadline; at most
//! `PENDING` openings are read at once (more connections are closed at once). Anything
//! else is closed without touching the run. The listener and the admissions run on the
//! master's runtime, which then runs on a thread of its own (`server::Cluster::bind`),
//! so heartbeats are heard while the time-loop thread blocks on a lane.

use crate::error::MasterError;
use crate::heartbeat::Beats;
use crash_link::lane::{self, FrameReader, OPENING_LEN, TAKEN};
use crash_link::LinkError;
use std::collections::HashMap;
use std::io::{self, Write};
use std::net::{IpAddr, TcpStream};
use std::ops::Range;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};
use tokio::io::AsyncReadExt;
use tokio::runtime::Runtime;

/// Lane openings read at once; further connections are closed at once.
const PENDING: usize = 64;

#[derive(Debug)]
enum Slot {
    Waiting,
    Arrived(TcpStream),
}

/// The lanes expected (a welcomed worker) and arrived, by worker index.
#[derive(Debug)]
pub(crate) struct Desk {
    slots: Mutex<HashMap<u32, Slot>>,
    arrived: Condvar,
    port: u16,
}

impl Desk {
    pub(crate) fn port(&self) -> u16 {
        self.port
    }

    /// Worker `index` is welcomed: its lane is taken when it arrives.
    pub(crate) fn expect(&self, index: u32) {
        if let Ok(mut s) = self.slots.lock() {
            s.insert(index, Slot::Waiting);
        }
    }

    /// Worker `index`'s lane, waiting for it until `deadline`. None: it did not come
    /// (the slot is closed, so a lane that comes later is refused and its worker stays
    /// on gRPC too).
    pub(crate) fn take(&self, index: u32, deadline: Instant) -> Option<TcpStream> {
        let mut s = self.slots.lock().ok()?;
        loop {
            match s.remove(&index) {
                Some(Slot::Arrived(t)) => return Some(t),
                Some(Slot::Waiting) => {
                    let left = deadline.saturating_duration_since(Instant::now());
                    if left.is_zero() {
                        return None;
                    }
                    s.insert(index, Slot::Waiting);
                    s = self.arrived.wait_timeout(s, left).ok()?.0;
                }
                None => return None,
            }
        }
    }

    /// An admitted lane of worker `index`: taken (and told so) if it is expected.
    fn arrive(&self, index: u32, mut tcp: TcpStream) -> Result<(), String> {
        let mut s = self.slots.lock().map_err(|_| "lane table poisoned")?;
        if !matches!(s.get(&index), Some(Slot::Waiting)) {
            return Err(format!("no lane is expected for worker {index} (any more)"));
        }
        // under the lock: the master's `take` sees either no answer sent and the slot
        // waiting, or the answer sent and the lane there
        tcp.write_all(&[TAKEN]).map_err(|e| e.to_string())?;
        s.insert(index, Slot::Arrived(tcp));
        self.arrived.notify_all();
        Ok(())
    }
}

/// Listen for lanes on `ip`:`port` (0: any free port) on the runtime `rt`.
pub(crate) fn start(
    rt: &Runtime,
    ip: IpAddr,
    port: u16,
    beats: Arc<Beats>,
    handshake: Duration,
) -> Result<Arc<Desk>, MasterError> {
    let net = |e: io::Error| MasterError::Network(format!("step lane on {ip}:{port}: {e}"));
    let l = std::net::TcpListener::bind((ip, port)).map_err(net)?;
    l.set_nonblocking(true).map_err(net)?;
    let desk = Arc::new(Desk {
        slots: Mutex::new(HashMap::new()),
        arrived: Condvar::new(),
        port: l.local_addr().map_err(net)?.port(),
    });
    let l = {
        let _in = rt.enter();
        tokio::net::TcpListener::from_std(l).map_err(net)?
    };
    let d = desk.clone();
    rt.spawn(async move {
        let gate = Arc::new(tokio::sync::Semaphore::new(PENDING));
        loop {
            let (tcp, peer) = match l.accept().await {
                Ok(c) => c,
                Err(e) => {
                    tracing::debug!("step lane: accept failed: {e}");
                    tokio::time::sleep(Duration::from_millis(10)).await;
                    continue;
                }
            };
            let Ok(permit) = gate.clone().try_acquire_owned() else {
                tracing::debug!("step lane: {PENDING} openings pending; closed {peer}");
                continue;
            };
            let (d, b) = (d.clone(), beats.clone());
            tokio::spawn(async move {
                if let Err(why) = admit(&d, &b, tcp, handshake).await {
                    tracing::warn!("refused a step-lane connection from {peer}: {why}");
                }
                drop(permit);
            });
        }
    });
    Ok(desk)
}

/// Read a lane's opening within `handshake` and hand the lane to its link.
async fn admit(
    desk: &Desk,
    beats: &Beats,
    mut tcp: tokio::net::TcpStream,
    handshake: Duration,
) -> Result<(), String> {
    let mut b = [0u8; OPENING_LEN];
    match tokio::time::timeout(handshake, tcp.read_exact(&mut b)).await {
        Ok(Ok(_)) => {}
        Ok(Err(e)) => return Err(format!("no complete opening: {e}")),
        Err(_) => {
            return Err(format!(
                "no opening within {:.1} s",
                handshake.as_secs_f64()
            ))
        }
    }
    let (index, token) = lane::parse_opening(&b).ok_or("not a step lane's opening")?;
    if !beats.holds(index, token) {
        return Err(format!("wrong session token for worker {index}"));
    }
    let tcp = tcp.into_std().map_err(|e| e.to_string())?;
    tcp.set_nonblocking(false).map_err(|e| e.to_string())?;
    lane::tune(&tcp).map_err(|e| e.to_string())?;
    tcp.set_write_timeout(Some(Duration::from_secs(1)))
        .map_err(|e| e.to_string())?;
    desk.arrive(index, tcp)
}

/// What bounds a wait on a lane: the reply timeout, and the worker's heartbeats
/// (silence counted from the later of its last beat and the start of the wait, as on
/// the gRPC stream).
pub(crate) struct Watch<'a> {
    pub(crate) start: Instant,
    pub(crate) timeout: Duration,
    pub(crate) silence: Option<Duration>,
    pub(crate) beats: &'a Beats,
    pub(crate) index: u32,
}

impl Watch<'_> {
    fn check(&self) -> Result<(), LinkError> {
        if self.start.elapsed() >= self.timeout {
            return Err(LinkError::Timeout {
                seconds: self.timeout.as_secs_f64(),
            });
        }
        if let Some(s) = self.silence {
            let since = self
                .beats
                .last(self.index)
                .map_or(self.start, |b| b.max(self.start));
            if since.elapsed() > s {
                return Err(LinkError::Silent {
                    seconds: since.elapsed().as_secs_f64(),
                });
            }
        }
        Ok(())
    }
}

/// How often a wait on a lane looks at the heartbeats and the reply timeout (as the
/// gRPC stream's wait does; at most 250 ms, so a short wait such as `close`'s is kept).
pub(crate) fn look(silence: Option<Duration>, timeout: Duration) -> Duration {
    silence
        .map_or(timeout, |s| s / 10)
        .clamp(Duration::from_millis(20), Duration::from_millis(250))
}

fn waits(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
    )
}

fn lost(e: io::Error) -> LinkError {
    LinkError::Lost(format!("step lane: {e}"))
}

/// A link's lane: the stream, the frames read ahead, the frame being written.
#[derive(Debug)]
pub(crate) struct LaneIo {
    stream: TcpStream,
    reader: FrameReader,
    /// The frame to write (`crash_link::lane::encode_frame`; reused).
    pub(crate) out: Vec<u8>,
}

impl LaneIo {
    /// Blocking calls return every `look` so a wait can look at the heartbeats and the
    /// reply timeout; replies longer than `limit` are refused.
    pub(crate) fn new(stream: TcpStream, limit: usize, look: Duration) -> io::Result<Self> {
        let look = look.max(Duration::from_millis(1));
        stream.set_read_timeout(Some(look))?;
        stream.set_write_timeout(Some(look))?;
        Ok(Self {
            stream,
            reader: FrameReader::new(limit),
            out: Vec::new(),
        })
    }

    /// Write the frame in `out`. While the worker does not read (its socket buffer
    /// full), take in what it sends meanwhile, so that neither end waits for the other
    /// when both have much to say (a pipeline of large commands and large replies).
    pub(crate) fn write(&mut self, w: &Watch) -> Result<(), LinkError> {
        let mut off = 0;
        while off < self.out.len() {
            match (&self.stream).write(&self.out[off..]) {
                Ok(0) => return Err(LinkError::Lost("the step lane is closed".into())),
                Ok(n) => off += n,
                Err(e) if waits(&e) => {
                    self.read_ahead()?;
                    w.check()?;
                }
                Err(e) => return Err(lost(e)),
            }
        }
        Ok(())
    }

    /// Read what the worker has sent without waiting for more.
    fn read_ahead(&mut self) -> Result<(), LinkError> {
        self.stream.set_nonblocking(true).map_err(lost)?;
        let r = self.reader.fill(&mut &self.stream);
        self.stream.set_nonblocking(false).map_err(lost)?;
        match r {
            Ok(0) => Err(LinkError::Lost("the worker closed its step lane".into())),
            Ok(_) => Ok(()),
            Err(e) if waits(&e) => Ok(()),
            Err(e) => Err(lost(e)),
        }
    }

    /// The next frame's body (see `body`).
    pub(crate) fn read(&mut self, w: &Watch) -> Result<Range<usize>, LinkError> {
        loop {
            match self.reader.take() {
                Ok(Some(r)) => return Ok(r),
                Ok(None) => {}
                Err(e) => return Err(LinkError::Lost(format!("step lane: {e}"))),
            }
            match self.reader.fill(&mut &self.stream) {
                Ok(0) => return Err(LinkError::Lost("the worker closed its step lane".into())),
                Ok(_) => {}
                Err(e) if waits(&e) => w.check()?,
                Err(e) => return Err(lost(e)),
            }
        }
    }

    pub(crate) fn body(&self, r: Range<usize>) -> &[u8] {
        self.reader.body(r)
    }

    /// Best effort, without waiting: write the frame in `out` if the socket takes it
    /// now, then close the lane (the worker reads the frame, then the end).
    pub(crate) fn last_word(&mut self) {
        if self.stream.set_nonblocking(true).is_ok() {
            let _ = (&self.stream).write(&self.out);
        }
        let _ = self.stream.shutdown(std::net::Shutdown::Write);
    }
}
