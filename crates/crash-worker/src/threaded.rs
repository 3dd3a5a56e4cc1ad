//! An in-process worker on its own thread: the master's `send` hands the command over
//! and returns, so several in-process workers compute at once (a shared-memory domain
//! decomposition, as an MPP code runs on one node: each worker its own bodies or
//! parts, the split groups' halos through the master's relay).
//!
//! Why: in-process workers used to compute one after the other inside `send`, so
//! `crash run --workers N` could only be slower than one worker. On 2 cores two of them
//! now run ten-spheres 2.05x faster than one thread, the showcase 1.80x (two rayon
//! threads: 2.01x, 1.93x; docs/performance.md, session 27), with the same bits.

use crate::engine::Engine;
use crash_link::poll::{poll_for, DEFAULT_BUDGET};
use crash_link::{Command, LinkError, Reply, WorkerLink};
use std::sync::mpsc::{channel, Receiver, Sender, TryRecvError};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

/// An in-process worker whose engine runs on a thread of its own with a rayon pool of
/// `threads` threads.
#[derive(Debug)]
pub struct ThreadedWorker {
    index: usize,
    engine: Arc<Mutex<Engine>>,
    /// None once dropped: a closed channel ends the thread's loop.
    commands: Option<Sender<Command>>,
    replies: Receiver<Reply>,
    pending: usize,
    thread: Option<JoinHandle<()>>,
}

/// The next message of `rx`: polled for the default budget, then a blocking wait (the
/// same reason as the workers' lane: a cross-vCPU wake-up costs tens of microseconds).
fn next<T>(rx: &Receiver<T>) -> Option<T> {
    let polled = poll_for(DEFAULT_BUDGET, || match rx.try_recv() {
        Ok(v) => Ok(Some(v)),
        Err(TryRecvError::Empty) => Ok(None),
        Err(TryRecvError::Disconnected) => Err(()),
    });
    match polled {
        Ok(Some(v)) => Some(v),
        Ok(None) => rx.recv().ok(),
        Err(()) => None,
    }
}

impl ThreadedWorker {
    /// Worker `index` on a new thread with a pool of `threads` compute threads.
    pub fn spawn(index: usize, threads: usize) -> std::io::Result<Self> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.max(1))
            .thread_name(move |i| format!("crash-worker-{index}.{i}"))
            .build()
            .map_err(std::io::Error::other)?;
        let engine = Arc::new(Mutex::new(Engine::default()));
        let (commands, cmd_rx) = channel::<Command>();
        let (reply_tx, replies) = channel::<Reply>();
        let shared = Arc::clone(&engine);
        let thread = std::thread::Builder::new()
            .name(format!("crash-worker-{index}"))
            .spawn(move || {
                // the whole loop on the pool's thread: no hand-over per command
                pool.install(move || {
                    while let Some(cmd) = next(&cmd_rx) {
                        let last = matches!(cmd, Command::Shutdown(_));
                        let mut engine = shared.lock().unwrap_or_else(PoisonError::into_inner);
                        let reply = engine.handle(cmd);
                        if reply_tx.send(reply).is_err() || last {
                            break;
                        }
                        // what the reply did not wait for (a split's own parts)
                        engine.settle();
                    }
                });
            })?;
        Ok(Self {
            index,
            engine,
            commands: Some(commands),
            replies,
            pending: 0,
            thread: Some(thread),
        })
    }
}

impl Drop for ThreadedWorker {
    fn drop(&mut self) {
        drop(self.commands.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl WorkerLink for ThreadedWorker {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError> {
        let ended = || LinkError::Lost(format!("in-process worker {} ended", self.index));
        self.commands
            .as_ref()
            .ok_or_else(ended)?
            .send(cmd)
            .map_err(|_| ended())?;
        self.pending += 1;
        Ok(())
    }

    fn recv(&mut self) -> Result<Reply, LinkError> {
        if self.pending == 0 {
            return Err(LinkError::Protocol("no reply pending".into()));
        }
        let r = next(&self.replies)
            .ok_or_else(|| LinkError::Lost(format!("in-process worker {} ended", self.index)))?;
        self.pending -= 1;
        Ok(r)
    }

    fn peer(&self) -> String {
        format!("in-process worker {} (own thread)", self.index)
    }

    fn has_definition(&self, id: u32) -> bool {
        self.engine
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .has_definition(id)
    }
}

/// An in-process worker: inline (it computes inside `send`, on the master's thread and
/// pool) or on a thread of its own.
#[derive(Debug)]
pub enum InProcess {
    Inline(Box<crate::LocalWorker>),
    Threaded(ThreadedWorker),
}

impl InProcess {
    /// `n` workers (at least one): all but the last on threads of their own, with pools
    /// of `threads` compute threads each; the last inline, so that it computes on the
    /// master's thread (and pool) while the others do, and no thread waits idle for the
    /// master. One worker is inline only.
    pub fn many(n: usize, threads: usize) -> std::io::Result<Vec<Self>> {
        let n = n.max(1);
        (0..n)
            .map(|i| {
                Ok(if i + 1 < n {
                    InProcess::Threaded(ThreadedWorker::spawn(i, threads)?)
                } else {
                    InProcess::Inline(Box::new(crate::LocalWorker::new(i)))
                })
            })
            .collect()
    }
}

impl InProcess {
    fn link(&self) -> &dyn WorkerLink {
        match self {
            InProcess::Inline(w) => w.as_ref(),
            InProcess::Threaded(w) => w,
        }
    }
    fn link_mut(&mut self) -> &mut dyn WorkerLink {
        match self {
            InProcess::Inline(w) => w.as_mut(),
            InProcess::Threaded(w) => w,
        }
    }
}

impl WorkerLink for InProcess {
    fn send(&mut self, cmd: Command) -> Result<(), LinkError> {
        self.link_mut().send(cmd)
    }
    fn recv(&mut self) -> Result<Reply, LinkError> {
        self.link_mut().recv()
    }
    fn peer(&self) -> String {
        self.link().peer()
    }
    fn has_definition(&self, id: u32) -> bool {
        self.link().has_definition(id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `send` hands the command over and returns; the reply comes from the worker's own
    /// thread; after Shutdown the thread has ended and a further command says so.
    #[test]
    fn a_threaded_worker_answers_from_its_own_thread_and_ends_on_shutdown() {
        let mut w = ThreadedWorker::spawn(0, 1).expect("spawn");
        assert!(
            matches!(w.recv(), Err(LinkError::Protocol(_))),
            "nothing pending"
        );
        w.send(Command::Shutdown("done".into())).expect("send");
        assert!(matches!(w.recv(), Ok(Reply::Ack)));
        if let Some(t) = w.thread.take() {
            t.join().expect("the worker thread ends after Shutdown");
        }
        assert!(matches!(
            w.send(Command::Shutdown("again".into())),
            Err(LinkError::Lost(_))
        ));
    }

    /// Two workers and their last one inline: the first two are threaded.
    #[test]
    fn all_but_the_last_in_process_worker_run_on_threads_of_their_own() {
        let ws = InProcess::many(3, 1).expect("spawn");
        let kinds: Vec<bool> = ws
            .iter()
            .map(|w| matches!(w, InProcess::Threaded(_)))
            .collect();
        assert_eq!(kinds, [true, true, false]);
        assert!(matches!(
            InProcess::many(0, 1).expect("one").as_slice(),
            [InProcess::Inline(_)]
        ));
    }
}
