//! A sink that writes the run directory with crash-io: energy.csv, contacts.csv, frames
//! (VTU + PVD, written by a background thread: `BackgroundSeries`)
//! and summary.json (with the per-stage timing of the master), and the restart file.

use crate::checkpoint::MasterCheckpoint;
use crate::error::MasterError;
use crate::groups_csv::{GroupsCsv, GROUPS_CSV};
use crate::input::{ResultRequest, RunSize};
use crate::result_files::ResultFiles;
use crate::sink::{GroupRow, ResultRows, Sink, SinkError};
use crate::stats::RunStats;
use crash_core::contact::PairStats;
use crash_core::EnergyTotals;
use crash_io::summary::{penetration_message, PENETRATION_LIMIT};
use crash_io::{
    hash_hex, write_summary, BackgroundSeries, CheckpointKey, ContactHistory, ContactRow,
    EnergyHistory, FrameBody, Indicators, SeriesWriter, Summary, VtuFormat, Warning, WarningKind,
    CONTACTS_CSV, ENERGY_CSV, SUMMARY_JSON,
};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Name of the restart file inside the run directory (one file, replaced atomically at
/// every checkpoint).
pub const RESTART_FILE: &str = "restart.ckp";

/// What a restart file holds: the master loop's state and the sink's own (the
/// summary's running indicators and the warnings raised so far).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RestartFile {
    pub master: MasterCheckpoint,
    #[serde(with = "IndicatorsBits")]
    pub indicators: Indicators,
    #[serde(with = "warnings_bits")]
    pub warnings: Vec<Warning>,
}

/// The same layout as `RestartFile`, borrowed (no copy of the bodies to write it).
#[derive(Serialize)]
struct RestartRef<'a> {
    master: &'a MasterCheckpoint,
    #[serde(with = "IndicatorsBits")]
    indicators: &'a Indicators,
    #[serde(with = "warnings_bits")]
    warnings: &'a Vec<Warning>,
}

/// `Indicators` as plain f64s: its own Deserialize reads JSON nulls (Option<f64>),
/// which a binary format cannot pair with the plain f64 its Serialize writes.
#[derive(Serialize, Deserialize)]
#[serde(remote = "Indicators")]
struct IndicatorsBits {
    energy_limit: f64,
    energy_balance_error: f64,
    final_balance_error: f64,
    hourglass_internal_ratio: f64,
    contact_generated_ratio: f64,
    max_penetration_ratio: f64,
    contact_energy_j: f64,
    min_contact_energy_j: f64,
    contact_flow_j: f64,
    peak_internal_j: f64,
    peak_hourglass_j: f64,
}

