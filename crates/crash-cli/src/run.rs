//! `crash run SCENE`: the whole run in this process, through the master loop with
//! in-process workers, writing the run directory with crash-io. With
//! `--checkpoint-every N` it keeps a restart file (OUT/restart.ckp); `--restart FILE`
//! continues a run from it in the same run directory.

use crate::progress::Progress;
use anyhow::Context;
use crash_core::contact::PairStats;
use crash_core::EnergyTotals;
use crash_io::FrameBody;
use crash_master::{
    read_restart_keyed, resume_with, run_with, FileSink, MasterCheckpoint, MasterError, RunInput,
    RunOptions, RunStats, Sink, SinkError, RESTART_FILE,
};
use crash_worker::InProcess;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The scene file (TOML) or an LS-DYNA keyword deck (.k, .key, .dyn).
    pub scene: PathBuf,
    /// Run directory [default: out/<scene name>].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// In-process workers, computing at once, each with its share of the groups (a
    /// group larger than its share split by elements, see --split): a shared-memory
    /// domain decomposition. Results are bit-identical for any number. [default: one
    /// worker of one thread per core (or per --threads), fewer for a scene of fewer than
    /// 1 024 elements a worker; one worker whose threads share the loops where the
    /// groups cannot spread over workers (docs/architecture-cluster.md, "Local mode")]
    #[arg(long)]
    pub workers: Option<usize>,
    /// Compute threads: with --workers, per worker, for its element and node loops
    /// [default: the cores shared out among the workers]; without it, in all (each
    /// becomes a worker of its own) [default: the cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Replace the scene's end time [s].
    #[arg(long)]
    pub end_time: Option<f64>,
    /// Replace the scene's output interval [s].
    #[arg(long)]
    pub output_interval: Option<f64>,
    /// Plain log lines instead of a progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Do not render pictures at the end.
    #[arg(long)]
    pub no_pictures: bool,
    /// Write a restart file (OUT/restart.ckp, replaced atomically each time) every N
    /// steps.
    #[arg(long, value_name = "N")]
    pub checkpoint_every: Option<u64>,
    /// Split a group over several workers by elements (with --workers >= 2): off,
    /// auto (a group above its fair share of the work), always. Same bits either way.
    #[arg(long, default_value = "auto", value_name = "WHEN")]
    pub split: crash_master::SplitMode,
    /// Continue the run from this restart file (same scene file; the run directory
    /// defaults to the file's directory and is continued: rows and frames after the
    /// checkpoint are replaced).
    #[arg(long, value_name = "FILE")]
    pub restart: Option<PathBuf>,
    /// Key restart files with the shared secret in this file (else CRASH_SECRET, if
    /// set): they are written with a MAC, and read only when it holds.
    #[arg(long, value_name = "PATH")]
    pub secret_file: Option<PathBuf>,
    /// Keyword decks: run contacts that have friction frictionless (a note says so)
    /// instead of refusing them.
    #[arg(long)]
    pub ignore_friction: bool,
    /// Exit 0 even when the run finished with warnings that make its results doubtful
    /// (they are still printed and listed in summary.json).
    #[arg(long)]
    pub allow_warnings: bool,
}

/// Exit code of a run that stopped on something else than physics: a worker lost, an
/// output file that could not be written.
pub const EXIT_FAILED: u8 = 1;
/// Exit code of a run stopped by a physical fault (a pass-through, tunnelling, an
/// instability, a collapsed element...): the results from that point on are wrong.
pub const EXIT_FAULT: u8 = 3;
/// Exit code of a run stopped by SIGINT (Ctrl-C) or SIGTERM after a complete step, with
/// its last frame, a restart file and summary.json marked interrupted:
/// `crash_master::stop::EXIT_INTERRUPTED` (130).
pub const EXIT_INTERRUPTED: u8 = crash_master::stop::EXIT_INTERRUPTED;
/// Exit code of a run that finished with a warning that makes its results doubtful
/// (energy balance beyond the scene's `energy_limit`, hourglass, contact energy,
/// penetration; docs/output.md), unless `--allow-warnings`.
pub const EXIT_WARNINGS: u8 = 4;

/// The file sink plus the progress display.
struct CliSink {
    files: FileSink,
    progress: Progress,
    last_time: f64,
}

impl CliSink {
    /// Print the warnings raised by the last call, once each.
    fn print_fresh(&mut self) {
        for w in self.files.take_fresh() {
            self.progress.message(&format!("crash: warning: {w}"));
        }
    }
}

impl Sink for CliSink {
    fn energy(&mut self, step: u64, time: f64, totals: &EnergyTotals) -> Result<(), SinkError> {
        let dt = time - self.last_time;
        self.last_time = time;
        self.progress.update(step, time, dt, totals.run_error);
        let r = self.files.energy(step, time, totals);
        self.print_fresh();
        r
    }

    fn contacts(&mut self, step: u64, time: f64, pairs: &[(u32, u32)]) -> Result<(), SinkError> {
        self.files.contacts(step, time, pairs)
    }

