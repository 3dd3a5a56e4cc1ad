//! Time histories as CSV: energy.csv (scene energy terms) and contacts.csv (per body
//! pair). Floats use Rust's shortest round-trip form (`{:e}`), so byte-identical files
//! mean bit-identical values. Rows are buffered; call `flush` at frames. Reopening for a
//! restart keeps the rows up to the restart time.

use crate::atomic::write_atomic;
use crate::error::{AtPath, IoError};
use crash_core::contact::PairStats;
use crash_core::EnergyTotals;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub const ENERGY_CSV: &str = "energy.csv";
pub const CONTACTS_CSV: &str = "contacts.csv";

pub const ENERGY_HEADER: &str =
    "time,kinetic,internal,hourglass,contact,damping,external_work,balance_error";
pub const CONTACTS_HEADER: &str = "time,body_a,body_b,normal_force,max_penetration";

/// Energy terms of the whole scene at one time [J]; balance_error is relative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyRow {
    pub time: f64,
    pub energy: EnergyTotals,
}

/// Contact between two bodies at one time: total normal force [N] and the largest
/// penetration [m].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactRow {
    pub time: f64,
    pub a: u32,
    pub b: u32,
    pub force: f64,
    pub penetration: f64,
}

impl ContactRow {
    /// The row of one contact pair as the contact stage reports it
    /// (`Group::contact_stats`).
    pub fn from_stats(time: f64, s: &PairStats) -> Self {
        Self {
            time,
            a: s.a,
            b: s.b,
            force: s.normal_force,
            penetration: s.max_penetration,
        }
    }
}

#[derive(Debug)]
pub(crate) struct CsvFile {
    path: PathBuf,
    pub(crate) w: BufWriter<File>,
}

/// Fields of a CSV line: commas inside double quotes do not count (RFC 4180).
fn field_count(line: &str) -> usize {
    let mut quoted = false;
    1 + line
        .chars()
        .filter(|&c| {
            if c == '"' {
                quoted = !quoted;
            }
            c == ',' && !quoted
        })
        .count()
}

/// The field at `col` of a line without quoted fields before it.
fn field(line: &str, col: usize) -> Option<&str> {
    line.split(',').nth(col)
}

impl CsvFile {
    pub(crate) fn create(path: &Path, header: &str) -> Result<Self, IoError> {
        write_atomic(path, |w| writeln!(w, "{header}"))?;
        Self::append(path)
    }

    fn append(path: &Path) -> Result<Self, IoError> {
        let f = OpenOptions::new().append(true).open(path).at(path)?;
        Ok(Self {
            path: path.to_path_buf(),
            w: BufWriter::with_capacity(1 << 16, f),
        })
    }

    /// Keep the header and the complete rows with time <= `up_to_time`; a torn last
    /// line (interrupted write) is dropped.
    fn reopen(path: &Path, header: &str, up_to_time: f64) -> Result<Self, IoError> {
        Self::reopen_at(path, header, 0, up_to_time)
    }

    /// `reopen` for files whose time is column `time_col` (the columns before it are
    /// never quoted).
    pub(crate) fn reopen_at(
        path: &Path,
        header: &str,
        time_col: usize,
        up_to_time: f64,
    ) -> Result<Self, IoError> {
        if !path.exists() {
            return Self::create(path, header);
        }
        let text = std::fs::read_to_string(path).at(path)?;
        let mut lines = text.split_inclusive('\n');
        match lines.next() {
            Some(h) if h.trim_end() == header => {}
            _ => return Err(IoError::format(path, format!("header is not '{header}'"))),
        }
        let ncol = header.split(',').count();
        let keep: Vec<&str> = lines
            .take_while(|l| {
                let complete = l.ends_with('\n') && field_count(l.trim_end()) == ncol;
                let t = field(l, time_col).and_then(|t| t.trim().parse::<f64>().ok());
                complete && t.is_some_and(|t| t <= up_to_time)
            })
            .collect();
        write_atomic(path, |w| {
            writeln!(w, "{header}")?;
            keep.iter().try_for_each(|l| w.write_all(l.as_bytes()))
        })?;
        Self::append(path)
    }