/// Warnings in a checkpoint: the JSON form as one string (its floats read back with
/// nulls as NaN, which the binary format could not pair).
mod warnings_bits {
    use crash_io::Warning;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(w: &Vec<Warning>, s: S) -> Result<S::Ok, S::Error> {
        let text = serde_json::to_string(w).map_err(serde::ser::Error::custom)?;
        s.serialize_str(&text)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Warning>, D::Error> {
        let text = String::deserialize(d)?;
        serde_json::from_str(&text).map_err(serde::de::Error::custom)
    }
}

/// The frame format a scene's `[outputs]` asks for (`precision`, `compression`).
pub fn frame_format(o: &crash_scene::outputs::Outputs) -> VtuFormat {
    VtuFormat {
        precision: if o.frames_f32 {
            crash_io::Precision::F32
        } else {
            crash_io::Precision::F64
        },
        compress: !o.frames_uncompressed,
    }
}

/// Read a restart file (errors name the file: missing, not a checkpoint, truncated,
/// corrupt, other version, keyed).
pub fn read_restart(path: &Path) -> Result<RestartFile, crash_io::IoError> {
    crash_io::read_checkpoint(path)
}

/// Read a restart file; with `key` (a shared secret is set), only a keyed one whose
/// MAC holds (an edited file is refused, naming it).
pub fn read_restart_keyed(
    path: &Path,
    key: Option<&CheckpointKey>,
) -> Result<RestartFile, crash_io::IoError> {
    crash_io::read_checkpoint_keyed(path, key)
}

#[derive(Debug)]
pub struct FileSink {
    dir: PathBuf,
    energy: EnergyHistory,
    contacts: ContactHistory,
    groups: GroupsCsv,
    /// matsum.csv, rcforc.csv, nodout.csv, spcforc.csv (`with_results`).
    results: ResultFiles,
    /// The checkpoint time a reopened directory continues from.
    resumed_at: Option<f64>,
    series: BackgroundSeries,
    /// Time spent handing frames to the writer thread on the caller's (the step
    /// loop's) thread [ns]; waits when the writer lags and drains at checkpoints
    /// included.
    handover_ns: u64,
    /// Time spent at the end waiting for the writer to finish the last frames [ns].
    drain_ns: u64,
    indicators: Indicators,
    /// Warnings raised so far (each once), and those not yet taken by `take_fresh`.
    warnings: Vec<Warning>,
    fresh: Vec<Warning>,
    /// Print each warning on stderr as it is raised.
    echo: bool,
    /// Body names by id (warnings name bodies).
    names: BTreeMap<u32, String>,
    summary: Summary,
    /// Where checkpoints go (None: they are ignored).
    restart: Option<PathBuf>,
    /// Their MAC key (a shared secret is set).
    key: Option<CheckpointKey>,
    /// What a rollback returns to: the indicators and warnings at the last checkpoint
    /// kept in memory.
    mark: Option<(Indicators, Vec<Warning>)>,
}

impl FileSink {
    /// Create the run directory's files. `size` gives the counts for the summary.
    pub fn create(
        dir: &Path,
        scene: &str,
        scene_hash: u64,
        size: RunSize,
    ) -> Result<Self, SinkError> {
        std::fs::create_dir_all(dir)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            energy: EnergyHistory::create(dir.join(ENERGY_CSV))?,
            contacts: ContactHistory::create(dir.join(CONTACTS_CSV))?,
            groups: GroupsCsv::create(&dir.join(GROUPS_CSV))?,
            results: ResultFiles::default(),
            resumed_at: None,
            series: BackgroundSeries::start(SeriesWriter::create(dir)?)?,
            handover_ns: 0,
            drain_ns: 0,
            indicators: Indicators::default(),
            warnings: Vec::new(),
            fresh: Vec::new(),
            echo: false,
            names: BTreeMap::new(),
            summary: Self::summary(scene, scene_hash, size),
            restart: None,
            key: None,
            mark: None,
        })
    }

    /// Continue the run directory of a restarted run: energy.csv and contacts.csv keep
    /// their rows up to the checkpoint's time, frames.pvd its frames up to that time
    /// (later ones are removed), and new rows and frames follow.
    pub fn reopen(
        dir: &Path,
        scene: &str,
        scene_hash: u64,
        size: RunSize,
        restart: &RestartFile,
    ) -> Result<Self, SinkError> {
        let m = &restart.master;
        let t = m.clock.time;
        // a frame at the checkpoint's time that the schedule did not ask for is the
        // last frame of a run stopped by a signal: dropped, so the restarted series
        // is the uninterrupted one
        let frames_until = if m.last_frame_step == Some(m.clock.step) || t <= 0.0 {
            t
        } else {
            f64::from_bits(t.to_bits() - 1)
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            energy: EnergyHistory::reopen(dir.join(ENERGY_CSV), t)?,
            contacts: ContactHistory::reopen(dir.join(CONTACTS_CSV), t)?,
            groups: GroupsCsv::reopen(&dir.join(GROUPS_CSV), t)?,
            results: ResultFiles::default(),
            resumed_at: Some(t),
            series: BackgroundSeries::start(SeriesWriter::reopen(dir, frames_until)?)?,
            handover_ns: 0,
            drain_ns: 0,
            indicators: restart.indicators,
            warnings: restart.warnings.clone(),
            fresh: Vec::new(),
            echo: false,
            names: BTreeMap::new(),
            summary: Self::summary(scene, scene_hash, size),
            restart: None,
            key: None,
            mark: None,
        })
    }

    /// How frames are stored (the scene's `[outputs] precision`; zlib by default).
    pub fn with_frame_format(mut self, format: VtuFormat) -> Self {
        self.series.set_format(format);
        self
    }

    /// Notes for the log (not warnings: nothing about the results), each once: the
    /// frame writer lagging behind the run.
    pub fn take_notes(&mut self) -> Vec<String> {
        self.series.take_stall_note().into_iter().collect()
    }

    /// Write the result files `req` asks for (a reopened directory keeps their rows up
    /// to the checkpoint).
    pub fn with_results(mut self, req: &ResultRequest) -> Result<Self, SinkError> {
        self.results = ResultFiles::open(&self.dir, req, self.resumed_at)?;
        Ok(self)
    }

    /// Record the element kernels' instruction-set path in summary.json.
    pub fn with_simd_path(mut self, path: &str) -> Self {
        self.summary.simd_path = path.to_string();
        self
    }

    /// Key every checkpoint with this MAC key (from the shared secret).
    pub fn with_checkpoint_key(mut self, key: Option<CheckpointKey>) -> Self {
        self.key = key;
        self
    }

    /// Write every checkpoint to `path` (atomically, replacing the previous one).
    pub fn with_checkpoints(mut self, path: PathBuf) -> Self {
        self.restart = Some(path);
        self
    }

    /// Judge the energy balance against this limit (the scene's `energy_limit`; the
    /// one limit of the warning and of the exit code).
    pub fn with_energy_limit(mut self, limit: f64) -> Self {
        self.indicators.energy_limit = limit;
        self
    }

    /// Name bodies in warnings.
    pub fn with_body_names(mut self, names: impl IntoIterator<Item = (u32, String)>) -> Self {
        self.names = names.into_iter().collect();
        self
    }

    /// Print every warning on stderr once, as it is raised.
    pub fn with_echo(mut self, echo: bool) -> Self {
        self.echo = echo;
        self
    }

    /// Warnings raised since the last call (each warning is handed out once).
    pub fn take_fresh(&mut self) -> Vec<Warning> {
        std::mem::take(&mut self.fresh)
    }

    /// Every warning raised so far.
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    fn name(&self, id: u32) -> String {
        self.names
            .get(&id)
            .cloned()
            .unwrap_or_else(|| format!("#{id}"))
    }

    fn raise(
        &mut self,
        kind: WarningKind,
        step: u64,
        time: f64,
        bodies: Vec<String>,
        message: String,
    ) {
        if self
            .warnings
            .iter()
            .any(|w| w.kind == kind && w.bodies == bodies)
        {
            return;
        }
        let w = Warning {
            kind,
            step,
            time_s: time,
            bodies,
            message,
            doubtful: true,
        };
        if self.echo {
            eprintln!("crash: warning: {w}");
        }
        self.warnings.push(w.clone());
        self.fresh.push(w);
    }

    fn summary(scene: &str, scene_hash: u64, size: RunSize) -> Summary {
        Summary {
            scene: scene.to_string(),
            scene_hash: hash_hex(scene_hash),
            bodies: size.bodies,
            nodes: size.nodes,
            elements: size.elements,
            ..Summary::default()
        }
    }
}

