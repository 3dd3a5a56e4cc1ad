//! Worker processes over gRPC: the master serves `crash.v1.Coordinator`, each worker
//! dials in and keeps one bidirectional stream open for the whole run.
//!
//! Threads: one current-thread tokio runtime, owned by the master's thread and driven
//! only while the master waits for replies (`RemoteWorker::recv` blocks on it). The
//! master's loop, the tonic server and all connections thus share one thread: a step
//! exchange costs no thread hand-over on the master side. TCP keepalive (answered by
//! the kernel) keeps connections alive while the master is busy between steps.

use crate::error::MasterError;
use crate::link::{LinkError, WorkerLink};
use crash_core::Body;
use crash_proto::msg::{command_to_pb, report_from_pb};
use crash_proto::pb::coordinator_server::{Coordinator, CoordinatorServer};
use crash_proto::pb::worker_message::Reply as PbReply;
use crash_proto::pb::{self, failure, master_message};
use crash_proto::report::fault_from_pb;
use crash_proto::{apply_state, Command, Reply, PROTOCOL_VERSION};
use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::runtime::Runtime;
use tokio::sync::{mpsc, oneshot};
use tokio_stream::wrappers::{TcpListenerStream, UnboundedReceiverStream};
use tonic::{Request, Response, Status, Streaming};

/// Largest message accepted (a Load of big bodies can be hundreds of MB).
pub const MAX_MESSAGE: usize = 1 << 31;

#[derive(Debug, Clone, Copy)]
pub struct RemoteOptions {
    /// How long to wait for all workers to attach.
    pub accept_timeout: Duration,
    /// A worker that does not answer a command within this time ends the run.
    pub reply_timeout: Duration,
}

impl Default for RemoteOptions {
    fn default() -> Self {
        Self {
            accept_timeout: Duration::from_secs(300),
            reply_timeout: Duration::from_secs(60),
        }
    }
}

type Outbound = mpsc::UnboundedSender<Result<pb::MasterMessage, Status>>;

/// A worker that said a valid Hello.
struct Attached {
    hello: pb::Hello,
    peer: String,
    inbound: Streaming<pb::WorkerMessage>,
    outbound: Outbound,
}

struct Service {
    attach: Mutex<Option<mpsc::UnboundedSender<Attached>>>,
}

#[tonic::async_trait]
impl Coordinator for Service {
    type AttachStream = UnboundedReceiverStream<Result<pb::MasterMessage, Status>>;

    async fn attach(
        &self,
        req: Request<Streaming<pb::WorkerMessage>>,
    ) -> Result<Response<Self::AttachStream>, Status> {
        let peer = req
            .remote_addr()
            .map_or_else(|| "unknown address".to_string(), |a| a.to_string());
        let mut inbound = req.into_inner();
        let first = tokio::time::timeout(Duration::from_secs(30), inbound.message()).await;
        let hello = match first {
            Ok(Ok(Some(pb::WorkerMessage {
                reply: Some(PbReply::Hello(h)),
            }))) => h,
            _ => {
                tracing::warn!("refused a connection from {peer}: it did not start with Hello");
                return Err(Status::invalid_argument("the first message must be Hello"));
            }
        };
        let who = format!("worker {}:{} at {peer}", hello.host, hello.pid);
        if hello.protocol_version != PROTOCOL_VERSION {
            let msg = format!(
                "protocol version mismatch: {who} speaks crash protocol v{}, this master speaks v{PROTOCOL_VERSION}; run matching versions of crash-master and crash-worker",
                hello.protocol_version
            );
            tracing::error!("refused {who}: {msg}");
            return Err(Status::failed_precondition(msg));
        }
        let (outbound, rx) = mpsc::unbounded_channel();
        let sender = self.attach.lock().ok().and_then(|g| g.clone());
        let accepted = sender.is_some_and(|s| {
            s.send(Attached {
                hello,
                peer: peer.clone(),
                inbound,
                outbound,
            })
            .is_ok()
        });
        if !accepted {
            tracing::warn!("refused {who}: the run has all its workers");
            return Err(Status::unavailable(
                "this master is not accepting workers: its run already has all its workers",
            ));
        }
        Ok(Response::new(UnboundedReceiverStream::new(rx)))
    }
}

