//! What an unadmitted peer can cost the master: bounded before any worker code runs.
//!
//! - Every accepted TCP connection is wrapped in [`Guarded`]: until a worker on it is
//!   admitted (a valid Hello, with its proof of the secret when one is set), reads
//!   fail once the handshake deadline has passed, which closes the connection (an
//!   idle or half-open socket, or a peer that never says Hello, is gone after a few
//!   seconds). At most [`MAX_PENDING`] such connections exist at once; more are
//!   closed as soon as they are accepted.
//! - Every request body is wrapped in [`LimitBody`], which reads the 5-byte gRPC
//!   frame headers as the bytes arrive and fails the stream when a message announces
//!   more than `HELLO_LIMIT` (before admission) or the run's limit (after), before
//!   tonic's decoder sees the length and reserves a buffer for it.

use bytes::Bytes;
use crash_link::HELLO_LIMIT;
use std::future::Future;
use std::io;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::TcpStream;
use tokio::time::Sleep;

/// Connections that have not (yet) admitted a worker, at most.
pub const MAX_PENDING: usize = 32;

/// One connection as the service sees it (in the request's extensions).
#[derive(Debug, Clone)]
pub struct ConnInfo {
    pub remote: Option<SocketAddr>,
    admitted: Arc<AtomicBool>,
    /// The message limit once admitted.
    limit: usize,
}

impl ConnInfo {
    /// A worker on this connection passed the handshake: lift the deadline and the
    /// small message limit.
    pub fn admit(&self) {
        self.admitted.store(true, Ordering::Release);
    }

    pub fn admitted(&self) -> bool {
        self.admitted.load(Ordering::Acquire)
    }
}

/// A TCP connection with a handshake deadline.
#[derive(Debug)]
pub struct Guarded {
    io: TcpStream,
    info: ConnInfo,
    deadline: Pin<Box<Sleep>>,
    pending: Option<Arc<AtomicUsize>>,
}

impl Guarded {
    fn release(&mut self) {
        if let Some(p) = self.pending.take() {
            p.fetch_sub(1, Ordering::AcqRel);
        }
    }

    /// Past the deadline without an admitted worker: the connection is closed.
    fn expired(&mut self, cx: &mut Context<'_>) -> bool {
        if self.info.admitted() {
            self.release();
            return false;
        }
        self.deadline.as_mut().poll(cx).is_ready()
    }
}

impl Drop for Guarded {
    fn drop(&mut self) {
        self.release();
    }
}

fn timed_out() -> io::Error {
    io::Error::new(
        io::ErrorKind::TimedOut,
        "no worker admitted on this connection within the handshake timeout",
    )
}

impl AsyncRead for Guarded {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        if self.expired(cx) {
            return Poll::Ready(Err(timed_out()));
        }
        Pin::new(&mut self.io).poll_read(cx, buf)
    }
}

impl AsyncWrite for Guarded {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.io).poll_write(cx, buf)
    }
    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.io).poll_flush(cx)
    }
    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.io).poll_shutdown(cx)
    }
    fn poll_write_vectored(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.io).poll_write_vectored(cx, bufs)
    }
    fn is_write_vectored(&self) -> bool {
        self.io.is_write_vectored()
    }
}

impl tonic::transport::server::Connected for Guarded {
    type ConnectInfo = ConnInfo;
    fn connect_info(&self) -> ConnInfo {
        self.info.clone()
    }
}

/// Wraps accepted connections; refuses those beyond `MAX_PENDING`.
#[derive(Debug, Clone)]
pub struct Gate {
    pending: Arc<AtomicUsize>,
    handshake: Duration,
    refused: Arc<AtomicUsize>,
    limit: usize,
}

impl Gate {
    pub fn new(handshake: Duration, limit: usize) -> Self {
        Self {
            limit,
            pending: Arc::new(AtomicUsize::new(0)),
            handshake,
            refused: Arc::new(AtomicUsize::new(0)),
        }
    }

