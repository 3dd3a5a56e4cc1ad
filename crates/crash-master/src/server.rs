//! The master's gRPC server: it serves `crash.v1.Coordinator` (and grpc.health.v1),
//! each worker dials in, says Hello and keeps one bidirectional stream open for the
//! whole run; `Cluster::accept` turns the attached workers into links
//! (`remote_link::RemoteWorker`), and `Joiner` those that attach later (the attach
//! channel stays open for the whole run).
//!
//! Threads: with the step lane (`lane`, plain TCP, the default) the tokio runtime runs
//! on a thread of its own (heartbeats, admissions, the gRPC streams), and the master's
//! loop reads and writes each worker's lane with blocking calls. Without it (TLS,
//! `step_lane` off) one current-thread runtime, owned by the master's thread, is driven
//! only while the master waits for replies (`RemoteWorker::recv` blocks on it): the
//! master's loop, the tonic server and all connections share one thread, and a step
//! exchange costs no thread hand-over on the master side. TCP keepalive (answered by
//! the kernel) keeps connections alive while the master is busy between steps.
//!
//! Admission (docs/reliability.md): the master opens each session with a Challenge
//! (a fresh nonce); the worker's Hello carries `HMAC-SHA256(secret, nonce || fields)`
//! when a secret is configured, checked in constant time. A peer that fails is refused
//! before it takes a worker slot or sees anything of the scene. Until a worker is
//! admitted on a connection, `guard` bounds what it can cost: a handshake deadline,
//! a Hello-sized message limit, a cap on pending connections. Peer text is escaped
//! (`crash_link::escape_peer`) before it is logged.
//!
//! Heartbeats (`heartbeat`): each admitted worker beats on a connection of its own with
//! the session token of its Welcome; a valid beat admits that connection too.

use crate::error::MasterError;
use crate::guard::{conn_info, limit_request, ConnInfo, Gate};
use crate::heartbeat::{Beats, DEFAULT_TIMEOUT};
use crate::joiner::Joiner;
use crate::remote_link::{Outbound, RemoteWorker};
use crash_link::{
    check_version, escape_peer, HelloFields, Secret, HEALTH_SERVICE, MAX_MESSAGE, MAX_MESSAGE_CAP,
    PROTOCOL_VERSION,
};
use crash_proto::pb::coordinator_server::{Coordinator, CoordinatorServer};
use crash_proto::pb::worker_message::Reply as PbReply;
use crash_proto::pb::{self, master_message};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::runtime::Runtime;
use tokio::sync::{mpsc, oneshot};
use tokio_stream::wrappers::{TcpListenerStream, UnboundedReceiverStream};
use tokio_stream::StreamExt;
use tonic::{Request, Response, Status, Streaming};

#[derive(Debug, Clone)]
pub struct RemoteOptions {
    /// How long to wait for all workers to attach.
    pub accept_timeout: Duration,
    /// A worker that does not answer a command within this time is lost (a safety
    /// net: heartbeats find a frozen worker sooner).
    pub reply_timeout: Duration,
    /// A worker from which no heartbeat came for this long, while the master waited
    /// for it, is lost (None: heartbeats are not checked).
    pub heartbeat_timeout: Option<Duration>,
    /// A connection on which no worker is admitted within this time is closed.
    pub handshake_timeout: Duration,
    /// The shared secret a worker must prove (None: any peer that reaches the port
    /// and speaks the protocol may attach).
    pub secret: Option<Secret>,
    /// Largest message decoded from an admitted worker (`crash_link::message_limit`);
    /// before admission only `HELLO_LIMIT`.
    pub max_message: usize,
    /// TLS: the master's certificate chain and private key (PEM); None: plain TCP.
    pub tls: Option<TlsIdentity>,
    /// Offer the step lane (`lane`; plain TCP only: with TLS commands stay on gRPC).
    pub step_lane: bool,
    /// The step lane's port (0: any free port; it is announced in each Welcome).
    pub step_lane_port: u16,
    /// Let the holders of split groups exchange their part states directly (a peer
    /// key in each Welcome; plain TCP only: with TLS the master relays them).
    pub direct_halo: bool,
}

/// The master's TLS certificate chain and key, PEM (from `--tls-cert`, `--tls-key`).
#[derive(Clone)]
pub struct TlsIdentity {
    pub cert_pem: Vec<u8>,
    pub key_pem: Vec<u8>,
}

impl std::fmt::Debug for TlsIdentity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // never the key
        write!(
            f,
            "TlsIdentity({} bytes of certificate)",
            self.cert_pem.len()
        )
    }
}

