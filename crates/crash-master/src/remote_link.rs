//! One worker process seen from the master: a `WorkerLink` over the worker's open
//! bidirectional stream. It remembers which body definitions it has sent (ids only),
//! so a body moving back travels as its state; it keeps no body data. While it waits
//! for a reply it watches the worker's heartbeats (`heartbeat`): a worker silent for
//! the heartbeat timeout is lost, however long its step takes otherwise.

use crate::heartbeat::Beats;
use crash_link::wire::{command_to_pb, reply_from_pb};
use crash_link::{escape_peer, Command, LinkError, Reply, WorkerLink};
use crash_proto::pb;
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
    /// wait: the beats are only handled while the master waits) is lost sooner.
    fn recv_within(&mut self, timeout: Duration) -> Result<Reply, LinkError> {
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
        match decoded {
            Ok(Reply::Error(e)) => Ok(Reply::Error(escape_peer(&e))),
            Ok(r) => Ok(r),
            Err(e) => Err(LinkError::Protocol(escape_peer(&e.to_string()))),
        }
    }
}

impl WorkerLink for RemoteWorker {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError> {
        let t = Instant::now();
        let msg = command_to_pb(&cmd, |id| self.sent.contains(&id));
        self.codec_ns += t.elapsed().as_nanos() as u64;
        if let Command::Load { bodies, .. } | Command::LoadCopies { bodies, .. } = &cmd {
            self.sent
                .extend(bodies.iter().filter(|b| b.def.is_some()).map(|b| b.id));
        }
        drop(cmd);
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

    fn take_codec_ns(&mut self) -> u64 {
        std::mem::take(&mut self.codec_ns)
    }

    fn abandon(&mut self, reason: &str) {
        // its beats are refused from now on (the worker stops beating); a worker that
        // wakes up later reads the Shutdown and exits
        self.beats.revoke(self.index as u32);
        let _ = self.send(Command::Shutdown(reason.into()));
        self.tx = None;
    }

    fn close(&mut self, reason: &str) {
        if self.send(Command::Shutdown(reason.into())).is_ok() {
            let _ = self.recv_within(Duration::from_secs(2));
        }
        // ending the response stream lets the worker exit
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
