//! The master's gRPC server: it serves `crash.v1.Coordinator` (and grpc.health.v1),
//! each worker dials in, says Hello and keeps one bidirectional stream open for the
//! whole run; `Cluster::accept` turns the attached workers into links
//! (`remote_link::RemoteWorker`).
//!
//! Threads: one current-thread tokio runtime, owned by the master's thread and driven
//! only while the master waits for replies (`RemoteWorker::recv` blocks on it). The
//! master's loop, the tonic server and all connections thus share one thread: a step
//! exchange costs no thread hand-over on the master side. TCP keepalive (answered by
//! the kernel) keeps connections alive while the master is busy between steps.

use crate::error::MasterError;
use crate::remote_link::{Outbound, RemoteWorker};
use crash_link::{check_version, HEALTH_SERVICE, PROTOCOL_VERSION};
use crash_proto::pb::coordinator_server::{Coordinator, CoordinatorServer};
use crash_proto::pb::worker_message::Reply as PbReply;
use crash_proto::pb::{self, master_message};
use std::collections::BTreeSet;
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
        if let Err(e) = check_version(hello.protocol_version, &who, "master") {
            tracing::error!("refused {who}: {e}");
            return Err(Status::failed_precondition(e.to_string()));
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
            reporter.set_service_status(HEALTH_SERVICE, tonic_health::ServingStatus::Serving),
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
                sent: BTreeSet::new(),
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