impl Default for RemoteOptions {
    fn default() -> Self {
        Self {
            accept_timeout: Duration::from_secs(300),
            reply_timeout: Duration::from_secs(600),
            heartbeat_timeout: Some(DEFAULT_TIMEOUT),
            handshake_timeout: Duration::from_secs(5),
            secret: None,
            max_message: MAX_MESSAGE,
            tls: None,
            step_lane: true,
            step_lane_port: 0,
            direct_halo: true,
        }
    }
}

/// A worker that said a valid Hello.
pub(crate) struct Attached {
    pub(crate) hello: pb::Hello,
    pub(crate) peer: String,
    pub(crate) inbound: Streaming<pb::WorkerMessage>,
    pub(crate) outbound: Outbound,
}

struct Service {
    attach: Arc<Mutex<Option<mpsc::UnboundedSender<Attached>>>>,
    beats: Arc<Beats>,
    secret: Option<Arc<Secret>>,
    handshake: Duration,
}

/// Why a peer was refused: the log line (escaped peer text) and the status it gets.
fn refuse(who: &str, status: Status) -> Status {
    tracing::warn!("refused {who}: {}", status.message());
    status
}

/// The handshake of one session after the Challenge went out: the Hello, its version
/// and proof; then the worker waits for `Cluster::accept`'s Welcome.
#[allow(clippy::too_many_arguments)] // one call site; the parts of one session
async fn handshake(
    attach: Arc<Mutex<Option<mpsc::UnboundedSender<Attached>>>>,
    secret: Option<Arc<Secret>>,
    timeout: Duration,
    conn: Option<ConnInfo>,
    peer: String,
    nonce: [u8; crash_link::auth::NONCE_LEN],
    mut inbound: Streaming<pb::WorkerMessage>,
    outbound: Outbound,
) -> Result<(), Status> {
    let first = tokio::time::timeout(timeout, inbound.message()).await;
    let hello = match first {
        Ok(Ok(Some(pb::WorkerMessage {
            reply: Some(PbReply::Hello(h)),
        }))) => h,
        Ok(Err(s)) => {
            return Err(refuse(
                &format!("a connection from {peer}"),
                Status::invalid_argument(format!(
                    "the first message was not a valid Hello: {}",
                    escape_peer(s.message())
                )),
            ))
        }
        Err(_) => {
            return Err(refuse(
                &format!("a connection from {peer}"),
                Status::deadline_exceeded(format!(
                    "no Hello within {:.0} s",
                    timeout.as_secs_f64()
                )),
            ))
        }
        _ => {
            return Err(refuse(
                &format!("a connection from {peer}"),
                Status::invalid_argument("the first message must be Hello"),
            ))
        }
    };
    let who = format!(
        "worker '{}' (pid {}) at {peer}",
        escape_peer(&hello.host),
        hello.pid
    );
    if let Err(e) = check_version(hello.protocol_version, &who, "master") {
        return Err(refuse(&who, Status::failed_precondition(e.to_string())));
    }
    if let Some(secret) = &secret {
        let fields = HelloFields {
            protocol_version: hello.protocol_version,
            threads: hello.threads,
            host: &hello.host,
            pid: hello.pid,
        };
        if hello.proof.is_empty() {
            return Err(refuse(
                &who,
                Status::unauthenticated(
                    "this master admits only workers that hold its shared secret, and this worker has none: start crash-worker with --secret-file FILE or CRASH_SECRET set to the master's secret",
                ),
            ));
        }
        if !secret.verify(&nonce, &fields, &hello.proof) {
            return Err(refuse(
                &who,
                Status::unauthenticated(
                    "the worker's proof of the shared secret is wrong: its secret differs from the master's",
                ),
            ));
        }
    }
    let sender = attach.lock().ok().and_then(|g| g.clone());
    let Some(sender) = sender else {
        return Err(refuse(
            &who,
            Status::unavailable("this master is not accepting workers: its run is over"),
        ));
    };
    if let Some(c) = &conn {
        c.admit();
    }
    let failed = sender.send(Attached {
        hello,
        peer,
        inbound,
        outbound,
    });
    if let Err(mpsc::error::SendError(a)) = failed {
        let _ = a.outbound.send(Err(refuse(
            &who,
            Status::unavailable("this master is not accepting workers: its run is over"),
        )));
    }
    Ok(())
}

#[tonic::async_trait]
impl Coordinator for Service {
    type AttachStream = UnboundedReceiverStream<Result<pb::MasterMessage, Status>>;

