//! A sink that writes the run directory with crash-io: energy.csv, contacts.csv, frames
//! (VTU + PVD)
//! and summary.json (with the per-stage timing of the master), and the restart file.

use crate::checkpoint::MasterCheckpoint;
use crate::error::MasterError;
use crate::input::RunSize;
use crate::sink::{Sink, SinkError};
use crate::stats::RunStats;
use crash_core::contact::PairStats;
use crash_core::EnergyTotals;
use crash_io::{
    hash_hex, write_summary, ContactHistory, ContactRow, EnergyHistory, FrameBody, Indicators,
    SeriesWriter, Summary, CONTACTS_CSV, ENERGY_CSV, SUMMARY_JSON,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Name of the restart file inside the run directory (one file, replaced atomically at
/// every checkpoint).
pub const RESTART_FILE: &str = "restart.ckp";

/// What a restart file holds: the master loop's state and the sink's own (the
/// summary's running indicators).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RestartFile {
    pub master: MasterCheckpoint,
    #[serde(with = "IndicatorsBits")]
    pub indicators: Indicators,
}

/// The same layout as `RestartFile`, borrowed (no copy of the bodies to write it).
#[derive(Serialize)]
struct RestartRef<'a> {
    master: &'a MasterCheckpoint,
    #[serde(with = "IndicatorsBits")]
    indicators: &'a Indicators,
}

/// `Indicators` as plain f64s: its own Deserialize reads JSON nulls (Option<f64>),
/// which a binary format cannot pair with the plain f64 its Serialize writes.
#[derive(Serialize, Deserialize)]
#[serde(remote = "Indicators")]
struct IndicatorsBits {
    final_balance_error: f64,
    peak_balance_error: f64,
    hourglass_internal_ratio: f64,
    contact_internal_ratio: f64,
    max_penetration_ratio: f64,
    min_contact_energy: f64,
    peak_internal: f64,
    peak_hourglass: f64,
    peak_contact: f64,
}

/// Read a restart file (errors name the file: missing, not a checkpoint, truncated,
/// corrupt, other version).
pub fn read_restart(path: &Path) -> Result<RestartFile, crash_io::IoError> {
    crash_io::read_checkpoint(path)
}

#[derive(Debug)]
pub struct FileSink {
    dir: PathBuf,
    energy: EnergyHistory,
    contacts: ContactHistory,
    series: SeriesWriter,
    indicators: Indicators,
    summary: Summary,
    /// Where checkpoints go (None: they are ignored).
    restart: Option<PathBuf>,
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
            series: SeriesWriter::create(dir)?,
            indicators: Indicators::default(),
            summary: Self::summary(scene, scene_hash, size),
            restart: None,
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
        let t = restart.master.clock.time;
        Ok(Self {
            dir: dir.to_path_buf(),
            energy: EnergyHistory::reopen(dir.join(ENERGY_CSV), t)?,
            contacts: ContactHistory::reopen(dir.join(CONTACTS_CSV), t)?,
            series: SeriesWriter::reopen(dir, t)?,
            indicators: restart.indicators,
            summary: Self::summary(scene, scene_hash, size),
            restart: None,
        })
    }

    /// Record the element kernels' instruction-set path in summary.json.
    pub fn with_simd_path(mut self, path: &str) -> Self {
        self.summary.simd_path = path.to_string();
        self
    }

    /// Write every checkpoint to `path` (atomically, replacing the previous one).
    pub fn with_checkpoints(mut self, path: PathBuf) -> Self {
        self.restart = Some(path);
        self
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
    fn energy(&mut self, _step: u64, time: f64, totals: &EnergyTotals) -> Result<(), SinkError> {
        self.indicators.observe_energy(totals);
        self.energy.write(time, totals)?;
        Ok(())
    }

    /// contacts.csv: one row per pair with pushed nodes, every step.
    fn contact_stats(
        &mut self,
        _step: u64,
        time: f64,
        stats: &[PairStats],
    ) -> Result<(), SinkError> {
        for s in stats.iter().filter(|s| s.active_nodes > 0) {
            self.indicators.observe_penetration(s.max_penetration_ratio);
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

    /// The restart file, after the rows up to the checkpoint are on disk (so a
    /// reopen after an interruption finds them all).
    fn checkpoint(&mut self, state: &MasterCheckpoint) -> Result<(), SinkError> {
        let Some(path) = &self.restart else {
            return Ok(());
        };
        self.energy.flush()?;
        self.contacts.flush()?;
        crash_io::write_checkpoint(
            path,
            &RestartRef {
                master: state,
                indicators: &self.indicators,
            },
        )?;
        Ok(())
    }

    fn frame_begin(&mut self, step: u64, time: f64) -> Result<(), SinkError> {
        self.series.begin_frame(time, step)?;
        Ok(())
    }

    fn frame_body(&mut self, body: &FrameBody) -> Result<(), SinkError> {
        self.series.frame_body(body)?;
        Ok(())
    }

    fn frame_end(&mut self) -> Result<(), SinkError> {
        self.series.end_frame()?;
        self.energy.flush()?;
        self.contacts.flush()?;
        Ok(())
    }

    fn finish(&mut self, stats: &RunStats, error: Option<&MasterError>) -> Result<(), SinkError> {
        self.energy.flush()?;
        self.contacts.flush()?;
        let s = &mut self.summary;
        s.steps = stats.steps;
        s.end_time = stats.time;
        s.dt_min = stats.dt_min;
        s.dt_max = stats.dt_max;
        s.wall_time_s = stats.wall_s;
        let cycles = (s.elements as f64 * stats.steps as f64).max(1.0);
        let st = &stats.stages;
        for (k, v) in [
            ("compute", st.compute_ns),
            ("barrier", st.barrier_ns),
            ("meim", st.meim_ns),
            ("migration", st.migration_ns),
            ("output", st.output_ns),
        ] {
            s.ns_per_element_cycle.insert(k.into(), v as f64 / cycles);
        }
        s.ns_per_element_cycle
            .insert("total".into(), stats.wall_s * 1e9 / cycles);
        s.max_energy_balance_error = stats.max_energy_error;
        s.indicators = self.indicators;
        s.warnings = self.indicators.warnings();
        s.final_state_hash = if error.is_none() {
            hash_hex(stats.final_hash)
        } else {
            String::new()
        };
        s.fault = error.map(|e| e.to_string());
        write_summary(self.dir.join(SUMMARY_JSON), s)?;
        Ok(())
    }
}
