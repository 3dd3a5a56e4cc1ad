//! A split group shared between workers (issue 16 point 2, the wiring). Every holder
//! keeps all parts of the group (`GroupSplit`) but computes only its own (`mine`); the
//! others are containers for the nodes that arrive from their holders. One step
//! is two exchanges, the master relaying; the contact pass of a step runs at the start
//! of the next one:
//!
//! 1. `contact` (the previous step's, when one is pending: with each body's element
//!    step over all holders, the soft penalty's reference step) then `integrate`: the
//!    holder's parts update their owned nodes and return what the others read of
//!    them (`PartState`: x, v, w at the export nodes, box, moves).
//! 2. `forces`: the other holders' `PartState`s fill the other parts (so every node
//!    the halos and contact views here read is current), the tunnelling
//!    guard runs on the largest move over all parts, the holder's parts compute their
//!    element forces, then the global figures (body boxes, pairs, closing-speed steps)
//!    give each body's stable step without any contact force; returns the holder's
//!    share of each body's report and each body's smallest element step over the parts
//!    here. The contact pass is left pending: its reference step needs every holder's
//!    element steps, which the master sends with the next step (or with a `Contact`
//!    before the whole bodies are assembled).
//!
//! What crosses the wire is what another part reads: each part sends x, v, w of its
//! *export nodes* only (`SharedGroup::export`: its owned nodes in another holder's
//! halo or contact view), plus its box and its largest distance from where the views
//! were built (or, while that is surely below the rebuild trigger, a bound on it: the
//! last distance plus the largest moves since). Every holder derives the same export
//! lists from the split and the views of all holders (node lists only for the views
//! held elsewhere) at each view build. The
//! global figures need no whole body: the body boxes are the min/max of the parts'
//! boxes, the view rebuild rule the max of the parts' distances, and the closing-speed
//! step (`SpeedRule::LimitDt`) the parts' momenta on a fixed quantum (integer sums:
//! the whole body's bits in any order) and each holder's largest speeds relative to
//! the means, merged by the master (`closing`).
//! A view build needs the whole bodies: once some node has moved farther than the
//! skin less one step's tunnelling budget, the next integration sends every owned
//! node, and the contact pass after it rebuilds the views (on every holder alike).

use super::closing::{pair_speeds, SplitFigures};
use super::export::exports;
use super::inner::Early;
use super::report::{add_reaction, element_in_whole, node_in_whole};
use super::GroupSplit;
use crate::body::Body;
use crate::clock::Clock;
use crate::contact::speeds::SpeedBoxes;
use crate::contact::sweep::Momentum;
use crate::contact::{check_moves, ContactConfig};
use crate::error::{CoreError, Fault};
use crate::forces::ForceSums;
use crate::group::{BodyReport, Reaction};
use crate::integrate::NodeSums;
use crate::Vec3;

pub use super::export::PartState;
pub use super::report::merge_report;
pub use super::SplitError;

/// A part's figures of one step (its own, or imported with its `PartState`).
#[derive(Debug, Clone, Copy)]
struct PartFigures {
    lo: Vec3,
    hi: Vec3,
    far: f64,
    max_move: f64,
    /// Whole-body index.
    max_move_node: u32,
    momentum: Momentum,
}

/// The smallest element critical step of body `id` over some of its parts, and its
/// element (whole-body index).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartDt {
    pub id: u32,
    pub dt: f64,
    pub element: u32,
}

impl PartDt {
    /// The smaller of two (ties: the lower element, as the whole body's element loop).
    pub fn min(self, o: PartDt) -> PartDt {
        if o.dt < self.dt || (o.dt == self.dt && o.element < self.element) {
            o
        } else {
            self
        }
    }
}