    async fn attach(
        &self,
        req: Request<Streaming<pb::WorkerMessage>>,
    ) -> Result<Response<Self::AttachStream>, Status> {
        let conn = conn_info(req.extensions());
        let peer = conn
            .as_ref()
            .and_then(|c| c.remote)
            .or_else(|| req.remote_addr())
            .map_or_else(|| "unknown address".to_string(), |a| a.to_string());
        let nonce = crash_link::auth::nonce().map_err(|e| Status::internal(e.to_string()))?;
        let inbound = req.into_inner();
        let (outbound, rx) = mpsc::unbounded_channel();
        let challenge = pb::MasterMessage {
            command: Some(master_message::Command::Challenge(pb::Challenge {
                protocol_version: PROTOCOL_VERSION,
                nonce: nonce.to_vec(),
                secret_required: self.secret.is_some(),
            })),
        };
        let _ = outbound.send(Ok(challenge));
        let (attach, secret, timeout) = (self.attach.clone(), self.secret.clone(), self.handshake);
        tokio::spawn(async move {
            let out = outbound.clone();
            if let Err(s) = handshake(
                attach, secret, timeout, conn, peer, nonce, inbound, outbound,
            )
            .await
            {
                let _ = out.send(Err(s));
            }
        });
        Ok(Response::new(UnboundedReceiverStream::new(rx)))
    }

    async fn heartbeat(&self, req: Request<pb::Beat>) -> Result<Response<pb::BeatAck>, Status> {
        let conn = conn_info(req.extensions());
        let b = req.into_inner();
        self.beats.beat(b.worker_index, &b.session_token)?;
        // the beating connection belongs to an admitted worker: no handshake deadline
        if let Some(c) = conn {
            c.admit();
        }
        Ok(Response::new(pb::BeatAck {}))
    }
}

/// The listening master and its attached workers.
pub struct Cluster {
    rt: Arc<Runtime>,
    addr: SocketAddr,
    workers: usize,
    opts: RemoteOptions,
    service: Arc<Service>,
    links: Vec<RemoteWorker>,
    /// Workers admitted after the start (the attach channel stays open for the run).
    joiner: Joiner,
    /// The step lane's port (None: not offered).
    lane_port: Option<u16>,
    stop: Option<oneshot::Sender<()>>,
}

impl std::fmt::Debug for Cluster {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cluster")
            .field("addr", &self.addr)
            .field("workers", &self.workers)
            .field("attached", &self.links.len())
            .finish()
    }
}

impl Cluster {
    /// Bind `listen` (port 0: any free port, see `local_addr`) and start serving.
    pub fn bind(
        listen: SocketAddr,
        workers: usize,
        opts: RemoteOptions,
    ) -> Result<Self, MasterError> {
        let lane_on = opts.step_lane && opts.tls.is_none();
        // With the lane the time-loop thread blocks on sockets and no longer drives the
        // runtime: it gets a thread of its own (heartbeats, lane admissions, gRPC).
        let rt = if lane_on {
            tokio::runtime::Builder::new_multi_thread()
                .worker_threads(1)
                .thread_name("crash-master-net")
                .enable_all()
                .build()
        } else {
            tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build()
        }
        .map_err(|e| MasterError::Network(format!("tokio runtime: {e}")))?;
        let listener = rt
            .block_on(tokio::net::TcpListener::bind(listen))
            .map_err(|e| MasterError::Network(format!("cannot listen on {listen}: {e}")))?;
        let addr = listener
            .local_addr()
            .map_err(|e| MasterError::Network(format!("listening address: {e}")))?;
        let (tx, rx) = mpsc::unbounded_channel();
        let beats = Arc::new(Beats::default());
        let desk = if lane_on {
            Some(crate::lane::start(
                &rt,
                addr.ip(),
                opts.step_lane_port,
                beats.clone(),
                opts.handshake_timeout,
            )?)
        } else {
            None
        };
        let service = Arc::new(Service {
            attach: Arc::new(Mutex::new(Some(tx))),
            beats,
            secret: opts.secret.clone().map(Arc::new),
            handshake: opts.handshake_timeout,
        });
        let server = CoordinatorServer::from_arc(service.clone())
            .max_decoding_message_size(opts.max_message)
            .max_encoding_message_size(MAX_MESSAGE_CAP);
        // grpc.health.v1.Health: SERVING for the coordinator while this cluster lives
        let (reporter, health) = tonic_health::server::health_reporter();
        rt.block_on(
            reporter.set_service_status(HEALTH_SERVICE, tonic_health::ServingStatus::Serving),
        );
        let (stop, stopped) = oneshot::channel::<()>();
        // every connection is guarded until a worker on it is admitted (guard.rs)
        let gate = Gate::new(opts.handshake_timeout, opts.max_message);
        let incoming = TcpListenerStream::new(listener).filter_map(move |r| match r {
            Ok(tcp) => {
                set_keepalive(&tcp);
                gate.admit_tcp(tcp).map(Ok::<_, std::io::Error>)
            }
            Err(e) => {
                tracing::debug!("accept failed: {e}");
                None
            }
        });
        let mut builder = tonic::transport::Server::builder();
        if let Some(id) = &opts.tls {
            let identity = tonic::transport::Identity::from_pem(&id.cert_pem, &id.key_pem);
            builder = builder
                .tls_config(tonic::transport::ServerTlsConfig::new().identity(identity))
                .map_err(|e| MasterError::Network(format!("TLS configuration: {e}")))?;
        }
        rt.spawn(async move {
            let r = builder
                // one Attach (and a health check) per connection
                .concurrency_limit_per_connection(4)
                .max_concurrent_streams(4)
                .http2_max_header_list_size(16 << 10)
                .layer(tower::util::MapRequestLayer::new(limit_request))
                .initial_stream_window_size(8 << 20)
                .initial_connection_window_size(16 << 20)
                .add_service(server)
                .add_service(health)
                .serve_with_incoming_shutdown(incoming, async {
                    let _ = stopped.await;
                })
                .await;
            if let Err(e) = r {
                tracing::error!("the gRPC server stopped: {e}");
            }
        });
        let rt = Arc::new(rt);
        let lane_port = desk.as_ref().map(|d| d.port());
        Ok(Self {
            joiner: Joiner::new(rt.clone(), rx, service.beats.clone(), opts.clone(), desk),
            lane_port,
            rt,
            addr,
            workers,
            opts,
            service,
            links: Vec::new(),
            stop: Some(stop),
        })
    }

