//! The step lane (protocol v14): after the gRPC handshake a worker opens a plain TCP
//! connection to the port its Welcome names, proves it with its index and session token
//! (`opening`), and from then on every command and reply travels there as one frame:
//! a 4-byte little-endian length, then the protobuf message (`pb::MasterMessage`,
//! `pb::WorkerMessage`). Both ends read and write it with blocking std calls from the
//! thread that computes, so a step's exchange runs no async runtime, HTTP/2 or gRPC
//! code (~40 % of the barrier's CPU on the gRPC stream, docs/scaling.md).
//!
//! The length is checked against the reader's limit before anything is allocated for
//! the frame, as the gRPC side's message limit is.

use crate::auth::NONCE_LEN;
use std::io::{self, Read};
use std::net::TcpStream;
use std::ops::Range;
use std::time::Duration;
use thiserror::Error;

/// First bytes of a lane's opening ("crash lane", version 1).
pub const MAGIC: [u8; 4] = *b"CRL1";
/// Length of a lane's opening: magic, worker index (u32 LE), session token.
pub const OPENING_LEN: usize = 4 + 4 + NONCE_LEN;
/// The byte the master answers a lane it takes (the worker then reads its commands
/// there); a lane it does not take is closed instead.
pub const TAKEN: u8 = 0xA5;
/// How long the master waits for a worker's lane after its Welcome before the worker's
/// commands go over gRPC (a lane the worker opens later is closed, and the worker then
/// falls back to gRPC too).
pub const WAIT: Duration = Duration::from_secs(5);
/// How long a worker tries to connect to the lane (less than `WAIT`).
pub const CONNECT: Duration = Duration::from_secs(2);

const FIRST_BUFFER: usize = 64 << 10;

/// Options of a lane's socket at either end: no Nagle delay (a frame is one write),
/// and kernel keepalive (10 s, then 3 probes 5 s apart) so a vanished host is noticed
/// while this end waits, as on the gRPC connections.
pub fn tune(s: &TcpStream) -> io::Result<()> {
    s.set_nodelay(true)?;
    let ka = socket2::TcpKeepalive::new()
        .with_time(Duration::from_secs(10))
        .with_interval(Duration::from_secs(5))
        .with_retries(3);
    socket2::SockRef::from(s).set_tcp_keepalive(&ka)
}

/// A lane's opening for worker `index` with its session token (None: a token of the
/// wrong length).
pub fn opening(index: u32, token: &[u8]) -> Option<[u8; OPENING_LEN]> {
    opening_with(MAGIC, index, token)
}

/// An opening of this shape with another magic (the peer connections').
pub fn opening_with(magic: [u8; 4], index: u32, token: &[u8]) -> Option<[u8; OPENING_LEN]> {
    if token.len() != NONCE_LEN {
        return None;
    }
    let mut b = [0u8; OPENING_LEN];
    b[..4].copy_from_slice(&magic);
    b[4..8].copy_from_slice(&index.to_le_bytes());
    b[8..].copy_from_slice(token);
    Some(b)
}

/// The worker index and token of an opening (None: not a lane's opening).
pub fn parse_opening(b: &[u8; OPENING_LEN]) -> Option<(u32, &[u8])> {
    if b[..4] != MAGIC {
        return None;
    }
    let index = u32::from_le_bytes([b[4], b[5], b[6], b[7]]);
    Some((index, &b[8..]))
}

#[derive(Debug, Error)]
pub enum FrameError {
    /// A frame longer than the reader accepts (refused before it is read).
    #[error("a message of {len} bytes exceeds the limit of {limit} bytes")]
    Oversize { len: usize, limit: usize },
    #[error("the message does not decode: {0}")]
    Decode(#[from] prost::DecodeError),
}

/// Encode `msg` as one frame into `out` (cleared first; its allocation is reused).
pub fn encode_frame(out: &mut Vec<u8>, msg: &impl prost::Message) -> Result<(), FrameError> {
    let len = msg.encoded_len();
    if len > crate::MAX_MESSAGE_CAP {
        return Err(FrameError::Oversize {
            len,
            limit: crate::MAX_MESSAGE_CAP,
        });
    }
    out.clear();
    out.reserve(4 + len);
    out.extend_from_slice(&(len as u32).to_le_bytes());
    // a Vec grows as needed: this fails only past its capacity limit
    msg.encode(out).map_err(|_| FrameError::Oversize {
        len,
        limit: crate::MAX_MESSAGE_CAP,
    })
}

/// Frames read from a stream into one reused buffer.
#[derive(Debug)]
pub struct FrameReader {
    buf: Vec<u8>,
    start: usize,
    end: usize,
    limit: usize,
}

impl FrameReader {
    /// A reader that refuses frames longer than `limit` bytes.
    pub fn new(limit: usize) -> Self {
        Self {
            buf: vec![0; FIRST_BUFFER],
            start: 0,
            end: 0,
            limit,
        }
    }

