//! The worker process side of a session: dial the master (retrying with backoff, so
//! workers may start first), say Hello, then answer commands one by one.
//!
//! Threads: the calling thread drives a current-thread tokio runtime while it waits for
//! a command, then computes it outside the runtime as worker 0 of the rayon compute
//! pool (the other pool threads join by work stealing); see `serve`. A thread of its
//! own, with its own small runtime and its own connection, sends the heartbeats, so a
//! long step cannot silence them (`heartbeat`).

use crate::engine::Engine;
use crash_link::peer::Peers;
use crash_link::wire::{command_from_pb, reply_to_pb};
use crash_link::{
    check_version, escape_peer, Command, HelloFields, Reply, Secret, MAX_MESSAGE_CAP,
    PROTOCOL_VERSION,
};
use crash_proto::pb::coordinator_client::CoordinatorClient;
use crash_proto::pb::master_message::Command as PbCommand;
use crash_proto::pb::{self, worker_message};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use thiserror::Error;
use tokio::sync::mpsc;
use tokio_stream::wrappers::UnboundedReceiverStream;
use tonic::transport::{Channel, Endpoint};
use tonic::{Code, Streaming};

#[derive(Debug, Clone)]
pub struct WorkerOptions {
    /// The master's URL, e.g. `http://127.0.0.1:50051`.
    pub master: String,
    /// Threads of the compute pool.
    pub threads: usize,
    /// How long to keep retrying the first connection.
    pub connect_timeout: Duration,
    /// Protocol version announced in Hello (tests of the refusal path set another).
    pub protocol_version: u32,
    /// The cluster's shared secret, proved in Hello (never sent).
    pub secret: Option<Secret>,
    /// Host name announced in Hello (default: $HOSTNAME).
    pub host: String,
    /// Sleep this long before computing each step (tests of a slow but alive worker).
    pub step_delay: Duration,
    /// Change each reply before it is sent (tests of the master's plausibility checks:
    /// a worker holding the secret that lies; tests/tests/hardening.rs).
    pub tamper: Option<fn(&mut Reply)>,
    /// TLS: the certificate (PEM) that signed the master's (`--tls-ca`); the master's
    /// URL is then https://. None: plain TCP (http://).
    pub tls_ca: Option<Vec<u8>>,
    /// Take the other workers' direct halo connections on this port (0: any free
    /// port; None: none, the master then relays this worker's part states).
    pub peer_port: Option<u16>,
    /// The host other workers dial for it (empty: the address the master sees).
    pub peer_host: String,
    /// How long to wait for the other holders' part states in a split step.
    pub peer_timeout: Duration,
    /// How long a wait for the next command on the step lane, or for the other
    /// holders' part states, polls before it blocks (crash-link `poll`).
    pub poll: Duration,
}

impl WorkerOptions {
    pub fn new(master: &str, threads: usize) -> Self {
        Self {
            master: master.to_string(),
            threads,
            connect_timeout: Duration::from_secs(60),
            protocol_version: PROTOCOL_VERSION,
            secret: None,
            host: std::env::var("HOSTNAME").unwrap_or_default(),
            step_delay: Duration::ZERO,
            tamper: None,
            tls_ca: None,
            peer_port: Some(0),
            peer_host: String::new(),
            peer_timeout: crash_link::peer::DEFAULT_TIMEOUT,
            poll: crash_link::poll::DEFAULT_BUDGET,
        }
    }
}

#[derive(Debug, Error)]
pub enum WorkerError {
    #[error("invalid master URL '{url}': {reason}")]
    Url { url: String, reason: String },
    #[error("could not reach the master at {url} within {secs:.0} s: {reason}")]
    Connect {
        url: String,
        secs: f64,
        reason: String,
    },
    #[error("the master at {url} refused this worker: {reason}")]
    Refused { url: String, reason: String },
    #[error("lost the master at {url}: {reason}")]
    Lost { url: String, reason: String },
    #[error("protocol error with the master at {url}: {reason}")]
    Protocol { url: String, reason: String },
    #[error("cannot start the worker: {0}")]
    Start(String),
    /// The TLS handshake failed: the master's certificate is not trusted.
    #[error("TLS with the master at {url} failed: {reason}; the master's certificate must be signed by the --tls-ca certificate and name the host in the URL")]
    Tls { url: String, reason: String },
}

