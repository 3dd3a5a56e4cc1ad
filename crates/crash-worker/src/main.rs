//! crash-worker: integrate groups of bodies for a crash-master over gRPC.

use clap::Parser;
use std::process::ExitCode;
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "crash-worker",
    version,
    about = "A crash worker: dials a crash-master and integrates the groups it is given"
)]
struct Args {
    /// The master's URL, e.g. http://10.0.0.5:50051 (retried with backoff until it answers).
    #[arg(long, required_unless_present = "probe")]
    master: Option<String>,
    /// Only check the health of the master at this URL (grpc.health.v1 Check of
    /// crash.v1.Coordinator), without attaching: exit 0 if it is serving, 1 otherwise.
    #[arg(long, value_name = "URL", conflicts_with = "master")]
    probe: Option<String>,
    /// Timeout of --probe [s] (the master answers while it waits on the network).
    #[arg(long, default_value_t = 5.0, value_name = "SECS")]
    probe_timeout: f64,
    /// Compute threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Give up when the master cannot be reached for this long [s].
    #[arg(long, default_value_t = 60.0)]
    connect_timeout: f64,
    /// File holding the cluster's shared secret (else the CRASH_SECRET environment
    /// variable), proved to the master in Hello; never give it on the command line.
    #[arg(long, value_name = "PATH")]
    secret_file: Option<std::path::PathBuf>,
    /// TLS: the certificate (PEM) that signed the master's (for a self-signed master
    /// certificate, that certificate itself); the master's URL is then https://.
    #[arg(long, value_name = "PEM")]
    tls_ca: Option<std::path::PathBuf>,
    /// Announce this host name in Hello instead of $HOSTNAME (tests of escaping).
    #[arg(long, hide = true)]
    host: Option<String>,
    /// Announce this protocol version instead of the built-in one (tests of refusal).
    #[arg(long, hide = true)]
    protocol_version: Option<u32>,
    /// Keep a CPU awake between messages with one lowest-priority (SCHED_IDLE)
    /// spinning thread: on virtual machines whose idle vCPUs take tens of microseconds
    /// to wake it cuts the per-step barrier (docs/scaling.md); it costs a core's idle
    /// time. Linux only.
    #[arg(long)]
    idle_spin: bool,
    /// Take the other workers' direct halo connections on this TCP port (0: any free
    /// port). Holders of a group split over workers send each other their part states
    /// there, one message each way per step, instead of through the master.
    #[arg(long, default_value_t = 0, value_name = "PORT")]
    peer_port: u16,
    /// The host other workers dial for that port (default: the address the master
    /// sees this worker at; set it behind NAT or a published container port).
    #[arg(long, value_name = "HOST")]
    peer_host: Option<String>,
    /// Take no direct halo connections: the master relays this worker's part states.
    #[arg(long)]
    no_peer: bool,
    /// How long to wait for the other holders' part states in a split step [s].
    #[arg(long, default_value_t = 30.0, value_name = "SECS")]
    peer_timeout: f64,
    /// Poll for the next command on the step lane, and for the other holders' part
    /// states, this long [us] before blocking, giving the CPU away between tries. A
    /// blocked process is woken through the kernel, which on virtual machines costs
    /// tens of microseconds a wake-up; a polling one reads the message at once
    /// (docs/architecture-cluster.md). 0: block at once.
    #[arg(long, default_value_t = crash_link::poll::DEFAULT_BUDGET.as_micros() as u64, value_name = "US")]
    poll_us: u64,
    /// Sleep this long before each step [ms] (tests of a slow but alive worker).
    #[arg(long, hide = true, default_value_t = 0)]
    step_delay_ms: u64,
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info")),
        )
        .with_writer(std::io::stderr)
        // colour codes only on a terminal: logs kept in files stay plain text
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let args = Args::parse();
    let tls_ca = match &args.tls_ca {
        Some(p) => match std::fs::read(p) {
            Ok(pem) => Some(pem),
            Err(e) => {
                eprintln!(
                    "crash-worker: error: cannot read the TLS CA certificate {}: {e}",
                    p.display()
                );
                return ExitCode::FAILURE;
            }
        },
        None => None,
    };
    if let Some(url) = &args.probe {
        let secs = if args.probe_timeout.is_finite() {
            args.probe_timeout.clamp(0.0, 3600.0)
        } else {
            5.0
        };
        let timeout = Duration::from_secs_f64(secs);
        return match crash_worker::probe::probe_tls(url, timeout, tls_ca.as_deref()) {
            Ok(()) => {
                eprintln!("crash-worker: the master at {url} is serving");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("crash-worker: probe failed: {e}");
                ExitCode::FAILURE
            }
        };
    }
    let Some(master) = &args.master else {
        eprintln!("crash-worker: error: --master URL is required");
        return ExitCode::FAILURE;
    };
    let threads = args.threads.unwrap_or_else(crash_core::threads::cores);
    if let Some(note) = crash_core::threads::oversubscription(threads, crash_core::threads::cores())
    {
        eprintln!("crash-worker: note: {note}");
    }
    eprintln!(
        "crash-worker: {} element kernels, {threads} threads",
        crash_core::element::simd::path_name()
    );
    let _spin = crash_link::spin::start_if(args.idle_spin, "crash-worker");
    let mut opts = crash_worker::WorkerOptions::new(master, threads);
    opts.connect_timeout = Duration::from_secs_f64(args.connect_timeout.max(0.0));
    if let Some(p) = args.secret_file.as_deref() {
        if crash_link::auth::readable_by_others(p) {
            eprintln!(
                "crash-worker: warning: the secret file {} is readable by other users (chmod 600 it)",
                p.display()
            );
        }
    }
    opts.secret = match crash_link::Secret::configured(args.secret_file.as_deref()) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("crash-worker: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    opts.tls_ca = tls_ca;
    if let Some(h) = args.host {
        opts.host = h;
    }
    if let Some(v) = args.protocol_version {
        opts.protocol_version = v;
    }
    opts.step_delay = Duration::from_millis(args.step_delay_ms);
    opts.peer_port = (!args.no_peer).then_some(args.peer_port);
    opts.peer_host = args.peer_host.unwrap_or_default();
    opts.peer_timeout = Duration::from_secs_f64(args.peer_timeout.clamp(0.01, 3600.0));
    opts.poll = Duration::from_micros(args.poll_us.min(1_000_000));
    match crash_worker::run(&opts) {
        Ok(reason) => {
            eprintln!("crash-worker: done ({reason})");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("crash-worker: error: {e}");
            ExitCode::FAILURE
        }
    }
}