    /// The length announced by the buffered frame header, if one is buffered.
    fn pending_len(&self) -> Option<usize> {
        (self.end - self.start >= 4).then(|| {
            let h = &self.buf[self.start..self.start + 4];
            u32::from_le_bytes([h[0], h[1], h[2], h[3]]) as usize
        })
    }

    /// The body of the next complete frame in the buffer (valid until the next `fill`);
    /// None when more bytes are needed.
    pub fn take(&mut self) -> Result<Option<Range<usize>>, FrameError> {
        let Some(len) = self.pending_len() else {
            return Ok(None);
        };
        if len > self.limit {
            return Err(FrameError::Oversize {
                len,
                limit: self.limit,
            });
        }
        if self.end - self.start < 4 + len {
            return Ok(None);
        }
        let body = self.start + 4..self.start + 4 + len;
        self.start = body.end;
        Ok(Some(body))
    }

    /// The bytes of a body `take` returned.
    pub fn body(&self, r: Range<usize>) -> &[u8] {
        &self.buf[r]
    }

    /// Decode the next complete frame as `M` (None: more bytes are needed).
    pub fn next_message<M: prost::Message + Default>(&mut self) -> Result<Option<M>, FrameError> {
        match self.take()? {
            Some(r) => Ok(Some(M::decode(&self.buf[r])?)),
            None => Ok(None),
        }
    }

    /// Read once from `r` into the buffer (one `read` call): the number of bytes read,
    /// 0 at the end of the stream. An oversize frame header fails here, before its
    /// body is given room.
    pub fn fill(&mut self, r: &mut impl Read) -> io::Result<usize> {
        if self.start == self.end {
            self.start = 0;
            self.end = 0;
        }
        // room for the frame being read (a header first)
        let need = match self.pending_len() {
            Some(len) if len > self.limit => {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    FrameError::Oversize {
                        len,
                        limit: self.limit,
                    },
                ))
            }
            Some(len) => 4 + len,
            None => 4,
        };
        if self.start + need > self.buf.len() || self.end == self.buf.len() {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
            // grown for a large frame, or for frames read ahead while the master writes
            let want = need.max(FIRST_BUFFER);
            if want > self.buf.len() {
                self.buf.resize(want, 0);
            } else if self.end == self.buf.len() {
                self.buf.resize(2 * self.buf.len(), 0);
            }
        }
        let n = r.read(&mut self.buf[self.end..])?;
        self.end += n;
        Ok(n)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a test panics on failure
mod tests {
    use super::*;
    use crash_proto::pb;

    fn beat(i: u32) -> pb::Beat {
        pb::Beat {
            worker_index: i,
            session_token: vec![7; 40],
        }
    }

    /// Frames written back to back come out one by one, whatever the read sizes.
    #[test]
    fn frames_round_trip_through_small_reads() {
        let mut wire = Vec::new();
        let mut f = Vec::new();
        for i in 0..50 {
            encode_frame(&mut f, &beat(i)).unwrap();
            wire.extend_from_slice(&f);
        }
        // a reader that hands out 3 bytes at a time
        struct Slow<'a>(&'a [u8]);
        impl Read for Slow<'_> {
            fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
                let n = out.len().min(3).min(self.0.len());
                out[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                Ok(n)
            }
        }
        let mut src = Slow(&wire);
        let mut r = FrameReader::new(1 << 10);
        let mut got = Vec::new();
        loop {
            match r.next_message::<pb::Beat>().unwrap() {
                Some(b) => got.push(b.worker_index),
                None => {
                    if r.fill(&mut src).unwrap() == 0 {
                        break;
                    }
                }
            }
        }
        assert_eq!(got, (0..50).collect::<Vec<_>>());
    }

    /// A header announcing more than the limit is refused before its body is read or
    /// given room.
    #[test]
    fn an_oversize_frame_is_refused_before_allocation() {
        let mut wire = ((64u32 << 20) + 1).to_le_bytes().to_vec();
        wire.extend_from_slice(&[0; 100]);
        let mut r = FrameReader::new(64 << 20);
        let mut src = &wire[..];
        r.fill(&mut src).unwrap();
        assert!(matches!(r.take(), Err(FrameError::Oversize { .. })));
        let e = r.fill(&mut src).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        assert!(r.buf.len() <= FIRST_BUFFER, "no room was made for it");
    }

    #[test]
    fn an_opening_carries_index_and_token() {
        let t = [9u8; NONCE_LEN];
        let o = opening(3, &t).unwrap();
        assert_eq!(parse_opening(&o), Some((3, &t[..])));
        assert!(opening(3, &t[..5]).is_none());
        let mut bad = o;
        bad[0] = b'X';
        assert!(parse_opening(&bad).is_none());
    }
}
