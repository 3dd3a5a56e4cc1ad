//! Trust nothing a worker sends: its step reports, checkpoint states and frames are
//! checked against what can be true before the master uses them (issue 14,
//! docs/reliability.md). A worker caught reporting the impossible is dropped as a lost
//! one is (`LinkError::Implausible`, then the rollback of `recover`).
//!
//! A physical blow-up never arrives here as a report: the core stops a group whose
//! nodes, energies or stable time step turn non-finite with `Fault::NonFinite`
//! (crash-core `group.rs`, `forces.rs`, `integrate.rs`), which the worker sends as a
//! Fault reply. So every non-finite number in a report is a worker's lie or defect.

use super::Master;
use crate::error::MasterError;
use crash_core::contact::{KinLoad, PairStats};
use crash_core::{BodyEnergy, BodyReport, BodyState, Fault, Vec3};
use crash_io::FrameBody;
use crash_link::{escape_peer, LinkError, StepReport, WorkerLink};

fn finite3(v: &Vec3) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

/// A pair's contact figures are finite.
pub(super) fn stats_finite(c: &PairStats) -> bool {
    c.max_penetration.is_finite()
        && c.max_penetration_ratio.is_finite()
        && c.normal_force.is_finite()
        && finite3(&c.force_on_a)
}

fn energy_ok(e: &BodyEnergy) -> Result<(), String> {
    let all = [
        ("kinetic", e.kinetic),
        ("internal", e.internal),
        ("hourglass", e.hourglass),
        ("contact", e.contact),
        ("damping", e.damping),
        ("external", e.external),
    ];
    if let Some((name, v)) = all.iter().find(|(_, v)| !v.is_finite()) {
        return Err(format!("{name} energy {v}"));
    }
    if e.kinetic < 0.0 {
        return Err(format!("negative kinetic energy {:e}", e.kinetic));
    }
    Ok(())
}

/// One body's report, against its node and element counts.
fn report_ok(r: &BodyReport, elements: usize) -> Result<(), String> {
    if plausible(r, elements) {
        return Ok(());
    }
    report_detail(r, elements)
}

/// The checks of `report_detail` without early exits or messages: true only when
/// every one passes. The master runs this once per body per step (10 000 bodies: a
/// fifth of its work with the detailed form); a false here may still be a good report
/// (a sum of finite numbers can overflow), which `report_detail` then clears.
fn plausible(r: &BodyReport, elements: usize) -> bool {
    let e = &r.energy;
    // x * 0 is 0 for every finite x and NaN otherwise
    let finite = (e.kinetic + e.internal + e.hourglass + e.contact + e.damping + e.external) * 0.0
        + (r.lo.x + r.lo.y + r.lo.z + r.hi.x + r.hi.y + r.hi.z) * 0.0
        + (r.max_move + r.hot_density) * 0.0;
    let limit = elements.max(1);
    (finite == 0.0)
        & (e.kinetic >= 0.0)
        & (r.stable_dt > 0.0)
        & (r.lo.x <= r.hi.x)
        & (r.lo.y <= r.hi.y)
        & (r.lo.z <= r.hi.z)
        & (r.max_move >= 0.0)
        & (r.dt_element < limit)
        & (r.hot_element < limit)
}

/// `report_ok` with a message naming the first check that fails.
fn report_detail(r: &BodyReport, elements: usize) -> Result<(), String> {
    energy_ok(&r.energy)?;
    // +inf: a body that sets no limit (every DOF prescribed)
    if r.stable_dt.is_nan() || r.stable_dt <= 0.0 {
        return Err(format!("stable time step {:e}", r.stable_dt));
    }
    if !(finite3(&r.lo) && finite3(&r.hi)) {
        return Err("a non-finite bounding box".into());
    }
    if r.lo.x > r.hi.x || r.lo.y > r.hi.y || r.lo.z > r.hi.z {
        return Err(format!(
            "a bounding box inside out (min {:?} above max {:?})",
            r.lo.as_slice(),
            r.hi.as_slice()
        ));
    }
    if !(r.max_move.is_finite() && r.max_move >= 0.0) {
        return Err(format!("largest nodal move {:e}", r.max_move));
    }
    if !r.hot_density.is_finite() {
        return Err(format!("energy density {}", r.hot_density));
    }
    let limit = elements.max(1);
    if r.dt_element >= limit || r.hot_element >= limit {
        return Err(format!(
            "element {} of a body of {elements} elements",
            r.dt_element.max(r.hot_element)
        ));
    }
    Ok(())
}

