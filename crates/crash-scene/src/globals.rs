//! Checks of the scene-wide keys and the materials (everything that needs no mesh).

use crate::context::Ctx;
use crate::error::{ErrorKind, SceneError};
use crate::schema::{MaterialSpec, SceneFile};
use crash_core::contact::{ContactConfig, ContactPass, PenaltyKind, SegmentSides, SpeedRule};
use crash_core::{CoreError, Material, Vec3};
use std::collections::BTreeMap;

pub const DEFAULT_SAFETY: f64 = 0.9;
pub use crash_core::driver::DEFAULT_ENERGY_LIMIT;
/// Output frames per run when output_interval is not given.
pub const DEFAULT_FRAMES: f64 = 100.0;

/// Checked scene-wide values (the contact margin may still be derived later).
#[derive(Debug, Clone, PartialEq)]
pub struct Globals {
    pub end_time: f64,
    pub safety: f64,
    pub gravity: Vec3,
    pub output_interval: f64,
    pub energy_limit: f64,
    pub contact: ContactConfig,
    /// The margin was given in the file (else it is derived from the bodies).
    pub margin_given: bool,
}

pub fn finite_vec(ctx: &Ctx, key: &str, v: Option<[f64; 3]>) -> Result<Vec3, SceneError> {
    let v = Vec3::from(v.unwrap_or([0.0; 3]));
    if v.iter().all(|c| c.is_finite()) {
        Ok(v)
    } else {
        Err(ctx.invalid(key, "components must be finite"))
    }
}

/// `end_time` is checked apart from the rest so that a command-line override is
/// checked alike (`overridden`: the value came from the command line).
pub fn check_end_time(ctx: &Ctx, end_time: f64, overridden: bool) -> Result<f64, SceneError> {
    if end_time.is_finite() && end_time > 0.0 {
        Ok(end_time)
    } else if overridden {
        Err(ctx.key_error(
            ErrorKind::Invalid,
            "end_time",
            format!("{end_time} (given on the command line): must be finite and > 0 (s)"),
        ))
    } else {
        Err(ctx.invalid("end_time", "must be finite and > 0 (s)"))
    }
}

/// `name` names the run directory (`out/<name>`), so it must be one plain path
/// component: a name that is empty, `.` or `..`, or holds a path separator, a drive
/// colon or a control character could write outside the output root. Refused, not
/// rewritten, so the directory is always called what the file says.
pub fn check_name(ctx: &Ctx, name: Option<&str>) -> Result<(), SceneError> {
    let Some(name) = name else { return Ok(()) };
    let bad = name.is_empty()
        || name == "."
        || name == ".."
        || name
            .chars()
            .any(|c| matches!(c, '/' | '\\' | ':') || c.is_control());
    if bad {
        return Err(ctx.invalid(
            "name",
            "must be one plain file name (it names the run directory out/<name>): not empty, not `.` or `..`, without `/`, `\\`, `:` or control characters, e.g. \"sphere-on-plate\"",
        ));
    }
    Ok(())
}

