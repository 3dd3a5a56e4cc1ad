//! Groups shown to users: rows for groups.csv (who computes what, how long it took),
//! the worker and group of every body in the frames, and log lines when groups merge,
//! split or move, naming bodies by name.

use super::{GroupLayout, Master};
use crate::error::MasterError;
use crate::sink::{GroupRow, Sink};
use crash_io::Placement;
use crash_link::{escape_peer, WorkerLink};
use std::collections::BTreeMap;

impl<L: WorkerLink> Master<'_, L> {
    /// Who computes group `g` (its ids in MEIM order): (worker, bodies, elements). One
    /// entry for a whole group; for a group within a split group (the split itself, or
    /// bodies that left it while it is kept: `time_loop`) one per holder with elements
    /// of it, with the bodies that have elements there and the elements its parts own.
    pub(super) fn group_shares(&self, g: &[u32]) -> Vec<(usize, Vec<u32>, usize)> {
        if let Some(s) = self.split_holding(g) {
            let shares: Vec<_> = s
                .shares(g)
                .into_iter()
                .filter(|(_, ids, _)| !ids.is_empty())
                .collect();
            if !shares.is_empty() {
                return shares;
            }
        }
        let idx: Vec<usize> = g.iter().filter_map(|&id| self.index(id)).collect();
        let worker = idx.first().and_then(|&i| self.worker_of[i]).unwrap_or(0);
        let elements = idx.iter().map(|&i| self.info[i].elements).sum();
        vec![(worker, g.to_vec(), elements)]
    }

    /// The split group whose bodies include all of `g` (the split itself, or bodies
    /// that left it while it is kept).
    fn split_holding(&self, g: &[u32]) -> Option<&super::split::SplitGroup> {
        self.splits.iter().find(|s| g.iter().all(|&id| s.has(id)))
    }

    /// The current MEIM groups as rows (a split group: one row per holder).
    pub(super) fn group_rows(&self) -> Vec<GroupRow> {
        let mut rows = Vec::new();
        for g in self.meim.groups() {
            let first = g.first().copied().unwrap_or(0);
            let split = self.split_holding(g).and_then(|s| s.ids().first().copied());
            for (worker, ids, elements) in self.group_shares(g) {
                rows.push(GroupRow {
                    group: first,
                    bodies: ids.iter().map(|&id| self.name(id).to_string()).collect(),
                    worker,
                    elements,
                    step_ns: self.step_ns(first, worker, split),
                });
            }
        }
        rows
    }

    /// The last step's compute time of the worker group that computes MEIM group
    /// `first` on `worker`: within a split group (`split`: its first id), that holder's
    /// time for its parts, which compute every group of the split together.
    fn step_ns(&self, first: u32, worker: usize, split: Option<u32>) -> u64 {
        let held = split.and_then(|sf| {
            self.split_ns
                .iter()
                .find(|&&(w, f, _)| w == worker && f == sf)
                .map(|&(_, _, ns)| ns)
        });
        held.or_else(|| {
            self.index(first)
                .and_then(|i| self.group_ns.get(i))
                .copied()
        })
        .unwrap_or(0)
    }

    /// Hand the group rows to the sink (once per step).
    pub(super) fn write_groups(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        if self.groups_step == Some(self.clock.step) {
            return Ok(());
        }
        self.groups_step = Some(self.clock.step);
        let rows = self.group_rows();
        sink.groups(self.clock.step, self.clock.time, &rows)
            .map_err(MasterError::sink)
    }

    /// The worker and group of body `id` now, for its frame.
    pub(super) fn placement_of(&self, id: u32) -> Option<Placement> {
        let i = self.index(id)?;
        let k = self.meim.group_of(id)?;
        Some(Placement {
            worker: self.worker_of[i]? as u32,
            group: self.meim.group(k).first().copied()?,
        })
    }

    /// Log the bodies of each split group that are out of its largest MEIM group (they
    /// left it; the split is kept: `time_loop`).
    pub(super) fn log_kept_splits(&self) {
        const SHOWN: usize = 8;
        for s in &self.splits {
            let mut members: BTreeMap<usize, usize> = BTreeMap::new();
            for &id in s.ids() {
                if let Some(k) = self.meim.group_of(id) {
                    *members.entry(k).or_default() += 1;
                }
            }
            // the most members, ties to the lowest group
            let Some((k, _)) = members.iter().rev().max_by_key(|(_, &n)| n) else {
                continue;
            };
            let core = self.meim.group(*k);
            let out: Vec<u32> = s
                .ids()
                .iter()
                .copied()
                .filter(|id| !core.contains(id))
                .collect();
            let more = match out.len().saturating_sub(SHOWN) {
                0 => String::new(),
                n => format!(" and {n} more"),
            };
            tracing::info!(
                "step {}: {}{more} out of contact with the split group of {}; the split is kept (every contact is still within the groups the workers hold)",
                self.clock.step,
                self.names_of(&out[..out.len().min(SHOWN)]),
                escape_peer(self.name(core.first().copied().unwrap_or(0))),
            );
        }
    }

    fn names_of(&self, ids: &[u32]) -> String {
        let names: Vec<String> = ids.iter().map(|&id| escape_peer(self.name(id))).collect();
        format!("[{}]", names.join(", "))
    }

    /// Log (tracing info) the merges, splits and moves from the layout `old` to `new`.
    pub(super) fn log_group_changes(&self, old: &[Vec<GroupLayout>], new: &[Vec<GroupLayout>]) {
        let groups = |lay: &[Vec<GroupLayout>]| -> Vec<(Vec<u32>, usize)> {
            let mut out: Vec<(Vec<u32>, usize)> = lay
                .iter()
                .enumerate()
                .flat_map(|(w, gs)| gs.iter().map(move |g| (g.0.clone(), w)))
                .collect();
            out.sort();
            out
        };
        let (old, new) = (groups(old), groups(new));
        let of = |gs: &[(Vec<u32>, usize)]| -> BTreeMap<u32, usize> {
            gs.iter()
                .enumerate()
                .flat_map(|(k, g)| g.0.iter().map(move |&id| (id, k)))
                .collect()
        };
        let (old_of, new_of) = (of(&old), of(&new));
        let step = self.clock.step;
        for (members, w) in &new {
            let mut from: Vec<usize> = members
                .iter()
                .filter_map(|id| old_of.get(id).copied())
                .collect();
            from.sort_unstable();
            from.dedup();
            if from.len() > 1 {
                let parts: Vec<String> = from.iter().map(|&k| self.names_of(&old[k].0)).collect();
                tracing::info!(
                    "step {step}: groups {} merged into {} on worker {w}",
                    parts.join(" + "),
                    self.names_of(members)
                );
            } else if let Some(&k) = from.first() {
                if old[k].0 == *members && old[k].1 != *w {
                    tracing::info!(
                        "step {step}: group {} moved from worker {} to worker {w}",
                        self.names_of(members),
                        old[k].1
                    );
                }
            }
        }
        for (members, _) in &old {
            let mut to: Vec<usize> = members
                .iter()
                .filter_map(|id| new_of.get(id).copied())
                .collect();
            to.sort_unstable();
            to.dedup();
            if to.len() > 1 {
                let parts: Vec<String> = to
                    .iter()
                    .map(|&k| format!("{} (worker {})", self.names_of(&new[k].0), new[k].1))
                    .collect();
                tracing::info!(
                    "step {step}: group {} split into {}",
                    self.names_of(members),
                    parts.join(" + ")
                );
            }
        }
    }
}
