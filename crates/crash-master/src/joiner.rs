//! Workers admitted while the run goes on (issue 14 points 1 and 3): the attach
//! channel of the gRPC server stays open for the whole run, so a worker that attaches
//! after the start passes the same handshake (Challenge, secret proof, version check,
//! guard limits, TLS) as those of the start; `Cluster::accept` welcomes the first ones
//! and the master takes the later ones at step boundaries (`join::Newcomers`).

use crate::heartbeat::{interval_for, Beats, DEFAULT_TIMEOUT};
use crate::lane::Desk;
use crate::remote_link::{Lane, RemoteWorker};
use crate::server::{Attached, RemoteOptions};
use crash_link::{escape_peer, PROTOCOL_VERSION};
use crash_proto::pb::{self, master_message};
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Duration;
use tokio::runtime::Runtime;
use tokio::sync::mpsc;
use tonic::Status;

/// Where a worker takes direct halo connections: the host it names (else the address
/// the master sees it at, `peer` as ip:port) and the port it names (None: 0, or no
/// address to give).
fn halo_address(peer: &str, host: &str, port: u32) -> Option<String> {
    let port = u16::try_from(port).ok().filter(|&p| p != 0)?;
    if host.is_empty() {
        let ip = peer.parse::<std::net::SocketAddr>().ok()?.ip();
        return Some(std::net::SocketAddr::new(ip, port).to_string());
    }
    // an IPv6 literal needs brackets before its port
    if host.contains(':') && !host.starts_with('[') {
        Some(format!("[{host}]:{port}"))
    } else {
        Some(format!("{host}:{port}"))
    }
}

/// Workers admitted while the run goes on: the same handshake (secret, TLS, version,
/// guard limits) as those of the start; the master takes them at step boundaries
/// (`join::Newcomers`).
pub struct Joiner {
    rt: Arc<Runtime>,
    rx: Option<mpsc::UnboundedReceiver<Attached>>,
    beats: Arc<Beats>,
    opts: RemoteOptions,
    /// The step lane's listener (None: commands on the gRPC streams).
    desk: Option<Arc<Desk>>,
    /// The key workers prove to each other on direct halo connections, one per run
    /// (None: not offered, with TLS or `direct_halo` off).
    peer_key: Option<[u8; crash_link::auth::NONCE_LEN]>,
}

impl std::fmt::Debug for Joiner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Joiner")
            .field("open", &self.rx.is_some())
            .finish()
    }
}

impl Joiner {
    pub(crate) fn new(
        rt: Arc<Runtime>,
        rx: mpsc::UnboundedReceiver<Attached>,
        beats: Arc<Beats>,
        opts: RemoteOptions,
        desk: Option<Arc<Desk>>,
    ) -> Self {
        let peer_key = if opts.direct_halo && opts.tls.is_none() {
            crash_link::auth::nonce()
                .inspect_err(|e| tracing::warn!("no direct halo exchange: {e}"))
                .ok()
        } else {
            None
        };
        Self {
            rt,
            rx: Some(rx),
            beats,
            opts,
            desk,
            peer_key,
        }
    }

    /// The channel of admitted workers (None once closed).
    pub(crate) fn channel(&mut self) -> Option<&mut mpsc::UnboundedReceiver<Attached>> {
        self.rx.as_mut()
    }

    /// Welcome an admitted worker as worker `index` of `workers`: its heartbeat token,
    /// its link.
    pub(crate) fn welcome(
        &self,
        a: Attached,
        index: usize,
        workers: usize,
    ) -> Result<RemoteWorker, String> {
        let token = self
            .beats
            .register(index as u32)
            .map_err(|e| e.to_string())?;
        // expected before the Welcome goes out: the worker opens it right after
        if let Some(d) = &self.desk {
            d.expect(index as u32);
        }
        let every = interval_for(self.opts.heartbeat_timeout.unwrap_or(DEFAULT_TIMEOUT));
        let welcome = pb::MasterMessage {
            command: Some(master_message::Command::Welcome(pb::Welcome {
                protocol_version: PROTOCOL_VERSION,
                worker_index: index as u32,
                workers: workers as u32,
                session_token: token,
                heartbeat_interval_ms: every.as_millis().clamp(1, 60_000) as u32,
                lane_port: self.desk.as_ref().map_or(0, |d| u32::from(d.port())),
                peer_key: self.peer_key.map_or_else(Vec::new, |k| k.to_vec()),
            })),
        };
        let halo_addr = self
            .peer_key
            .and_then(|_| halo_address(&a.peer, &a.hello.peer_host, a.hello.peer_port));
        if a.outbound.send(Ok(welcome)).is_err() {
            self.beats.revoke(index as u32);
            return Err(format!("worker {index} at {} left before Welcome", a.peer));
        }
        Ok(RemoteWorker {
            rt: self.rt.clone(),
            index,
            peer: format!(
                "{} (pid {} on '{}')",
                a.peer,
                a.hello.pid,
                escape_peer(&a.hello.host)
            ),
            threads: a.hello.threads,
            tx: Some(a.outbound),
            inbound: a.inbound,
            sent: BTreeSet::new(),
            codec_ns: 0,
            timeout: self.opts.reply_timeout,
            beats: self.beats.clone(),
            heartbeat_timeout: self.opts.heartbeat_timeout,
            lane: match &self.desk {
                Some(d) => Lane::Pending {
                    desk: d.clone(),
                    deadline: std::time::Instant::now() + crash_link::lane::WAIT,
                },
                None => Lane::Off,
            },
            limit: self.opts.max_message,
            halo_addr,
        })
    }

    /// Refuse the workers still waiting for their Welcome (the run is over).
    pub(crate) fn close(&mut self) {
        if let Some(mut rx) = self.rx.take() {
            rx.close();
            while let Ok(a) = rx.try_recv() {
                let _ = a.outbound.send(Err(Status::unavailable(
                    "this master is not accepting workers: its run is over",
                )));
            }
        }
    }
}

impl crate::join::Newcomers<RemoteWorker> for Joiner {
    fn join(&mut self, first: usize, wait: Duration) -> Vec<RemoteWorker> {
        let Some(rx) = self.rx.as_mut() else {
            return Vec::new();
        };
        let mut got = Vec::new();
        while let Ok(a) = rx.try_recv() {
            got.push(a);
        }
        if got.is_empty() && !wait.is_zero() {
            // the runtime runs while we wait: handshakes in progress complete
            if let Some(a) = self.rt.block_on(async {
                let end = tokio::time::Instant::now() + wait;
                while tokio::time::Instant::now() < end && !crate::stop::requested() {
                    // look at the stop flag (SIGTERM) every 100 ms
                    if let Ok(next) =
                        tokio::time::timeout(Duration::from_millis(100), rx.recv()).await
                    {
                        return next;
                    }
                }
                None
            }) {
                got.push(a);
            }
            while let Ok(a) = rx.try_recv() {
                got.push(a);
            }
        }
        let mut out = Vec::with_capacity(got.len());
        for a in got {
            let index = first + out.len();
            let (peer, host, pid, threads) = (
                a.peer.clone(),
                escape_peer(&a.hello.host),
                a.hello.pid,
                a.hello.threads,
            );
            match self.welcome(a, index, index + 1) {
                Ok(l) => {
                    tracing::info!(
                        "worker {index} joined from {peer} ('{host}', pid {pid}, {threads} threads) during the run"
                    );
                    out.push(l);
                }
                Err(e) => tracing::warn!("{e}"),
            }
        }
        out
    }
}