pub fn globals(
    ctx: &Ctx,
    s: &SceneFile,
    end_time: f64,
    output_interval: Option<f64>,
) -> Result<Globals, SceneError> {
    let safety = s.dt_safety.unwrap_or(DEFAULT_SAFETY);
    if !(safety.is_finite() && safety > 0.0 && safety <= 1.0) {
        return Err(ctx.invalid(
            "dt_safety",
            "must be in (0, 1] (fraction of the critical time step)",
        ));
    }
    let gravity = finite_vec(ctx, "gravity", s.gravity)?;
    let output_interval = output_interval
        .or(s.output_interval)
        .unwrap_or(end_time / DEFAULT_FRAMES);
    if !(output_interval.is_finite() && output_interval > 0.0) {
        return Err(ctx.invalid("output_interval", "must be finite and > 0 (s)"));
    }
    let energy_limit = s.energy_limit.unwrap_or(DEFAULT_ENERGY_LIMIT);
    if !(energy_limit.is_finite() && energy_limit > 0.0 && energy_limit <= 1.0) {
        return Err(ctx.invalid(
            "energy_limit",
            "must be in (0, 1] (energy balance error relative to the largest energy)",
        ));
    }
    let c = &s.contact;
    let d = ContactConfig::default();
    let margin = c.margin.unwrap_or(0.0);
    if !(margin.is_finite() && margin >= 0.0) {
        return Err(ctx.invalid(
            "contact.margin",
            "must be finite and >= 0 (m); omit it for the derived default",
        ));
    }
    let penalty_scale = c.penalty_scale.unwrap_or(d.penalty_scale);
    if !(penalty_scale.is_finite() && penalty_scale > 0.0) {
        return Err(ctx.invalid("contact.penalty_scale", "must be finite and > 0"));
    }
    let penalty = match c.penalty.as_deref() {
        None => d.penalty,
        Some("soft") => PenaltyKind::Soft,
        Some("element") => PenaltyKind::Element,
        Some(_) => return Err(ctx.invalid("contact.penalty", "must be \"soft\" or \"element\"")),
    };
    let damping_ratio = c.damping_ratio.unwrap_or(d.damping_ratio);
    if !(damping_ratio.is_finite() && (0.0..=1.0).contains(&damping_ratio)) {
        return Err(ctx.invalid(
            "contact.damping_ratio",
            "must be in [0, 1] (fraction of critical damping)",
        ));
    }
    let speed_rule = match c.speed_rule.as_deref() {
        None => d.speed_rule,
        Some("limit_dt") => SpeedRule::LimitDt,
        Some("stop") => SpeedRule::Stop,
        Some(_) => {
            return Err(ctx.invalid("contact.speed_rule", "must be \"limit_dt\" or \"stop\""))
        }
    };
    let pass = match c.pass.as_deref() {
        None => d.pass,
        Some("nodes") => ContactPass::Nodes,
        Some("segments") => ContactPass::Segments,
        Some(_) => return Err(ctx.invalid("contact.pass", "must be \"nodes\" or \"segments\"")),
    };
    if pass == ContactPass::Segments && penalty != PenaltyKind::Soft {
        return Err(ctx.invalid(
            "contact.pass",
            "\"segments\" needs contact.penalty = \"soft\" (its stiffness is per area)",
        ));
    }
    let sides = match c.sides.as_deref() {
        None => d.sides,
        Some(_) if pass != ContactPass::Segments => {
            return Err(ctx.invalid(
                "contact.sides",
                "applies to contact.pass = \"segments\" only (the node passes run both ways)",
            ))
        }
        Some("auto") => SegmentSides::Auto,
        Some("finer") => SegmentSides::Finer,
        Some("both") => SegmentSides::Both,
        Some(_) => {
            return Err(ctx.invalid("contact.sides", "must be \"auto\", \"finer\" or \"both\""))
        }
    };
    Ok(Globals {
        end_time,
        safety,
        gravity,
        output_interval,
        energy_limit,
        contact: ContactConfig {
            enabled: c.enabled.unwrap_or(d.enabled),
            margin,
            penalty_scale,
            penalty,
            damping_ratio,
            speed_rule,
            pass,
            sides,
        },
        margin_given: c.margin.is_some(),
    })
}