impl Sink for FileSink {
    fn energy(&mut self, step: u64, time: f64, totals: &EnergyTotals) -> Result<(), SinkError> {
        self.indicators.observe_energy(totals);
        for (kind, message) in self.indicators.exceeded() {
            self.raise(kind, step, time, Vec::new(), message);
        }
        self.energy.write(time, totals)?;
        Ok(())
    }

    /// contacts.csv: one row per pair with pushed nodes, every step.
    fn contact_stats(
        &mut self,
        step: u64,
        time: f64,
        stats: &[PairStats],
    ) -> Result<(), SinkError> {
        for s in stats.iter().filter(|s| s.active_nodes > 0) {
            self.indicators.observe_penetration(s.max_penetration_ratio);
            if s.max_penetration_ratio > PENETRATION_LIMIT {
                let bodies = vec![self.name(s.a), self.name(s.b)];
                let message = penetration_message(s.max_penetration_ratio);
                self.raise(WarningKind::Penetration, step, time, bodies, message);
            }
            self.contacts.write(&ContactRow {
                time,
                a: s.a,
                b: s.b,
                force: s.normal_force,
                penetration: s.max_penetration,
            })?;
        }
        Ok(())
    }

    fn results(&mut self, step: u64, time: f64, rows: &ResultRows<'_>) -> Result<(), SinkError> {
        self.results.write(step, time, rows, &self.names)
    }