/// A state: node and element counts of the definition, finite nodal values.
fn state_ok(s: &BodyState, nodes: usize, elements: usize) -> Result<(), String> {
    if s.x.len() != nodes || s.v.len() != nodes || s.w.len() != nodes {
        return Err(format!(
            "a state of {} positions, {} velocities, {} rotations for a body of {nodes} nodes",
            s.x.len(),
            s.v.len(),
            s.w.len()
        ));
    }
    if s.shell.len() != elements {
        return Err(format!(
            "a state of {} elements for a body of {elements}",
            s.shell.len()
        ));
    }
    if !s.x.iter().chain(&s.v).chain(&s.w).all(finite3) {
        return Err("a non-finite nodal value".into());
    }
    energy_ok(&s.energy)
}

/// A frame body: counts of the definition, finite nodal values, connectivity in range.
fn frame_ok(b: &FrameBody, nodes: usize, elements: usize) -> Result<(), String> {
    let n = [b.x.len(), b.v.len(), b.w.len()];
    if n.iter().any(|&k| k != nodes) {
        return Err(format!(
            "a frame of {n:?} nodal values for a body of {nodes} nodes"
        ));
    }
    // a deferred capture never crossed the wire (`pending` is not sent): an in-process
    // worker's, whose initial positions and connectivity are the body's own
    if b.pending.is_none() {
        if b.x0.len() != nodes {
            return Err(format!(
                "a frame of {} initial positions for a body of {nodes} nodes",
                b.x0.len()
            ));
        }
        if b.tris.len() + b.quads.len() != elements {
            return Err(format!(
                "a frame of {} elements for a body of {elements}",
                b.tris.len() + b.quads.len()
            ));
        }
        let conn = b.tris.iter().flatten().chain(b.quads.iter().flatten());
        if conn.into_iter().any(|&i| i as usize >= nodes) {
            return Err("an element referring to a node beyond the body's".into());
        }
    }
    if !b.x.iter().chain(&b.v).chain(&b.w).all(finite3) {
        return Err("a non-finite nodal value".into());
    }
    Ok(())
}

