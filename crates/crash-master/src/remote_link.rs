//! One worker process seen from the master: a `WorkerLink` over the worker's open
//! bidirectional stream. It remembers which body definitions it has sent (ids only),
//! so a body moving back travels as its state; it keeps no body data. While it waits
//! for a reply it watches the worker's heartbeats (`heartbeat`): a worker silent for
//! the heartbeat timeout is lost, however long its step takes otherwise.
//!
//! With the step lane (`lane`), commands and replies travel on the worker's lane as
//! soon as it is open (the first command waits for it, up to `crash_link::lane::WAIT`
//! after the Welcome); the stream then carries only the session's end.

use crate::heartbeat::Beats;
use crate::lane::{Desk, LaneIo, Watch};
use crash_link::wire::{command_to_pb, reply_from_pb};
use crash_link::{escape_peer, Command, LinkError, Reply, WorkerLink};
use crash_proto::pb;
use crash_proto::ProtoError;
use prost::Message;
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::runtime::Runtime;
use tonic::Status;
use tonic::Streaming;

pub(crate) type Outbound = tokio::sync::mpsc::UnboundedSender<Result<pb::MasterMessage, Status>>;

/// A worker process seen from the master.
pub struct RemoteWorker {
    pub(crate) rt: Arc<Runtime>,
    pub(crate) index: usize,
    pub(crate) peer: String,
    pub(crate) threads: u32,
    pub(crate) tx: Option<Outbound>,
    pub(crate) inbound: Streaming<pb::WorkerMessage>,
    /// Ids of the body definitions this worker has received.
    pub(crate) sent: BTreeSet<u32>,
    pub(crate) timeout: Duration,
    /// Encoding and decoding time since the last `take_codec_ns` [ns].
    pub(crate) codec_ns: u64,
    pub(crate) beats: Arc<Beats>,
    pub(crate) heartbeat_timeout: Option<Duration>,
    /// The step lane of this worker (`Lane::Off`: commands on the stream).
    pub(crate) lane: Lane,
    /// Largest reply accepted on the lane [bytes] (`RemoteOptions::max_message`).
    pub(crate) limit: usize,
    /// Where the worker takes direct halo connections (None: nowhere).
    pub(crate) halo_addr: Option<String>,
}

/// Where a worker's commands travel.
#[derive(Debug)]
pub(crate) enum Lane {
    /// On the gRPC stream.
    Off,
    /// Offered in the Welcome: the first command waits for it until `deadline`.
    Pending {
        desk: Arc<Desk>,
        deadline: Instant,
    },
    On(Box<LaneIo>),
    /// Closed by `abandon` or `close`.
    Closed,
}

impl std::fmt::Debug for RemoteWorker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RemoteWorker")
            .field("index", &self.index)
            .field("peer", &self.peer)
            .field("threads", &self.threads)
            .field("definitions", &self.sent.len())
            .finish()
    }
}

impl RemoteWorker {
    pub fn threads(&self) -> u32 {
        self.threads
    }

    /// The next reply within `timeout`; with heartbeats, a worker silent for the
    /// heartbeat timeout (counted from the later of its last beat and the start of this
    /// wait: without the step lane the beats are only handled while the master waits)
    /// is lost sooner.
    fn recv_within(&mut self, timeout: Duration) -> Result<Reply, LinkError> {
        self.open_lane(None)?;
        match &mut self.lane {
            Lane::On(io) => {
                let w = Watch {
                    start: Instant::now(),
                    timeout,
                    silence: self.heartbeat_timeout,
                    beats: &self.beats,
                    index: self.index as u32,
                };
                let body = io.read(&w)?;
                let t = Instant::now();
                let decoded = pb::WorkerMessage::decode(io.body(body))
                    .map_err(|e| ProtoError::Invalid(format!("step lane: {e}")))
                    .and_then(|m| reply_from_pb(&m));
                self.codec_ns += t.elapsed().as_nanos() as u64;
                return peer_reply(decoded);
            }
            Lane::Closed => return Err(LinkError::Lost("already shut down".into())),
            _ => {}
        }
        let start = Instant::now();
        let (index, beats, silence) = (
            self.index as u32,
            self.beats.clone(),
            self.heartbeat_timeout,
        );
        // look at the beats this often while waiting
        let look = silence.map_or(timeout, |s| {
            (s / 10).clamp(Duration::from_millis(20), Duration::from_millis(250))
        });
        let inbound = &mut self.inbound;
        let got = self.rt.block_on(async {
            loop {
                let left = timeout.saturating_sub(start.elapsed());
                if left.is_zero() {
                    return Err(LinkError::Timeout {
                        seconds: timeout.as_secs_f64(),
                    });
                }
                // the timer must be created inside the runtime; message() keeps its
                // state in the stream, so a timed-out wait loses nothing
                if let Ok(m) = tokio::time::timeout(left.min(look), inbound.message()).await {
                    return Ok(m);
                }
                if let Some(s) = silence {
                    let since = beats.last(index).map_or(start, |b| b.max(start));
                    if since.elapsed() > s {
                        return Err(LinkError::Silent {
                            seconds: since.elapsed().as_secs_f64(),
                        });
                    }
                }
            }
        });
        let msg = match got {
            Err(e) => return Err(e),
            Ok(Err(s)) => {
                return Err(LinkError::Lost(format!(
                    "{}: {}",
                    s.code(),
                    escape_peer(s.message())
                )))
            }
            Ok(Ok(None)) => return Err(LinkError::Lost("the worker closed its stream".into())),
            Ok(Ok(Some(m))) => m,
        };
        // a worker's error text reaches the master's log: escaped
        let t = Instant::now();
        let decoded = reply_from_pb(&msg);
        self.codec_ns += t.elapsed().as_nanos() as u64;
        peer_reply(decoded)
    }