/// Run one worker session to its end. Returns the master's shutdown reason.
pub fn run(opts: &WorkerOptions) -> Result<String, WorkerError> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| WorkerError::Start(format!("tokio runtime: {e}")))?;
    // This thread is worker 0 of the compute pool: a command's compute starts here,
    // the other threads join through work stealing, and no hand-over between a
    // communication thread and a compute thread sits in the step's critical path.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads.max(1))
        .use_current_thread()
        .thread_name(|i| format!("crash-compute-{i}"))
        .build()
        .map_err(|e| WorkerError::Start(format!("compute pool: {e}")))?;
    // the port goes into the Hello; a worker that cannot listen has its states relayed
    let mut peers = opts.peer_port.and_then(|port| {
        Peers::bind(port, opts.peer_timeout)
            .map(|mut p| {
                p.set_poll(opts.poll);
                p
            })
            .inspect_err(|e| {
                tracing::warn!(
                    "cannot listen for direct halo connections on port {port}: {e}; the master will relay this worker's part states"
                )
            })
            .ok()
    });
    let (tx, inbound, welcome) = rt.block_on(attach(opts, peers.as_ref().map(Peers::port)))?;
    if let Some(p) = peers.as_mut() {
        p.join(welcome.worker_index, welcome.peer_key.clone());
        if p.offered() {
            tracing::debug!("direct halo connections on port {}", p.port());
        }
    }
    let alive = Arc::new(AtomicBool::new(true));
    heartbeat(opts, &welcome, alive.clone())?;
    let lane = crate::lane::open(opts, &welcome)?;
    let result = serve(opts, &rt, &pool, tx, inbound, lane, peers);
    alive.store(false, Ordering::Relaxed);
    result
}

/// Beat every `heartbeat_interval_ms` on a connection of its own, from a thread with
/// its own runtime: the master hears the worker while its main thread computes a long
/// step (the main runtime is driven only between commands). Stops when `alive` turns
/// false or the master no longer knows this worker.
fn heartbeat(
    opts: &WorkerOptions,
    welcome: &pb::Welcome,
    alive: Arc<AtomicBool>,
) -> Result<(), WorkerError> {
    let url = opts.master.clone();
    let ep = endpoint(&url, opts.tls_ca.as_deref())?;
    let beat = pb::Beat {
        worker_index: welcome.worker_index,
        session_token: welcome.session_token.clone(),
    };
    let every = Duration::from_millis(u64::from(welcome.heartbeat_interval_ms.clamp(10, 60_000)));
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| WorkerError::Start(format!("heartbeat runtime: {e}")))?;
    std::thread::Builder::new()
        .name("crash-heartbeat".into())
        .spawn(move || {
            rt.block_on(async move {
                let mut client: Option<CoordinatorClient<Channel>> = None;
                while alive.load(Ordering::Relaxed) {
                    if client.is_none() {
                        client = ep.connect().await.ok().map(CoordinatorClient::new);
                    }
                    if let Some(c) = client.as_mut() {
                        match tokio::time::timeout(4 * every, c.heartbeat(beat.clone())).await {
                            Ok(Ok(_)) => {}
                            Ok(Err(s)) if s.code() == Code::NotFound => {
                                tracing::warn!(
                                    "the master at {url} no longer counts this worker: {}",
                                    escape_peer(s.message())
                                );
                                return;
                            }
                            // a fresh connection at the next beat
                            _ => client = None,
                        }
                    }
                    tokio::time::sleep(every).await;
                }
            })
        })
        .map_err(|e| WorkerError::Start(format!("heartbeat thread: {e}")))?;
    Ok(())
}

