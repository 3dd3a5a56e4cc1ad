//! crash-master: serve a scene to N crash-worker processes and run it.

use anyhow::Context;
use clap::Parser;
use crash_link::{Secret, SECRET_ENV};
use crash_master::{
    read_restart_keyed, resume_remote, run_remote, Cluster, CostModel, FileSink, MasterError,
    RemoteOptions, RunInput, RunOptions, RESTART_FILE,
};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// Exit code of a run stopped by a physical fault (as `crash run`'s).
const EXIT_FAULT: u8 = 3;

#[derive(Parser, Debug)]
#[command(
    name = "crash-master",
    version,
    about = "Run a crash scene on N crash-worker processes over gRPC"
)]
struct Args {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Address to listen on for workers (port 0: any free port, printed at start).
    /// Loopback by default: give e.g. 0.0.0.0:50051 to admit workers on other hosts.
    #[arg(long, default_value = "127.0.0.1:50051")]
    listen: SocketAddr,
    /// File holding the cluster's shared secret (at least 16 bytes; else the
    /// CRASH_SECRET environment variable): only workers that prove it are admitted.
    /// Without either, any peer that reaches the port may attach.
    #[arg(long, value_name = "PATH")]
    secret_file: Option<PathBuf>,
    /// A connection on which no worker completes the handshake within this time is
    /// closed [s].
    #[arg(long, default_value_t = 5.0)]
    handshake_timeout: f64,
    /// Number of workers to wait for.
    #[arg(long)]
    workers: usize,
    /// Run directory (energy.csv, frames, summary.json).
    #[arg(long)]
    out: PathBuf,
    /// Replace the scene's end time [s].
    #[arg(long)]
    end_time: Option<f64>,
    /// Replace the scene's output interval [s].
    #[arg(long)]
    output_interval: Option<f64>,
    /// Wait this long for all workers to attach [s].
    #[arg(long, default_value_t = 300.0)]
    accept_timeout: f64,
    /// A worker that does not answer a command within this time is lost [s] (a safety
    /// net: a frozen worker is found by its missing heartbeats much sooner).
    #[arg(long, default_value_t = 600.0)]
    reply_timeout: f64,
    /// A worker from which no heartbeat came for this long (while the master waits for
    /// it) is lost [s]; 0: heartbeats are not checked.
    #[arg(long, default_value_t = 5.0)]
    heartbeat_timeout: f64,
    /// Take a checkpoint in memory after this much wall time since the last one [s]:
    /// when a worker is lost, the run goes back to it on the other workers. 0: none
    /// (then, unless --checkpoint-every is given, a lost worker ends the run).
    #[arg(long, default_value_t = 5.0)]
    checkpoint_seconds: f64,
    /// When every worker was lost, wait this long for a worker to join (the same
    /// admission as at the start) and continue from the last checkpoint on it [s];
    /// 0: stop at once (with the checkpoint on disk for --resume).
    #[arg(long, default_value_t = 60.0, value_name = "SECONDS")]
    rejoin_timeout: f64,
    /// MEIM boxes are inflated by this multiple of the contact margin (>= 1).
    #[arg(long, default_value_t = 2.0)]
    margin_factor: f64,
    /// Balance with estimated costs (elements + contact nodes) instead of measured
    /// times: placement is then reproducible.
    #[arg(long)]
    estimated_costs: bool,
    /// Split a group over several workers by elements: off, auto (a group above its
    /// fair share of the work), always. Same bits either way.
    #[arg(long, default_value = "auto", value_name = "WHEN")]
    split: crash_master::SplitMode,
    /// Keep a CPU awake between messages with one lowest-priority (SCHED_IDLE)
    /// spinning thread: on virtual machines whose idle vCPUs take tens of microseconds
    /// to wake it cuts the per-step barrier (docs/scaling.md); it costs a core's idle
    /// time. Linux only.
    #[arg(long)]
    idle_spin: bool,
    /// Write a restart file OUT/restart.ckp (replaced atomically) every N steps, and at
    /// every timed checkpoint (--checkpoint-seconds) too. It is
    /// continued with `crash-master --resume OUT/restart.ckp` on any number of workers,
    /// or in one process with `crash run SCENE --restart OUT/restart.ckp`.
    #[arg(long, value_name = "N")]
    checkpoint_every: Option<u64>,
    /// Continue the run of this scene from a restart file (its checkpoint's clock,
    /// states and schedule) with the workers that attach now, in the run directory
    /// --out: rows and frames after the checkpoint are replaced.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Serve workers over TLS with this certificate (chain, PEM); workers then dial
    /// https://HOST:PORT with --tls-ca. `crash-master cert` makes a self-signed pair.
    #[arg(long, value_name = "PEM", requires = "tls_key")]
    tls_cert: Option<PathBuf>,
    /// The private key of --tls-cert (PEM).
    #[arg(long, value_name = "PEM", requires = "tls_cert")]
    tls_key: Option<PathBuf>,
    /// Keep every command on the workers' gRPC streams instead of the step lane (a
    /// plain TCP connection per worker, admitted by its session token, on a second
    /// port of the --listen address; docs/architecture-cluster.md). With TLS the lane
    /// is never offered.
    #[arg(long)]
    no_step_lane: bool,
    /// Relay the part states of groups split over workers through the master instead
    /// of letting the workers exchange them directly (one message each way between
    /// them per step, on ports they announce; plain TCP only: with TLS they are always
    /// relayed).
    #[arg(long)]
    no_direct_halo: bool,
    /// The step lane's port (0: any free port, announced to each worker in its
    /// Welcome); set it when a firewall must let the lane through. A worker that cannot
    /// reach the lane keeps its commands on gRPC.
    #[arg(long, default_value_t = 0, value_name = "PORT")]
    step_lane_port: u16,
}

