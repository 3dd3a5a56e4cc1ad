//! Direct halo exchange between the holders of split groups (protocol v18).
//!
//! Through the master, a split step is two round trips: the holders' part states go
//! up in their Step reports and come down again in a Halo command. Here each holder
//! sends its part states straight to the other holders and reads theirs, so a split
//! step is one round trip with the master plus one message each way between workers,
//! and the master relays nothing.
//!
//! Every worker listens on a TCP port of its own (`Peers::bind`, announced in Hello).
//! Connections are made on first use and kept: of two workers, the one with the
//! higher index dials the other's address (from the split's spec) and opens with
//! `CRP1`, its worker index and the run's peer key (from the Welcome, 32 random bytes
//! the master makes per run); anything else is closed. Then every exchange writes
//! one length-prefixed `PeerHalo` frame to each peer and reads one from each, all at
//! once (non-blocking sockets and `poll`), so two large frames cannot block each
//! other's writers. Any failure (unreachable, closed, silent past the timeout, a
//! frame of another step, garbage) closes every peer connection and is returned: the
//! master then rolls back and relays from there on (crash-master `master/split.rs`).
//!
//! Plain TCP only, like the step lane: a master serving TLS offers no peer key, and
//! the part states then go through it.

use crate::lane::{encode_frame, opening_with, tune, FrameReader, OPENING_LEN};
use crash_proto::pb;
use std::collections::BTreeMap;
use std::io::{self, ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::os::fd::AsRawFd;
use std::time::{Duration, Instant};
use thiserror::Error;

/// First bytes of a peer connection's opening ("crash peer", version 1).
pub const MAGIC: [u8; 4] = *b"CRP1";
/// How long a worker tries to connect to a peer, and waits for an accepted
/// connection's opening.
pub const CONNECT: Duration = Duration::from_secs(2);
/// How long a worker waits for its peers' frames by default (a peer computes its own
/// parts meanwhile; a vanished peer host is found by the master's heartbeats sooner).
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(30);

#[derive(Debug, Error)]
pub enum PeerError {
    #[error("worker {worker} ({addr}): {what}")]
    Link {
        worker: u32,
        addr: String,
        what: String,
    },
    #[error("{0}")]
    Setup(String),
}

/// One open connection to another worker.
#[derive(Debug)]
struct Conn {
    s: TcpStream,
    reader: FrameReader,
}

/// One peer's frames of the exchange in flight.
#[derive(Debug)]
struct Slot {
    w: u32,
    addr: String,
    frame: Vec<u8>,
    sent: usize,
    got: Option<pb::PeerHalo>,
}

impl Slot {
    fn link(&self, what: String) -> PeerError {
        PeerError::Link {
            worker: self.w,
            addr: self.addr.clone(),
            what,
        }
    }

    /// Write what the socket takes now.
    fn write(&mut self, c: &mut Conn) -> Result<(), PeerError> {
        while self.sent < self.frame.len() {
            match c.s.write(&self.frame[self.sent..]) {
                Ok(0) => return Err(self.link("the connection closed".into())),
                Ok(n) => self.sent += n,
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(self.link(format!("write: {e}"))),
            }
        }
        Ok(())
    }

    /// Read what has arrived, until the frame is complete.
    fn read(&mut self, c: &mut Conn) -> Result<(), PeerError> {
        while self.got.is_none() {
            match c.reader.take() {
                Ok(Some(r)) => {
                    let m = <pb::PeerHalo as prost::Message>::decode(c.reader.body(r))
                        .map_err(|e| self.link(format!("a frame that does not decode: {e}")))?;
                    self.got = Some(m);
                }
                Ok(None) => match c.reader.fill(&mut c.s) {
                    Ok(0) => return Err(self.link("the connection closed".into())),
                    Ok(_) => {}
                    Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == ErrorKind::Interrupted => {}
                    Err(e) => return Err(self.link(format!("read: {e}"))),
                },
                Err(e) => return Err(self.link(e.to_string())),
            }
        }
        Ok(())
    }
}

/// This worker's side of the direct halo exchange.
#[derive(Debug)]
pub struct Peers {
    listener: TcpListener,
    port: u16,
    /// This worker's index and the run's peer key (after the Welcome).
    me: Option<(u32, Vec<u8>)>,
    conns: BTreeMap<u32, Conn>,
    timeout: Duration,
    /// The exchange in flight (`send` to `receive`) and when it gives up.
    slots: Vec<Slot>,
    deadline: Instant,
    /// How long a wait for the peers' frames polls before it blocks (`crate::poll`).
    poll: Duration,
    /// Accepted connections whose opening has not all come yet.
    openings: Vec<Opening>,
}

/// Equal in constant time (keys).
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

/// A peer connection's opening: magic, worker index (u32 LE), the run's peer key.
fn opening(index: u32, key: &[u8]) -> Option<[u8; OPENING_LEN]> {
    opening_with(MAGIC, index, key)
}

impl Peers {
    /// Listen on `port` (0: any free port) of every interface.
    pub fn bind(port: u16, timeout: Duration) -> io::Result<Self> {
        let any6 = SocketAddr::from((std::net::Ipv6Addr::UNSPECIFIED, port));
        let any4 = SocketAddr::from((std::net::Ipv4Addr::UNSPECIFIED, port));
        // both families where the host has IPv6, else IPv4 only
        let listener = TcpListener::bind(any6).or_else(|_| TcpListener::bind(any4))?;
        listener.set_nonblocking(true)?;
        let port = listener.local_addr()?.port();
        Ok(Self {
            listener,
            port,
            me: None,
            conns: BTreeMap::new(),
            timeout,
            slots: Vec::new(),
            deadline: Instant::now(),
            poll: Duration::ZERO,
            openings: Vec::new(),
        })
    }

    /// The port other workers dial.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// This worker's index in the run and the run's peer key (from the Welcome; an
    /// empty key: the master offers no direct exchange).
    pub fn join(&mut self, index: u32, key: Vec<u8>) {
        self.conns.clear();
        self.me = (key.len() == OPENING_LEN - 8).then_some((index, key));
    }

    /// Whether the master offered the direct exchange.
    pub fn offered(&self) -> bool {
        self.me.is_some()
    }

    /// Poll this long for the peers' frames before blocking (`crate::poll`; zero: block
    /// at once).
    pub fn set_poll(&mut self, budget: Duration) {
        self.poll = budget;
    }

    /// Close every connection (after a failure: whatever was in flight is dropped).
    pub fn close_all(&mut self) {
        self.conns.clear();
        self.slots.clear();
    }

    /// Send each peer `(worker, address, frame)` its frame and read one frame from
    /// each, in worker order. On any failure every connection is closed.
    pub fn exchange(
        &mut self,
        out: Vec<(u32, String, pb::PeerHalo)>,
    ) -> Result<Vec<(u32, pb::PeerHalo)>, PeerError> {
        self.send(out)?;
        self.receive()
    }

    /// Start an exchange: connect where needed and write what the sockets take now;
    /// `receive` finishes it (the caller computes meanwhile).
    pub fn send(&mut self, out: Vec<(u32, String, pb::PeerHalo)>) -> Result<(), PeerError> {
        let r = self.send_inner(out);
        if r.is_err() {
            self.close_all();
        }
        r
    }

    /// Finish the exchange `send` started: the rest of the frames out, one frame in
    /// from each peer, in worker order.
    pub fn receive(&mut self) -> Result<Vec<(u32, pb::PeerHalo)>, PeerError> {
        let r = self.receive_inner();
        if r.is_err() {
            self.close_all();
        }
        r
    }

    fn send_inner(&mut self, out: Vec<(u32, String, pb::PeerHalo)>) -> Result<(), PeerError> {
        let (me, key) = self
            .me
            .clone()
            .ok_or_else(|| PeerError::Setup("the master offered no direct exchange".into()))?;
        self.deadline = Instant::now() + self.timeout;
        self.slots.clear();
        for (w, addr, msg) in out {
            if w == me {
                return Err(PeerError::Setup(format!("worker {w} is this worker")));
            }
            let mut frame = Vec::new();
            encode_frame(&mut frame, &msg).map_err(|e| PeerError::Setup(e.to_string()))?;
            self.slots.push(Slot {
                w,
                addr,
                frame,
                sent: 0,
                got: None,
            });
        }
        self.slots.sort_by_key(|s| s.w);
        // the higher index dials
        for s in self.slots.iter().filter(|s| s.w < me) {
            if let std::collections::btree_map::Entry::Vacant(v) = self.conns.entry(s.w) {
                v.insert(
                    dial(&s.addr, me, &key).map_err(|e| s.link(format!("cannot connect: {e}")))?,
                );
            }
        }
        for s in &mut self.slots {
            if let Some(c) = self.conns.get_mut(&s.w) {
                s.write(c)?;
            }
        }
        Ok(())
    }

    fn receive_inner(&mut self) -> Result<Vec<(u32, pb::PeerHalo)>, PeerError> {
        let (me, key) = self
            .me
            .clone()
            .ok_or_else(|| PeerError::Setup("the master offered no direct exchange".into()))?;
        let poll_until = Instant::now() + self.poll;
        loop {
            // accept the lower-indexed peers' connections still missing
            let waiting = self.slots.iter().any(|s| !self.conns.contains_key(&s.w));
            if waiting {
                self.accept_ready(me, &key)?;
            }
            let mut done = true;
            let mut fds = Vec::with_capacity(self.slots.len() + 1);
            for s in &mut self.slots {
                let Some(c) = self.conns.get_mut(&s.w) else {
                    done = false;
                    continue;
                };
                s.write(c)?;
                s.read(c)?;
                let (w, r) = (s.sent < s.frame.len(), s.got.is_none());
                if w || r {
                    done = false;
                    let events =
                        if w { libc::POLLOUT } else { 0 } | if r { libc::POLLIN } else { 0 };
                    fds.push(libc::pollfd {
                        fd: c.s.as_raw_fd(),
                        events,
                        revents: 0,
                    });
                }
            }
            if done {
                break;
            }
            if waiting {
                let pending = self.openings.iter().map(|o| o.s.as_raw_fd());
                for fd in std::iter::once(self.listener.as_raw_fd()).chain(pending) {
                    fds.push(libc::pollfd {
                        fd,
                        events: libc::POLLIN,
                        revents: 0,
                    });
                }
            }
            // a bounded busy wait first (crate::poll): the frames are usually close
            if Instant::now() < poll_until {
                std::thread::yield_now();
                continue;
            }
            let left = self.deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                let silent: Vec<String> = self
                    .slots
                    .iter()
                    .filter(|s| s.got.is_none())
                    .map(|s| format!("worker {} ({})", s.w, s.addr))
                    .collect();
                return Err(PeerError::Setup(format!(
                    "no halo from {} within {:.1} s",
                    silent.join(", "),
                    self.timeout.as_secs_f64()
                )));
            }
            let ms = left.as_millis().clamp(1, i32::MAX as u128) as i32;
            if let Err(e) = poll(&mut fds, ms) {
                if e.kind() != ErrorKind::Interrupted {
                    return Err(PeerError::Setup(format!("poll: {e}")));
                }
            }
        }
        Ok(std::mem::take(&mut self.slots)
            .into_iter()
            .filter_map(|s| s.got.map(|g| (s.w, g)))
            .collect())
    }

    /// Take every connection waiting on the listener, then read the openings that
    /// have come (never waiting for one: a stranger that connects and says nothing
    /// costs no time); keep those that prove the run's key and name a higher index
    /// than ours. Others, and openings not complete within `CONNECT`, are closed with
    /// a warning.
    fn accept_ready(&mut self, me: u32, key: &[u8]) -> Result<(), PeerError> {
        loop {
            match self.listener.accept() {
                Ok((s, from)) => {
                    s.set_nonblocking(true)
                        .map_err(|e| PeerError::Setup(format!("peer socket: {e}")))?;
                    self.openings.push(Opening {
                        s,
                        from,
                        b: [0; OPENING_LEN],
                        got: 0,
                        until: Instant::now() + CONNECT,
                    });
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(PeerError::Setup(format!("accept: {e}"))),
            }
        }
        for mut o in std::mem::take(&mut self.openings) {
            match o.read(key) {
                Ok(None) if Instant::now() < o.until => self.openings.push(o),
                Ok(None) => tracing::warn!(
                    "closed a peer connection from {}: no opening within {:.0} s",
                    o.from,
                    CONNECT.as_secs_f64()
                ),
                Ok(Some(w)) if w > me => {
                    let c =
                        ready(o.s).map_err(|e| PeerError::Setup(format!("peer socket: {e}")))?;
                    self.conns.insert(w, c);
                }
                Ok(Some(w)) => tracing::warn!(
                    "closed a peer connection from {}: worker {w} does not dial worker {me}",
                    o.from
                ),
                Err(e) => tracing::warn!("closed a peer connection from {}: {e}", o.from),
            }
        }
        Ok(())
    }
}

/// An accepted connection whose opening is still being read.
#[derive(Debug)]
struct Opening {
    s: TcpStream,
    from: SocketAddr,
    b: [u8; OPENING_LEN],
    got: usize,
    until: Instant,
}

impl Opening {
    /// Read what has come of the opening: the dialling worker's index once complete
    /// and proved, None while incomplete.
    fn read(&mut self, key: &[u8]) -> io::Result<Option<u32>> {
        while self.got < OPENING_LEN {
            match self.s.read(&mut self.b[self.got..]) {
                Ok(0) => return Err(io::Error::new(ErrorKind::UnexpectedEof, "closed")),
                Ok(n) => self.got += n,
                Err(e) if e.kind() == ErrorKind::WouldBlock => return Ok(None),
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        let b = &self.b;
        if b[..4] != MAGIC || !same(&b[8..], key) {
            return Err(io::Error::new(
                ErrorKind::PermissionDenied,
                "not a peer opening with this run's key",
            ));
        }
        Ok(Some(u32::from_le_bytes([b[4], b[5], b[6], b[7]])))
    }
}

/// Wait until one of `fds` is ready or `ms` milliseconds passed.
#[allow(unsafe_code)]
fn poll(fds: &mut [libc::pollfd], ms: i32) -> io::Result<()> {
    // SAFETY: `fds` is a valid array of `fds.len()` pollfd structs that outlives the
    // call; poll only writes their `revents`.
    let n = unsafe { libc::poll(fds.as_mut_ptr(), fds.len() as libc::nfds_t, ms) };
    if n < 0 {
        Err(io::Error::last_os_error())
    } else {
        Ok(())
    }
}

/// A connection ready for frames: no Nagle delay, keepalive, non-blocking.
fn ready(s: TcpStream) -> io::Result<Conn> {
    tune(&s)?;
    s.set_read_timeout(None)?;
    s.set_nonblocking(true)?;
    Ok(Conn {
        s,
        reader: FrameReader::new(crate::MAX_MESSAGE_CAP),
    })
}

/// Connect to `addr` (host:port) and send the opening.
fn dial(addr: &str, me: u32, key: &[u8]) -> io::Result<Conn> {
    let open = opening(me, key)
        .ok_or_else(|| io::Error::new(ErrorKind::InvalidInput, "a peer key of the wrong length"))?;
    let mut last = io::Error::new(ErrorKind::NotFound, "the address resolves to nothing");
    for a in addr.to_socket_addrs()? {
        match TcpStream::connect_timeout(&a, CONNECT) {
            Ok(mut s) => {
                s.write_all(&open)?;
                return ready(s);
            }
            Err(e) => last = e,
        }
    }
    Err(last)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a test panics on failure
mod tests {
    use super::*;

    fn frame(step: u64, n: usize) -> pb::PeerHalo {
        pb::PeerHalo {
            step,
            abort: false,
            parts: Some(pb::PartStates {
                parts: vec![pb::PartState {
                    id: 1,
                    xvw: vec![7; n],
                    ..Default::default()
                }],
            }),
        }
    }

    fn pair(timeout: Duration) -> (Peers, Peers, String, String) {
        let key = vec![5u8; 32];
        let mut a = Peers::bind(0, timeout).unwrap();
        let mut b = Peers::bind(0, timeout).unwrap();
        a.join(0, key.clone());
        b.join(1, key);
        let (pa, pb) = (
            format!("127.0.0.1:{}", a.port()),
            format!("127.0.0.1:{}", b.port()),
        );
        (a, b, pa, pb)
    }

    /// Two workers exchange frames larger than the sockets' buffers at once, step after
    /// step, over the connection made at the first.
    #[test]
    fn two_workers_exchange_large_frames_both_ways_on_one_connection() {
        let (mut a, mut b, pa, pb) = pair(Duration::from_secs(10));
        let t = std::thread::spawn(move || {
            let mut got = Vec::new();
            for step in 0..3 {
                let r = b
                    .exchange(vec![(0, pa.clone(), frame(step, 8 << 20))])
                    .unwrap();
                got.push((
                    r[0].0,
                    r[0].1.step,
                    r[0].1.parts.as_ref().unwrap().parts[0].xvw.len(),
                ));
            }
            got
        });
        let mut mine = Vec::new();
        for step in 0..3 {
            let r = a
                .exchange(vec![(1, pb.clone(), frame(step, 3 << 20))])
                .unwrap();
            mine.push((
                r[0].0,
                r[0].1.step,
                r[0].1.parts.as_ref().unwrap().parts[0].xvw.len(),
            ));
        }
        assert_eq!(
            mine,
            vec![(1, 0, 8 << 20), (1, 1, 8 << 20), (1, 2, 8 << 20)]
        );
        assert_eq!(
            t.join().unwrap(),
            vec![(0, 0, 3 << 20), (0, 1, 3 << 20), (0, 2, 3 << 20)]
        );
    }

    /// A connection without the run's key is closed; the rightful peer still gets in.
    #[test]
    fn a_peer_without_the_runs_key_is_refused() {
        let (mut a, mut b, pa, pb) = pair(Duration::from_secs(10));
        let mut intruder = TcpStream::connect(&pa).unwrap();
        intruder
            .write_all(&opening(1, &[6u8; 32]).unwrap())
            .unwrap();
        let t = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(100));
            b.exchange(vec![(0, pa, frame(4, 10))]).unwrap()[0].1.step
        });
        let r = a.exchange(vec![(1, pb, frame(4, 10))]).unwrap();
        assert_eq!(r[0].1.step, 4);
        assert_eq!(t.join().unwrap(), 4);
        // the intruder's connection was closed without a byte
        let mut buf = [0u8; 1];
        intruder
            .set_read_timeout(Some(Duration::from_secs(2)))
            .unwrap();
        assert!(matches!(intruder.read(&mut buf), Ok(0) | Err(_)));
    }

    /// A stranger that connects and says nothing costs the exchange no time: the
    /// openings are read as they come, not waited for.
    #[test]
    fn a_silent_connection_does_not_hold_up_the_exchange() {
        let (mut a, mut b, pa, pb) = pair(Duration::from_secs(10));
        let _silent = TcpStream::connect(&pa).unwrap();
        let t0 = Instant::now();
        let t = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(50));
            b.exchange(vec![(0, pa, frame(5, 10))]).unwrap()[0].1.step
        });
        assert_eq!(
            a.exchange(vec![(1, pb, frame(5, 10))]).unwrap()[0].1.step,
            5
        );
        assert_eq!(t.join().unwrap(), 5);
        assert!(t0.elapsed() < CONNECT / 2, "{:?}", t0.elapsed());
    }

    /// A peer that never comes is an error naming it, after the timeout; one whose
    /// address takes nothing is an error at once.
    #[test]
    fn a_silent_or_unreachable_peer_is_an_error_that_names_it() {
        let (mut a, _b, _pa, pb) = pair(Duration::from_millis(300));
        let e = a
            .exchange(vec![(1, pb, frame(0, 10))])
            .unwrap_err()
            .to_string();
        assert!(e.contains("no halo from worker 1"), "{e}");
        let (_a, mut b, _pa, _pb) = pair(Duration::from_millis(300));
        let closed = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = closed.local_addr().unwrap().to_string();
        drop(closed);
        let e = b
            .exchange(vec![(0, addr, frame(0, 10))])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("worker 0") && e.contains("cannot connect"),
            "{e}"
        );
    }
}
