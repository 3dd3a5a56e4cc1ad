//! Contact across parts (issue 16 point 2, second layer: in one process). A group of
//! bodies, each split into parts (`Split`), steps bit-identically to the whole group,
//! contact included.
//!
//! The parts of one holder (a worker; each part alone without a holder table) evaluate
//! every hit that touches one of their owned nodes, as the slave or as a segment
//! corner, on one *contact view*: a sub-body of every contact body of the group holding
//! the nodes and segments within reach of one of the holder's parts, plus one ring of
//! segments around them so that every nodal normal a hit reads sums all of its
//! segments. The view keeps the whole bodies' node and element order and masses, so
//! the contact stage run on it (`contact_forces_given`) finds, for each node within
//! reach, the same closest segment and force, and adds the pushes in the same order
//! (sorted pairs, first pass then second, node order). Each part keeps the sums of its
//! owned nodes and ignores the rest: a hit on a cut between holders is computed by both.
//! One view per holder rather than per part: a sphere whole on the holder of the floor
//! part under it is one contact stage with it, not two that both compute their pair.
//!
//! Reach (`partition::select`): a hit needs its slave within c = (t_a + t_b)/2 of its
//! segment. With G = t_max plus twice the skin (c <= t_max; each of two nodes moves at
//! most `skin` between view builds), the view's slaves are the nodes within G of another
//! body that are owned here or within G of one of the holder's elements of another
//! body; its segments those within G of a slave of another body (so the
//! closest-segment choice is the whole body's), then the corners and the ring. Owned
//! nodes far from every other body are not in the view (their contact force is zero):
//! before session 21 a view held every node within G of the holder's elements, its
//! own parts' halves of each body included (about 60 % of the showcase's nodes per
//! holder, against a few per cent now). The view is rebuilt when some node has moved
//! farther than the skin (`VIEW_SKIN` margins) less the tunnelling budget since it was
//! built.
//!
//! Under the segment pass (`ContactPass::Segments`) the views reach farther, by
//! `partition::select_points`'s rule (a point pushes the nodes around its segments'
//! corners), and the pass's stiffening step comes back from the views (`views_pass`).
//!
//! Global figures: the candidate pairs (body boxes: min/max over the parts), the
//! element critical steps (min over the parts) and the closing-speed step of each pair
//! (a mass-weighted mean velocity summed in node order over the whole body: an ordered
//! reduction, here over the gathered velocities) are computed once per step for all
//! parts, as the whole group's stage computes them.

use super::view::{in_whole, NOT_IN_VIEW};
pub use super::view::{View, ViewRule};
use super::{partition_body, Split};
use crate::body::Body;
use crate::clock::Clock;
use crate::contact::stage::pairs_of;
use crate::contact::stage::{
    closing_dt, contact_forces_given, element_form_dt, has_reference, Given,
};
use crate::contact::surface::Surface;
use crate::contact::sweep::BodySpeed;
use crate::contact::{check_moves, ContactConfig, PairStats, PenaltyKind};
use crate::contact::{ContactPass, SpeedRule};
use crate::error::{CoreError, Fault};
use crate::Vec3;
use std::collections::BTreeMap;

/// The views' skin over the largest search margin. A build costs about as much as a
/// few dozen steps of the views (R-tree queries for every node and element, sub-bodies,
/// surfaces), and a view is rebuilt once a node has moved the skin less the tunnelling
/// budget (half a margin): twice the margin builds a third as often as one margin,
/// for views a few per cent larger (the showcase split over 2 workers, in process: 10
/// builds instead of 30, 5-6 % less compute).
pub const VIEW_SKIN: f64 = 2.0;

/// The closing-speed step of each candidate pair of different bodies (by body ids;
/// None where they do not close), a figure of the whole bodies.
pub type Closing = BTreeMap<(u32, u32), Option<f64>>;

