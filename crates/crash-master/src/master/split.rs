//! Groups split over workers (issue 16 point 2): which groups are split and how, and
//! the assembly of whole bodies for frames, checkpoints and merging back (after the
//! contact pass the last step left pending: a `Contact` with the element steps kept).
//! The second half of a split step (the halo, direct or relayed) is halo.rs.
//!
//! A group is split when its estimated cost exceeds the fair share (total / live
//! workers) by the balance tolerance (`SplitMode::Auto`), or whenever there are two
//! workers (`SplitMode::Always`, for tests), and only when it holds no kinematic body
//! or copy and no history node is asked for (their figures are not merged yet); under
//! the segment pass its contact pass runs in the step (`contact_in_step`). Each
//! body whose cost exceeds the group's cost over the workers is cut into one part per
//! live worker (part q on slot q); when none is, a group's largest body carrying at
//! least half the share (a floor under many bodies) is cut so. The smaller bodies stay
//! whole, each on the slot of the cut largest body's region it lies on (else the least
//! loaded slot so far), unless that would load the slot more than 5 % above the share:
//! then the least loaded slot, or they are cut too. Slot 0 is the group's worker (its
//! *home*): it answers for the bodies (frames, states) from the whole bodies it
//! assembles.

use super::Master;
use crate::error::MasterError;
use crate::input::SplitMode;
use crash_core::contact::{BodyBox, ContactPass};
use crash_core::partition::{longest_axis, partition_body};
use crash_core::Vec3;
use crash_io::PartCells;
use crash_link::{BodyLoad, Command, Reply, SplitSpec, StepReport, WorkerLink};
use std::collections::BTreeMap;

/// How far above its share a slot of a split group may be loaded by a body placed
/// whole before that body is cut too (cutting costs a halo and contact views: a few
/// per cent of the body's work).
const CUT_TOLERANCE: f64 = 0.05;

/// A group's largest body is cut (placing the others by region) when no body exceeds
/// the share and it carries at least this fraction of it: a floor under many bodies.
const FLOOR_SHARE: f64 = 0.5;

/// The box `lo`..`hi` cut into `k` regions as `partition::bisect` cuts a body of
/// uniform density: each cut normal to the longest side, k / 2 parts' share below it.
/// Region q approximates part q of a body with that box (the placement only needs
/// which part a body lies on, not the exact cut: any placement gives the same bits).
fn regions(lo: Vec3, hi: Vec3, k: usize) -> Vec<(Vec3, Vec3)> {
    if k <= 1 {
        return vec![(lo, hi)];
    }
    let ext = hi - lo;
    let axis = longest_axis(&ext);
    let kl = k / 2;
    let (mut mid_hi, mut mid_lo) = (hi, lo);
    mid_hi[axis] = lo[axis] + ext[axis] * kl as f64 / k as f64;
    mid_lo[axis] = mid_hi[axis];
    let mut out = regions(lo, mid_hi, kl);
    out.extend(regions(mid_lo, hi, k - kl));
    out
}

/// The region nearest to `p` (distance to its box; the first on ties).
fn nearest(regions: &[(Vec3, Vec3)], p: &Vec3) -> usize {
    let d = |(lo, hi): &(Vec3, Vec3)| (p - p.sup(lo).inf(hi)).norm();
    (0..regions.len()).fold(0, |a, b| {
        if d(&regions[b]) < d(&regions[a]) {
            b
        } else {
            a
        }
    })
}

/// A group split over workers.
#[derive(Debug, Clone)]
pub(crate) struct SplitGroup {
    /// Bodies, part counts, the slot of each part (as in `SplitSpec`).
    pub(super) ids: Vec<u32>,
    parts: Vec<u32>,
    holder: Vec<Vec<u32>>,
    /// Worker of each slot; slot 0 is the home.
    pub(super) workers: Vec<usize>,
    /// Where each slot's worker takes direct halo connections (empty: nowhere).
    peers: Vec<String>,
    /// The worker and part of each element of each body (the frames' cell fields).
    cells: BTreeMap<u32, PartCells>,
    /// The place of each body in `ids` (a group of thousands of bodies is looked up per
    /// body and per pair).
    place: BTreeMap<u32, usize>,
}