    /// The guarded connection, or None (dropped: closed) when too many are pending.
    pub fn admit_tcp(&self, io: TcpStream) -> Option<Guarded> {
        let n = self.pending.fetch_add(1, Ordering::AcqRel);
        if n >= MAX_PENDING {
            self.pending.fetch_sub(1, Ordering::AcqRel);
            if self
                .refused
                .fetch_add(1, Ordering::Relaxed)
                .is_multiple_of(1000)
            {
                tracing::warn!(
                    "closed a new connection: {MAX_PENDING} connections are already waiting for their handshake"
                );
            }
            return None;
        }
        let _ = io.set_nodelay(true);
        Some(Guarded {
            info: ConnInfo {
                remote: io.peer_addr().ok(),
                admitted: Arc::new(AtomicBool::new(false)),
                limit: self.limit,
            },
            io,
            deadline: Box::pin(tokio::time::sleep(self.handshake)),
            pending: Some(self.pending.clone()),
        })
    }
}

/// A request body that fails as soon as a gRPC message announces more than the
/// connection's current limit.
#[derive(Debug)]
pub struct LimitBody {
    inner: tonic::body::Body,
    info: Option<ConnInfo>,
    header: [u8; 5],
    have: usize,
    remaining: u64,
}

impl LimitBody {
    pub fn new(inner: tonic::body::Body, info: Option<ConnInfo>) -> Self {
        Self {
            inner,
            info,
            header: [0; 5],
            have: 0,
            remaining: 0,
        }
    }

    fn limit(&self) -> usize {
        match &self.info {
            Some(i) if !i.admitted() => HELLO_LIMIT,
            Some(i) => i.limit,
            None => crash_link::MAX_MESSAGE,
        }
    }

    /// Follow the framing through `data`; Err(announced length) past the limit.
    fn scan(&mut self, mut data: &[u8]) -> Result<(), u64> {
        while !data.is_empty() {
            if self.remaining > 0 {
                let take = self.remaining.min(data.len() as u64);
                self.remaining -= take;
                data = &data[take as usize..];
            } else {
                self.header[self.have] = data[0];
                self.have += 1;
                data = &data[1..];
                if self.have == 5 {
                    self.have = 0;
                    let len = u32::from_be_bytes([
                        self.header[1],
                        self.header[2],
                        self.header[3],
                        self.header[4],
                    ]) as u64;
                    if len > self.limit() as u64 {
                        return Err(len);
                    }
                    self.remaining = len;
                }
            }
        }
        Ok(())
    }
}

impl http_body::Body for LimitBody {
    type Data = Bytes;
    type Error = tonic::Status;

    fn poll_frame(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<http_body::Frame<Bytes>, tonic::Status>>> {
        let frame = match Pin::new(&mut self.inner).poll_frame(cx) {
            Poll::Ready(Some(Ok(f))) => f,
            other => return other,
        };
        if let Some(d) = frame.data_ref() {
            let d = d.clone();
            if let Err(len) = self.scan(&d) {
                let limit = self.limit();
                return Poll::Ready(Some(Err(tonic::Status::resource_exhausted(format!(
                    "a message of {len} bytes exceeds this connection's limit of {limit} bytes{}",
                    if limit == HELLO_LIMIT {
                        " before the handshake"
                    } else {
                        ""
                    }
                )))));
            }
        }
        Poll::Ready(Some(Ok(frame)))
    }

    fn is_end_stream(&self) -> bool {
        self.inner.is_end_stream()
    }

    fn size_hint(&self) -> http_body::SizeHint {
        self.inner.size_hint()
    }
}

/// The connection of a request, over plain TCP or TLS (whose info wraps it).
pub fn conn_info(ext: &http::Extensions) -> Option<ConnInfo> {
    ext.get::<ConnInfo>().cloned().or_else(|| {
        ext.get::<tonic::transport::server::TlsConnectInfo<ConnInfo>>()
            .map(|t| t.get_ref().clone())
    })
}

/// Wrap a request's body with the limit of its connection.
pub fn limit_request(req: http::Request<tonic::body::Body>) -> http::Request<tonic::body::Body> {
    let info = conn_info(req.extensions());
    req.map(|b| tonic::body::Body::new(LimitBody::new(b, info)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_is_followed_across_chunks() {
        let mut b = LimitBody::new(tonic::body::Body::empty(), None);
        let mut msg = vec![0u8, 0, 0, 0, 3, 1, 2, 3];
        msg.extend_from_slice(&[0, 0x7f, 0xff, 0xff, 0xff]);
        // split anywhere: the small message passes, the huge header fails
        assert!(b.scan(&msg[..6]).is_ok());
        assert!(b.scan(&msg[6..10]).is_ok());
        assert_eq!(b.scan(&msg[10..]), Err(0x7fff_ffff));
    }
}