    /// The restart file, after the rows up to the checkpoint are on disk (so a
    /// reopen after an interruption finds them all).
    fn checkpoint(&mut self, state: &MasterCheckpoint) -> Result<(), SinkError> {
        let Some(path) = &self.restart else {
            return Ok(());
        };
        // the restart promises the frames up to its time: wait for the writer
        let t = Instant::now();
        self.series.flush()?;
        self.handover_ns += t.elapsed().as_nanos() as u64;
        self.energy.flush()?;
        self.contacts.flush()?;
        self.groups.flush()?;
        self.results.flush()?;
        crash_io::write_checkpoint_keyed(
            path,
            &RestartRef {
                master: state,
                indicators: &self.indicators,
                warnings: &self.warnings,
            },
            self.key.as_ref(),
        )?;
        Ok(())
    }

    fn groups(&mut self, _step: u64, time: f64, rows: &[GroupRow]) -> Result<(), SinkError> {
        Ok(self.groups.rows(time, rows)?)
    }

    fn remember(&mut self, _state: &MasterCheckpoint) -> Result<(), SinkError> {
        self.mark = Some((self.indicators, self.warnings.clone()));
        Ok(())
    }

    /// Back to the checkpoint's time: energy.csv, contacts.csv and the result files keep
    /// their rows up to it (a torn last line is dropped), frames.pvd its frames up to it
    /// (later frame files removed), as a `--resume` does; the indicators and warnings
    /// return to what they were then.
    fn rollback(&mut self, state: &MasterCheckpoint) -> Result<(), SinkError> {
        let t = state.clock.time;
        self.energy.flush()?;
        self.contacts.flush()?;
        self.energy = EnergyHistory::reopen(self.dir.join(ENERGY_CSV), t)?;
        self.contacts = ContactHistory::reopen(self.dir.join(CONTACTS_CSV), t)?;
        self.groups.flush()?;
        self.groups = GroupsCsv::reopen(&self.dir.join(GROUPS_CSV), t)?;
        self.results.rollback(t)?;
        // the writer thread first writes what it holds, then starts again from the
        // frames up to the checkpoint
        self.series.finish()?;
        let format = self.series.format();
        self.series = BackgroundSeries::start(SeriesWriter::reopen(&self.dir, t)?)?;
        self.series.set_format(format);
        if let Some((indicators, warnings)) = &self.mark {
            self.indicators = *indicators;
            self.warnings = warnings.clone();
        }
        self.fresh.clear();
        Ok(())
    }

    /// The frame goes to the writer thread: these three return once it is queued.
    fn frame_begin(&mut self, step: u64, time: f64) -> Result<(), SinkError> {
        let t = Instant::now();
        let r = self.series.begin_frame(time, step);
        self.handover_ns += t.elapsed().as_nanos() as u64;
        Ok(r?)
    }

    fn frame_body(&mut self, body: FrameBody) -> Result<(), SinkError> {
        let t = Instant::now();
        let r = self.series.frame_body(body);
        self.handover_ns += t.elapsed().as_nanos() as u64;
        Ok(r?)
    }