/// `crash-master cert --out DIR --host NAME...`: a self-signed certificate and key.
#[derive(Parser, Debug)]
#[command(
    name = "crash-master cert",
    about = "Make a self-signed TLS certificate (DIR/cert.pem) and key (DIR/key.pem) for crash-master --tls-cert/--tls-key and crash-worker --tls-ca"
)]
struct CertArgs {
    /// Directory for cert.pem and key.pem.
    #[arg(long)]
    out: PathBuf,
    /// A host name or IP address the workers dial (repeat for several).
    #[arg(long = "host", required = true)]
    hosts: Vec<String>,
}

fn cert(args: CertArgs) -> ExitCode {
    match crash_master::cert::write_pair(&args.out, &args.hosts) {
        Ok((c, k)) => {
            eprintln!(
                "crash-master: wrote {} and {} (for {})",
                c.display(),
                k.display(),
                args.hosts.join(", ")
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("crash-master: error: {e}");
            ExitCode::FAILURE
        }
    }
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
    // SIGTERM, SIGINT: finish the step, checkpoint, last frame, summary, exit 130;
    // a second signal ends the process at once (exit 130)
    if let Err(e) = crash_master::stop::install_handlers() {
        eprintln!("crash-master: warning: cannot handle SIGTERM/SIGINT: {e}");
    }
    if std::env::args_os().nth(1).is_some_and(|a| a == "cert") {
        return cert(CertArgs::parse_from(std::env::args_os().skip(1)));
    }
    let args = Args::parse();
    let out = args.out.clone();
    let _spin = crash_link::spin::start_if(args.idle_spin, "crash-master");
    match run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if let Some(i @ MasterError::Interrupted { .. }) = e.downcast_ref::<MasterError>() {
                eprintln!("crash-master: {i}: continue with --resume {}/{RESTART_FILE} (and the same options)", out.display());
                return ExitCode::from(crash_master::stop::EXIT_INTERRUPTED);
            }
            eprintln!("crash-master: error: {e:#}");
            // a physical fault (after a replay confirmed it, docs/reliability.md):
            // the exit code of `crash run`
            match e.downcast_ref::<MasterError>() {
                Some(MasterError::Fault(_) | MasterError::Margin { .. }) => {
                    ExitCode::from(EXIT_FAULT)
                }
                _ => ExitCode::FAILURE,
            }
        }
    }
}

