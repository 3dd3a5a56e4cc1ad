//! Assignment of groups to workers: balanced by cost, sticky (fewest migrations).
//!
//! 1. A group whose bodies are all on one worker stays there.
//! 2. A group spread over several workers (a merge) goes to the worker that already
//!    holds the largest part of its cost (ties: lowest worker index), so the fewest
//!    bytes move.
//! 3. Groups with no placement yet (the start) are placed largest first on the least
//!    loaded worker (LPT).
//! 4. Rebalance: while the most and least loaded workers differ by more than
//!    `tolerance` x the mean load, move the group from the most loaded worker whose cost
//!    is nearest half the difference (only moves that lower the maximum count).
//!
//! Placement never changes results (a group computes the same bits anywhere), so costs
//! may be measured times that differ from run to run.

use std::cmp::Ordering;

/// Worker per group. `groups` hold body indices (0..n), `cost` and `current` are per
/// body index.
pub fn assign(
    groups: &[Vec<usize>],
    cost: &[f64],
    current: &[Option<usize>],
    workers: usize,
    tolerance: f64,
    rebalance: bool,
) -> Vec<usize> {
    let workers = workers.max(1);
    let gcost: Vec<f64> = groups
        .iter()
        .map(|g| g.iter().map(|&b| cost[b]).sum())
        .collect();
    let mut load = vec![0.0; workers];
    let mut out: Vec<Option<usize>> = vec![None; groups.len()];
    for (k, g) in groups.iter().enumerate() {
        let mut share = vec![0.0; workers];
        let mut placed = false;
        for &b in g {
            if let Some(w) = current[b] {
                if w < workers {
                    // +tiny: a zero-cost body still votes for its worker
                    share[w] += cost[b] + 1e-300;
                    placed = true;
                }
            }
        }
        if placed {
            let mut best = 0;
            for w in 1..workers {
                if share[w] > share[best] {
                    best = w;
                }
            }
            out[k] = Some(best);
            load[best] += gcost[k];
        }
    }
    let mut fresh: Vec<usize> = (0..groups.len()).filter(|&k| out[k].is_none()).collect();
    fresh.sort_by(|&a, &b| gcost[b].total_cmp(&gcost[a]).then(a.cmp(&b)));
    for k in fresh {
        let w = lightest(&load);
        out[k] = Some(w);
        load[w] += gcost[k];
    }
    let mut out: Vec<usize> = out.into_iter().map(|w| w.unwrap_or(0)).collect();
    if rebalance {
        balance(&mut out, &gcost, &mut load, tolerance);
    }
    out
}

fn lightest(load: &[f64]) -> usize {
    let mut best = 0;
    for w in 1..load.len() {
        if load[w] < load[best] {
            best = w;
        }
    }
    best
}

fn heaviest(load: &[f64]) -> usize {
    let mut best = 0;
    for w in 1..load.len() {
        if load[w] > load[best] {
            best = w;
        }
    }
    best
}

fn balance(out: &mut [usize], gcost: &[f64], load: &mut [f64], tolerance: f64) {
    let mean = load.iter().sum::<f64>() / load.len() as f64;
    for _ in 0..out.len() {
        let (hi, lo) = (heaviest(load), lightest(load));
        let diff = load[hi] - load[lo];
        if diff.partial_cmp(&(tolerance * mean)) != Some(Ordering::Greater) || hi == lo {
            return;
        }
        let mut pick: Option<usize> = None;
        for k in 0..out.len() {
            if out[k] != hi || gcost[k].partial_cmp(&diff) != Some(Ordering::Less) {
                continue;
            }
            let better = match pick {
                None => true,
                Some(p) => (gcost[k] - 0.5 * diff).abs() < (gcost[p] - 0.5 * diff).abs(),
            };
            if better {
                pick = Some(k);
            }
        }
        let Some(k) = pick else { return };
        out[k] = lo;
        load[hi] -= gcost[k];
        load[lo] += gcost[k];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_is_largest_first_on_the_lightest_worker() {
        let groups = vec![vec![0], vec![1], vec![2], vec![3]];
        let cost = [1.0, 5.0, 2.0, 4.0];
        let w = assign(&groups, &cost, &[None; 4], 2, 0.1, true);
        // LPT: 5 -> w0, 4 -> w1, 2 -> w1 (4 < 5), 1 -> w0 (6 = 6: lowest index)
        assert_eq!(w, vec![0, 0, 1, 1]);
    }

    #[test]
    fn merged_group_goes_where_most_of_it_is_and_split_groups_are_rebalanced() {
        let cost = [3.0, 1.0, 1.0];
        let current = [Some(1), Some(0), Some(1)];
        // bodies 0 and 1 merged: body 0 carries more cost, on worker 1
        let w = assign(&[vec![0, 1], vec![2]], &cost, &current, 2, 0.1, false);
        assert_eq!(w, vec![1, 1]);
        // without rebalancing the unchanged layout stays (sticky)
        let all_one = [Some(0), Some(0), Some(0)];
        let w = assign(&[vec![0], vec![1], vec![2]], &cost, &all_one, 2, 0.1, false);
        assert_eq!(w, vec![0, 0, 0]);
        // with it, the group nearest half the imbalance (5 / 2) moves: body 0 (3)
        let w = assign(&[vec![0], vec![1], vec![2]], &cost, &all_one, 2, 0.1, true);
        assert_eq!(w, vec![1, 0, 0]);
        // balanced within the tolerance: nothing moves
        let w = assign(
            &[vec![0], vec![1], vec![2]],
            &cost,
            &[Some(0), Some(1), Some(1)],
            2,
            0.5,
            true,
        );
        assert_eq!(w, vec![0, 1, 1]);
    }

    #[test]
    fn one_big_group_is_not_moved_back_and_forth() {
        let cost = [10.0, 1.0];
        let cur = [Some(0), Some(1)];
        let w = assign(&[vec![0], vec![1]], &cost, &cur, 2, 0.1, true);
        assert_eq!(w, vec![0, 1]);
    }
}
