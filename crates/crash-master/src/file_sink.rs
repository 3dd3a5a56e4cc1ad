//! A sink that writes the run directory with crash-io: energy.csv, contacts.csv, frames
//! (VTU + PVD)
//! and summary.json (with the per-stage timing of the master).

use crate::error::MasterError;
use crate::sink::{Sink, SinkError};
use crate::stats::RunStats;
use crash_core::contact::PairStats;
use crash_core::{Body, EnergyTotals};
use crash_io::{
    hash_hex, write_summary, ContactHistory, ContactRow, EnergyHistory, Frame, Indicators,
    SeriesWriter, Summary, CONTACTS_CSV, ENERGY_CSV, SUMMARY_JSON,
};
use std::path::{Path, PathBuf};

#[derive(Debug)]
pub struct FileSink {
    dir: PathBuf,
    energy: EnergyHistory,
    contacts: ContactHistory,
    series: SeriesWriter,
    indicators: Indicators,
    summary: Summary,
}

impl FileSink {
    /// Create the run directory's files. `bodies` give the counts for the summary.
    pub fn create(
        dir: &Path,
        scene: &str,
        scene_hash: u64,
        bodies: &[Body],
    ) -> Result<Self, SinkError> {
        std::fs::create_dir_all(dir)?;
        let summary = Summary {
            scene: scene.to_string(),
            scene_hash: hash_hex(scene_hash),
            bodies: bodies.len(),
            nodes: bodies.iter().map(Body::node_count).sum(),
            elements: bodies.iter().map(Body::element_count).sum(),
            ..Summary::default()
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            energy: EnergyHistory::create(dir.join(ENERGY_CSV))?,
            contacts: ContactHistory::create(dir.join(CONTACTS_CSV))?,
            series: SeriesWriter::create(dir)?,
            indicators: Indicators::default(),
            summary,
        })
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

    fn frame(&mut self, step: u64, time: f64, bodies: &[Body]) -> Result<(), SinkError> {
        let refs: Vec<&Body> = bodies.iter().collect();
        self.series.write(&Frame::capture(time, step, &refs))?;
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
