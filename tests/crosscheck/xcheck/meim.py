"""The master's interaction graph and placement (docs/architecture-cluster.md, "MEIM,
groups and placement"): one node per body, an edge per pair of contact bodies whose MEIM
boxes overlap; an edge appears at once and is removed after its boxes stayed apart for
more than `split_after` updates; groups are the connected components, numbered by their
smallest id; groups are placed on ranks (sticky, merge to the largest share, new groups
largest first on the least loaded rank, then rebalance)."""


class Meim:
    def __init__(self, ids, split_after=50):
        self.ids = sorted(ids)
        self.split_after = split_after
        self.edges = {}          # (a, b) -> step last seen
        self.groups = [[i] for i in self.ids]

    def update(self, step, pairs):
        changed = False
        seen = set(pairs)
        for p in sorted(seen):
            if p in self.edges:
                self.edges[p] = step
            else:
                self.edges[p] = step
                changed = True
        for p in sorted(self.edges):
            if p not in seen and step - self.edges[p] > self.split_after:
                del self.edges[p]
                changed = True
        if changed:
            self._components()
        return changed

    def _components(self):
        parent = {i: i for i in self.ids}

        def find(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for a, b in self.edges:
            ra, rb = find(a), find(b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
        comp = {}
        for i in self.ids:
            comp.setdefault(find(i), []).append(i)
        self.groups = sorted(comp.values(), key=lambda g: g[0])


def assign(groups, cost, current, workers, tolerance=0.25, rebalance=True):
    """Rank per group. groups: lists of body ids; cost, current: dicts by id."""
    gcost = [sum(cost[b] for b in g) for g in groups]
    load = [0.0] * workers
    out = [None] * len(groups)
    for k, g in enumerate(groups):
        share = [0.0] * workers
        placed = False
        for b in g:
            w = current.get(b)
            if w is not None and w < workers:
                share[w] += cost[b] + 1e-300
                placed = True
        if placed:
            best = 0
            for w in range(1, workers):
                if share[w] > share[best]:
                    best = w
            out[k] = best
            load[best] += gcost[k]
    fresh = [k for k in range(len(groups)) if out[k] is None]
    fresh.sort(key=lambda k: (-gcost[k], k))
    for k in fresh:
        w = min(range(workers), key=lambda i: (load[i], i))
        out[k] = w
        load[w] += gcost[k]
    if rebalance:
        mean = sum(load) / workers
        for _ in range(len(out)):
            hi = max(range(workers), key=lambda i: (load[i], -i))
            lo = min(range(workers), key=lambda i: (load[i], i))
            diff = load[hi] - load[lo]
            if not diff > tolerance * mean or hi == lo:
                break
            pick = None
            for k in range(len(out)):
                if out[k] != hi or not gcost[k] < diff:
                    continue
                if pick is None or abs(gcost[k] - 0.5 * diff) < abs(gcost[pick] - 0.5 * diff):
                    pick = k
            if pick is None:
                break
            out[pick] = lo
            load[hi] -= gcost[pick]
            load[lo] += gcost[pick]
    return out
