//! The closing-speed step (`SpeedRule::LimitDt`) of a group split over workers, from
//! figures each holder computes on its own parts and the master merges, without any
//! node's velocity crossing the wire.
//!
//! A pair's closing speed is the smaller over u in {u_a, u_b} of max_a |v - u| +
//! max_b |v - u| (contact/sweep.rs), u_a and u_b the bodies' mean velocities. The means come
//! from momenta on a fixed quantum (`Momentum`: integer sums, so the parts' sums added
//! in any order are the whole body's bits): every part sends its momentum with its
//! state, and every holder forms the same means. The maxima over a holder's own nodes
//! travel to the master in the reply to the halo (`PairSpeed`), which takes the maximum
//! of each over the holders (order-free), turns them into each pair's step
//! (`PairSpeed::dt`, the one-process formula), limits the bodies' stable steps with
//! them, and sends the merged figures with the next step, whose contact pass reads
//! them. The figures are those one process computes, so the bits are the same in every
//! mode.

use super::contact::Closing;
use super::shared::PartDt;
use super::GroupSplit;
use crate::contact::speeds::SpeedBoxes;
use crate::contact::stage::{closing_dt_of, has_reference};
use crate::contact::sweep::closing_of;
use crate::contact::PenaltyKind;
use crate::Vec3;
use std::borrow::Cow;
use std::collections::BTreeMap;

/// A pair's closing-speed figures over some nodes of its bodies: the body ids (in the
/// group's pair order), the pair's mean thickness c = (t_a + t_b)/2, and the four maxima
/// of `contact::sweep::speed_maxima` over those nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairSpeed {
    pub a: u32,
    pub b: u32,
    pub c: f64,
    pub max: [f64; 4],
}

impl PairSpeed {
    /// Over the nodes of both (maxima: the same bits in any order).
    pub fn merge(self, o: PairSpeed) -> PairSpeed {
        PairSpeed {
            max: std::array::from_fn(|k| self.max[k].max(o.max[k])),
            ..self
        }
    }

    /// The pair's closing-speed step (None: the bodies do not close).
    pub fn dt(&self) -> Option<f64> {
        closing_dt_of(self.c, closing_of(self.max))
    }
}

/// What a split group's contact figures are between holders and master: each body's
/// smallest element step over some parts (its element), and each pair's closing-speed
/// figures. A holder reports those of its parts; the master sends the merged ones
/// (every part) with the next step, for the contact pass left pending.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SplitFigures {
    pub dts: Vec<PartDt>,
    pub pairs: Vec<PairSpeed>,
}

impl SplitFigures {
    pub fn is_empty(&self) -> bool {
        self.dts.is_empty() && self.pairs.is_empty()
    }

    /// Add another holder's figures: each body's element step the smaller (ties: the
    /// lower element), each pair's maxima the larger; bodies and pairs not yet here
    /// are appended. Min and max: the same result in any order.
    pub fn merge(&mut self, o: SplitFigures) {
        let me = std::mem::take(self);
        *self = SplitFigures::merge_all([me, o]);
    }

    /// Every holder's figures merged as `merge` one after the other would: each body
    /// and pair once, in the order of first appearance. By sorting positions (no map
    /// to build per call: the master merges every split step, on its critical path).
    pub fn merge_all(all: impl IntoIterator<Item = SplitFigures>) -> SplitFigures {
        let (mut dts, mut pairs) = (Vec::new(), Vec::new());
        for f in all {
            dts.extend(f.dts);
            pairs.extend(f.pairs);
        }
        SplitFigures {
            dts: fold_first_seen(dts, |d| d.id, PartDt::min),
            pairs: fold_first_seen(pairs, |p| (p.a, p.b), PairSpeed::merge),
        }
    }

    /// The closing-speed step of every pair, by body ids (the contact pass's `Closing`).
    pub(super) fn closing(&self) -> Closing {
        self.pairs.iter().map(|p| ((p.a, p.b), p.dt())).collect()
    }

