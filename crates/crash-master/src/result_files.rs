//! matsum.csv, rcforc.csv, nodout.csv and spcforc.csv of a run directory (crash-io
//! writes the rows): each exists when its interval is > 0, and goes back to a time with
//! energy.csv on a restart or a rollback.

use crate::input::ResultRequest;
use crate::sink::{ResultRows, SinkError};
use crash_io::matsum_read::{MATSUM_CSV, MATSUM_HEADER};
use crash_io::{
    IoError, ResultFile, NODOUT_CSV, NODOUT_HEADER, RCFORC_CSV, RCFORC_HEADER, SPCFORC_CSV,
    SPCFORC_HEADER,
};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const FILES: [(&str, &str); 4] = [
    (MATSUM_CSV, MATSUM_HEADER),
    (RCFORC_CSV, RCFORC_HEADER),
    (NODOUT_CSV, NODOUT_HEADER),
    (SPCFORC_CSV, SPCFORC_HEADER),
];

#[derive(Debug, Default)]
pub struct ResultFiles {
    dir: PathBuf,
    /// matsum, rcforc, nodout, spcforc (None: not asked for).
    files: [Option<ResultFile>; 4],
}

impl ResultFiles {
    /// The files `req` asks for: new, or (`from` Some(t)) reopened keeping the rows up
    /// to time t.
    pub fn open(dir: &Path, req: &ResultRequest, from: Option<f64>) -> Result<Self, IoError> {
        let on = [req.matsum, req.rcforc, req.nodout, req.spcforc].map(|i| i > 0.0);
        let mut files: [Option<ResultFile>; 4] = Default::default();
        for (k, (name, header)) in FILES.iter().enumerate() {
            if on[k] {
                let p = dir.join(name);
                files[k] = Some(match from {
                    Some(t) => ResultFile::reopen(p, header, t)?,
                    None => ResultFile::create(p, header)?,
                });
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            files,
        })
    }

    /// Back to time t: every open file keeps its rows up to t.
    pub fn rollback(&mut self, t: f64) -> Result<(), IoError> {
        for (k, f) in self.files.iter_mut().enumerate() {
            if let Some(f) = f {
                f.flush()?;
                *f = ResultFile::reopen(self.dir.join(FILES[k].0), FILES[k].1, t)?;
            }
        }
        Ok(())
    }

    pub fn flush(&mut self) -> Result<(), IoError> {
        self.files.iter_mut().flatten().try_for_each(|f| f.flush())
    }

    /// The rows due now; bodies named by `names` (else `#id`).
    pub fn write(
        &mut self,
        step: u64,
        time: f64,
        rows: &ResultRows<'_>,
        names: &BTreeMap<u32, String>,
    ) -> Result<(), SinkError> {
        let name = |id: u32| names.get(&id).cloned().unwrap_or_else(|| format!("#{id}"));
        let [matsum, rcforc, nodout, spcforc] = &mut self.files;
        if let (Some(f), Some(reports)) = (matsum.as_mut(), rows.matsum) {
            for r in reports {
                f.matsum(step, time, &name(r.id), &r.energy)?;
            }
        }
        if let (Some(f), Some(pairs)) = (rcforc.as_mut(), rows.rcforc) {
            for s in pairs.iter().filter(|s| s.active_nodes > 0) {
                f.rcforc(step, time, &name(s.a), &name(s.b), s.force_on_a)?;
            }
        }
        if let (Some(f), Some(nodes)) = (nodout.as_mut(), rows.nodout) {
            for (tag, p) in nodes {
                f.nodout(step, time, &name(p.body), *tag, [p.u, p.v, p.a])?;
            }
        }
        if let (Some(f), Some(reports)) = (spcforc.as_mut(), rows.spcforc) {
            for r in reports {
                if let Some(re) = &r.reaction {
                    f.spcforc(step, time, &name(r.id), re)?;
                }
            }
        }
        Ok(())
    }
}