/// Why a split group cannot step: a fault of the run (as the whole group would have
/// it), or a contact view that cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum SplitError {
    #[error("{0}")]
    Fault(#[from] Fault),
    #[error("{0}")]
    View(#[from] CoreError),
}

/// A group of bodies, each split into parts, with contact between all of them.
#[derive(Debug, Clone)]
pub struct GroupSplit {
    pub splits: Vec<Split>,
    pub contact: ContactConfig,
    pub gravity: Vec3,
    pub rule: ViewRule,
    /// The whole bodies: definitions, and x, v, w gathered from the parts each step
    /// (for the global figures and to fill the views, what would cross the wire).
    pub(super) whole: Vec<Body>,
    /// Whole-body surfaces (element-form stable step constants), per contact body.
    pub(super) surfaces: Vec<Option<Surface>>,
    /// One view per holder (`view_parts`), and the positions they were built at.
    pub views: Vec<View>,
    pub(super) reference: Vec<Vec<Vec3>>,
    /// Node motion allowed between view builds [m].
    pub skin: f64,
    /// View builds so far.
    pub builds: u64,
    /// Which parts this process computes (`mine[i][q]`; all of them unless the group is
    /// shared between workers, `partition::shared`): the others' views are not built.
    pub mine: Vec<Vec<bool>>,
    /// Select the node lists of the other parts' views too (no sub-bodies): a shared
    /// group derives from them what each part sends the other holders.
    pub(super) all_lists: bool,
    /// Contact statistics of the last pass, the parts computed here (`contact_stats`).
    stats: Vec<PairStats>,
    /// The holder of each part (`holder[i][q]`; empty: every part its own), so that
    /// a holder's parts share one contact view and only what another holder reads
    /// crosses the wire (`export::exports`). Set before the first view build.
    pub holder: Vec<Vec<u32>>,
}

impl GroupSplit {
    /// Split body i of `bodies` into `parts[i]` parts (recursive coordinate bisection).
    pub fn new(
        bodies: &[Body],
        parts: &[usize],
        contact: ContactConfig,
        gravity: Vec3,
        rule: ViewRule,
    ) -> Result<Self, CoreError> {
        let splits = bodies
            .iter()
            .zip(parts)
            .map(|(b, &k)| Split::new(b, &partition_body(&b.def, k)?))
            .collect::<Result<Vec<_>, _>>()?;
        let surfaces = bodies
            .iter()
            .map(|b| b.def.contact.then(|| Surface::new(b)))
            .collect();
        let skin = VIEW_SKIN
            * bodies
                .iter()
                .filter(|b| b.def.contact)
                .map(|b| contact.margin_for(b))
                .fold(0.0, f64::max);
        Ok(Self {
            splits,
            contact,
            gravity,
            rule,
            whole: bodies.to_vec(),
            surfaces,
            views: Vec::new(),
            reference: Vec::new(),
            skin,
            builds: 0,
            mine: parts.iter().map(|&k| vec![true; k]).collect(),
            all_lists: false,
            holder: Vec::new(),
            stats: Vec::new(),
        })
    }

    /// Start like `Group::start`: constraints, element forces and contact forces at the
    /// initial configuration. Returns the stable step of each body (no safety factor).
    pub fn start(&mut self) -> Result<Vec<f64>, SplitError> {
        let dt = self
            .splits
            .iter_mut()
            .map(|s| s.start())
            .collect::<Result<Vec<_>, _>>()?;
        self.contact(dt, 0.0, 0)
    }

    /// One step of length h from `clock` (the pipeline of `Group::advance`): integrate
    /// the owned nodes, tunnelling guard, halo exchange, element forces, contact forces.
    /// Returns the stable step of each body.
    pub fn advance(&mut self, clock: &Clock, h: f64) -> Result<Vec<f64>, SplitError> {
        let step = clock.after(h).step;
        let mut moves = Vec::with_capacity(self.splits.len());
        for s in &mut self.splits {
            let sums = s.integrate(clock, h, self.gravity)?;
            // the largest move over the parts (its node named in the whole body)
            let m = s
                .parts
                .iter()
                .zip(&sums)
                .map(|(p, n)| (n.max_move, p.node[n.max_move_node] as usize))
                .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
            moves.push(m);
        }
        check_moves(&self.whole, &self.contact, &moves, h, step)?;
        let mut dt = Vec::with_capacity(self.splits.len());
        for s in &mut self.splits {
            s.exchange();
            dt.push(s.forces(h, step)?);
        }
        self.contact(dt, h, step)
    }

    /// Write every body's owned x, v, w into `out` (the whole bodies).
    pub fn gather_into(&self, out: &mut [Body]) {
        for (s, b) in self.splits.iter().zip(out) {
            s.gather_into(b);
        }
    }

    /// Contact forces into the parts' `f_contact`; `element_dt[i]` body i's element
    /// critical step. Returns each body's stable step.
    pub(super) fn contact(
        &mut self,
        element_dt: Vec<f64>,
        h: f64,
        step: u64,
    ) -> Result<Vec<f64>, SplitError> {
        let bounds = self.whole_bounds();
        let (dt, closing) = self.figures_given(&element_dt, &bounds);
        let rebuild = self.views.is_empty() || self.moved_beyond_skin();
        let (_, limits) = self.views_pass(&element_dt, &closing, &bounds, h, step, rebuild)?;
        Ok(dt.iter().zip(&limits).map(|(d, l)| d.min(*l)).collect())
    }

    /// Gather the whole bodies from the parts and give each body's node box (min/max
    /// over its parts' owned nodes), for `figures_given` and the views' pairs. None of
    /// the figures reads a contact force, so they are known before the contact pass
    /// (`partition::shared` sends them with the element pass's report).
    pub(super) fn whole_bounds(&mut self) -> Vec<(Vec3, Vec3)> {
        self.gather_whole();
        self.splits
            .iter()
            .map(|s| {
                s.parts
                    .iter()
                    .map(|p| crate::mesh::bounds(&p.body.state.x[..p.owned]))
                    .fold(crate::mesh::bounds(&[]), |(lo, hi), (l, u)| {
                        (lo.inf(&l), hi.sup(&u))
                    })
            })
            .collect()
    }

    /// Write every part's owned x, v, w into the whole bodies.
    pub(super) fn gather_whole(&mut self) {
        for (s, b) in self.splits.iter().zip(&mut self.whole) {
            s.gather_into(b);
        }
    }

    /// The global figures of a step (candidate pairs, the closing-speed step of each
    /// pair by body ids, None where they do not close, and each body's stable step:
    /// `element_dt` limited by the contact), with each body's node box given
    /// (`bounds[i]`: min/max over its parts' owned nodes) and the whole bodies'
    /// velocities current (their positions need not be: the closing speed reads
    /// velocities and masses only). A holder of some parts passes the element steps of
    /// its parts only (infinite for a body with no part here): a pair is skipped here
    /// only if neither body has a part here, so every pair's limits reach the shares
    /// of the bodies it holds.
    pub(super) fn figures_given(
        &self,
        element_dt: &[f64],
        bounds: &[(Vec3, Vec3)],
    ) -> (Vec<f64>, Closing) {
        let (mut dt, pairs) = self.pair_limits(element_dt, bounds);
        let mut closing = BTreeMap::new();
        let mut speeds: BTreeMap<usize, BodySpeed> = BTreeMap::new();
        for (ia, ib) in pairs {
            let (a, b) = (&self.whole[ia], &self.whole[ib]);
            if !has_reference(self.contact.penalty, element_dt[ia].min(element_dt[ib])) {
                continue;
            }
            speeds.entry(ia).or_insert_with(|| BodySpeed::of(a));
            speeds.entry(ib).or_insert_with(|| BodySpeed::of(b));
            let d = closing_dt(a, b, &speeds[&ia], &speeds[&ib]);
            if let Some(d) = d {
                dt[ia] = dt[ia].min(d);
                dt[ib] = dt[ib].min(d);
            }
            closing.insert((a.def.id, b.def.id), d);
        }
        (dt, closing)
    }

    /// Each body's element step limited by the element-form steps of its pairs, and the
    /// pairs whose closing-speed step the rule asks for (`SpeedRule::LimitDt`, two
    /// bodies), from the body boxes `bounds`.
    pub(super) fn pair_limits(
        &self,
        element_dt: &[f64],
        bounds: &[(Vec3, Vec3)],
    ) -> (Vec<f64>, Vec<(usize, usize)>) {
        let cfg = self.contact;
        let mut dt = element_dt.to_vec();
        let mut closing = Vec::new();
        if !cfg.enabled {
            return (dt, closing);
        }
        let bounds: Vec<(Vec3, Vec3)> = bounds
            .iter()
            .zip(&self.whole)
            .map(|(&bb, b)| {
                if b.def.contact {
                    bb
                } else {
                    (Vec3::zeros(), Vec3::zeros())
                }
            })
            .collect();
        for (ia, ib) in pairs_of(&self.whole, &cfg, &bounds) {
            if cfg.penalty == PenaltyKind::Element {
                if let (Some(sa), Some(sb)) = (&self.surfaces[ia], &self.surfaces[ib]) {
                    let d = element_form_dt(&cfg, sa, sb).min(element_form_dt(&cfg, sb, sa));
                    dt[ia] = dt[ia].min(d);
                    dt[ib] = dt[ib].min(d);
                }
            }
            if cfg.speed_rule == SpeedRule::LimitDt && ia != ib {
                closing.push((ia, ib));
            }
        }
        (dt, closing)
    }

    /// The contact pass of the parts computed here, on their views, at the positions
    /// `figures` gathered: `element_dt[i]` body i's element critical step over all its
    /// parts (the soft penalty's reference step reads it), `closing` from `figures`.
    /// Returns whether the views were rebuilt, and each body's step limit from the
    /// views' passes (the smallest over them; infinite where none): the segment pass's
    /// stiffening step, booked from the points each view counts, so that the minimum
    /// over all holders is the whole group's. The node passes' limits (element form,
    /// closing speed) are `figures_given`'s already.
    pub(super) fn views_pass(
        &mut self,
        element_dt: &[f64],
        closing: &Closing,
        bounds: &[(Vec3, Vec3)],
        h: f64,
        step: u64,
        rebuild: bool,
    ) -> Result<(bool, Vec<f64>), SplitError> {
        let cfg = self.contact;
        let mut limits = vec![f64::INFINITY; self.whole.len()];
        if !cfg.enabled {
            for p in self.splits.iter_mut().flat_map(|s| &mut s.parts) {
                p.body.state.f_contact.clear();
            }
            return Ok((false, limits));
        }
        if rebuild {
            self.build_views()?;
        }
        self.stats.clear();
        for view in self.views.iter_mut() {
            if !view.parts.iter().any(|&(i, q)| self.mine[i][q]) {
                continue;
            }
            for (vb, (&j, fill)) in view
                .bodies
                .iter_mut()
                .zip(view.index.iter().zip(&view.fill))
            {
                // x and v (all the contact stage reads of a node) from the parts
                // owning the nodes (what a shared group imports)
                let (s, parts) = (&mut vb.state, &self.splits[j].parts);
                for r in fill {
                    let w = &parts[r.part as usize].body.state;
                    let (a, b, n) = (r.view as usize, r.local as usize, r.len as usize);
                    s.x[a..a + n].copy_from_slice(&w.x[b..b + n]);
                    s.v[a..a + n].copy_from_slice(&w.v[b..b + n]);
                }
            }
            if !view.bodies.is_empty() {
                let edt: Vec<f64> = view.index.iter().map(|&j| element_dt[j]).collect();
                // the whole bodies' boxes: the pairs are the whole group's among the
                // view's bodies, and a view node outside a view body's box grown by
                // the margin is outside that body's reach anyway (no box to compute)
                let vbounds: Vec<(Vec3, Vec3)> = view.index.iter().map(|&j| bounds[j]).collect();
                let dt = contact_forces_given(
                    &mut view.bodies,
                    &cfg,
                    &mut view.state,
                    &edt,
                    &vbounds,
                    h,
                    step,
                    Given {
                        closing: Some(closing),
                        figures: &[],
                        counted: &view.counted,
                        counted_segments: &view.counted_segments,
                        slave_segments: &view.slave_segments,
                    },
                )
                .map_err(|f| in_whole(f, view))?;
                // (the node passes' limits on a view are the whole group's or larger)
                if cfg.pass == ContactPass::Segments {
                    for (&j, d) in view.index.iter().zip(dt) {
                        limits[j] = limits[j].min(d);
                    }
                }
            }
            for (&(i, q), at) in view.parts.iter().zip(&view.owned_at) {
                if !self.mine[i][q] {
                    continue;
                }
                let part = &mut self.splits[i].parts[q];
                let fc = &mut part.body.state.f_contact;
                fc.clear();
                let Some((own, owned_at)) = at else {
                    continue;
                };
                fc.resize(part.node.len(), Vec3::zeros());
                let own = &view.bodies[*own].state.f_contact;
                for (k, &at) in owned_at.iter().enumerate() {
                    // (no hit can touch an owned node left out of the view)
                    if at != NOT_IN_VIEW {
                        fc[k] = own[at as usize];
                    }
                }
            }
            PairStats::merge_sorted(&mut self.stats, view.state.stats());
        }
        Ok((rebuild, limits))
    }

    fn moved_beyond_skin(&self) -> bool {
        let s2 = self.skin * self.skin;
        self.whole.iter().zip(&self.reference).any(|(b, r)| {
            b.state.x.iter().zip(r).any(|(x, r)| {
                // NaN counts as moved
                let d2 = (x - r).norm_squared();
                d2.is_nan() || d2 > s2
            })
        })
    }

    /// Nodes in the contact views summed over the parts (every body's), and the parts'
    /// owned nodes.
    pub fn view_nodes(&self) -> (usize, usize) {
        let nodes = self
            .views
            .iter()
            .map(|v| v.node.iter().map(Vec::len).sum::<usize>())
            .sum();
        let owned = self.splits.iter().map(|s| s.node_counts().0).sum();
        (nodes, owned)
    }

    /// Contact statistics of the last pass over the parts computed here, sorted by
    /// pair: each push booked once, by the view of the part owning its slave node, so
    /// over every holder they add up to the whole group's (`PairStats::merge`).
    pub fn contact_stats(&self) -> &[PairStats] {
        &self.stats
    }
}
