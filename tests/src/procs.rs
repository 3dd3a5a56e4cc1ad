//! Child processes of the cluster tests: killed on drop, stderr collected, every wait
//! bounded.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A release binary of the workspace, next to the running test executable
/// (`target/release/deps/..` -> `target/release/NAME`), or in `$CRASH_BIN_DIR` when set
/// (benches comparing two builds in one sitting run the same bench with each).
pub fn bin(name: &str) -> String {
    if let Some(dir) = std::env::var_os("CRASH_BIN_DIR") {
        let path = Path::new(&dir).join(name);
        assert!(path.exists(), "{} is missing", path.display());
        return path.to_string_lossy().into_owned();
    }
    let exe = std::env::current_exe().unwrap();
    let dir = exe
        .parent()
        .and_then(|d| {
            if d.ends_with("deps") {
                d.parent()
            } else {
                Some(d)
            }
        })
        .unwrap()
        .to_path_buf();
    let path = dir.join(name);
    assert!(
        path.exists(),
        "{} is missing: build the workspace first (cargo build --release --workspace)",
        path.display()
    );
    path.to_string_lossy().into_owned()
}

pub fn master_bin() -> String {
    bin("crash-master")
}

pub fn worker_bin() -> String {
    bin("crash-worker")
}

/// A child process whose stderr is collected line by line.
#[allow(missing_debug_implementations)]
pub struct Proc {
    pub name: String,
    child: Child,
    lines: mpsc::Receiver<String>,
    pub log: Arc<Mutex<String>>,
}

impl Proc {
    pub fn spawn(name: &str, exe: &str, args: &[&str]) -> Proc {
        Self::spawn_env(name, exe, args, &[])
    }

    /// As `spawn`, with these environment variables set (CRASH_SECRET is removed
    /// unless given here, so a developer's environment does not leak into a test).
    pub fn spawn_env(name: &str, exe: &str, args: &[&str], env: &[(&str, &str)]) -> Proc {
        let mut child = Command::new(exe)
            .args(args)
            .env("RUST_LOG", "info")
            .env_remove("CRASH_SECRET")
            .envs(env.iter().copied())
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let err = child.stderr.take().unwrap();
        let (tx, lines) = mpsc::channel();
        let log = Arc::new(Mutex::new(String::new()));
        let l2 = log.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                l2.lock().unwrap().push_str(&line);
                l2.lock().unwrap().push('\n');
                let _ = tx.send(line);
            }
        });
        Proc {
            name: name.into(),
            child,
            lines,
            log,
        }
    }

    /// Wait (bounded) for a stderr line containing `pat`; returns it.
    pub fn expect_line(&self, pat: &str, timeout: Duration) -> String {
        let end = Instant::now() + timeout;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(l) if l.contains(pat) => return l,
                Ok(_) => {}
                Err(_) => panic!(
                    "{}: no line with '{pat}' within {timeout:?}; stderr:\n{}",
                    self.name,
                    self.log()
                ),
            }
        }
    }

    /// Wait (bounded) for the process to exit.
    pub fn wait(&mut self, timeout: Duration) -> ExitStatus {
        let end = Instant::now() + timeout;
        loop {
            if let Some(s) = self.child.try_wait().unwrap() {
                // let the reader thread take the last lines
                std::thread::sleep(Duration::from_millis(50));
                return s;
            }
            if Instant::now() > end {
                panic!(
                    "{}: still running after {timeout:?}; stderr:\n{}",
                    self.name,
                    self.log()
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    pub fn log(&self) -> String {
        self.log.lock().unwrap().clone()
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Send a signal by name (STOP, CONT) with kill(1).
    pub fn signal(&self, sig: &str) {
        let ok = Command::new("kill")
            .args([&format!("-{sig}"), &self.pid().to_string()])
            .status()
            .unwrap()
            .success();
        assert!(ok, "kill -{sig} failed");
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        // a stopped process must be continued to die promptly
        let _ = Command::new("kill")
            .args(["-CONT", &self.pid().to_string()])
            .stderr(Stdio::null())
            .status();
        self.kill();
    }
}

/// A fresh directory under the target dir's `tmp/`.
pub fn out_dir(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let target = exe
        .ancestors()
        .find(|a| a.file_name().is_some_and(|n| n == "target"))
        .map_or_else(std::env::temp_dir, Path::to_path_buf);
    let d = target
        .join("tmp")
        .join(format!("cluster-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Start a master on a free loopback port; returns it and the workers' URL.
pub fn master(scene: &Path, workers: usize, out: &Path, extra: &[&str]) -> (Proc, String) {
    master_env(scene, workers, out, extra, &[])
}

/// As `master`, with environment variables set (e.g. CRASH_SECRET).
pub fn master_env(
    scene: &Path,
    workers: usize,
    out: &Path,
    extra: &[&str],
    env: &[(&str, &str)],
) -> (Proc, String) {
    let w = workers.to_string();
    let mut args = vec![
        scene.to_str().unwrap(),
        "--listen",
        "127.0.0.1:0",
        "--workers",
        &w,
        "--out",
        out.to_str().unwrap(),
        "--accept-timeout",
        "60",
    ];
    args.extend_from_slice(extra);
    let m = Proc::spawn_env("crash-master", &master_bin(), &args, env);
    let line = m.expect_line("listening on", Duration::from_secs(60));
    let addr = line.rsplit(' ').next().unwrap().trim().to_string();
    (m, format!("http://{addr}"))
}

pub fn worker(url: &str, threads: usize, extra: &[&str]) -> Proc {
    worker_env(url, threads, extra, &[])
}

/// As `worker`, with environment variables set (e.g. CRASH_SECRET).
pub fn worker_env(url: &str, threads: usize, extra: &[&str], env: &[(&str, &str)]) -> Proc {
    let t = threads.to_string();
    let mut args = vec!["--master", url, "--threads", &t, "--connect-timeout", "30"];
    args.extend_from_slice(extra);
    Proc::spawn_env("crash-worker", &worker_bin(), &args, env)
}

/// A field of /proc/PID/status in kB (VmRSS, VmSize, ...).
pub fn proc_status_kb(pid: u32, field: &str) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    s.lines()
        .find_map(|l| l.strip_prefix(field)?.strip_prefix(':'))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}