/// A group of bodies split into parts over `holders` workers, the parts of holder
/// `slot` computed here.
#[derive(Debug, Clone)]
pub struct SharedGroup {
    pub split: GroupSplit,
    /// Body ids, in the group's order.
    pub ids: Vec<u32>,
    /// Per body and part: the node sums of the last integration (own parts only).
    sums: Vec<Vec<Option<NodeSums>>>,
    /// Per body and part: the element sums of the last force pass (own parts only).
    forces: Vec<Vec<Option<ForceSums>>>,
    /// The contact pass the last `forces` left for the next step.
    pending: Option<Pending>,
    /// Per body and part: the local indices of the owned nodes some other part reads
    /// (its halo and contact-view nodes), in order: all that crosses the wire in a step
    /// without a view build. The same on every holder (a function of the split and of
    /// the whole bodies' positions at the last view build).
    pub export: Vec<Vec<Vec<u32>>>,
    /// Per body and part: the figures of the last integration (own parts only).
    figures: Vec<Vec<Option<PartFigures>>>,
    /// Per body and part: the owned velocities' boxes when the last integration took
    /// them (a part that is a whole body: `Body::integrate_with_figures`); else
    /// `pair_speeds` makes them.
    speeds: Vec<Vec<Option<SpeedBoxes>>>,
    /// The next integration sends every owned node (a view build follows it).
    due: bool,
    /// The last integration sent every owned node.
    sent_full: bool,
    /// The whole bodies were gathered in the last `forces`: the pending pass rebuilds
    /// the views there.
    rebuild: bool,
    /// A view build is due when some node has moved this far from where the views
    /// were built: one more step (at most the tunnelling guard's budget per node)
    /// keeps it within the skin, and the build needs a step to gather the bodies.
    trigger: f64,
    /// Per body: the whole body's mass and its momentum scale (`Momentum::scale`).
    mass: Vec<(f64, f64)>,
    /// Per body and part (own parts): a bound on the distance of an owned node from
    /// where the views were built (the last exact distance plus the largest moves
    /// since), and the view build it is for (`GroupSplit::builds`).
    far_bound: Vec<Vec<f64>>,
    bound_build: u64,
    /// Per body and part (own parts): the element chunks that read only owned nodes,
    /// and those computed early for the step in flight (`inner_forces`: its number).
    pub(super) inner: Vec<Vec<Vec<bool>>>,
    pub(super) early: Vec<Vec<Option<Early>>>,
}

/// The fraction of the view-rebuild trigger below which a part sends its bound on
/// the distance from the views' positions rather than the distance: the bound's
/// rounding (a sum of a few hundred moves) is far below the margin left.
const NEAR: f64 = 1.0 - 1e-6;

/// The bound is not safely below the trigger (or is NaN): the distance is needed.
fn near_trigger(bound: f64, trigger: f64) -> bool {
    use std::cmp::Ordering::{Equal, Less};
    !matches!(bound.partial_cmp(&(NEAR * trigger)), Some(Less | Equal))
}

/// A contact pass left for later: the step's length and number (its closing-speed
/// steps come merged over the holders with the element steps).
#[derive(Debug, Clone)]
struct Pending {
    h: f64,
    step: u64,
    /// Each body's node box at the step's positions (min/max over all its parts).
    bounds: Vec<(Vec3, Vec3)>,
}