fn run(args: Args) -> anyhow::Result<()> {
    let scene = crash_scene::load(&args.scene)?.with_overrides(crash_scene::Overrides {
        end_time: args.end_time,
        output_interval: args.output_interval,
    })?;
    // planned, not built: each body is built when it is handed to its worker, so the
    // master's memory does not grow with the model
    let plan = scene.plan()?;
    let energy_limit = plan.energy_limit;
    let frame_format = crash_master::frame_format(&plan.outputs);
    let names: Vec<(u32, String)> = scene
        .spec
        .bodies
        .iter()
        .enumerate()
        .map(|(i, b)| (i as u32, b.name.clone()))
        .collect();
    let input = RunInput::from_plan(scene, plan);
    let secret = Secret::configured(args.secret_file.as_deref())?;
    // restart files carry a MAC under a key from the secret (docs/reliability.md)
    let key = secret.as_ref().map(Secret::checkpoint_key);
    let restart = match &args.resume {
        Some(path) => {
            let r = read_restart_keyed(path, key.as_ref()).map_err(|e| anyhow::anyhow!("{e}"))?;
            // before the run directory is reopened (that drops rows after the checkpoint)
            r.master
                .check_continues(input.scene_hash, input.config.end_time)
                .with_context(|| format!("cannot resume from {}", path.display()))?;
            Some(r)
        }
        None => None,
    };
    let sink = match &restart {
        None => FileSink::create(&args.out, &input.name, input.scene_hash, input.size()),
        Some(r) => FileSink::reopen(&args.out, &input.name, input.scene_hash, input.size(), r),
    };
    let mut sink = sink
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("cannot open the run directory {}", args.out.display()))?
        .with_checkpoints(args.out.join(RESTART_FILE))
        .with_checkpoint_key(key)
        .with_energy_limit(energy_limit)
        .with_frame_format(frame_format)
        .with_body_names(names)
        .with_echo(true)
        .with_results(&input.results)
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("cannot create the result files in {}", args.out.display()))?;
    if let Some(p) = args.secret_file.as_deref() {
        if crash_link::auth::readable_by_others(p) {
            eprintln!(
                "crash-master: warning: the secret file {} is readable by other users (chmod 600 it)",
                p.display()
            );
        }
    }
    let tls = match (&args.tls_cert, &args.tls_key) {
        (Some(c), Some(k)) => Some(crash_master::TlsIdentity {
            cert_pem: std::fs::read(c)
                .with_context(|| format!("cannot read the TLS certificate {}", c.display()))?,
            key_pem: std::fs::read(k)
                .with_context(|| format!("cannot read the TLS key {}", k.display()))?,
        }),
        _ => None,
    };
    let tls_on = tls.is_some();
    let mut cluster = Cluster::bind(
        args.listen,
        args.workers,
        RemoteOptions {
            accept_timeout: Duration::from_secs_f64(args.accept_timeout.max(0.0)),
            reply_timeout: Duration::from_secs_f64(args.reply_timeout.clamp(0.001, 1e9)),
            heartbeat_timeout: (args.heartbeat_timeout > 0.0)
                .then(|| Duration::from_secs_f64(args.heartbeat_timeout.min(1e9))),
            handshake_timeout: Duration::from_secs_f64(args.handshake_timeout.clamp(0.1, 3600.0)),
            secret,
            max_message: crash_link::message_limit(
                input.briefs.iter().map(|b| b.elements).max().unwrap_or(0),
            ),
            tls,
            step_lane: !args.no_step_lane,
            step_lane_port: args.step_lane_port,
            direct_halo: !args.no_direct_halo,
        },
    )?;
    // Tests and scripts read this line to learn the port (the address ends it).
    if tls_on {
        eprintln!("crash-master: TLS on: workers dial https://HOST:PORT with --tls-ca");
    }
    eprintln!("crash-master: listening on {}", cluster.local_addr());
    match cluster.lane_addr() {
        Some(a) => eprintln!("crash-master: step lane on {a}"),
        None if tls_on => {
            eprintln!(
                "crash-master: with TLS the step lane is not offered: commands travel on gRPC"
            )
        }
        None => eprintln!("crash-master: step lane off: commands travel on gRPC"),
    }
    if cluster.secret_required() {
        eprintln!("crash-master: workers must prove the shared secret");
    } else {
        eprintln!(
            "crash-master: warning: no shared secret (--secret-file or {SECRET_ENV}): any peer that reaches {} can attach as a worker and receive the scene",
            cluster.local_addr()
        );
    }
    cluster.accept()?;
    eprintln!(
        "crash-master: {} workers attached, running '{}'",
        args.workers, input.name
    );
    let opts = RunOptions {
        margin_factor: args.margin_factor,
        cost: if args.estimated_costs {
            CostModel::Estimated
        } else {
            CostModel::Measured
        },
        checkpoint_every: args.checkpoint_every.unwrap_or(0),
        checkpoint_seconds: if args.checkpoint_seconds.is_finite() {
            args.checkpoint_seconds.max(0.0)
        } else {
            0.0
        },
        rejoin_seconds: if args.rejoin_timeout.is_finite() {
            args.rejoin_timeout.max(0.0)
        } else {
            0.0
        },
        // a fault a worker reports is replayed on another before it is believed
        confirm_faults: true,
        split: args.split,
        ..RunOptions::default()
    };
    let stats = match restart {
        None => run_remote(input, &mut cluster, &mut sink, &opts)?,
        Some(r) => {
            eprintln!(
                "crash-master: resuming from step {} (t = {:.6e} s)",
                r.master.clock.step, r.master.clock.time
            );
            resume_remote(input, r.master, &mut cluster, &mut sink, &opts)?
        }
    };
    eprintln!(
        "crash-master: done: {} steps to t = {:.6e} s in {:.2} s, {} migrations, final state hash {:016x}",
        stats.steps,
        stats.time,
        stats.wall_s,
        stats.migrations.len(),
        stats.final_hash
    );
    Ok(())
}