    fn contact_stats(
        &mut self,
        step: u64,
        time: f64,
        stats: &[PairStats],
    ) -> Result<(), SinkError> {
        let r = self.files.contact_stats(step, time, stats);
        self.print_fresh();
        r
    }

    fn groups(
        &mut self,
        step: u64,
        time: f64,
        rows: &[crash_master::GroupRow],
    ) -> Result<(), SinkError> {
        self.files.groups(step, time, rows)
    }

    fn results(
        &mut self,
        step: u64,
        time: f64,
        rows: &crash_master::ResultRows<'_>,
    ) -> Result<(), SinkError> {
        self.files.results(step, time, rows)
    }

    fn checkpoint(&mut self, state: &MasterCheckpoint) -> Result<(), SinkError> {
        // a stop's checkpoint is the first call after the signal
        self.progress.note_stop();
        self.files.checkpoint(state)
    }

    fn frame_begin(&mut self, step: u64, time: f64) -> Result<(), SinkError> {
        self.files.frame_begin(step, time)
    }

    fn frame_body(&mut self, body: FrameBody) -> Result<(), SinkError> {
        self.files.frame_body(body)
    }

    fn frame_end(&mut self) -> Result<(), SinkError> {
        let r = self.files.frame_end();
        for n in self.files.take_notes() {
            self.progress.message(&format!("crash: note: {n}"));
        }
        r
    }

    fn finish(&mut self, stats: &RunStats, error: Option<&MasterError>) -> Result<(), SinkError> {
        self.progress.finish();
        self.files.finish(stats, error)
    }
}

/// One-line description of a penetration found at t = 0.
pub fn penetration_message(built: &crash_scene::Built, p: &crash_scene::Penetration) -> String {
    let name = |id: u32| {
        built
            .bodies
            .iter()
            .find(|b| b.def.id == id)
            .map_or_else(|| format!("#{id}"), |b| format!("'{}'", b.def.name))
    };
    format!(
        "bodies {} and {} interpenetrate at t = 0: {} of {} is {:.3e} m inside {} ({} {} penetrate); move them apart",
        name(p.node_body),
        name(p.segment_body),
        p.at,
        name(p.node_body),
        p.depth,
        name(p.segment_body),
        p.nodes,
        p.at.counted()
    )
}

/// Read a restart file and check that it belongs to this scene and that the end time
/// lies after it (before the run directory is reopened).
fn load_restart(
    path: &Path,
    scene_hash: u64,
    end_time: f64,
    args: &RunArgs,
    key: Option<&crash_io::CheckpointKey>,
) -> anyhow::Result<crash_master::RestartFile> {
    let r = read_restart_keyed(path, key)
        .with_context(|| format!("cannot restart from {}", path.display()))?;
    if r.master.scene_hash != scene_hash {
        anyhow::bail!(
            "cannot restart from {}: it was written by a run of another scene (scene hash {:016x}; {} has {:016x}); restart with the scene file of the original run",
            path.display(),
            r.master.scene_hash,
            args.scene.display(),
            scene_hash
        );
    }
    r.master
        .check_continues(scene_hash, end_time)
        .with_context(|| format!("cannot restart from {}", path.display()))?;
    Ok(r)
}

