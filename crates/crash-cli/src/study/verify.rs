//! Running the verification suite: every case, element kind and level, and the checks
//! of `crash study` (finest level within tolerance, observed order of convergence).

use super::cases::{Case, CASES};
use super::ladder::{dt_orders, kind_name, orders, Level, Measurement};
use crash_core::shapes::ElementKind;

/// A level that could not be measured.
#[derive(Debug, Clone)]
pub struct Failure {
    pub level: Level,
    /// In the time-step ladder (else the mesh ladder).
    pub dt: bool,
    pub message: String,
}

/// The ladders of one case and element kind.
#[derive(Debug, Clone)]
pub struct LadderResult {
    pub case: &'static Case,
    pub kind: ElementKind,
    /// Mesh refinement at the default safety factor.
    pub mesh: Vec<Measurement>,
    /// Time-step refinement at one mesh (may be empty).
    pub dt: Vec<Measurement>,
    /// Levels that could not be measured, and why (the ladder goes on past them).
    pub failures: Vec<Failure>,
}

impl LadderResult {
    pub fn label(&self) -> String {
        format!("{} ({})", self.case.id, kind_name(self.kind))
    }

    pub fn mesh_orders(&self) -> Vec<Option<f64>> {
        orders(&self.mesh)
    }

    pub fn dt_orders(&self) -> Vec<Option<f64>> {
        dt_orders(&self.dt)
    }

    /// The observed order between the two finest levels of the quick ladder (the
    /// asymptotic range; the full ladder goes on to where the error meets the
    /// discretization-independent floor of the measurement or the element's limit).
    pub fn checked_order(&self) -> Option<f64> {
        let q = self.case.quick;
        let at = |n: u32| self.mesh.iter().find(|m| m.level.mesh == n);
        match (q.len().checked_sub(2).map(|k| q[k]), q.last()) {
            (Some(a), Some(&b)) => match (at(a), at(b)) {
                (Some(ma), Some(mb)) => orders(&[ma.clone(), mb.clone()])[0],
                _ => None,
            },
            _ => None,
        }
    }

    /// What fails the case's own criteria (empty: it passes). Coarser levels that
    /// stopped are reported in the tables but do not fail the case.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        let name = self.label();
        let finest_measured = self.mesh.last().map(|m| m.level.mesh);
        for f in &self.failures {
            if f.dt || finest_measured.is_none_or(|m| f.level.mesh > m) {
                p.push(format!(
                    "{name}: level {} (dt safety {}) failed: {}",
                    f.level.mesh, f.level.safety, f.message
                ));
            }
        }
        match self.mesh.last() {
            None => p.push(format!("{name}: no level measured")),
            Some(m) if m.error.is_nan() || m.error > self.case.tolerance => p.push(format!(
                "{name}: error {:.3e} at the finest level (mesh {}) exceeds the tolerance {:.1e}",
                m.error, m.level.mesh, self.case.tolerance
            )),
            Some(_) => {}
        }
        for m in self
            .dt
            .iter()
            .filter(|m| m.error.is_nan() || m.error > self.case.tolerance)
        {
            p.push(format!(
                "{name}: error {:.3e} at dt safety {} exceeds the tolerance {:.1e}",
                m.error, m.level.safety, self.case.tolerance
            ));
        }
        if let Some(min) = self.case.min_order {
            match self.checked_order() {
                Some(o) if o >= min => {}
                other => p.push(format!(
                    "{name}: observed order {} between the two finest quick levels is below {min}",
                    other.map_or("(undefined)".to_string(), |o| format!("{o:.2}"))
                )),
            }
        }
        p
    }
}

/// Which ladders to run.
#[derive(Debug, Clone, Default)]
pub struct Selection {
    pub quick: bool,
    /// Case ids to run (empty: all).
    pub only: Vec<String>,
}

impl Selection {
    pub fn cases(&self) -> Vec<&'static Case> {
        CASES
            .iter()
            .filter(|c| self.only.is_empty() || self.only.iter().any(|o| o == c.id))
            .collect()
    }
}

/// Run the selected ladders; `log` gets one line per measured level.
pub fn run_suite(sel: &Selection, mut log: impl FnMut(&str)) -> Vec<LadderResult> {
    let mut out = Vec::new();
    for case in sel.cases() {
        for &kind in case.kinds {
            out.push(run_case(case, kind, sel.quick, &mut log));
        }
    }
    out
}

pub fn run_case(
    case: &'static Case,
    kind: ElementKind,
    quick: bool,
    log: &mut impl FnMut(&str),
) -> LadderResult {
    let mut res = LadderResult {
        case,
        kind,
        mesh: Vec::new(),
        dt: Vec::new(),
        failures: Vec::new(),
    };
    let levels = if quick { case.quick } else { case.full };
    for &n in levels {
        match (case.run)(kind, Level::mesh(n)) {
            Ok(m) => {
                log(&line(&res, &m));
                res.mesh.push(m);
            }
            Err(e) => {
                log(&format!("{}: level {n}: {e}", res.label()));
                res.failures.push(Failure {
                    level: Level::mesh(n),
                    dt: false,
                    message: e.to_string(),
                });
            }
        }
    }
    if quick {
        return res;
    }
    let Some(&mesh) = case.quick.last() else {
        return res;
    };
    for &safety in case.dt_ladder {
        match (case.run)(kind, Level { mesh, safety }) {
            Ok(m) => {
                log(&line(&res, &m));
                res.dt.push(m);
            }
            Err(e) => {
                log(&format!(
                    "{}: level {mesh}, dt safety {safety}: {e}",
                    res.label()
                ));
                res.failures.push(Failure {
                    level: Level { mesh, safety },
                    dt: true,
                    message: e.to_string(),
                });
            }
        }
    }
    res
}

fn line(res: &LadderResult, m: &Measurement) -> String {
    format!(
        "{}: {} {} safety {}: {} elements, {} steps, {:.2} s: {} = {:.6e} (reference {:.6e}), error {:.3e}",
        res.label(),
        res.case.mesh_param,
        m.level.mesh,
        m.level.safety,
        m.elements,
        m.steps,
        m.wall_s,
        res.case.quantity,
        m.value,
        m.reference,
        m.error
    )
}