/// The master's endpoint, with TLS for an https URL (`tls_ca`: the trusted certificate).
pub(crate) fn endpoint(url: &str, tls_ca: Option<&[u8]>) -> Result<Endpoint, WorkerError> {
    let bad = |reason: String| WorkerError::Url {
        url: url.into(),
        reason,
    };
    let https = url.starts_with("https://");
    let mut ep = Endpoint::from_shared(url.to_string()).map_err(|e| bad(e.to_string()))?;
    match (https, tls_ca) {
        (true, Some(ca)) => {
            let tls = tonic::transport::ClientTlsConfig::new()
                .ca_certificate(tonic::transport::Certificate::from_pem(ca));
            ep = ep.tls_config(tls).map_err(|e| bad(format!("TLS: {e}")))?;
        }
        (true, None) => {
            return Err(bad(
                "an https:// master needs the certificate that signed its own (--tls-ca)".into(),
            ))
        }
        (false, Some(_)) => {
            return Err(bad(
                "--tls-ca is given: dial the master as https://HOST:PORT".into(),
            ))
        }
        (false, None) => {}
    }
    Ok(ep
        .connect_timeout(Duration::from_secs(5))
        .tcp_nodelay(true)
        // Kernel keepalive notices a vanished master host even while the master
        // process is busy (it answers no HTTP/2 ping while writing output).
        .tcp_keepalive(Some(Duration::from_secs(10)))
        .tcp_keepalive_interval(Some(Duration::from_secs(5)))
        .tcp_keepalive_retries(Some(3))
        .initial_stream_window_size(8 << 20)
        .initial_connection_window_size(16 << 20))
}

/// Connect, retrying with exponential backoff (0.1 s doubling to 2 s).
async fn connect(
    url: &str,
    timeout: Duration,
    tls_ca: Option<&[u8]>,
) -> Result<Channel, WorkerError> {
    let ep = endpoint(url, tls_ca)?;
    let t0 = Instant::now();
    let mut wait = Duration::from_millis(100);
    loop {
        match ep.connect().await {
            Ok(ch) => return Ok(ch),
            Err(e) => {
                let chain = error_chain(&e);
                // a certificate refused now is refused at every retry
                if tls_ca.is_some() && chain.contains("certificate") {
                    return Err(WorkerError::Tls {
                        url: url.into(),
                        reason: chain,
                    });
                }
                if t0.elapsed() + wait > timeout {
                    return Err(WorkerError::Connect {
                        url: url.into(),
                        secs: timeout.as_secs_f64(),
                        reason: error_chain(&e),
                    });
                }
                tracing::debug!("master at {url} not reachable yet ({e}); retrying");
                tokio::time::sleep(wait).await;
                wait = (wait * 2).min(Duration::from_secs(2));
            }
        }
    }
}

fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        s.push_str(": ");
        s.push_str(&c.to_string());
        src = c.source();
    }
    s
}

fn hello(opts: &WorkerOptions, nonce: &[u8], peer_port: Option<u16>) -> pb::WorkerMessage {
    let (protocol_version, threads, pid) = (
        opts.protocol_version,
        opts.threads as u32,
        std::process::id(),
    );
    let proof = opts.secret.as_ref().map_or_else(Vec::new, |s| {
        s.prove(
            nonce,
            &HelloFields {
                protocol_version,
                threads,
                host: &opts.host,
                pid,
            },
        )
    });
    pb::WorkerMessage {
        reply: Some(worker_message::Reply::Hello(pb::Hello {
            protocol_version,
            threads,
            host: opts.host.clone(),
            pid,
            proof,
            peer_port: peer_port.map_or(0, u32::from),
            peer_host: opts.peer_host.clone(),
        })),
    }
}

/// A status from the master as this worker's error (its text escaped).
fn refused_or_lost(url: &str, s: &tonic::Status) -> WorkerError {
    let reason = escape_peer(s.message());
    match s.code() {
        Code::FailedPrecondition
        | Code::Unavailable
        | Code::Unauthenticated
        | Code::ResourceExhausted => WorkerError::Refused {
            url: url.into(),
            reason,
        },
        c => WorkerError::Lost {
            url: url.into(),
            reason: format!("{c}: {reason}"),
        },
    }
}

/// Dial the master, answer its Challenge with Hello, check its Welcome.
async fn attach(
    opts: &WorkerOptions,
    peer_port: Option<u16>,
) -> Result<
    (
        mpsc::UnboundedSender<pb::WorkerMessage>,
        Streaming<pb::MasterMessage>,
        pb::Welcome,
    ),
    WorkerError,