impl<L: WorkerLink> Master<'_, L> {
    /// Drop worker `w` for reporting `what` (recorded as lost: the run rolls back to
    /// its checkpoint on the others).
    pub(super) fn implausible(&mut self, w: usize, what: &str) -> MasterError {
        let e = LinkError::Implausible(escape_peer(what));
        self.lost.push((w, e.clone()));
        self.worker_error(w, e)
    }

    /// Worker `w`'s step report: each body it holds exactly once and nothing else,
    /// every number possible.
    /// Marks `seen` for each body reported (cleared by the gather, once per step);
    /// `held` is how many bodies `w` holds (`held_counts`).
    pub(super) fn check_report(
        &mut self,
        w: usize,
        held: usize,
        rep: &StepReport,
    ) -> Result<(), String> {
        for r in &rep.bodies {
            let i = match self.index(r.id) {
                Some(i) if self.worker_of[i] == Some(w) => i,
                _ => return Err(format!("a report of body {}, which it does not hold", r.id)),
            };
            if std::mem::replace(&mut self.seen[i], true) {
                return Err(format!("body {} twice", r.id));
            }
            report_ok(r, self.info[i].elements).map_err(|e| format!("body {}: {e}", r.id))?;
        }
        if rep.bodies.len() != held {
            return Err(format!(
                "{} body reports for the {held} bodies it holds",
                rep.bodies.len()
            ));
        }
        for c in &rep.contacts {
            let own = |id: u32| self.index(id).is_some_and(|i| self.worker_of[i] == Some(w));
            // a kinematic body may be a read-only copy in one of its groups
            let near = |id: u32| own(id) || self.is_kinematic(id);
            let finite = stats_finite(c);
            let pair = (own(c.a) || own(c.b)) && near(c.a) && near(c.b) && c.a <= c.b;
            if !(pair && finite) {
                return Err(format!("contact statistics of the pair ({}, {})", c.a, c.b));
            }
            for (id, l) in [(c.a, &c.kin_a), (c.b, &c.kin_b)] {
                self.kin_load_ok(id, l).map_err(|e| {
                    format!(
                        "contact load of the pair ({}, {}) on body {id}: {e}",
                        c.a, c.b
                    )
                })?;
            }
        }
        Ok(())
    }

    /// A pair's load on a kinematic body: finite, on nodes it has (none on other bodies).
    fn kin_load_ok(&self, id: u32, l: &KinLoad) -> Result<(), String> {
        if l.is_empty() {
            return Ok(());
        }
        let Some(i) = self.index(id).filter(|&i| self.info[i].kinematic) else {
            return Err("a load recorded for a body that is not kinematic".into());
        };
        if !l.power.is_finite() || !l.by_program.iter().all(|(_, f)| finite3(f)) {
            return Err("a non-finite force or power".into());
        }
        let nodes = self.info[i].nodes;
        match l
            .nodes
            .iter()
            .find(|(n, f)| *n as usize >= nodes || !finite3(f))
        {
            Some((n, _)) => Err(format!("node {n} (of {nodes}) or its force")),
            None => Ok(()),
        }
    }

    /// A fault from worker `w`: its group and the bodies it names are the worker's own
    /// (a made-up fault about bodies it holds cannot be told from a real one).
    pub(super) fn check_fault(&self, w: usize, group_first: u32, f: &Fault) -> Result<(), String> {
        let (body, other) = match f {
            Fault::NonFinite { body, .. }
            | Fault::Collapsed { body, .. }
            | Fault::Inverted { body, .. }
            | Fault::EnergyRunaway { body, .. }
            | Fault::DtCollapse { body, .. }
            | Fault::Tunnelling { body, .. } => (*body, None),
            Fault::PassThrough { body, other, .. } => (*body, Some(*other)),
        };
        // a worker holding parts of a split group may report its faults too
        let own = |id: u32| {
            self.index(id).is_some_and(|i| self.worker_of[i] == Some(w)) || self.holds_part(w, id)
        };
        // the bodies a fault names may include a read-only copy of a kinematic body
        let near = |id: u32| own(id) || self.is_kinematic(id);
        if !own(group_first) {
            return Err(format!(
                "a fault naming body {group_first}, which it does not hold"
            ));
        }
        for id in [Some(body), other].into_iter().flatten() {
            if !near(id) {
                return Err(format!("a fault naming body {id}, which it does not hold"));
            }
        }
        Ok(())
    }

    /// Checkpoint states from worker `w`: bodies it holds, counts of their definitions.
    pub(super) fn check_states(&self, w: usize, states: &[(u32, BodyState)]) -> Result<(), String> {
        for (id, s) in states {
            let i = match self.index(*id) {
                Some(i) if self.worker_of[i] == Some(w) => i,
                _ => return Err(format!("a state of body {id}, which it does not hold")),
            };
            let inf = &self.info[i];
            state_ok(s, inf.nodes, inf.elements).map_err(|e| format!("body {id}: {e}"))?;
        }
        Ok(())
    }

    /// Frame bodies from worker `w` (their ids were checked against the request).
    pub(super) fn check_frame(&self, bodies: &[FrameBody]) -> Result<(), String> {
        for b in bodies {
            let Some(i) = self.index(b.id) else {
                return Err(format!("a frame of body {}, which is not in the run", b.id));
            };
            let inf = &self.info[i];
            frame_ok(b, inf.nodes, inf.elements).map_err(|e| format!("body {}: {e}", b.id))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn good() -> BodyReport {
        BodyReport {
            stable_dt: 1e-6,
            lo: Vec3::new(-1.0, -1.0, -1.0),
            hi: Vec3::new(1.0, 1.0, 1.0),
            ..BodyReport::empty(3)
        }
    }

    #[test]
    fn a_possible_report_passes_and_each_impossible_value_is_named() {
        assert_eq!(report_ok(&good(), 10), Ok(()));
        let mut inf_dt = good();
        inf_dt.stable_dt = f64::INFINITY;
        assert_eq!(report_ok(&inf_dt, 10), Ok(()));
        type Spoil = Box<dyn Fn(&mut BodyReport)>;
        let cases: Vec<(Spoil, &str)> = vec![
            (Box::new(|r| r.energy.kinetic = -1.0), "negative kinetic"),
            (
                Box::new(|r| r.energy.internal = f64::NAN),
                "internal energy NaN",
            ),
            (
                Box::new(|r| r.energy.external = f64::INFINITY),
                "external energy inf",
            ),
            (Box::new(|r| r.stable_dt = 0.0), "stable time step"),
            (Box::new(|r| r.stable_dt = f64::NAN), "stable time step"),
            (Box::new(|r| r.lo.x = 2.0), "inside out"),
            (Box::new(|r| r.hi.z = f64::NAN), "non-finite bounding box"),
            (Box::new(|r| r.max_move = -1.0), "largest nodal move"),
            (
                Box::new(|r| r.hot_element = 10),
                "element 10 of a body of 10",
            ),
        ];
        for (spoil, what) in cases {
            let mut r = good();
            spoil(&mut r);
            let e = report_ok(&r, 10).expect_err(what);
            assert!(e.contains(what), "{e} should name {what}");
        }
    }

    /// The branch-free check and the detailed one agree on every value of every field
    /// (finite, zero, negative, huge, infinite, NaN), except that finite values whose
    /// sum overflows fail the fast check and are cleared by the detailed one.
    #[test]
    fn the_fast_check_accepts_exactly_what_the_detailed_one_accepts() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            1e-300,
            f64::MAX,
            -f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        type Field = fn(&mut BodyReport) -> &mut f64;
        let fields: [Field; 13] = [
            |r| &mut r.energy.kinetic,
            |r| &mut r.energy.internal,
            |r| &mut r.energy.hourglass,
            |r| &mut r.energy.contact,
            |r| &mut r.energy.damping,
            |r| &mut r.energy.external,
            |r| &mut r.stable_dt,
            |r| &mut r.lo.x,
            |r| &mut r.lo.z,
            |r| &mut r.hi.y,
            |r| &mut r.max_move,
            |r| &mut r.hot_density,
            |r| &mut r.hi.x,
        ];
        for (k, f) in fields.iter().enumerate() {
            for &v in &values {
                let mut r = good();
                *f(&mut r) = v;
                let detailed = report_detail(&r, 10).is_ok();
                let fast = plausible(&r, 10);
                assert!(
                    !fast || detailed,
                    "field {k} = {v}: fast accepts, detailed refuses"
                );
                if fast != detailed {
                    // only an overflow of the sum of finite values may differ
                    assert!(v.is_finite() && v.abs() == f64::MAX, "field {k} = {v}");
                }
                assert_eq!(report_ok(&r, 10).is_ok(), detailed, "field {k} = {v}");
            }
        }
        for (dt_el, hot_el, ok) in [(9, 9, true), (10, 0, false), (0, 10, false)] {
            let mut r = good();
            (r.dt_element, r.hot_element) = (dt_el, hot_el);
            assert_eq!(plausible(&r, 10), ok);
            assert_eq!(report_detail(&r, 10).is_ok(), ok);
        }
    }
}