    /// The closing-speed steps that limit the bodies' stable steps, as (body id, step):
    /// those of pairs whose `penalty` has a reference step from the merged element
    /// steps `dts` (the soft penalty skips a pair without one, as the one-process
    /// stage does).
    pub fn limits(&self, penalty: PenaltyKind) -> Vec<(u32, f64)> {
        // the first of each id, as a search in order would find (a stable sort keeps
        // each id's entries in order)
        let mut dts: Vec<(u32, f64)> = self.dts.iter().map(|d| (d.id, d.dt)).collect();
        dts.sort_by_key(|d| d.0);
        dts.dedup_by_key(|d| d.0);
        let dt_of = |id: u32| {
            dts.binary_search_by_key(&id, |d| d.0)
                .map_or(f64::INFINITY, |k| dts[k].1)
        };
        let mut out = Vec::new();
        for p in &self.pairs {
            if !has_reference(penalty, dt_of(p.a).min(dt_of(p.b))) {
                continue;
            }
            if let Some(d) = p.dt() {
                out.push((p.a, d));
                out.push((p.b, d));
            }
        }
        out
    }
}

/// `items` with those of equal key folded by `f` into the first (in order), kept in
/// the order of each key's first appearance.
fn fold_first_seen<T: Copy, K: Ord>(
    items: Vec<T>,
    key: impl Fn(&T) -> K,
    f: impl Fn(T, T) -> T,
) -> Vec<T> {
    let mut at: Vec<usize> = (0..items.len()).collect();
    // stable: equal keys keep their order of appearance
    at.sort_by_key(|&i| key(&items[i]));
    let mut firsts: Vec<(usize, T)> = Vec::with_capacity(items.len());
    let mut k = 0;
    while k < at.len() {
        let first = at[k];
        let mut v = items[first];
        k += 1;
        while k < at.len() && key(&items[at[k]]) == key(&items[first]) {
            v = f(v, items[at[k]]);
            k += 1;
        }
        firsts.push((first, v));
    }
    firsts.sort_unstable_by_key(|e| e.0);
    firsts.into_iter().map(|e| e.1).collect()
}