impl SplitGroup {
    fn spec(&self, slot: usize) -> SplitSpec {
        SplitSpec {
            ids: self.ids.clone(),
            parts: self.parts.clone(),
            holder: self.holder.clone(),
            slot: slot as u32,
            workers: self.workers.iter().map(|&w| w as u32).collect(),
            peers: self.peers.clone(),
        }
    }

    /// Every holder takes direct halo connections.
    pub(super) fn direct(&self) -> bool {
        self.peers.iter().all(|p| !p.is_empty())
    }

    /// The group's bodies, in MEIM order.
    pub(super) fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// Whether body `id` is in the group.
    pub(super) fn has(&self, id: u32) -> bool {
        self.place.contains_key(&id)
    }

    /// Per holder (slot order): its worker, the bodies of `g` (bodies of this group)
    /// with elements there and how many (empty before the cells are known).
    pub(super) fn shares(&self, g: &[u32]) -> Vec<(usize, Vec<u32>, usize)> {
        if self.cells.is_empty() {
            return Vec::new();
        }
        self.workers
            .iter()
            .map(|&w| {
                let mut ids = Vec::new();
                let mut elements = 0;
                for (&id, c) in self.cells.iter().filter(|(id, _)| g.contains(id)) {
                    let k = c.worker.iter().filter(|&&x| x as usize == w).count();
                    if k > 0 {
                        ids.push(id);
                        elements += k;
                    }
                }
                (w, ids, elements)
            })
            .collect()
    }

    pub(super) fn home(&self) -> usize {
        self.workers[0]
    }

    /// The part of each element of the bodies (cut as every holder cuts them:
    /// `partition_body` is deterministic) and the worker holding it.
    fn cells_of(&self, bodies: &[BodyLoad]) -> BTreeMap<u32, PartCells> {
        let mut out = BTreeMap::new();
        for b in bodies {
            let (Some(&i), Some(def)) = (self.place.get(&b.id), &b.def) else {
                continue;
            };
            let part = match self.parts[i] {
                1 => vec![0; def.element_count()],
                k => match partition_body(def, k as usize) {
                    Ok(p) => p.part_of,
                    // the holders refuse the same cut; nothing to show
                    Err(_) => continue,
                },
            };
            let worker = part
                .iter()
                .map(|&q| {
                    let slot = self.holder[i].get(q as usize).copied().unwrap_or(0);
                    self.workers.get(slot as usize).copied().unwrap_or(0) as u32
                })
                .collect();
            out.insert(b.id, PartCells { worker, part });
        }
        out
    }
}