> {
    let url = opts.master.as_str();
    let lost = |reason: String| WorkerError::Lost {
        url: url.into(),
        reason,
    };
    let protocol = |reason: &str| WorkerError::Protocol {
        url: url.into(),
        reason: reason.into(),
    };
    // Connect and open the session, retrying with backoff within the connect timeout:
    // a master whose pending-connection slots are full (guard.rs) closes a new
    // connection at once, which fails the call before any answer.
    let t0 = Instant::now();
    let mut wait = Duration::from_millis(100);
    let (tx, mut inbound) = loop {
        let left = opts.connect_timeout.saturating_sub(t0.elapsed());
        let channel = connect(url, left, opts.tls_ca.as_deref()).await?;
        // The worker trusts the master it was pointed at: it accepts what the master's
        // run needs (the master bounds what it accepts from workers, docs/reliability.md).
        let mut client = CoordinatorClient::new(channel)
            .max_decoding_message_size(MAX_MESSAGE_CAP)
            .max_encoding_message_size(MAX_MESSAGE_CAP);
        let (tx, rx) = mpsc::unbounded_channel();
        match client.attach(UnboundedReceiverStream::new(rx)).await {
            Ok(r) => break (tx, r.into_inner()),
            Err(s)
                if matches!(
                    s.code(),
                    Code::Unknown | Code::Unavailable | Code::Cancelled
                ) =>
            {
                if t0.elapsed() + wait > opts.connect_timeout {
                    return Err(refused_or_lost(url, &s));
                }
                tracing::debug!("the master at {url} closed the connection ({s}); retrying");
                tokio::time::sleep(wait).await;
                wait = (wait * 2).min(Duration::from_secs(2));
            }
            Err(s) => return Err(refused_or_lost(url, &s)),
        }
    };
    // Handshake: the master's Challenge, our Hello with the proof, its Welcome.
    let challenge = match inbound.message().await {
        Ok(Some(pb::MasterMessage {
            command: Some(PbCommand::Challenge(c)),
        })) => c,
        Ok(Some(_)) => return Err(protocol("the first message was not Challenge")),
        Ok(None) => {
            return Err(lost(
                "the master closed the session before its Challenge".into(),
            ))
        }
        Err(s) => return Err(refused_or_lost(url, &s)),
    };
    if opts.protocol_version == PROTOCOL_VERSION {
        check_version(challenge.protocol_version, "the master", "worker").map_err(|e| {
            WorkerError::Refused {
                url: url.into(),
                reason: e.to_string(),
            }
        })?;
    }
    if challenge.secret_required && opts.secret.is_none() {
        tracing::warn!(
            "the master requires a shared secret and this worker has none (--secret-file or CRASH_SECRET)"
        );
    }
    tx.send(hello(opts, &challenge.nonce, peer_port))
        .map_err(|_| WorkerError::Start("outbound stream closed".into()))?;
    let welcome = match inbound.message().await {
        Ok(Some(pb::MasterMessage {
            command: Some(PbCommand::Welcome(w)),
        })) => {
            if opts.protocol_version == PROTOCOL_VERSION {
                check_version(w.protocol_version, "the master", "worker").map_err(|e| {
                    WorkerError::Refused {
                        url: url.into(),
                        reason: e.to_string(),
                    }
                })?;
            }
            tracing::info!(
                "attached to {url} as worker {} of {}",
                w.worker_index,
                w.workers
            );
            w
        }
        Ok(Some(_)) => return Err(protocol("the message after Hello was not Welcome")),
        Ok(None) => return Err(lost("the master closed the session before Welcome".into())),
        Err(s) => return Err(refused_or_lost(url, &s)),
    };
    Ok((tx, inbound, welcome))
}