impl SharedGroup {
    /// Split body i of `bodies` (whole, at their current state) into `parts[i]` parts;
    /// `mine[i][q]`: part q of body i is computed here. The energy record and current
    /// energies of each body go with its part 0 (the sums over parts continue them).
    pub fn new(
        bodies: &[Body],
        parts: &[usize],
        mine: Vec<Vec<bool>>,
        contact: ContactConfig,
        gravity: Vec3,
    ) -> Result<Self, CoreError> {
        if mine.len() != bodies.len() || mine.iter().zip(parts).any(|(m, &k)| m.len() != k) {
            return Err(CoreError::Other {
                body: "split group".into(),
                what: "the parts computed here do not fit the split".into(),
            });
        }
        let mut split = GroupSplit::new(bodies, parts, contact, gravity, Default::default())?;
        for (s, b) in split.splits.iter_mut().zip(bodies) {
            let st = &mut s.parts[0].body.state;
            st.energy = b.state.energy;
            st.internal_now = b.state.internal_now;
            st.hourglass_now = b.state.hourglass_now;
        }
        split.mine = mine;
        split.all_lists = true;
        let sums = parts.iter().map(|&k| vec![None; k]).collect();
        let forces = parts.iter().map(|&k| vec![None; k]).collect();
        let figures = parts.iter().map(|&k| vec![None; k]).collect();
        let ids = bodies.iter().map(|b| b.def.id).collect();
        let budget = bodies
            .iter()
            .filter(|b| b.def.contact)
            .map(|b| contact.step_budget(b))
            .fold(0.0, f64::max);
        // 1 % below the exact bound: the distances are rounded
        let trigger = 0.99 * (split.skin - budget);
        let export = exports(&split);
        let inner = split
            .splits
            .iter()
            .map(|s| {
                s.parts
                    .iter()
                    .map(|p| p.body.chunks_within(p.owned))
                    .collect()
            })
            .collect();
        Ok(Self {
            split,
            ids,
            sums,
            forces,
            pending: None,
            export,
            figures,
            speeds: parts.iter().map(|&k| vec![None; k]).collect(),
            due: contact.enabled,
            sent_full: false,
            rebuild: false,
            trigger,
            mass: bodies
                .iter()
                .map(|b| {
                    let m = b.total_mass();
                    (m, Momentum::scale(m))
                })
                .collect(),
            far_bound: parts.iter().map(|&k| vec![0.0; k]).collect(),
            bound_build: 0,
            inner,
            early: parts
                .iter()
                .map(|&k| (0..k).map(|_| None).collect())
                .collect(),
        })
    }

    pub(super) fn mine(&self, i: usize, q: usize) -> bool {
        self.split.mine[i][q]
    }

    /// A contact pass is pending (`forces` ran, `contact` not yet): integrating or
    /// assembling now would read stale contact forces.
    pub fn contact_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// The holder of every part (`holder[i][q]`, as the split's spec gives it): only
    /// what a part on another holder reads is exported.
    pub fn with_holders(mut self, holder: Vec<Vec<u32>>) -> Self {
        self.split.holder = holder;
        self.export = exports(&self.split);
        self
    }