pub fn run(args: &RunArgs) -> anyhow::Result<ExitCode> {
    let deck = crash_scene::keyword::DeckOptions {
        ignore_friction: args.ignore_friction,
    };
    let scene =
        crash_scene::load_input(&args.scene, &deck)?.with_overrides(crash_scene::Overrides {
            end_time: args.end_time,
            output_interval: args.output_interval,
        })?;
    let built = scene.build()?;
    for n in &built.notes {
        match n.strip_prefix("warning: ") {
            Some(w) => eprintln!("crash: warning: {w}"),
            None => eprintln!("crash: note: {n}"),
        }
    }
    if let Some(p) = crash_scene::check_initial_overlap(&built.bodies, &built.contact) {
        anyhow::bail!("{}", penetration_message(&built, &p));
    }
    let energy_limit = built.energy_limit;
    let frame_format = crash_master::frame_format(&built.outputs);
    let secret = crash_link::Secret::configured(args.secret_file.as_deref())?;
    let key = secret.as_ref().map(crash_link::Secret::checkpoint_key);
    let restart = match &args.restart {
        Some(path) => Some((
            path,
            load_restart(path, built.scene_hash, built.end_time, args, key.as_ref())?,
        )),
        None => None,
    };
    let out = match (&args.out, &restart) {
        (Some(o), _) => o.clone(),
        (None, Some((path, _))) => path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf),
        (None, None) => PathBuf::from("out").join(&built.name),
    };
    let names: Vec<(u32, String)> = built
        .bodies
        .iter()
        .map(|b| (b.def.id, b.def.name.clone()))
        .collect();
    let input = RunInput::from_built(built);
    // every in-process worker computes on a pool of its own (the last on this one)
    let cores = crash_core::threads::cores();
    let (workers, threads) = match args.workers {
        Some(w) => {
            let w = w.max(1);
            (w, crash_core::threads::per_worker(args.threads, w, cores))
        }
        None => {
            let splits = input.groups_may_split(args.split);
            let deformable = input.briefs.iter().filter(|b| !b.kinematic).count();
            let elements = input.size().elements;
            crash_core::threads::domains(args.threads, elements, cores, splits, deformable)
        }
    };
    if let Some(note) = crash_core::threads::oversubscription_of_workers(workers, threads, cores) {
        eprintln!("crash: note: {note}");
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start the thread pool")?;
    let files = match &restart {
        Some((_, r)) => FileSink::reopen(&out, &input.name, input.scene_hash, input.size(), r)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("cannot reopen the run directory {}", out.display()))?,
        None => FileSink::create(&out, &input.name, input.scene_hash, input.size())
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("cannot create the run directory {}", out.display()))?,
    };
    let simd = crash_core::element::simd::path_name();
    let files = files
        .with_checkpoints(out.join(RESTART_FILE))
        .with_checkpoint_key(key)
        .with_simd_path(simd)
        .with_energy_limit(energy_limit)
        .with_frame_format(frame_format)
        .with_body_names(names)
        .with_results(&input.results)
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("cannot create the result files in {}", out.display()))?;
    let start_time = restart.as_ref().map_or(0.0, |(_, r)| r.master.clock.time);
    let mut sink = CliSink {
        files,
        progress: Progress::new(input.config.end_time, start_time, args.quiet),
        last_time: start_time,
    };
    let opts = RunOptions {
        checkpoint_every: args.checkpoint_every.unwrap_or(0),
        split: args.split,
        ..RunOptions::default()
    };
    if let Some((path, r)) = &restart {
        eprintln!(
            "crash: restarting from {} at step {}, t = {:.6e} s",
            path.display(),
            r.master.clock.step,
            r.master.clock.time
        );
    }
    eprintln!(
        "crash: running '{}' ({} bodies, {} elements) to t = {:.4e} s with {workers} worker(s) x {threads} thread(s){}, {simd} element kernels, writing {}",
        input.name,
        input.briefs.len(),
        input.size().elements,
        input.config.end_time,
        if args.workers.is_none() && workers > 1 {
            " (a domain per thread; --workers 1 shares the loops instead)"
        } else {
            ""
        },
        out.display()
    );
    let mut workers =
        InProcess::many(workers, threads).context("cannot start the in-process workers")?;
    let result = pool.install(|| match restart {
        Some((_, r)) => resume_with(input, r.master, &mut workers, &mut sink, &opts),
        None => run_with(input, &mut workers, &mut sink, &opts),
    });
    let stats = match result {
        Ok(s) => s,
        Err(MasterError::Interrupted { step, time }) => {
            eprintln!(
                "crash: interrupted at step {step}, t = {time:.6e} s: the last frame, {} and summary.json (interrupted) are in {}; continue with: crash run {} --restart {} (and the same options)",
                RESTART_FILE,
                out.display(),
                args.scene.display(),
                out.join(RESTART_FILE).display()
            );
            return Ok(ExitCode::from(EXIT_INTERRUPTED));
        }
        Err(e) => {
            let (clock_step, clock_time) = sink_progress(&out);
            eprintln!("crash: run stopped: {e}");
            eprintln!(
                "crash: {clock_step} steps done, t = {clock_time:.4e} s reached; the frames written so far and summary.json are in {}",
                out.display()
            );
            let code = match e {
                MasterError::Fault(_) | MasterError::Margin { .. } => EXIT_FAULT,
                _ => EXIT_FAILED,
            };
            return Ok(ExitCode::from(code));
        }
    };
    eprintln!(
        "crash: done: {} steps, dt {:.3e}..{:.3e} s, {:.2} s wall, energy-balance error {:.3e} (limit {energy_limit:.3e}), final state hash {:016x}",
        stats.steps, stats.dt_min, stats.dt_max, stats.wall_s, stats.max_energy_error, stats.final_hash
    );
    if !args.no_pictures {
        match crash_io::render_run(&out) {
            Ok(files) => eprintln!(
                "crash: {} pictures in {}",
                files.len(),
                out.join("pictures").display()
            ),
            Err(e) => eprintln!("crash: warning: pictures failed: {e}"),
        }
    }
    let warnings = sink.files.warnings();
    let doubtful = warnings.iter().filter(|w| w.doubtful).count();
    if doubtful > 0 {
        eprintln!(
            "crash: the run finished with {doubtful} warning(s) that make its results doubtful (listed in {})",
            out.join(crash_io::SUMMARY_JSON).display()
        );
        if !args.allow_warnings {
            return Ok(ExitCode::from(EXIT_WARNINGS));
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Steps done and time reached, as summary.json records them (after a fault too).
fn sink_progress(out: &Path) -> (u64, f64) {
    crash_io::read_summary(out.join(crash_io::SUMMARY_JSON))
        .map_or((0, f64::NAN), |s| (s.steps, s.time_reached_s))
}