    fn frame_end(&mut self) -> Result<(), SinkError> {
        let t = Instant::now();
        let r = self.series.end_frame();
        self.handover_ns += t.elapsed().as_nanos() as u64;
        r?;
        self.results.flush()?;
        if self.echo {
            for n in self.take_notes() {
                eprintln!("crash: note: {n}");
            }
        }
        self.energy.flush()?;
        self.contacts.flush()?;
        self.groups.flush()?;
        Ok(())
    }

    /// Drains the frame writer first: summary.json comes after the last frame. A
    /// writer error becomes the run's fault (when it has none) and is returned.
    fn finish(&mut self, stats: &RunStats, error: Option<&MasterError>) -> Result<(), SinkError> {
        let t = Instant::now();
        let frames = self.series.finish();
        self.drain_ns += t.elapsed().as_nanos() as u64;
        self.energy.flush()?;
        self.contacts.flush()?;
        self.groups.flush()?;
        self.results.flush()?;
        let s = &mut self.summary;
        s.steps = stats.steps;
        s.time_reached_s = stats.time;
        s.dt_min_s = stats.dt_min;
        s.dt_max_s = stats.dt_max;
        s.last_dt_s = stats.last_dt;
        s.wall_time_s = stats.wall_s;
        let cycles = (s.elements as f64 * stats.steps as f64).max(1.0);
        let st = &stats.stages;
        for (k, v) in [
            ("compute", st.compute_ns),
            ("barrier", st.barrier_ns),
            ("meim", st.meim_ns),
            ("migration", st.migration_ns),
            ("output", st.output_ns),
            ("output_handover", self.handover_ns),
            ("output_final_drain", self.drain_ns),
        ] {
            s.ns_per_element_cycle.insert(k.into(), v as f64 / cycles);
        }
        s.ns_per_element_cycle
            .insert("total".into(), stats.wall_s * 1e9 / cycles);
        let b = &stats.barrier;
        let [mc, wc, mg, ww] = b.parts_us();
        let steps = stats.steps.max(1) as f64;
        for (k, v) in [
            ("median", b.median_us()),
            ("master_codec", mc),
            ("worker_codec", wc),
            ("master_merge", mg),
            ("wire_wake", ww),
            ("master_work", st.meim_ns as f64 / steps / 1e3),
        ] {
            if v.is_finite() {
                s.barrier_us_per_step.insert(k.into(), v);
            }
        }
        s.cluster = crash_io::ClusterSummary {
            workers: stats.workers,
            migrations: stats.migrations.len(),
            group_changes: stats.group_changes,
            splits_kept: stats.splits_kept,
            splits: stats.splits,
            halo_direct_steps: stats.halo_direct_steps,
            halo_relayed_steps: stats.halo_relayed_steps,
            max_groups: stats.max_groups,
            final_groups: stats
                .final_groups
                .iter()
                .map(|(ids, w)| crash_io::GroupSummary {
                    group: ids.first().copied().unwrap_or(0),
                    bodies: ids.clone(),
                    worker: *w,
                })
                .collect(),
            compute_ns_per_worker: stats.worker_compute_ns.clone(),
        };
        s.energy_balance_error = stats.max_energy_error;
        s.energy_limit = self.indicators.energy_limit;
        s.indicators = self.indicators;
        s.warnings = self.warnings.clone();
        // a clean stop wrote its last frame: its hash is known
        let interrupted = matches!(error, Some(MasterError::Interrupted { .. }));
        s.final_state_hash = if (error.is_none() || interrupted) && frames.is_ok() {
            hash_hex(stats.final_hash)
        } else {
            String::new()
        };
        s.fault = match (error, &frames) {
            (Some(e), _) => Some(e.to_string()),
            (None, Err(e)) => Some(format!("output: {e}")),
            (None, Ok(())) => None,
        };
        s.interrupted = interrupted;
        write_summary(self.dir.join(SUMMARY_JSON), s)?;
        Ok(frames?)
    }
}