    pub(crate) fn flush(&mut self) -> Result<(), IoError> {
        self.w.flush().at(&self.path)
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }
}

/// energy.csv writer.
#[derive(Debug)]
pub struct EnergyHistory(CsvFile);

impl EnergyHistory {
    pub fn create(path: impl AsRef<Path>) -> Result<Self, IoError> {
        CsvFile::create(path.as_ref(), ENERGY_HEADER).map(Self)
    }

    pub fn reopen(path: impl AsRef<Path>, up_to_time: f64) -> Result<Self, IoError> {
        CsvFile::reopen(path.as_ref(), ENERGY_HEADER, up_to_time).map(Self)
    }

    pub fn write(&mut self, time: f64, e: &EnergyTotals) -> Result<(), IoError> {
        let f = &mut self.0;
        writeln!(
            f.w,
            "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            time,
            e.kinetic,
            e.internal,
            e.hourglass,
            e.contact,
            e.damping,
            e.external,
            e.balance_error
        )
        .at(&f.path)
    }

    pub fn flush(&mut self) -> Result<(), IoError> {
        self.0.flush()
    }
}

/// contacts.csv writer.
#[derive(Debug)]
pub struct ContactHistory(CsvFile);

impl ContactHistory {
    pub fn create(path: impl AsRef<Path>) -> Result<Self, IoError> {
        CsvFile::create(path.as_ref(), CONTACTS_HEADER).map(Self)
    }

    pub fn reopen(path: impl AsRef<Path>, up_to_time: f64) -> Result<Self, IoError> {
        CsvFile::reopen(path.as_ref(), CONTACTS_HEADER, up_to_time).map(Self)
    }

    pub fn write(&mut self, r: &ContactRow) -> Result<(), IoError> {
        let f = &mut self.0;
        writeln!(
            f.w,
            "{:e},{},{},{:e},{:e}",
            r.time, r.a, r.b, r.force, r.penetration
        )
        .at(&f.path)
    }

    pub fn flush(&mut self) -> Result<(), IoError> {
        self.0.flush()
    }
}

/// Parse the data rows of a CSV with the expected header into f64 columns.
fn read_rows(path: &Path, header: &str) -> Result<Vec<Vec<f64>>, IoError> {
    let text = std::fs::read_to_string(path).at(path)?;
    let mut lines = text.lines();
    if lines.next().map(str::trim) != Some(header) {
        return Err(IoError::format(path, format!("header is not '{header}'")));
    }
    let ncol = header.split(',').count();
    lines
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            let row = l
                .split(',')
                .map(|v| v.trim().parse::<f64>())
                .collect::<Result<Vec<f64>, _>>()
                .map_err(|e| IoError::format(path, format!("line {}: {e}", i + 2)))?;
            if row.len() != ncol {
                return Err(IoError::format(
                    path,
                    format!("line {}: {} columns, {ncol} expected", i + 2, row.len()),
                ));
            }
            Ok(row)
        })
        .collect()
}

pub fn read_energy_csv(path: impl AsRef<Path>) -> Result<Vec<EnergyRow>, IoError> {
    Ok(read_rows(path.as_ref(), ENERGY_HEADER)?
        .into_iter()
        .map(|r| EnergyRow {
            time: r[0],
            energy: EnergyTotals {
                kinetic: r[1],
                internal: r[2],
                hourglass: r[3],
                contact: r[4],
                damping: r[5],
                external: r[6],
                balance_error: r[7],
                run_error: 0.0, // not a column of energy.csv
            },
        })
        .collect())
}

pub fn read_contacts_csv(path: impl AsRef<Path>) -> Result<Vec<ContactRow>, IoError> {
    Ok(read_rows(path.as_ref(), CONTACTS_HEADER)?
        .into_iter()
        .map(|r| ContactRow {
            time: r[0],
            a: r[1] as u32,
            b: r[2] as u32,
            force: r[3],
            penetration: r[4],
        })
        .collect())
}