fn material(ctx: &Ctx, name: &str, m: &MaterialSpec) -> Result<Material, SceneError> {
    let key = format!("materials.{name}");
    let kelvin = m.kelvin.unwrap_or(0.0);
    let r = match (m.young, m.poisson, m.lambda1, m.lambda2) {
        (Some(e), Some(nu), None, None) => Material::new(m.density, e, nu, kelvin),
        (None, None, Some(l1), Some(l2)) => Material::from_lame(m.density, l1, l2, kelvin),
        (None, None, None, None) => {
            return Err(ctx.missing(
                &format!("{key}.young"),
                "give young (Pa) and poisson, or the Lamé pair lambda1 and lambda2 (Pa)",
            ))
        }
        (Some(_), None, None, None) => {
            return Err(ctx.missing(
                &format!("{key}.poisson"),
                "young needs poisson (in [0, 0.5))",
            ))
        }
        (None, Some(_), None, None) => {
            return Err(ctx.missing(&format!("{key}.young"), "poisson needs young (Pa)"))
        }
        (None, None, Some(_), None) => {
            return Err(ctx.missing(
                &format!("{key}.lambda2"),
                "lambda1 needs lambda2 (Pa, the shear modulus)",
            ))
        }
        (None, None, None, Some(_)) => {
            return Err(ctx.missing(&format!("{key}.lambda1"), "lambda2 needs lambda1 (Pa)"))
        }
        _ => {
            let k = if m.lambda1.is_some() {
                "lambda1"
            } else {
                "lambda2"
            };
            return Err(ctx.key_error(
                ErrorKind::Invalid,
                &format!("{key}.{k}"),
                "give either young and poisson, or lambda1 and lambda2, not both",
            ));
        }
    };
    r.map_err(|e| match e {
        CoreError::Material { field, valid, .. } => ctx.invalid(&format!("{key}.{field}"), valid),
        other => ctx.invalid(&key, other),
    })
}

/// Every material, checked, by name.
pub fn materials(ctx: &Ctx, s: &SceneFile) -> Result<BTreeMap<String, Material>, SceneError> {
    let mut out = BTreeMap::new();
    for (name, m) in &s.materials {
        out.insert(name.clone(), material(ctx, name, m)?);
    }
    Ok(out)
}

/// Body names unique and non-empty, materials defined.
pub fn references(
    ctx: &Ctx,
    s: &SceneFile,
    mats: &BTreeMap<String, Material>,
) -> Result<(), SceneError> {
    if s.bodies.is_empty() {
        return Err(ctx.missing("bodies", "a scene needs at least one [[bodies]] table"));
    }
    let mut seen = BTreeMap::new();
    for (i, b) in s.bodies.iter().enumerate() {
        let key = format!("bodies[{i}].name");
        if b.name.trim().is_empty() {
            return Err(ctx.invalid(&key, "must not be empty"));
        }
        if let Some(j) = seen.insert(b.name.as_str(), i) {
            return Err(ctx.invalid(
                &key,
                format!("bodies[{j}] has the same name: names must be unique"),
            ));
        }
        if !mats.contains_key(&b.material) {
            let defined: Vec<&str> = mats.keys().map(String::as_str).collect();
            let list = if defined.is_empty() {
                "none: add a [materials.NAME] table".to_string()
            } else {
                defined.join(", ")
            };
            return Err(ctx.value_error(
                ErrorKind::Reference,
                &format!("bodies[{i}].material"),
                format!("no material of that name; defined: {list}"),
            ));
        }
    }
    Ok(())
}

/// Every `curve` named by a prescribed motion or a load is defined.
pub fn curve_references(
    ctx: &Ctx,
    s: &SceneFile,
    curves: &BTreeMap<String, crate::curves::Curve>,
) -> Result<(), SceneError> {
    let defined = || {
        if curves.is_empty() {
            "none: add a [curves.NAME] table".to_string()
        } else {
            curves.keys().cloned().collect::<Vec<_>>().join(", ")
        }
    };
    for (i, b) in s.bodies.iter().enumerate() {
        let named = b
            .prescribe
            .iter()
            .enumerate()
            .map(|(k, p)| (format!("bodies[{i}].prescribe[{k}].curve"), &p.curve))
            .chain(
                b.load
                    .iter()
                    .enumerate()
                    .map(|(k, l)| (format!("bodies[{i}].load[{k}].curve"), &l.curve)),
            );
        for (key, c) in named {
            if let Some(name) = c {
                if !curves.contains_key(name) {
                    return Err(ctx.value_error(
                        ErrorKind::Reference,
                        &key,
                        format!("no curve of that name; defined: {}", defined()),
                    ));
                }
            }
        }
    }
    Ok(())
}
