//! A scene planned without keeping its bodies, for a coordinator whose memory must not
//! grow with the model: each body is built once to learn its brief (counts, box,
//! thickness, flags) and what the default contact margin needs, then dropped; the pairs
//! whose boxes meet are rebuilt two at a time for the interpenetration check. The
//! coordinator then builds each body again when it hands it to a worker
//! ([`Scene::body`]), so it never holds more than two bodies. Bodies, margin, hash and
//! errors are exactly those of [`Scene::build`].

use crate::build::{body, check_memory, output_interval, overlap_error, BodyInfo};
use crate::error::SceneError;
use crate::margin::{default_margin_of, MarginInputs};
use crate::outputs::{self, Outputs};
use crate::shape::plan;
use crate::Scene;
use crash_core::contact::{candidate_pairs, initial_penetrations, BodyBox, ContactConfig};
use crash_core::hash::Fnv;
use crash_core::{Body, BodyBrief, RunConfig, Vec3};

/// A scene ready to run, without its bodies.
#[derive(Debug, Clone)]
pub struct Plan {
    pub name: String,
    /// Per body (ids 0..n in file order).
    pub briefs: Vec<BodyBrief>,
    pub info: Vec<BodyInfo>,
    pub gravity: Vec3,
    pub end_time: f64,
    pub safety: f64,
    pub output_interval: f64,
    pub contact: ContactConfig,
    pub margin_derived: bool,
    pub energy_limit: f64,
    pub scene_hash: u64,
    /// Output requests (as `Built::outputs`).
    pub outputs: Outputs,
    /// What the build adjusted, for the console (as `Built::notes`).
    pub notes: Vec<String>,
}

impl Plan {
    /// The core driver's configuration for this scene (other fields default).
    pub fn run_config(&self) -> RunConfig {
        RunConfig {
            end_time: self.end_time,
            safety: self.safety,
            energy_limit: self.energy_limit,
            ..RunConfig::default()
        }
    }
}

impl Scene {
    /// Build body `i` alone (the same bits as `build().bodies[i]`).
    pub fn body(&self, i: usize) -> Result<Body, SceneError> {
        let spec = self.spec.bodies.get(i).ok_or_else(|| {
            self.ctx.key_error(
                crate::ErrorKind::Reference,
                "bodies",
                format!("there is no body {i}"),
            )
        })?;
        let mut ignored = Fnv::default();
        let planned = plan(&self.ctx, &self.dir, i, spec, &mut ignored, &self.inputs)?;
        let curves = crate::curves::curves(&self.ctx, &self.spec)?;
        Ok(body(self, &self.ctx, i, spec, planned.generate(), &curves)?.0)
    }

    /// Plan the run: every check of `build`, without keeping the bodies.
    pub fn plan(&self) -> Result<Plan, SceneError> {
        let g = &self.globals;
        let ctx = &self.ctx;
        let mut hash = self.hash;
        let n = self.spec.bodies.len();
        let mut plans = Vec::with_capacity(n);
        for (i, b) in self.spec.bodies.iter().enumerate() {
            plans.push(plan(ctx, &self.dir, i, b, &mut hash, &self.inputs)?);
        }
        check_memory(
            ctx,
            &plans,
            self.memory_limit.or_else(crate::memory::available),
        )?;
        let curves = crate::curves::curves(ctx, &self.spec)?;
        let (mut briefs, mut info, mut inputs, mut tags) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for (i, (b, p)) in self.spec.bodies.iter().zip(plans).enumerate() {
            let (body, inf, t) = body(self, ctx, i, b, p.generate(), &curves)?;
            briefs.push(BodyBrief::of(&body));
            inputs.push(MarginInputs::of(&body));
            info.push(inf);
            tags.push(t);
        }
        let ids: Vec<u32> = briefs.iter().map(|b| b.id).collect();
        let outputs = outputs::resolve(ctx, &self.spec, &ids, &tags)?;
        let dt = inputs
            .iter()
            .map(|m| m.dt_estimate)
            .fold(f64::INFINITY, f64::min);
        let (output_interval, notes) = output_interval(g, dt);
        let mut contact = g.contact;
        if !g.margin_given && contact.enabled {
            contact.margin = default_margin_of(&inputs, g.gravity, g.end_time, g.safety);
        }
        if contact.enabled {
            self.check_overlap(&briefs, &contact)?;
        }
        Ok(Plan {
            name: self.name.clone(),
            briefs,
            info,
            gravity: g.gravity,
            end_time: g.end_time,
            safety: g.safety,
            output_interval,
            contact,
            margin_derived: !g.margin_given,
            energy_limit: g.energy_limit,
            scene_hash: hash.finish(),
            outputs,
            notes,
        })
    }

    /// The deepest initial penetration over the pairs of contact bodies whose boxes
    /// meet (the pairs `check_initial_overlap` examines, in the same order).
    fn check_overlap(&self, briefs: &[BodyBrief], cfg: &ContactConfig) -> Result<(), SceneError> {
        let boxes: Vec<BodyBox> = briefs
            .iter()
            .filter(|b| b.contact)
            .map(|b| b.bbox())
            .collect();
        let mut pairs = candidate_pairs(&boxes, cfg.margin);
        pairs.sort_unstable();
        let mut worst: Option<crash_core::contact::Penetration> = None;
        for (a, b) in pairs.into_iter().filter(|(a, b)| a != b) {
            let two = [self.body(a as usize)?, self.body(b as usize)?];
            for p in initial_penetrations(&two, cfg) {
                if worst.as_ref().is_none_or(|w| w.depth < p.depth) {
                    worst = Some(p);
                }
            }
        }
        match worst {
            Some(p) => Err(overlap_error(self, &self.ctx, &p)),
            None => Ok(()),
        }
    }
}