/// The listening master and its attached workers.
pub struct Cluster {
    rt: Arc<Runtime>,
    addr: SocketAddr,
    workers: usize,
    opts: RemoteOptions,
    rx: Option<mpsc::UnboundedReceiver<Attached>>,
    service: Arc<Service>,
    links: Vec<RemoteWorker>,
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
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .map_err(|e| MasterError::Network(format!("tokio runtime: {e}")))?;
        let listener = rt
            .block_on(tokio::net::TcpListener::bind(listen))
            .map_err(|e| MasterError::Network(format!("cannot listen on {listen}: {e}")))?;
        let addr = listener
            .local_addr()
            .map_err(|e| MasterError::Network(format!("listening address: {e}")))?;
        let (tx, rx) = mpsc::unbounded_channel();
        let service = Arc::new(Service {
            attach: Mutex::new(Some(tx)),
        });
        let server = CoordinatorServer::from_arc(service.clone())
            .max_decoding_message_size(MAX_MESSAGE)
            .max_encoding_message_size(MAX_MESSAGE);
        // grpc.health.v1.Health: SERVING for the coordinator while this cluster lives
        let (reporter, health) = tonic_health::server::health_reporter();
        rt.block_on(
            reporter
                .set_service_status(crate::health::SERVICE, tonic_health::ServingStatus::Serving),
        );
        let (stop, stopped) = oneshot::channel::<()>();
        let incoming = TcpListenerStream::new(listener);
        rt.spawn(async move {
            let r = tonic::transport::Server::builder()
                .tcp_nodelay(true)
                .tcp_keepalive(Some(Duration::from_secs(10)))
                .tcp_keepalive_interval(Some(Duration::from_secs(5)))
                .tcp_keepalive_retries(Some(3))
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
        Ok(Self {
            rt: Arc::new(rt),
            addr,
            workers,
            opts,
            rx: Some(rx),
            service,
            links: Vec::new(),
            stop: Some(stop),
        })
    }

    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Wait until all workers have attached, then welcome them (indices in order of
    /// arrival). Later workers are refused.
    pub fn accept(&mut self) -> Result<(), MasterError> {
        let Some(mut rx) = self.rx.take() else {
            return Ok(());
        };
        let n = self.workers;
        let t = self.opts.accept_timeout;
        let attached: Vec<Attached> = self.rt.block_on(async {
            let mut got = Vec::new();
            let _ = tokio::time::timeout(t, async {
                while got.len() < n {
                    match rx.recv().await {
                        Some(a) => {
                            tracing::info!(
                                "worker {} attached from {} ({} threads)",
                                got.len(),
                                a.peer,
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
        // stop accepting: later attaches are refused with a clear message
        if let Ok(mut g) = self.service.attach.lock() {
            *g = None;
        }
        drop(rx);
        if attached.len() < n {
            return Err(MasterError::Network(format!(
                "only {} of {n} workers attached to {} within {:.0} s",
                attached.len(),
                self.addr,
                t.as_secs_f64()
            )));
        }
        for (i, a) in attached.into_iter().enumerate() {
            let welcome = pb::MasterMessage {
                command: Some(master_message::Command::Welcome(pb::Welcome {
                    protocol_version: PROTOCOL_VERSION,
                    worker_index: i as u32,
                    workers: n as u32,
                })),
            };
            a.outbound.send(Ok(welcome)).map_err(|_| {
                MasterError::Network(format!("worker {i} at {} left before Welcome", a.peer))
            })?;
            self.links.push(RemoteWorker {
                rt: self.rt.clone(),
                index: i,
                peer: format!("{} (pid {} on '{}')", a.peer, a.hello.pid, a.hello.host),
                threads: a.hello.threads,
                tx: Some(a.outbound),
                inbound: a.inbound,
                mirror: BTreeMap::new(),
                timeout: self.opts.reply_timeout,
            });
        }
        Ok(())
    }

    pub fn links_mut(&mut self) -> &mut [RemoteWorker] {
        &mut self.links
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        self.links.clear();
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
    }
}

/// A worker process seen from the master. Keeps a copy of the definition of every
/// body it sent (the mirror): snapshots and unloads then travel as states only.
pub struct RemoteWorker {
    rt: Arc<Runtime>,
    index: usize,
    peer: String,
    threads: u32,
    tx: Option<Outbound>,
    inbound: Streaming<pb::WorkerMessage>,
    mirror: BTreeMap<u32, Body>,
    timeout: Duration,
}

impl std::fmt::Debug for RemoteWorker {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RemoteWorker")
            .field("index", &self.index)
            .field("peer", &self.peer)
            .field("threads", &self.threads)
            .field("bodies", &self.mirror.len())
            .finish()
    }
}

impl RemoteWorker {
    pub fn threads(&self) -> u32 {
        self.threads
    }

    fn recv_within(&mut self, timeout: Duration) -> Result<Reply, LinkError> {
        // the timer must be created inside the runtime
        let inbound = &mut self.inbound;
        let msg = match self
            .rt
            .block_on(async { tokio::time::timeout(timeout, inbound.message()).await })
        {
            Err(_) => {
                return Err(LinkError::Timeout(format!(
                    "no reply within {:.1} s",
                    timeout.as_secs_f64()
                )))
            }
            Ok(Err(s)) => return Err(LinkError::Lost(format!("{}: {}", s.code(), s.message()))),
            Ok(Ok(None)) => return Err(LinkError::Lost("the worker closed its stream".into())),
            Ok(Ok(Some(m))) => m,
        };
        self.decode(msg).map_err(LinkError::Protocol)
    }

    fn decode(&mut self, msg: pb::WorkerMessage) -> Result<Reply, String> {
        Ok(match msg.reply.ok_or("empty reply")? {
            PbReply::Ack(_) => Reply::Ack,
            PbReply::Report(r) => Reply::Report(report_from_pb(&r).map_err(|e| e.to_string())?),
            PbReply::Unloaded(b) => {
                let mut out = Vec::with_capacity(b.states.len());
                for s in &b.states {
                    let mut body = self
                        .mirror
                        .remove(&s.id)
                        .ok_or_else(|| format!("unloaded body {} was never sent", s.id))?;
                    apply_state(&mut body, s).map_err(|e| e.to_string())?;
                    out.push(body);
                }
                Reply::Unloaded(out)
            }
            PbReply::Snapshot(b) => {
                let mut out = Vec::with_capacity(b.states.len());
                for s in &b.states {
                    let body = self
                        .mirror
                        .get_mut(&s.id)
                        .ok_or_else(|| format!("snapshot of body {} that was never sent", s.id))?;
                    apply_state(body, s).map_err(|e| e.to_string())?;
                    out.push(body.clone());
                }
                Reply::Snapshot(out)
            }
            PbReply::Failure(f) => match f.kind.ok_or("empty failure")? {
                failure::Kind::Fault(fault) => Reply::Fault {
                    group_first: f.group_first,
                    fault: fault_from_pb(&fault).map_err(|e| e.to_string())?,
                },
                failure::Kind::Error(e) => Reply::Error(e),
            },
            PbReply::Hello(_) => return Err("a second Hello".into()),
        })
    }
}

impl WorkerLink for RemoteWorker {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError> {
        let msg = command_to_pb(&cmd);
        if let Command::Load(bodies) = cmd {
            for b in bodies {
                self.mirror.insert(b.id, b);
            }
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