/// Answer commands until Shutdown, from the step lane when it is open (blocking reads
/// and writes on this thread), else from the gRPC stream. The runtime is driven only
/// while waiting for the next command on the stream (and while flushing the reply,
/// which happens in that same wait): compute never runs inside it. The protocol is
/// strictly one reply per command, so nothing needs the connection to progress during
/// compute; TCP keepalive is answered by the kernel.
fn serve(
    opts: &WorkerOptions,
    rt: &tokio::runtime::Runtime,
    pool: &rayon::ThreadPool,
    tx: mpsc::UnboundedSender<pb::WorkerMessage>,
    mut inbound: Streaming<pb::MasterMessage>,
    mut lane: Option<crate::lane::WorkerLane>,
    peers: Option<Peers>,
) -> Result<String, WorkerError> {
    let url = opts.master.as_str();
    let lost = |reason: String| WorkerError::Lost {
        url: url.into(),
        reason,
    };
    let mut engine = match peers {
        Some(p) => Engine::new().with_peers(p),
        None => Engine::new(),
    };
    // encoding time of the previous reply, reported with the next one
    let mut last_encode_ns = 0u64;
    loop {
        let (msg, wire_ns) = match lane.as_mut() {
            Some(l) => l.next().map_err(lost)?,
            None => match rt.block_on(inbound.message()) {
                Ok(Some(m)) => (m, 0),
                Ok(None) => {
                    return Err(lost(
                        "the master ended the session without a shutdown".into(),
                    ))
                }
                Err(s) => return Err(refused_or_lost(url, &s)),
            },
        };
        let t0 = Instant::now();
        let decoded = command_from_pb(&msg);
        let decode_ns = wire_ns + t0.elapsed().as_nanos() as u64;
        let (mut reply, shutdown) = match decoded {
            Ok(cmd) => {
                let shutdown = match &cmd {
                    Command::Shutdown(r) => Some(escape_peer(r)),
                    _ => None,
                };
                if matches!(cmd, Command::Step { .. }) && !opts.step_delay.is_zero() {
                    std::thread::sleep(opts.step_delay);
                }
                (pool.install(|| engine.handle(cmd)), shutdown)
            }
            Err(e) => (Reply::Error(e.to_string()), None),
        };
        if let Reply::Report(rep) = &mut reply {
            rep.codec_ns = decode_ns + last_encode_ns;
        }
        if let Reply::Frame(bodies) = &mut reply {
            // the wire carries whole frames: what the capture left to derive, on the pool
            use rayon::prelude::*;
            pool.install(|| bodies.par_iter_mut().for_each(|b| b.complete()));
        }
        if let Some(tamper) = opts.tamper {
            tamper(&mut reply);
        }
        let t1 = Instant::now();
        let reply = reply_to_pb(&reply);
        last_encode_ns = t1.elapsed().as_nanos() as u64;
        if let Some(l) = lane.as_mut() {
            match l.send(&reply) {
                Ok(ns) => {
                    last_encode_ns += ns;
                    // what the reply did not wait for (a split's own parts)
                    pool.install(|| engine.settle());
                }
                // the master may close the lane right after a Shutdown
                Err(_) if shutdown.is_some() => {}
                Err(e) => {
                    if let Some(Ok(Command::Shutdown(r))) =
                        l.last_word().map(|m| command_from_pb(&m))
                    {
                        return Err(lost(format!(
                            "the master dropped this worker: {}",
                            escape_peer(&r)
                        )));
                    }
                    return Err(lost(e));
                }
            }
        } else if tx.send(reply).is_err() {
            // the master ended the session: say why if it did (a worker it dropped)
            let why = rt.block_on(async {
                tokio::time::timeout(Duration::from_secs(1), inbound.message()).await
            });
            if let Ok(Ok(Some(m))) = why {
                if let Ok(Command::Shutdown(r)) = command_from_pb(&m) {
                    return Err(lost(format!(
                        "the master dropped this worker: {}",
                        escape_peer(&r)
                    )));
                }
            }
            return Err(lost("the outbound stream closed".into()));
        }
        if let Some(reason) = shutdown {
            // Close our side and let the master close its own, so the Ack is flushed.
            drop(lane);
            drop(tx);
            rt.block_on(async {
                let _ = tokio::time::timeout(Duration::from_secs(5), async {
                    while let Ok(Some(_)) = inbound.message().await {}
                })
                .await;
            });
            return Ok(reason);
        }
    }
}
