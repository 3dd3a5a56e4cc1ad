//! The result files an analyst reads, named after the LS-DYNA ASCII files they stand
//! for: matsum.csv (energies per body), rcforc.csv (contact force vector per body
//! pair), nodout.csv (history nodes), spcforc.csv (support reactions per body). Long
//! format: one row per body (pair, node) per output time, `step,time_s` first, units
//! in the header, body names quoted when they hold a comma or a quote (RFC 4180).
//! Floats in Rust's shortest round-trip form, as energy.csv.

use crate::error::{AtPath, IoError};
use crate::history::CsvFile;
use crash_core::{BodyEnergy, Reaction, Vec3};
use std::borrow::Cow;
use std::io::Write;
use std::path::Path;

pub const RCFORC_CSV: &str = "rcforc.csv";
pub const NODOUT_CSV: &str = "nodout.csv";
pub const SPCFORC_CSV: &str = "spcforc.csv";

/// Force on body_a from body_b (body_b gets the opposite) and its magnitude.
pub const RCFORC_HEADER: &str = "step,time_s,body_a,body_b,fx_N,fy_N,fz_N,f_N";
pub const NODOUT_HEADER: &str =
    "step,time_s,body,node,ux_m,uy_m,uz_m,vx_m_s,vy_m_s,vz_m_s,ax_m_s2,ay_m_s2,az_m_s2";
/// Force and moment the supports exert on the body, and their resultant moment about
/// the origin O = (0, 0, 0).
pub const SPCFORC_HEADER: &str =
    "step,time_s,body,fx_N,fy_N,fz_N,mx_Nm,my_Nm,mz_Nm,mox_Nm,moy_Nm,moz_Nm";

/// A name as a CSV field: quoted (quotes doubled) when it holds a comma, a quote or a
/// line break.
pub fn csv_name(name: &str) -> Cow<'_, str> {
    if name.contains([',', '"', '\n', '\r']) {
        Cow::Owned(format!("\"{}\"", name.replace('"', "\"\"")))
    } else {
        Cow::Borrowed(name)
    }
}

/// One of the four files: created with its header, or reopened keeping its rows up to
/// a time (a restart, a rollback after a lost worker).
#[derive(Debug)]
pub struct ResultFile(CsvFile);

impl ResultFile {
    pub fn create(path: impl AsRef<Path>, header: &str) -> Result<Self, IoError> {
        CsvFile::create(path.as_ref(), header).map(Self)
    }

    pub fn reopen(path: impl AsRef<Path>, header: &str, up_to_time: f64) -> Result<Self, IoError> {
        CsvFile::reopen_at(path.as_ref(), header, 1, up_to_time).map(Self)
    }

    pub fn flush(&mut self) -> Result<(), IoError> {
        self.0.flush()
    }

    fn row(&mut self, args: std::fmt::Arguments<'_>) -> Result<(), IoError> {
        let f = &mut self.0;
        let path = f.path().to_path_buf();
        f.w.write_fmt(args).at(&path)
    }

    /// matsum.csv: one body's energies [J].
    pub fn matsum(
        &mut self,
        step: u64,
        time: f64,
        body: &str,
        e: &BodyEnergy,
    ) -> Result<(), IoError> {
        self.row(format_args!(
            "{step},{time:e},{},{:e},{:e},{:e},{:e}\n",
            csv_name(body),
            e.kinetic,
            e.internal,
            e.hourglass,
            e.damping
        ))
    }

    /// rcforc.csv: the force on `a` from `b` [N].
    pub fn rcforc(
        &mut self,
        step: u64,
        time: f64,
        a: &str,
        b: &str,
        f: Vec3,
    ) -> Result<(), IoError> {
        self.row(format_args!(
            "{step},{time:e},{},{},{:e},{:e},{:e},{:e}\n",
            csv_name(a),
            csv_name(b),
            f.x,
            f.y,
            f.z,
            f.norm()
        ))
    }

    /// nodout.csv: displacement, velocity, acceleration of one node.
    pub fn nodout(
        &mut self,
        step: u64,
        time: f64,
        body: &str,
        node: u64,
        [u, v, a]: [Vec3; 3],
    ) -> Result<(), IoError> {
        self.row(format_args!(
            "{step},{time:e},{},{node},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            csv_name(body),
            u.x,
            u.y,
            u.z,
            v.x,
            v.y,
            v.z,
            a.x,
            a.y,
            a.z
        ))
    }

    /// spcforc.csv: the supports' force [N], moment [N m] and resultant moment about
    /// the origin [N m] on one body.
    pub fn spcforc(
        &mut self,
        step: u64,
        time: f64,
        body: &str,
        r: &Reaction,
    ) -> Result<(), IoError> {
        let (f, m, o) = (r.force, r.moment, r.moment_origin);
        self.row(format_args!(
            "{step},{time:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            csv_name(body),
            f.x,
            f.y,
            f.z,
            m.x,
            m.y,
            m.z,
            o.x,
            o.y,
            o.z
        ))
    }
}
