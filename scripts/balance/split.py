#!/usr/bin/env python3
"""Split a run's step time from a CRASH_STEP_TRACE file (scripts/balance/trace.patch).

Usage: split.py TRACE [TRACE ...]   (one file per run; cluster and local alike)
Per run: mean per step [us] of the step period (start to next start), the exchange's
wall, the slowest worker's compute, each worker's compute, the sum of all group
times (CPU spent in groups), and the imbalance max - mean; then the same in windows
of 500 steps (how unbalanced the workers are over time).
"""
import sys
from collections import defaultdict


def load(path):
    steps = defaultdict(dict)  # step -> worker -> (start, wall, compute, groups)
    for line in open(path):
        f = line.rstrip("\n").split(",")
        step, start, wall, w, comp = (int(x) for x in f[:5])
        groups = {}
        if len(f) > 5 and f[5]:
            for g in f[5].split(" "):
                a, b = g.split(":")
                groups[int(a)] = int(b)
        steps[step][w] = (start, wall, comp, groups)
    return dict(sorted(steps.items()))


def summarise(steps, lo=None, hi=None):
    keys = [s for s in steps if (lo is None or s >= lo) and (hi is None or s < hi)]
    n = 0
    acc = defaultdict(float)
    nw = max(len(v) for v in steps.values())
    for s in keys:
        ws = steps[s]
        start = next(iter(ws.values()))[0]
        wall = next(iter(ws.values()))[1]
        comps = [ws[w][2] for w in sorted(ws)]
        gsum = sum(sum(ws[w][3].values()) for w in ws)
        acc["wall"] += wall
        acc["max"] += max(comps)
        acc["mean"] += sum(comps) / len(comps)
        acc["gsum"] += gsum
        for w, c in enumerate(comps):
            acc[f"w{w}"] += c
        n += 1
    # period from consecutive starts
    starts = [next(iter(steps[s].values()))[0] for s in keys]
    if len(starts) > 1:
        acc["period"] = (starts[-1] - starts[0]) / (len(starts) - 1) * n
    return n, {k: v / n / 1e3 for k, v in acc.items()}, nw


for path in sys.argv[1:]:
    steps = load(path)
    n, a, nw = summarise(steps)
    ws = " / ".join(f"{a[f'w{w}']:.0f}" for w in range(nw))
    print(f"{path}: {n} steps, {nw} worker(s); per step [us]: period {a.get('period', 0):.0f}, "
          f"exchange wall {a['wall']:.0f}, slowest compute {a['max']:.0f}, "
          f"per worker {ws}, groups' sum {a['gsum']:.0f}, max - mean {a['max'] - a['mean']:.0f}, "
          f"wall - slowest {a['wall'] - a['max']:.0f}, period - wall {a.get('period', 0) - a['wall']:.0f}")
    last = max(steps)
    for lo in range(0, last + 1, 500):
        n, a, _ = summarise(steps, lo, lo + 500)
        if n == 0:
            continue
        ws = " / ".join(f"{a[f'w{w}']:.0f}" for w in range(nw))
        print(f"  steps {lo:5}-{lo + 499:5}: period {a.get('period', 0):5.0f} slowest {a['max']:5.0f} "
              f"workers {ws:>13} groups' sum {a['gsum']:5.0f} max-mean {a['max'] - a['mean']:4.0f}")


def detail(path, win=50):
    """Imbalance split into the placement's share (window means of each worker's
    compute, `win` steps) and the per-step jitter; and the groups per worker."""
    steps = load(path)
    keys = list(steps)
    nw = max(len(v) for v in steps.values())
    if nw < 2:
        return
    sys_, tot, n = 0.0, 0.0, 0
    for i in range(0, len(keys), win):
        ks = keys[i:i + win]
        means = [sum(steps[s][w][2] for s in ks if w in steps[s]) / len(ks) for w in range(nw)]
        sys_ += (max(means) - sum(means) / nw) * len(ks)
        for s in ks:
            c = [steps[s][w][2] for w in range(nw) if w in steps[s]]
            tot += max(c) - sum(c) / len(c)
        n += len(ks)
    print(f"  imbalance per step [us]: {tot / n / 1e3:.0f}, of which between {win}-step means "
          f"(placement) {sys_ / n / 1e3:.0f}, jitter {(tot - sys_) / n / 1e3:.0f}")
    for lo in range(0, keys[-1] + 1, 500):
        ks = [s for s in keys if lo <= s < lo + 500]
        parts = []
        for w in range(nw):
            acc = defaultdict(float)
            for s in ks:
                for g, t in steps[s].get(w, (0, 0, 0, {}))[3].items():
                    acc[g] += t
            parts.append(" ".join(f"{g}:{acc[g] / len(ks) / 1e3:.0f}" for g in sorted(acc)))
        print(f"  steps {lo:5}+: " + " | ".join(parts))


for path in sys.argv[1:]:
    detail(path)
