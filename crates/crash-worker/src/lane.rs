//! The worker's end of the step lane (`crash_link::lane`): after its Welcome the worker
//! connects to the lane's port on the host it dialled, sends its opening (index and
//! session token) and waits for the master's answer; from then on it reads each command
//! with a blocking read on its compute thread and writes each reply with one write.
//!
//! A lane that cannot be reached within `lane::CONNECT`, or that the master closes
//! instead of taking (it came after the master stopped waiting), leaves the worker on
//! gRPC: the master then sends its commands there too.

use crate::client::{WorkerError, WorkerOptions};
use crash_link::lane::{self, FrameReader, TAKEN};
use crash_link::poll::poll_for;
use crash_link::MAX_MESSAGE_CAP;
use crash_proto::pb;
use std::io::{self, Read, Write};
use std::net::{IpAddr, SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

/// How long the worker waits for the master to take or refuse its lane (the master
/// answers as soon as it has read the opening).
const ANSWER: Duration = Duration::from_secs(60);

/// An open lane.
#[derive(Debug)]
pub(crate) struct WorkerLane {
    stream: TcpStream,
    reader: FrameReader,
    out: Vec<u8>,
    /// How long a wait for the next command polls before it blocks (crash-link `poll`).
    poll: Duration,
}

/// The command already read if there is one (and the time its decoding took [ns]),
/// else one read from `stream` (blocking or not, as the stream is set): None when no
/// whole command has come yet.
fn read_once(
    reader: &mut FrameReader,
    stream: &mut TcpStream,
) -> Result<Option<(pb::MasterMessage, u64)>, String> {
    let t = Instant::now();
    match reader.next_message::<pb::MasterMessage>() {
        Ok(Some(m)) => return Ok(Some((m, t.elapsed().as_nanos() as u64))),
        Ok(None) => {}
        Err(e) => return Err(format!("step lane: {e}")),
    }
    match reader.fill(stream) {
        Ok(0) => Err("the master closed the step lane".into()),
        Ok(_) => Ok(None),
        Err(e)
            if matches!(
                e.kind(),
                io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted
            ) =>
        {
            Ok(None)
        }
        Err(e) => Err(format!("step lane: {e}")),
    }
}

/// The lane's addresses: the host of the master's URL with the lane's port.
fn addresses(url: &str, port: u16) -> io::Result<Vec<SocketAddr>> {
    let uri: tonic::transport::Uri = url
        .parse()
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, format!("{e}")))?;
    let host = uri
        .host()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "no host in the URL"))?;
    let bare = host.trim_start_matches('[').trim_end_matches(']');
    if let Ok(ip) = bare.parse::<IpAddr>() {
        return Ok(vec![SocketAddr::new(ip, port)]);
    }
    Ok((bare, port).to_socket_addrs()?.collect())
}

fn connect(url: &str, port: u16) -> io::Result<TcpStream> {
    let mut last = io::Error::new(io::ErrorKind::NotFound, "the host has no address");
    for a in addresses(url, port)? {
        match TcpStream::connect_timeout(&a, lane::CONNECT) {
            Ok(s) => return Ok(s),
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// Open the lane `welcome` offers. None: not offered, not reachable or not taken (the
/// commands then come over gRPC).
pub(crate) fn open(
    opts: &WorkerOptions,
    welcome: &pb::Welcome,
) -> Result<Option<WorkerLane>, WorkerError> {
    let url = opts.master.as_str();
    let Ok(port) = u16::try_from(welcome.lane_port) else {
        return Err(WorkerError::Protocol {
            url: url.into(),
            reason: format!("step lane port {} out of range", welcome.lane_port),
        });
    };
    if port == 0 {
        return Ok(None);
    }
    let Some(opening) = lane::opening(welcome.worker_index, &welcome.session_token) else {
        return Err(WorkerError::Protocol {
            url: url.into(),
            reason: "the Welcome's session token has the wrong length".into(),
        });
    };
    let mut stream = match connect(url, port).and_then(|s| {
        lane::tune(&s)?;
        Ok(s)
    }) {
        Ok(s) => s,
        Err(e) => {
            tracing::warn!(
                "cannot reach the master's step lane (port {port} on the host of {url}: {e}): commands come over gRPC"
            );
            return Ok(None);
        }
    };
    let answer = stream
        .write_all(&opening)
        .and_then(|()| stream.set_read_timeout(Some(ANSWER)))
        .and_then(|()| {
            let mut b = [0u8; 1];
            let n = stream.read(&mut b)?;
            Ok((n, b[0]))
        });
    match answer {
        Ok((1, TAKEN)) => {}
        Ok((0, _)) => {
            tracing::warn!(
                "the master did not take this worker's step lane (it came too late): commands come over gRPC"
            );
            return Ok(None);
        }
        Ok((_, b)) => {
            return Err(WorkerError::Protocol {
                url: url.into(),
                reason: format!("the step lane's answer was {b:#04x}"),
            })
        }
        Err(e) => {
            return Err(WorkerError::Lost {
                url: url.into(),
                reason: format!("no answer on the step lane: {e}"),
            })
        }
    }
    stream
        .set_read_timeout(None)
        .map_err(|e| WorkerError::Lost {
            url: url.into(),
            reason: format!("step lane: {e}"),
        })?;
    tracing::info!("commands come over the step lane (port {port})");
    Ok(Some(WorkerLane {
        stream,
        reader: FrameReader::new(MAX_MESSAGE_CAP),
        out: Vec::new(),
        poll: opts.poll,
    }))
}

impl WorkerLane {
    /// The next command (blocking) and the time spent decoding it [ns]. Err: the
    /// master closed the lane or the frame is not a command.
    pub(crate) fn next(&mut self) -> Result<(pb::MasterMessage, u64), String> {
        let (reader, stream) = (&mut self.reader, &mut self.stream);
        // first a bounded poll with non-blocking reads (crash-link `poll`), then block
        if !self.poll.is_zero() {
            let err = |e: io::Error| format!("step lane: {e}");
            stream.set_nonblocking(true).map_err(err)?;
            let got = poll_for(self.poll, || read_once(reader, stream));
            stream.set_nonblocking(false).map_err(err)?;
            if let Some(got) = got? {
                return Ok(got);
            }
        }
        loop {
            if let Some(got) = read_once(reader, stream)? {
                return Ok(got);
            }
        }
    }

    /// Send a reply (one write); the time spent encoding it [ns].
    pub(crate) fn send(&mut self, reply: &pb::WorkerMessage) -> Result<u64, String> {
        let t = Instant::now();
        lane::encode_frame(&mut self.out, reply).map_err(|e| e.to_string())?;
        let ns = t.elapsed().as_nanos() as u64;
        self.stream
            .write_all(&self.out)
            .map_err(|e| format!("step lane: {e}"))?;
        Ok(ns)
    }

    /// After a failed send: the command the master left before it closed the lane, if
    /// one comes within a second (the Shutdown of a worker it dropped).
    pub(crate) fn last_word(&mut self) -> Option<pb::MasterMessage> {
        self.stream
            .set_read_timeout(Some(Duration::from_secs(1)))
            .ok()?;
        self.next().ok().map(|(m, _)| m)
    }
}