impl<L: WorkerLink> Master<'_, L> {
    /// Body `id`'s node box of the last report (None before any).
    fn box_of_id(&self, id: u32) -> Option<(Vec3, Vec3)> {
        let r = self.reports.get(self.index(id)?)?;
        (r.id == id && r.lo.iter().chain(r.hi.iter()).all(|x| x.is_finite()))
            .then_some((r.lo, r.hi))
    }

    /// The split of the group `ids` over the live workers (home first), or None when
    /// the rule leaves it whole. `boxes` gives a body's node box by id (the last
    /// reports', or at the start the briefs').
    fn plan(
        &self,
        ids: &[u32],
        copies: &[u32],
        total: f64,
        live: &[usize],
        boxes: &dyn Fn(u32) -> Option<(Vec3, Vec3)>,
    ) -> Option<SplitGroup> {
        let k = live.len();
        // (RunInput::groups_may_split is the scene-wide form of these refusals: keep
        // the two together)
        if k < 2 || !copies.is_empty() || !self.results.history.is_empty() {
            return None;
        }
        let idx: Vec<usize> = ids.iter().filter_map(|&id| self.index(id)).collect();
        if idx.len() != ids.len() || idx.iter().any(|&i| self.info[i].kinematic) {
            return None;
        }
        let cost: f64 = idx.iter().map(|&i| self.cost[i]).sum();
        let fair = total / k as f64;
        let large = match self.opts.split {
            SplitMode::Off => false,
            SplitMode::Auto => cost > fair * (1.0 + self.opts.balance_tolerance),
            SplitMode::Always => true,
        };
        if !large {
            return None;
        }
        let home = self.worker_of[idx[0]]?;
        let mut workers = vec![home];
        workers.extend(live.iter().copied().filter(|&w| w != home));
        let share = cost / k as f64;
        let mut load = vec![0.0; k];
        let (mut parts, mut holder) = (vec![1u32; idx.len()], vec![Vec::new(); idx.len()]);
        // the bodies above the share are cut first, one part per slot; then each other
        // body goes whole to the least loaded slot, unless that slot would exceed the
        // share by more than CUT_TOLERANCE: then it is cut too (the showcase: the sphere
        // in 2, then the plate, which would load one slot 1.19x the share, in 2)
        let cut = |c: f64, elements: usize| elements >= k && c > share;
        for (b, &i) in idx.iter().enumerate() {
            if cut(self.cost[i], self.info[i].elements) {
                parts[b] = k as u32;
                holder[b] = (0..k as u32).collect();
                for l in &mut load {
                    *l += self.cost[i] / k as f64;
                }
            }
        }
        // a floor under many bodies (no body above the share, the largest at least half
        // of it): cut the floor, so that each slot holds a region with what lies on it
        let largest = (0..idx.len()).fold(0, |a, b| {
            if self.cost[idx[b]] > self.cost[idx[a]] {
                b
            } else {
                a
            }
        });
        let li = idx[largest];
        if parts.iter().all(|&p| p == 1)
            && idx.len() > k
            && self.cost[li] >= FLOOR_SHARE * share
            && self.info[li].elements >= k
        {
            parts[largest] = k as u32;
            holder[largest] = (0..k as u32).collect();
            for l in &mut load {
                *l += self.cost[li] / k as f64;
            }
        }
        // the regions of the largest cut body's parts (its box cut as the parts are),
        // for placing the whole bodies near the part they lie on
        let regions = (parts[largest] > 1)
            .then(|| boxes(ids[largest]))
            .flatten()
            .map(|(lo, hi)| regions(lo, hi, k));
        for (b, &i) in idx.iter().enumerate() {
            let c = self.cost[i];
            if parts[b] > 1 {
                continue;
            }
            let least = (0..k).fold(0, |a, b| if load[b] < load[a] { b } else { a });
            let fits = |s: usize| load[s] + c <= share * (1.0 + CUT_TOLERANCE);
            let near = regions
                .as_ref()
                .zip(boxes(ids[b]))
                .map(|(r, (lo, hi))| nearest(r, &(0.5 * (lo + hi))))
                .filter(|&s| fits(s));
            let s = near.unwrap_or(least);
            if !fits(s) && self.info[i].elements >= k {
                parts[b] = k as u32;
                holder[b] = (0..k as u32).collect();
                for l in &mut load {
                    *l += c / k as f64;
                }
            } else {
                load[s] += c;
                holder[b] = vec![s as u32];
            }
        }
        if parts.iter().all(|&p| p == 1) && holder.iter().all(|h| h[0] == 0) {
            return None;
        }
        Some(SplitGroup {
            place: ids.iter().enumerate().map(|(i, &id)| (id, i)).collect(),
            ids: ids.to_vec(),
            parts,
            holder,
            peers: workers
                .iter()
                .map(|&w| self.links[w].halo_address().unwrap_or_default())
                .collect(),
            workers,
            cells: BTreeMap::new(),
        })
    }

    /// The splits the rule picks at the start, planned before the bodies are loaded
    /// (from the briefs' boxes): every holder is loaded with the group and starts it,
    /// so the split needs no bodies relayed (`split_groups`).
    pub(super) fn plan_at_start(&mut self, boxes: &[BodyBox]) {
        let nw = self.links.len();
        if self.opts.split == SplitMode::Off {
            return;
        }
        let live: Vec<usize> = (0..nw).filter(|&w| self.live[w]).collect();
        let total: f64 = self.cost.iter().sum();
        // the briefs are in body order, as `info`
        let brief = |id: u32| {
            let b = boxes.get(self.index(id)?)?;
            (b.id == id).then_some((b.lo, b.hi))
        };
        let plans: Vec<SplitGroup> = (0..self.meim.group_count())
            .filter_map(|k| {
                let (ids, copies) = (self.meim.group(k), self.meim.copies(k));
                self.plan(ids, copies, total, &live, &brief)
            })
            .collect();
        self.planned = plans;
    }

    /// The groups worker `w` holds beside its own until the planned splits are made
    /// (it holds parts of them, not their home).
    pub(super) fn shadows_of(&self, w: usize) -> impl Iterator<Item = &[u32]> + '_ {
        let held = move |p: &&SplitGroup| p.workers.iter().skip(1).any(|&x| x == w);
        self.planned.iter().filter(held).map(|p| &p.ids[..])
    }

    /// The planned split holding body `id`, by body id (`plan_at_start`).
    pub(super) fn planned_by_id(&self) -> BTreeMap<u32, usize> {
        let each = self.planned.iter().enumerate();
        each.flat_map(|(k, p)| p.ids.iter().map(move |&id| (id, k)))
            .collect()
    }

    /// What the master keeps of a body of planned split `k` as it goes to its holders
    /// (the worker of each slot but the home's: loaded with it too): its skeleton
    /// (frames from the parts) and the part of each element.
    pub(super) fn keep_planned(&mut self, k: usize, load: &BodyLoad) -> Vec<usize> {
        let Some(p) = self.planned.get_mut(k) else {
            return Vec::new();
        };
        let cells = p.cells_of(std::slice::from_ref(load));
        p.cells.extend(cells);
        let others = p.workers[1..].to_vec();
        self.keep_skeletons(std::slice::from_ref(load));
        others
    }

    /// The Start reports without the groups a worker holds only until the planned
    /// split (their home reports them, with the same bits).
    pub(super) fn drop_shadows(&self, reps: &mut [StepReport]) {
        let planned = self.planned_by_id();
        for (k, p) in self.planned.iter().enumerate() {
            let shadow = |id: u32| planned.get(&id) == Some(&k);
            for &w in p.workers.iter().skip(1) {
                let Some(r) = reps.get_mut(w) else { continue };
                r.bodies.retain(|b| !shadow(b.id));
                r.groups.retain(|g| !shadow(g.first));
                r.contacts.retain(|c| !shadow(c.a) && !shadow(c.b));
                r.probes.retain(|n| !shadow(n.body));
            }
        }
    }

    /// Split the groups the rule picks (after the start and after every regroup).
    pub(crate) fn split_groups(&mut self) -> Result<(), MasterError> {
        if !self.planned.is_empty() {
            return self.split_planned();
        }
        if self.opts.split == SplitMode::Off || !self.splits.is_empty() {
            return Ok(());
        }
        let live: Vec<usize> = (0..self.links.len()).filter(|&w| self.live[w]).collect();
        let total: f64 = self.cost.iter().sum();
        let nw = self.links.len();
        for k in 0..self.meim.group_count() {
            let (ids, copies) = (self.meim.group(k).to_vec(), self.meim.copies(k).to_vec());
            let Some(plan) = self.plan(&ids, &copies, total, &live, &|id| self.box_of_id(id))
            else {
                continue;
            };
            let home = plan.home();
            let mut cmds = vec![Vec::new(); nw];
            cmds[home].push(Command::Split(plan.spec(0)));
            let Some(Reply::Unloaded(bodies)) = self.exchange(cmds)?.swap_remove(home).pop() else {
                return Err(self.bad_reply(home, "Split"));
            };
            self.keep_skeletons(&bodies);
            let mut plan = plan;
            plan.cells = plan.cells_of(&bodies);
            let mut cmds = vec![Vec::new(); nw];
            for (slot, &w) in plan.workers.iter().enumerate().skip(1) {
                cmds[w].push(Command::Share {
                    at: self.clock,
                    spec: plan.spec(slot),
                    bodies: bodies.clone(),
                });
            }
            self.expect_acks(cmds, "Share")?;
            self.announce_split(plan);
        }
        Ok(())
    }

    /// The splits planned at the start: every holder already holds the group at this
    /// clock (loaded and started with it), so each gets a `Share` without bodies and
    /// all build their parts at once.
    fn split_planned(&mut self) -> Result<(), MasterError> {
        let nw = self.links.len();
        let planned = std::mem::take(&mut self.planned);
        let mut cmds = vec![Vec::new(); nw];
        for plan in &planned {
            for (slot, &w) in plan.workers.iter().enumerate() {
                cmds[w].push(Command::Share {
                    at: self.clock,
                    spec: plan.spec(slot),
                    bodies: Vec::new(),
                });
            }
        }
        self.expect_acks(cmds, "Share")?;
        for plan in planned {
            self.announce_split(plan);
        }
        Ok(())
    }

    /// Log a split and keep it.
    fn announce_split(&mut self, plan: SplitGroup) {
        let cut: Vec<String> = plan
            .ids
            .iter()
            .zip(&plan.parts)
            .map(|(&id, &p)| format!("{} in {p}", self.name(id)))
            .collect();
        tracing::info!(
            "step {}: group of {} bodies split over workers {:?}: {}; {}",
            self.clock.step,
            plan.ids.len(),
            plan.workers,
            cut.join(", "),
            if plan.direct() && !self.direct_failed {
                "the workers exchange its halos directly"
            } else {
                "the master relays its halos"
            }
        );
        self.stats.splits += 1;
        self.splits.push(plan);
    }

    /// The worker and part of each element of body `id` when its group is split.
    pub(super) fn split_cells(&self, id: u32) -> Option<PartCells> {
        self.splits.iter().find_map(|s| s.cells.get(&id).cloned())
    }

    /// Run the contact pass the last step left pending on every holder, with the
    /// element steps kept from it (before the whole bodies are assembled); its
    /// statistics complete the held rows (held.rs).
    pub(super) fn flush_split_contact(&mut self) -> Result<(), MasterError> {
        if self.split_contact.is_empty() {
            return Ok(());
        }
        let mut reps = vec![StepReport::default(); self.links.len()];
        for (w, rep) in self.run_split_contact()? {
            reps[w].split_contacts.extend(rep.split_contacts);
        }
        self.take_split_stats(&mut reps)
    }

    /// Send every holder a `Contact` with the element steps the last step kept (the
    /// pending pass runs there); the reports by worker.
    fn run_split_contact(&mut self) -> Result<Vec<(usize, StepReport)>, MasterError> {
        let dts = std::mem::take(&mut self.split_contact);
        let cmds = self.to_holders(|| Command::Contact(dts.clone()));
        let mut out = Vec::new();
        for (w, r) in self.exchange(cmds)?.into_iter().enumerate() {
            for reply in r {
                let Reply::Report(rep) = reply else {
                    return Err(self.bad_reply(w, "Contact"));
                };
                out.push((w, rep));
            }
        }
        Ok(out)
    }

    /// Under the segment pass, the split groups' contact pass runs in the step, right
    /// after the Halo (a Contact with the element steps just merged), not at the start
    /// of the next Step: its stiffening step (docs/theory-contact.md, "Depth") limits
    /// the bodies' next step, which is chosen before that Step. Each holder reports the
    /// limit from the points its views count; the minimum over the holders goes into
    /// the body's merged report at its home (`reps`), the statistics into this step's
    /// rows (`split_now`). One more exchange per step: the price of the bits.
    pub(super) fn contact_in_step(&mut self, reps: &mut [StepReport]) -> Result<(), MasterError> {
        let in_step = self.contact.enabled && self.contact.pass == ContactPass::Segments;
        if !in_step || self.split_contact.is_empty() {
            return Ok(());
        }
        let mut shares = Vec::new();
        for (w, rep) in self.run_split_contact()? {
            for &(id, dt) in &rep.split_limits {
                if !self.holds_part(w, id) || dt.is_nan() || dt <= 0.0 {
                    let what = format!("a contact step limit of body {id}");
                    return Err(self.implausible(w, &what));
                }
                let home = self.split_home(id);
                let body = reps
                    .get_mut(home)
                    .and_then(|r| r.bodies.iter_mut().find(|b| b.id == id));
                if let Some(b) = body {
                    b.stable_dt = b.stable_dt.min(dt);
                }
            }
            if let Some(r) = reps.get_mut(w) {
                r.compute_ns += rep.compute_ns;
            }
            shares.push((w, rep.split_contacts));
        }
        self.split_now = Some(self.merged_split_shares(shares.into_iter())?);
        Ok(())
    }

    /// One command for every worker holding parts of a split group (none for the
    /// others).
    pub(super) fn to_holders(&self, make: impl Fn() -> Command) -> Vec<Vec<Command>> {
        let mut cmds: Vec<Vec<Command>> = vec![Vec::new(); self.links.len()];
        for s in &self.splits {
            for &w in &s.workers {
                if cmds[w].is_empty() {
                    cmds[w].push(make());
                }
            }
        }
        cmds
    }

    /// The home worker of split body `id`'s group (0 when it is in none).
    pub(super) fn split_home(&self, id: u32) -> usize {
        self.splits
            .iter()
            .find(|s| s.has(id))
            .map_or(0, |s| s.home())
    }

    /// Whether worker `w` holds parts of a split group.
    pub(super) fn holds_parts(&self, w: usize) -> bool {
        self.splits.iter().any(|s| s.workers.contains(&w))
    }

    /// Worker `w` computes parts of a split group holding body `id`.
    pub(super) fn holds_part(&self, w: usize, id: u32) -> bool {
        self.splits
            .iter()
            .any(|s| s.workers.contains(&w) && s.has(id))
    }

    /// Assemble the split groups' whole bodies at their homes (before a frame, a
    /// checkpoint or merging back).
    pub(super) fn assemble_splits(&mut self) -> Result<(), MasterError> {
        if self.splits.is_empty() {
            return Ok(());
        }
        self.flush_split_contact()?;
        let nw = self.links.len();
        let mut cmds: Vec<Vec<Command>> = vec![Vec::new(); nw];
        for s in &self.splits {
            for &w in &s.workers[1..] {
                if cmds[w].is_empty() {
                    cmds[w].push(Command::Parts);
                }
            }
        }
        let mut parts = Vec::new();
        for (w, r) in self.exchange(cmds)?.into_iter().enumerate() {
            for reply in r {
                let Reply::Parts(p) = reply else {
                    return Err(self.bad_reply(w, "Parts"));
                };
                parts.extend(p);
            }
        }
        let mut cmds: Vec<Vec<Command>> = vec![Vec::new(); nw];
        for s in &self.splits {
            let (these, rest): (Vec<_>, Vec<_>) = parts.into_iter().partition(|p| s.has(p.0));
            parts = rest;
            match cmds[s.home()].first_mut() {
                Some(Command::Assemble(a)) => a.extend(these),
                _ => cmds[s.home()].push(Command::Assemble(these)),
            }
        }
        self.expect_acks(cmds, "Assemble")
    }

    /// Merge every split group back onto its home (before a regroup).
    pub(super) fn unsplit(&mut self) -> Result<(), MasterError> {
        if self.splits.is_empty() {
            return Ok(());
        }
        self.assemble_splits()?;
        let cmds = self.to_holders(|| Command::Unsplit);
        self.expect_acks(cmds, "Unsplit")?;
        tracing::info!("step {}: split groups merged back", self.clock.step);
        self.splits.clear();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_cut_the_longest_side_as_the_bisection_shares_it() {
        let (lo, hi) = (Vec3::new(-3.0, -1.0, 0.0), Vec3::new(3.0, 1.0, 0.1));
        let r = regions(lo, hi, 3);
        // 3 parts: one third below the first cut (normal to x), then the rest in 2
        assert_eq!(r.len(), 3);
        assert_eq!((r[0].0.x, r[0].1.x), (-3.0, -1.0));
        assert_eq!((r[1].0.x, r[1].1.x, r[2].1.x), (-1.0, 1.0, 3.0));
        assert_eq!(nearest(&r, &Vec3::new(-2.5, 0.0, 0.5)), 0);
        assert_eq!(nearest(&r, &Vec3::new(0.5, 5.0, 0.0)), 1);
        assert_eq!(nearest(&r, &Vec3::new(9.0, 0.0, 0.0)), 2);
        assert_eq!(regions(lo, hi, 1), vec![(lo, hi)]);
    }
}