    /// Resolve a pending lane: wait for it until its deadline (or `now`), then use it
    /// or stay on the stream.
    fn open_lane(&mut self, now: Option<Instant>) -> Result<(), LinkError> {
        let Lane::Pending { desk, deadline } = &self.lane else {
            return Ok(());
        };
        let until = now.unwrap_or(*deadline);
        self.lane = match desk.take(self.index as u32, until) {
            Some(tcp) => {
                let look = crate::lane::look(self.heartbeat_timeout, self.timeout);
                let io = LaneIo::new(tcp, self.limit, look)
                    .map_err(|e| LinkError::Lost(format!("step lane: {e}")))?;
                Lane::On(Box::new(io))
            }
            None => {
                if now.is_none() {
                    tracing::warn!(
                        "worker {} at {} did not open the step lane within {:.0} s: its commands go over gRPC (is the lane's port reachable from it?)",
                        self.index,
                        self.peer,
                        crash_link::lane::WAIT.as_secs_f64()
                    );
                }
                Lane::Off
            }
        };
        Ok(())
    }
}

/// A decoded reply as the master takes it: a worker's error text escaped (it reaches
/// the master's log).
fn peer_reply(decoded: Result<Reply, ProtoError>) -> Result<Reply, LinkError> {
    match decoded {
        Ok(Reply::Error(e)) => Ok(Reply::Error(escape_peer(&e))),
        Ok(r) => Ok(r),
        Err(e) => Err(LinkError::Protocol(escape_peer(&e.to_string()))),
    }
}

impl WorkerLink for RemoteWorker {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError> {
        self.open_lane(None)?;
        let t = Instant::now();
        let msg = command_to_pb(&cmd, |id| self.sent.contains(&id));
        let framed = match &mut self.lane {
            Lane::On(io) => Some(crash_link::lane::encode_frame(&mut io.out, &msg)),
            _ => None,
        };
        self.codec_ns += t.elapsed().as_nanos() as u64;
        if let Command::Load { bodies, .. } | Command::LoadCopies { bodies, .. } = &cmd {
            self.sent
                .extend(bodies.iter().filter(|b| b.def.is_some()).map(|b| b.id));
        }
        drop(cmd);
        match &mut self.lane {
            Lane::On(io) => {
                drop(msg);
                if let Some(Err(e)) = framed {
                    return Err(LinkError::Protocol(e.to_string()));
                }
                let w = Watch {
                    start: Instant::now(),
                    timeout: self.timeout,
                    silence: self.heartbeat_timeout,
                    beats: &self.beats,
                    index: self.index as u32,
                };
                return io.write(&w);
            }
            Lane::Closed => return Err(LinkError::Lost("already shut down".into())),
            _ => {}
        }
        self.tx
            .as_ref()
            .ok_or_else(|| LinkError::Lost("already shut down".into()))?
            .send(Ok(msg))
            .map_err(|_| LinkError::Lost("the connection is closed".into()))
    }

    fn recv(&mut self) -> Result<Reply, LinkError> {
        self.recv_within(self.timeout)
    }

    fn peer(&self) -> String {
        self.peer.clone()
    }

    fn has_definition(&self, id: u32) -> bool {
        self.sent.contains(&id)
    }

    fn halo_address(&self) -> Option<String> {
        self.halo_addr.clone()
    }

    fn take_codec_ns(&mut self) -> u64 {
        std::mem::take(&mut self.codec_ns)
    }

    fn abandon(&mut self, reason: &str) {
        // its beats are refused from now on (the worker stops beating); a worker that
        // wakes up later reads the Shutdown and exits
        self.beats.revoke(self.index as u32);
        // no wait for a lane still pending (a later one is refused)
        let _ = self.open_lane(Some(Instant::now()));
        if let Lane::On(io) = &mut self.lane {
            let cmd = Command::Shutdown(reason.into());
            if crash_link::lane::encode_frame(&mut io.out, &command_to_pb(&cmd, |_| false)).is_ok()
            {
                io.last_word();
            }
        } else {
            let _ = self.send(Command::Shutdown(reason.into()));
        }
        self.lane = Lane::Closed;
        self.tx = None;
    }

    fn close(&mut self, reason: &str) {
        if self.send(Command::Shutdown(reason.into())).is_ok() {
            let _ = self.recv_within(Duration::from_secs(2));
        }
        // ending the lane and the response stream lets the worker exit
        self.lane = Lane::Closed;
        self.tx = None;
        let inbound = &mut self.inbound;
        self.rt.block_on(async {
            let _ = tokio::time::timeout(Duration::from_millis(500), async {
                while let Ok(Some(_)) = inbound.message().await {}
            })
            .await;
        });
    }
}