    /// Phase 1: integrate the owned nodes of the parts computed here over the step of
    /// length h from `clock`; their states for the other holders. The pending contact
    /// pass, if any, must have run (`contact`).
    pub fn integrate(&mut self, clock: &Clock, h: f64) -> Result<Vec<PartState>, Fault> {
        // chunks computed early for a step that never got its forces are stale
        for e in self.early.iter_mut().flatten() {
            *e = None;
        }
        let sc = clock.step_of(h);
        let gravity = self.split.gravity;
        let full = self.due;
        // the views were built since the last integration: the bounds start again
        let fresh = self.bound_build != self.split.builds;
        self.bound_build = self.split.builds;
        let mut out = Vec::new();
        for (i, s) in self.split.splits.iter_mut().enumerate() {
            let contact = self.split.whole[i].def.contact;
            let reference = self.split.reference.get(i);
            // the momentum only where the closing speed reads it
            let scale = self.mass[i].1;
            let closing = contact
                && self.split.contact.enabled
                && self.split.contact.speed_rule == crate::contact::SpeedRule::LimitDt;
            // every part of the body, then the fault one process would name
            let mut fault = None;
            // a body in one part is the whole body (the momentum's scale is its mass)
            let single = s.parts.len() == 1;
            for (q, p) in s.parts.iter_mut().enumerate() {
                self.sums[i][q] = None;
                self.figures[i][q] = None;
                self.speeds[i][q] = None;
                if !self.split.mine[i][q] {
                    continue;
                }
                // a part that is its whole body (a floor's spheres) takes its momentum
                // and velocity boxes in the node loop, as a whole group's bodies do: the
                // same values (an integer sum; boxes per chunk) without two more passes
                let whole = single && p.body.def.halo_nodes == 0;
                let integrated = if closing && whole {
                    p.body.integrate_with_figures(&sc, gravity)
                } else {
                    p.body.integrate(&sc, gravity).map(|n| (n, None))
                };
                let (n, taken) = match integrated {
                    Ok(n) => n,
                    Err(f) => {
                        fault = Some(Fault::first_of(fault, node_in_whole(f, &p.node)));
                        continue;
                    }
                };
                let st = &p.body.state;
                let o = p.owned;
                // the integration's box is the owned nodes' (it skips the halo)
                let (lo, hi) = (n.lo, n.hi);
                // the largest distance from the views' positions only when the bound
                // (the last one plus this step's largest move: the triangle
                // inequality) comes near the trigger; below it, the bound is
                // sent: the rule `far > trigger` reads the same either way
                let bound = if fresh {
                    n.max_move
                } else {
                    self.far_bound[i][q] + n.max_move
                };
                let far = match reference {
                    Some(r) if contact && near_trigger(bound, self.trigger) => p.node[..o]
                        .iter()
                        .zip(&st.x[..o])
                        .map(|(&g, x)| (x - r[g as usize]).norm_squared())
                        .fold(0.0, |a: f64, d| if d > a || d.is_nan() { d } else { a })
                        // sqrt is monotone and correctly rounded: the largest distance
                        .sqrt(),
                    Some(_) if contact => bound,
                    _ => 0.0,
                };
                self.far_bound[i][q] = far;
                let ex = &self.export[i][q];
                let pick = |a: &[Vec3], all: bool| -> Vec<Vec3> {
                    if all {
                        a[..o].to_vec()
                    } else {
                        ex.iter().map(|&k| a[k as usize]).collect()
                    }
                };
                let fig = PartFigures {
                    lo,
                    hi,
                    far,
                    max_move: n.max_move,
                    max_move_node: p.node[n.max_move_node],
                    momentum: match &taken {
                        Some(t) if closing => t.momentum,
                        _ if closing => Momentum::of(&st.v[..o], &p.body.def.mass[..o], scale),
                        _ => Momentum::default(),
                    },
                };
                self.speeds[i][q] = taken.map(|t| t.speeds);
                out.push(PartState {
                    id: self.ids[i],
                    part: q as u32,
                    x: pick(&st.x, full),
                    v: pick(&st.v, full),
                    w: pick(&st.w, full),
                    lo,
                    hi,
                    far,
                    max_move: fig.max_move,
                    max_move_node: fig.max_move_node,
                    momentum: fig.momentum,
                });
                self.figures[i][q] = Some(fig);
                self.sums[i][q] = Some(n);
            }
            if let Some(f) = fault {
                return Err(f);
            }
        }
        self.sent_full = full;
        Ok(out)
    }