/// Each pair's closing-speed figures over the owned nodes of the parts computed here
/// (`split.mine`; pairs with no part here: none), relative to the bodies' mean
/// velocities `means`; `taken[i][q]`: part q of body i's velocity boxes when the
/// integration took them.
pub(super) fn pair_speeds(
    split: &GroupSplit,
    pairs: &[(usize, usize)],
    means: &[Vec3],
    taken: &[Vec<Option<SpeedBoxes>>],
) -> Vec<PairSpeed> {
    // the velocity boxes of each owned part here, and its largest speed relative to
    // its body's mean, once per pass (a floor's parts are in a pair with every body on
    // it)
    type Boxes<'a> = Vec<(&'a [Vec3], Cow<'a, SpeedBoxes>)>;
    let mut boxes: BTreeMap<usize, (Boxes, f64)> = BTreeMap::new();
    let mut out = Vec::new();
    for &(ia, ib) in pairs {
        let here = |i: usize| split.mine[i].iter().any(|&m| m);
        if !here(ia) && !here(ib) {
            continue;
        }
        for i in [ia, ib] {
            boxes.entry(i).or_insert_with(|| {
                let b: Boxes = split.splits[i]
                    .parts
                    .iter()
                    .zip(&split.mine[i])
                    .enumerate()
                    .filter(|(_, (_, &m))| m)
                    .map(|(q, (p, _))| {
                        let v = &p.body.state.v[..p.owned];
                        let given = taken.get(i).and_then(|t| t.get(q)).and_then(Option::as_ref);
                        (
                            v,
                            given.map_or_else(|| Cow::Owned(SpeedBoxes::of(v)), Cow::Borrowed),
                        )
                    })
                    .collect();
                let own = b
                    .iter()
                    .map(|(v, s)| s.max_speed(v, &means[i]))
                    .fold(0.0, f64::max);
                (b, own)
            });
        }
        let over = |i: usize, u: &Vec3| {
            boxes[&i]
                .0
                .iter()
                .map(|(v, b)| b.max_speed(v, u))
                .fold(0.0, f64::max)
        };
        let (a_ua, b_ub) = (boxes[&ia].1, boxes[&ib].1);
        let (a_ub, b_ua) = (over(ia, &means[ib]), over(ib, &means[ia]));
        let (a, b) = (&split.whole[ia].def, &split.whole[ib].def);
        out.push(PairSpeed {
            a: a.id,
            b: b.id,
            c: 0.5 * (a.section.thickness + b.section.thickness),
            max: [a_ua, a_ub, b_ua, b_ub],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_maxima_give_the_pairs_step_in_any_order() {
        let p = |max| PairSpeed {
            a: 1,
            b: 2,
            c: 2e-3,
            max,
        };
        let (x, y, z) = (
            p([1.0, 4.0, 0.5, 0.0]),
            p([3.0, 1.0, 0.0, 2.0]),
            p([0.0; 4]),
        );
        let m = x.merge(y).merge(z);
        assert_eq!(m, z.merge(y.merge(x)));
        assert_eq!(m.max, [3.0, 4.0, 0.5, 2.0]);
        // min(3 + 0.5, 4 + 2) = 3.5
        assert_eq!(m.dt(), closing_dt_of(2e-3, 3.5));
        assert_eq!(z.dt(), None);
    }

    #[test]
    fn a_pair_without_a_reference_step_limits_nothing_under_the_soft_penalty() {
        let figs = SplitFigures {
            dts: vec![
                PartDt {
                    id: 1,
                    dt: f64::INFINITY,
                    element: 0,
                },
                PartDt {
                    id: 2,
                    dt: f64::INFINITY,
                    element: 0,
                },
            ],
            pairs: vec![PairSpeed {
                a: 1,
                b: 2,
                c: 1e-3,
                max: [1.0; 4],
            }],
        };
        assert!(figs.limits(PenaltyKind::Soft).is_empty());
        let d = closing_dt_of(1e-3, 2.0).unwrap_or(0.0);
        assert_eq!(figs.limits(PenaltyKind::Element), vec![(1, d), (2, d)]);
    }

    /// The keyed merge keeps what a search in order gave: each key once, at the place
    /// it first came, the smaller element step (ties: the lower element) and the larger
    /// maxima; new keys appended in the order they come.
    #[test]
    fn merged_figures_keep_each_key_once_in_order_of_arrival() {
        let d = |id, dt, element| PartDt { id, dt, element };
        let p = |a, b, m| PairSpeed {
            a,
            b,
            c: 1e-3,
            max: [m; 4],
        };
        let holders = [
            SplitFigures {
                dts: vec![d(5, 2.0, 9), d(3, 1.0, 4)],
                pairs: vec![p(3, 5, 1.0)],
            },
            SplitFigures {
                dts: vec![d(7, 3.0, 1), d(3, 1.0, 2), d(5, 2.5, 0)],
                pairs: vec![p(5, 7, 2.0), p(3, 5, 4.0)],
            },
            SplitFigures {
                dts: vec![d(7, 0.5, 8), d(7, 0.5, 6)],
                pairs: vec![p(3, 5, 0.5), p(3, 7, 1.0)],
            },
        ];
        let mut m = holders[0].clone();
        m.merge(holders[1].clone());
        m.merge(holders[2].clone());
        assert_eq!(m.dts, vec![d(5, 2.0, 9), d(3, 1.0, 2), d(7, 0.5, 6)]);
        assert_eq!(m.pairs, vec![p(3, 5, 4.0), p(5, 7, 2.0), p(3, 7, 1.0)]);
        // all at once: the same
        assert_eq!(SplitFigures::merge_all(holders), m);
        // the limits read each body's step once, whichever holder sent it first
        let lim = m.limits(PenaltyKind::Soft);
        let again = SplitFigures::merge_all([m.clone(), m.clone()]);
        assert_eq!(again, m);
        assert_eq!(again.limits(PenaltyKind::Soft), lim);
    }
}
