//! Reading matsum.csv: energies per body over time (long format, one row per body per
//! output time), for the per-body energy plot.

use crate::error::{AtPath, IoError};
use std::path::Path;

pub const MATSUM_CSV: &str = "matsum.csv";
pub const MATSUM_HEADER: &str = "step,time_s,body,kinetic_J,internal_J,hourglass_J,damping_J";

/// One body's energies at one time [J].
#[derive(Debug, Clone, PartialEq)]
pub struct MatsumRow {
    pub step: u64,
    pub time: f64,
    /// Body name.
    pub body: String,
    pub kinetic: f64,
    pub internal: f64,
    pub hourglass: f64,
    pub damping: f64,
}

/// Split a CSV line at commas outside double quotes; quotes around a field are dropped
/// and a doubled quote inside one stands for a quote (RFC 4180), so a body name may
/// hold a comma.
fn split_fields(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// Read matsum.csv; every error names the file, the line and what was expected.
pub fn read_matsum_csv(path: impl AsRef<Path>) -> Result<Vec<MatsumRow>, IoError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).at(path)?;
    let mut lines = text.lines();
    if lines.next().map(str::trim) != Some(MATSUM_HEADER) {
        return Err(IoError::format(
            path,
            format!("line 1: header is not '{MATSUM_HEADER}'"),
        ));
    }
    let mut rows = Vec::new();
    for (i, l) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let line = i + 2;
        let f = split_fields(l.trim_end());
        if f.len() != 7 {
            return Err(IoError::format(
                path,
                format!(
                    "line {line}: {} columns, 7 expected ({MATSUM_HEADER})",
                    f.len()
                ),
            ));
        }
        let num = |k: usize| -> Result<f64, IoError> {
            f[k].trim().parse::<f64>().map_err(|e| {
                IoError::format(
                    path,
                    format!("line {line}, column {}: '{}': {e}", k + 1, f[k]),
                )
            })
        };
        let step = f[0].trim().parse::<u64>().map_err(|e| {
            IoError::format(
                path,
                format!("line {line}, column 1 (step): '{}': {e}", f[0]),
            )
        })?;
        rows.push(MatsumRow {
            step,
            time: num(1)?,
            body: f[2].trim().to_string(),
            kinetic: num(3)?,
            internal: num(4)?,
            hourglass: num(5)?,
            damping: num(6)?,
        });
    }
    Ok(rows)
}
