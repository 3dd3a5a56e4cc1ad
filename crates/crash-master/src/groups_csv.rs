//! groups.csv: which bodies form each group, on which worker, how many elements and
//! how long the group's last step took, written when groups change and at output times.

use crate::sink::GroupRow;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

pub const GROUPS_CSV: &str = "groups.csv";
const HEADER: &str = "time_s,group,bodies,worker,elements,step_ns";

#[derive(Debug)]
pub struct GroupsCsv {
    out: BufWriter<File>,
}

/// A CSV field: quoted, quotes doubled (body names come from scene files).
fn quoted(s: &str) -> String {
    format!("\"{}\"", s.replace('"', "\"\""))
}

impl GroupsCsv {
    pub fn create(path: &Path) -> std::io::Result<Self> {
        let mut out = BufWriter::new(File::create(path)?);
        writeln!(out, "{HEADER}")?;
        Ok(Self { out })
    }

    /// Keep the rows up to time `t` (a resumed run writes the later ones again).
    pub fn reopen(path: &Path, t: f64) -> std::io::Result<Self> {
        let old = std::fs::read_to_string(path).unwrap_or_default();
        let mut out = BufWriter::new(File::create(path)?);
        writeln!(out, "{HEADER}")?;
        for line in old.lines().skip(1) {
            let time = line.split(',').next().and_then(|v| v.parse::<f64>().ok());
            if time.is_some_and(|time| time <= t * (1.0 + 1e-12)) {
                writeln!(out, "{line}")?;
            }
        }
        Ok(Self { out })
    }

    pub fn rows(&mut self, time: f64, rows: &[GroupRow]) -> std::io::Result<()> {
        for r in rows {
            writeln!(
                self.out,
                "{time:e},{},{},{},{},{}",
                r.group,
                quoted(&r.bodies.join(" ")),
                r.worker,
                r.elements,
                r.step_ns
            )?;
        }
        Ok(())
    }

    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}