    /// Whether workers must prove the shared secret.
    pub fn secret_required(&self) -> bool {
        self.service.secret.is_some()
    }

    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The step lane's address (None: not offered: TLS or `step_lane` off).
    pub fn lane_addr(&self) -> Option<SocketAddr> {
        self.lane_port.map(|p| SocketAddr::new(self.addr.ip(), p))
    }

    /// Wait until all workers have attached, then welcome them (indices in order of
    /// arrival). The attach channel stays open: workers that attach later join the run
    /// at a step boundary (`Joiner`).
    pub fn accept(&mut self) -> Result<(), MasterError> {
        if !self.links.is_empty() {
            return Ok(());
        }
        let Some(rx) = self.joiner.channel() else {
            return Ok(());
        };
        let n = self.workers;
        let t = self.opts.accept_timeout;
        let attached: Vec<Attached> = self.rt.block_on(async {
            let mut got = Vec::new();
            let _ = tokio::time::timeout(t, async {
                while got.len() < n && !crate::stop::requested() {
                    // look at the stop flag (SIGTERM) every 100 ms
                    let Ok(next) =
                        tokio::time::timeout(Duration::from_millis(100), rx.recv()).await
                    else {
                        continue;
                    };
                    match next {
                        Some(a) => {
                            tracing::info!(
                                "worker {} attached from {} ('{}', pid {}, {} threads)",
                                got.len(),
                                a.peer,
                                escape_peer(&a.hello.host),
                                a.hello.pid,
                                a.hello.threads
                            );
                            got.push(a);
                        }
                        None => break,
                    }
                }
            })
            .await;
            got
        });
        if crate::stop::requested() {
            return Err(MasterError::Interrupted { step: 0, time: 0.0 });
        }
        if attached.len() < n {
            return Err(MasterError::Network(format!(
                "only {} of {n} workers attached to {} within {:.0} s",
                attached.len(),
                self.addr,
                t.as_secs_f64()
            )));
        }
        for (i, a) in attached.into_iter().enumerate() {
            let link = self.joiner.welcome(a, i, n).map_err(MasterError::Network)?;
            self.links.push(link);
        }
        Ok(())
    }

    /// The workers of the start and the source of those that join later.
    pub fn parts(&mut self) -> (&mut [RemoteWorker], &mut Joiner) {
        (&mut self.links, &mut self.joiner)
    }

    pub fn links_mut(&mut self) -> &mut [RemoteWorker] {
        &mut self.links
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if let Ok(mut g) = self.service.attach.lock() {
            *g = None;
        }
        self.joiner.close();
        self.links.clear();
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
    }
}

/// TCP keepalive (10 s, then 3 probes 5 s apart, answered by the kernel): notices a
/// vanished worker host even while this process is busy. Set on the accepted socket,
/// since the server's own option applies only to connections it accepts itself.
fn set_keepalive(tcp: &tokio::net::TcpStream) {
    let ka = socket2::TcpKeepalive::new()
        .with_time(Duration::from_secs(10))
        .with_interval(Duration::from_secs(5))
        .with_retries(3);
    if let Err(e) = socket2::SockRef::from(tcp).set_tcp_keepalive(&ka) {
        tracing::debug!("cannot set TCP keepalive: {e}");
    }
}