    /// Phase 2: take the other holders' part states (`imports`: every part not computed
    /// here, each once), check the largest move of every body, copy the halos, element
    /// forces of the parts computed here, the global figures. `clock` is the clock
    /// before the step of length h; `reactions`: report the supports' reactions.
    /// Returns the share of each body's report from the parts here (bodies with no
    /// part here: none; the stable step is the element step of the parts here limited
    /// by the contact, so the minimum over the shares is the body's), and each body's
    /// smallest element step over the parts here. Leaves the contact pass pending.
    pub fn forces(
        &mut self,
        imports: &[PartState],
        clock: &Clock,
        h: f64,
        reactions: bool,
    ) -> Result<(Vec<BodyReport>, SplitFigures), SplitError> {
        if self.pending.is_some() {
            return Err(CoreError::Other {
                body: "split group".into(),
                what: "a step's element forces before the last contact pass".into(),
            }
            .into());
        }
        let step = clock.after(h).step;
        let mut got = self.figures.clone();
        for p in imports {
            let bad = |what: &str| CoreError::Other {
                body: format!("body {}", p.id),
                what: format!("part {}: {what}", p.part),
            };
            let i = self
                .ids
                .iter()
                .position(|&id| id == p.id)
                .ok_or_else(|| bad("not in this split group"))?;
            let q = p.part as usize;
            if q >= got[i].len() || self.mine(i, q) || got[i][q].is_some() {
                return Err(bad("not expected here, or twice").into());
            }
            let part = &mut self.split.splits[i].parts[q];
            let (o, ex) = (part.owned, &self.export[i][q]);
            if self.sent_full && p.x.len() != o {
                return Err(bad("every owned node expected (a view build)").into());
            }
            let st = &mut part.body.state;
            for (to, from) in [(&mut st.x, &p.x), (&mut st.v, &p.v), (&mut st.w, &p.w)] {
                if from.len() == o {
                    to[..o].copy_from_slice(from);
                } else if from.len() == ex.len() {
                    for (&k, y) in ex.iter().zip(from) {
                        to[k as usize] = *y;
                    }
                } else {
                    return Err(bad("wrong node count").into());
                }
            }
            got[i][q] = Some(PartFigures {
                lo: p.lo,
                hi: p.hi,
                far: p.far,
                max_move: p.max_move,
                max_move_node: p.max_move_node,
                momentum: p.momentum,
            });
        }
        let got: Vec<Vec<PartFigures>> = got
            .into_iter()
            .enumerate()
            .map(|(i, g)| {
                g.into_iter()
                    .enumerate()
                    .map(|(q, f)| {
                        f.ok_or_else(|| CoreError::Other {
                            body: format!("body {}", self.ids[i]),
                            what: format!("part {q} neither computed here nor imported"),
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()
            })
            .collect::<Result<_, _>>()?;
        // the largest move of each body over all parts (ties: the lowest node)
        let mut moves = Vec::with_capacity(self.ids.len());
        for g in &got {
            let mut m = (0.0f64, u32::MAX);
            for f in g {
                let this = (f.max_move, f.max_move_node);
                if this.0 > m.0 || (this.0 == m.0 && this.1 < m.1) {
                    m = this;
                }
            }
            moves.push((m.0, if m.1 == u32::MAX { 0 } else { m.1 as usize }));
        }
        check_moves(&self.split.whole, &self.split.contact, &moves, h, step)?;
        if self.sent_full {
            // every node arrived: the whole bodies for the view build of the pending pass
            self.split.gather_whole();
            self.rebuild = true;
            self.due = false;
        } else {
            let far = got
                .iter()
                .zip(&self.split.whole)
                .filter(|(_, b)| b.def.contact)
                .flat_map(|(g, _)| g.iter().map(|f| f.far))
                .fold(0.0, |a: f64, d| if d > a || d.is_nan() { d } else { a });
            // NaN: a fault is found elsewhere; build anyway
            self.due = far > self.trigger || far.is_nan();
        }
        let mut out = vec![None; self.ids.len()];
        for (i, s) in self.split.splits.iter_mut().enumerate() {
            for (q, m) in self.split.mine[i].iter().enumerate() {
                if *m {
                    s.exchange_into(q);
                }
            }
            let mut fault = None;
            for (q, p) in s.parts.iter_mut().enumerate() {
                self.forces[i][q] = None;
                if !self.split.mine[i][q] {
                    continue;
                }
                // the chunks computed while the other holders' states travelled
                let done = match self.early[i][q].take() {
                    Some((at, done)) if at == step => done,
                    _ => p.body.no_chunks(),
                };
                let f = match p.body.finish_forces(h, done, step) {
                    Ok(f) => f,
                    Err(f) => {
                        fault = Some(Fault::first_of(fault, element_in_whole(f, &p.element)));
                        continue;
                    }
                };
                let d = PartDt {
                    id: self.ids[i],
                    dt: f.dt,
                    element: p.element.get(f.dt_element).copied().unwrap_or(0),
                };
                out[i] = Some(out[i].map_or(d, |o: PartDt| o.min(d)));
                self.forces[i][q] = Some(f);
            }
            if let Some(f) = fault {
                return Err(f.into());
            }
        }
        let local: Vec<f64> = out
            .iter()
            .map(|d| d.map_or(f64::INFINITY, |d| d.dt))
            .collect();
        let bounds: Vec<(Vec3, Vec3)> = got
            .iter()
            .map(|g| {
                g.iter().fold(crate::mesh::bounds(&[]), |(lo, hi), f| {
                    (lo.inf(&f.lo), hi.sup(&f.hi))
                })
            })
            .collect();
        let (limit, pairs) = self.split.pair_limits(&local, &bounds);
        let means: Vec<Vec3> = got
            .iter()
            .zip(&self.mass)
            .map(|(g, &(m, scale))| {
                let p = g.iter().fold(Momentum::default(), |a, f| a + f.momentum);
                p.mean(m, scale)
            })
            .collect();
        let speeds = pair_speeds(&self.split, &pairs, &means, &self.speeds);
        let mut shares = Vec::new();
        for (i, s) in self.split.splits.iter().enumerate() {
            let mut r: Option<BodyReport> = None;
            let mut reaction: Option<Reaction> = None;
            for (q, p) in s.parts.iter().enumerate() {
                let (Some(n), Some(f)) = (&self.sums[i][q], &self.forces[i][q]) else {
                    continue;
                };
                let hot = p.element.get(f.hot_element).copied().unwrap_or(0) as usize;
                let share = BodyReport {
                    id: self.ids[i],
                    energy: p.body.state.energy,
                    stable_dt: limit[i],
                    dt_element: out[i].map_or(0, |d| d.element as usize),
                    lo: n.lo,
                    hi: n.hi,
                    max_move: n.max_move,
                    hot_element: hot,
                    hot_density: f.hot_density,
                    reaction: None,
                };
                if reactions && p.body.def.fixed.iter().any(|&m| m != 0) {
                    let add = Reaction {
                        force: n.reaction_force,
                        moment: n.reaction_moment,
                        moment_origin: n.reaction_moment_origin,
                    };
                    reaction = Some(reaction.map_or(add, |a| add_reaction(a, add)));
                }
                r = Some(match r {
                    None => share,
                    Some(a) => merge_report(a, share),
                });
            }
            if let Some(mut r) = r {
                if reactions {
                    r.reaction = reaction;
                }
                shares.push(r);
            }
        }
        self.pending = Some(Pending { h, step, bounds });
        let figures = SplitFigures {
            dts: out.into_iter().flatten().collect(),
            pairs: speeds,
        };
        Ok((shares, figures))
    }

    /// The pending contact pass (left by `forces`) on the views of the parts here, with
    /// each body's element step over all holders (`dt`, in the group's body order).
    /// Returns the step limits the pass set on the group's bodies here (the segment
    /// pass's stiffening step, by body id; none under the node passes, whose limits
    /// `forces` gave): the minimum over the holders is the whole group's.
    pub fn contact(&mut self, figures: &SplitFigures) -> Result<Vec<(u32, f64)>, SplitError> {
        let dt = &figures.dts;
        if dt.len() != self.ids.len() || dt.iter().zip(&self.ids).any(|(d, &id)| d.id != id) {
            return Err(CoreError::Other {
                body: "split group".into(),
                what: "element steps for other bodies than the group's".into(),
            }
            .into());
        }
        let Some(p) = self.pending.take() else {
            return Err(CoreError::Other {
                body: "split group".into(),
                what: "no contact pass pending".into(),
            }
            .into());
        };
        let edt: Vec<f64> = dt.iter().map(|d| d.dt).collect();
        let rebuild = std::mem::take(&mut self.rebuild);
        if self.split.views.is_empty() && !rebuild && self.split.contact.enabled {
            return Err(CoreError::Other {
                body: "split group".into(),
                what: "contact views to build without the whole bodies".into(),
            }
            .into());
        }
        let (rebuilt, limits) =
            self.split
                .views_pass(&edt, &figures.closing(), &p.bounds, p.h, p.step, rebuild)?;
        if rebuilt {
            self.export = exports(&self.split);
        }
        Ok(self
            .ids
            .iter()
            .zip(limits)
            .filter(|(_, l)| l.is_finite())
            .map(|(&id, l)| (id, l))
            .collect())
    }
}
