//! An idle spinner: one thread at the lowest scheduling priority (Linux `SCHED_IDLE`)
//! that spins for as long as it lives, so that the CPU it runs on does not halt while
//! the process waits for a message.
//!
//! Why: on a virtual machine a halted virtual CPU is woken by the hypervisor, which on
//! the project's VM costs tens of microseconds per wake-up: a loopback ping-pong between
//! two processes takes 65-77 us a round trip with both vCPUs idle, 19.5 us while one
//! vCPU runs a `SCHED_IDLE` spinner (docs/scaling.md, "The barrier's floor"). Every step
//! of a cluster run pays two such wake-ups (the command, the reply). A `SCHED_IDLE`
//! thread runs only when nothing else wants its CPU and is preempted at once by any
//! normal thread that wakes, and the scheduler prefers a CPU that runs only such threads
//! when it places a woken task: the spinner costs the run's own threads nothing but
//! keeps a vCPU ready for them. What it costs: one core's worth of otherwise idle time
//! (and power), and on a host whose CPUs share a core (SMT) some of that core's issue
//! slots. MPI libraries busy-wait for the same reason. Opt-in (`--idle-spin`).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

/// A running spinner; stops (and is joined) when dropped.
#[derive(Debug)]
pub struct IdleSpinner {
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

impl IdleSpinner {
    /// Start the spinner. Errors when the thread cannot be given the idle policy (not
    /// Linux, or refused): then no thread spins, since a spinner at normal priority
    /// would take time from the run.
    pub fn start() -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, rx) = std::sync::mpsc::channel();
        let flag = stop.clone();
        let handle = std::thread::Builder::new()
            .name("crash-idle-spin".into())
            .spawn(move || {
                let set = idle_policy();
                let ok = set.is_ok();
                let _ = tx.send(set);
                if ok {
                    while !flag.load(Ordering::Relaxed) {
                        for _ in 0..256 {
                            std::hint::spin_loop();
                        }
                    }
                }
            })?;
        let set = rx
            .recv()
            .unwrap_or_else(|_| Err(std::io::Error::other("the spinner thread ended")));
        match set {
            Ok(()) => Ok(Self {
                stop,
                handle: Some(handle),
            }),
            Err(e) => {
                let _ = handle.join();
                Err(e)
            }
        }
    }
}

impl Drop for IdleSpinner {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// `--idle-spin` of crash-master and crash-worker: a spinner when `wanted`, a console
/// note (from `who`) when it cannot run. Keep the value for as long as the process
/// should spin.
pub fn start_if(wanted: bool, who: &str) -> Option<IdleSpinner> {
    if !wanted {
        return None;
    }
    match IdleSpinner::start() {
        Ok(s) => {
            eprintln!("{who}: --idle-spin: one idle-priority thread keeps a CPU awake");
            Some(s)
        }
        Err(e) => {
            eprintln!("{who}: note: --idle-spin is not available here ({e}); going on without it");
            None
        }
    }
}

/// The calling thread's policy is SCHED_IDLE from now on.
#[cfg(target_os = "linux")]
#[allow(unsafe_code)]
fn idle_policy() -> std::io::Result<()> {
    let param = libc::sched_param { sched_priority: 0 };
    // SAFETY: pid 0 is the calling thread; `param` is a valid, initialised struct that
    // outlives the call.
    let r = unsafe { libc::sched_setscheduler(0, libc::SCHED_IDLE, &param) };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

#[cfg(not(target_os = "linux"))]
fn idle_policy() -> std::io::Result<()> {
    Err(std::io::Error::new(
        std::io::ErrorKind::Unsupported,
        "an idle scheduling policy is available on Linux only",
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The task directory of the spinner thread in /proc/self/task, if it runs.
    #[cfg(target_os = "linux")]
    fn spinner_task() -> Option<std::path::PathBuf> {
        std::fs::read_dir("/proc/self/task")
            .expect("/proc")
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .find(|p| {
                std::fs::read_to_string(p.join("comm")).is_ok_and(|c| c.trim() == "crash-idle-spin")
            })
    }

    /// The spinner thread runs under SCHED_IDLE (read back from /proc) and stops when
    /// dropped.
    #[cfg(target_os = "linux")]
    #[test]
    fn the_spinner_runs_at_idle_priority_and_stops_when_dropped() {
        let s = IdleSpinner::start().expect("SCHED_IDLE needs no privilege on Linux");
        let task = spinner_task().expect("the spinner thread is listed");
        let stat = std::fs::read_to_string(task.join("stat")).expect("stat");
        // field 41 of /proc/TID/stat is the policy (SCHED_IDLE = 5); fields after the
        // command name, which is in parentheses
        let after = &stat[stat.rfind(')').expect("comm") + 2..];
        let policy: i32 = after
            .split(' ')
            .nth(41 - 3)
            .and_then(|f| f.parse().ok())
            .expect("policy field");
        assert_eq!(policy, libc::SCHED_IDLE);
        drop(s);
        // The join returns when the thread clears its tid, which the kernel does before
        // it removes the task from /proc: allow the listing a moment to catch up (CI
        // once saw it still listed right after the join).
        let gone = (0..500).any(|_| {
            let gone = spinner_task().is_none();
            if !gone {
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
            gone
        });
        assert!(
            gone,
            "the spinner must stop when dropped (still listed after 5 s)"
        );
    }
}
