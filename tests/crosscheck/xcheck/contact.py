"""Penalty node-to-segment contact of docs/theory-contact.md: level i (inflated body
boxes), level ii (nodes against segments: here a uniform grid instead of crash's R-trees;
the chosen segment depends only on exact distances, so any complete candidate search
gives the same result), closest-point projection, gap with thickness, soft and element
penalties, damping, pair statistics, tunnelling guard."""

import math

import numpy as np

from .vec import dot, cross, norm
from .body import Fault

REFERENCE_SAFETY = 0.9
TIE = 1e-9
CLOSING_FRACTION = 0.2


def closing_speed(a, b):
    """Upper bound of the speed of a node of a relative to a point of b: the smaller of
    max|v_a - u| + max|v_b - u| with u the centre-of-mass velocity of a, then of b."""
    def com(x):
        return (x.v * x.mass[:, None]).sum(axis=0) / x.mass.sum()

    def bound(u):
        return float(norm(a.v - u).max()) + float(norm(b.v - u).max())

    return min(bound(com(a)), bound(com(b)))


def margin_for(cfg, body):
    return cfg["margin"] if cfg["margin"] > 0.0 else body.thickness


def segment_nodes(body):
    """The corner nodes of a body's segments, triangles then quads, 4 per row (a
    triangle's slot 3 repeats node 2)."""
    nt, nq = len(body.tris), len(body.quads)
    nodes = np.zeros((nt + nq, 4), dtype=np.int64)
    if nt:
        nodes[:nt, :3] = body.tris
        nodes[:nt, 3] = body.tris[:, 2]
    if nq:
        nodes[nt:] = body.quads
    return nodes


class Surface:
    """Segments of a body (triangles, then quads), their smallest node mass, the
    element-form stiffness per unit scale, node adjacency for self-contact."""

    def __init__(self, body):
        nt, nq = len(body.tris), len(body.quads)
        self.count = np.concatenate([np.full(nt, 3), np.full(nq, 4)]).astype(np.int64)
        nodes = segment_nodes(body)
        self.nodes = nodes
        m = body.mass[nodes]
        m[:nt, 3] = np.inf
        self.seg_mass = m.min(axis=1)
        x0 = body.x0
        k_unit = np.zeros(nt + nq)
        if nt:
            p = [x0[body.tris[:, k]] for k in range(3)]
            area = 0.5 * norm(cross(p[1] - p[0], p[2] - p[0]))
            ln = np.maximum(np.maximum(norm(p[1] - p[0]), norm(p[2] - p[1])), norm(p[0] - p[2]))
            k_unit[:nt] = body.plate_modulus * area / ln
        if nq:
            p = [x0[body.quads[:, k]] for k in range(4)]
            area = 0.5 * norm(cross(p[2] - p[0], p[3] - p[1]))
            ln = np.maximum(norm(p[2] - p[0]), norm(p[3] - p[1]))
            k_unit[nt:] = body.plate_modulus * area / ln
        self.k_unit = k_unit
        self.mass_per_k = float(np.min(self.seg_mass / k_unit))
        self.inv_k = float(np.min(1.0 / k_unit))
        self.min_mass = float(body.mass.min())
        self._adj = None
        self.n = len(body.x)

    def adjacency_keys(self):
        """Sorted keys i * n + k of node pairs sharing a segment (and i == k)."""
        if self._adj is None:
            keys = []
            for s in range(4):
                for r in range(4):
                    a, b = self.nodes[:, s], self.nodes[:, r]
                    keys.append(a * self.n + b)
            keys.append(np.arange(self.n) * (self.n + 1))
            self._adj = np.unique(np.concatenate(keys))
        return self._adj


def triangle_weights(p, a, b, c):
    """Ericson, Real-Time Collision Detection 5.1.5: barycentric weights of the closest
    point of triangle abc to p, rows vectorised; region tests in the book's order."""
    n = len(p)
    ab = b - a
    ac = c - a
    ap = p - a
    d1 = dot(ab, ap)
    d2 = dot(ac, ap)
    bp = p - b
    d3 = dot(ab, bp)
    d4 = dot(ac, bp)
    cp = p - c
    d5 = dot(ab, cp)
    d6 = dot(ac, cp)
    vc = d1 * d4 - d3 * d2
    vb = d5 * d2 - d1 * d6
    va = d3 * d6 - d5 * d4
    w = np.empty((n, 3))
    done = np.zeros(n, dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        # vertex a
        m = (d1 <= 0.0) & (d2 <= 0.0)
        w[m] = (1.0, 0.0, 0.0)
        done |= m
        # vertex b
        m = ~done & (d3 >= 0.0) & (d4 <= d3)
        w[m] = (0.0, 1.0, 0.0)
        done |= m
        # edge ab
        m = ~done & (vc <= 0.0) & (d1 >= 0.0) & (d3 <= 0.0)
        v = d1[m] / (d1[m] - d3[m])
        w[m, 0], w[m, 1], w[m, 2] = 1.0 - v, v, 0.0
        done |= m
        # vertex c
        m = ~done & (d6 >= 0.0) & (d5 <= d6)
        w[m] = (0.0, 0.0, 1.0)
        done |= m
        # edge ac
        m = ~done & (vb <= 0.0) & (d2 >= 0.0) & (d6 <= 0.0)
        t = d2[m] / (d2[m] - d6[m])
        w[m, 0], w[m, 1], w[m, 2] = 1.0 - t, 0.0, t
        done |= m
        # edge bc
        m = ~done & (va <= 0.0) & ((d4 - d3) >= 0.0) & ((d5 - d6) >= 0.0)
        t = (d4[m] - d3[m]) / ((d4[m] - d3[m]) + (d5[m] - d6[m]))
        w[m, 0], w[m, 1], w[m, 2] = 0.0, 1.0 - t, t
        done |= m
        # interior
        m = ~done
        denom = 1.0 / (va[m] + vb[m] + vc[m])
        v = vb[m] * denom
        t = vc[m] * denom
        w[m, 0], w[m, 1], w[m, 2] = 1.0 - v - t, v, t
    return w


def _unit_normal(a, b, c):
    n = cross(b - a, c - a)
    ln = norm(n)
    out = np.zeros_like(n)
    out[:, 2] = 1.0
    ok = ln > 0.0
    out[ok] = n[ok] / ln[ok, None]
    return out


def project(p, seg_nodes, count, x):
    """Closest point of each segment (rows) to each p: (dist, point, weights (n, 4),
    face normal, sub-triangle, its barycentric weights (n, 3))."""
    n = len(p)
    dist = np.full(n, np.inf)
    point = np.zeros((n, 3))
    weights = np.zeros((n, 4))
    fnormal = np.zeros((n, 3))
    sub = np.zeros(n, dtype=np.int64)
    bary = np.zeros((n, 3))
    xs = [x[seg_nodes[:, k]] for k in range(4)]
    t = count == 3
    if np.any(t):
        pt = p[t]
        w = triangle_weights(pt, xs[0][t], xs[1][t], xs[2][t])
        pp = xs[0][t] * w[:, 0:1] + xs[1][t] * w[:, 1:2] + xs[2][t] * w[:, 2:3]
        d = pt - pp
        dist[t] = np.sqrt(dot(d, d))
        point[t] = pp
        weights[t, :3] = w
        fnormal[t] = _unit_normal(xs[0][t], xs[1][t], xs[2][t])
        bary[t] = w
    q = ~t
    if np.any(q):
        pq = p[q]
        X = [xs[k][q] for k in range(4)]
        cen = (X[0] + X[1] + X[2] + X[3]) * 0.25
        best = np.full(len(pq), np.inf)
        bpoint = np.zeros((len(pq), 3))
        bw = np.zeros((len(pq), 4))
        bn = np.zeros((len(pq), 3))
        bk = np.zeros(len(pq), dtype=np.int64)
        bb = np.zeros((len(pq), 3))
        for k in range(4):
            k1 = (k + 1) % 4
            w3 = triangle_weights(pq, cen, X[k], X[k1])
            wk = np.repeat(0.25 * w3[:, 0:1], 4, axis=1)
            wk[:, k] += w3[:, 1]
            wk[:, k1] += w3[:, 2]
            pp = X[0] * wk[:, 0:1] + X[1] * wk[:, 1:2] + X[2] * wk[:, 2:3] + X[3] * wk[:, 3:4]
            d = pq - pp
            dk = np.sqrt(dot(d, d))
            better = dk < best          # strict: the first sub-triangle wins ties
            if k == 0:
                better = np.ones(len(pq), dtype=bool)
            best = np.where(better, dk, best)
            bpoint[better] = pp[better]
            bw[better] = wk[better]
            bn[better] = _unit_normal(cen[better], X[k][better], X[k1][better])
            bk[better] = k
            bb[better] = w3[better]
        dist[q], point[q], weights[q], fnormal[q] = best, bpoint, bw, bn
        sub[q], bary[q] = bk, bb
    return dist, point, weights, fnormal, sub, bary


def _candidates(p, body, surf, c):
    """Every (node row, segment) whose segment node box is within Euclidean distance
    < c of the node (a uniform grid over the boxes grown by c). Returns (rows, segs, lb)."""
    x = body.x
    sn = surf.nodes
    xs = x[sn]                              # (ns, 4, 3)
    lo = xs.min(axis=1)
    hi = xs.max(axis=1)
    ext = float((hi - lo).max()) if len(lo) else 0.0
    G = ext + 2.0 * c + 1e-300
    origin = lo.min(axis=0) - c
    glo = np.floor((lo - c - origin) / G).astype(np.int64)
    ghi = np.floor((hi + c - origin) / G).astype(np.int64)
    dims = np.maximum(ghi.max(axis=0) + 2, 1)
    keys, segs = [], []
    ids = np.arange(len(sn))
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                cell = glo + np.array([dx, dy, dz])
                ok = np.all(cell <= ghi, axis=1)
                k = (cell[ok, 0] * dims[1] + cell[ok, 1]) * dims[2] + cell[ok, 2]
                keys.append(k)
                segs.append(ids[ok])
    keys = np.concatenate(keys)
    segs = np.concatenate(segs)
    order = np.argsort(keys, kind="stable")
    keys, segs = keys[order], segs[order]
    pc = np.floor((p - origin) / G).astype(np.int64)
    inside = np.all((pc >= 0) & (pc < dims), axis=1)
    pk = (pc[:, 0] * dims[1] + pc[:, 1]) * dims[2] + pc[:, 2]
    pk = np.where(inside, pk, -1)
    start = np.searchsorted(keys, pk, side="left")
    end = np.searchsorted(keys, pk, side="right")
    cnt = np.where(inside, end - start, 0)
    rows = np.repeat(np.arange(len(p)), cnt)
    off = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    sj = segs[np.repeat(start, cnt) + off]
    # exact lower bound: distance from p to the segment's node box
    pr = p[rows]
    d = np.maximum(lo[sj] - pr, 0.0) + np.maximum(pr - hi[sj], 0.0)
    lb = np.sqrt(dot(d, d))
    keep = lb < c
    return rows[keep], sj[keep]


def search(nb, sb, surf, self_pass):
    """Nodes of nb within contact distance of sb's segments: (node, segment, dist,
    point, weights, face normal, depth), in node order (theory-contact.md level ii)."""
    c = 0.5 * (nb.thickness + sb.thickness)
    lo = sb.x.min(axis=0) - c
    hi = sb.x.max(axis=0) + c
    inside = np.all((nb.x >= lo) & (nb.x <= hi), axis=1)
    idx = np.nonzero(inside)[0]
    empty = None
    if len(idx) == 0:
        return empty
    p = nb.x[idx]
    rows, sj = _candidates(p, sb, surf, c)
    if self_pass and len(rows):
        keys = idx[rows, None] * surf.n + surf.nodes[sj]
        near = np.isin(keys, surf.adjacency_keys()).any(axis=1)
        rows, sj = rows[~near], sj[~near]
    if len(rows) == 0:
        return empty
    dist, point, weights, fnormal, sub, bary = project(p[rows], surf.nodes[sj], surf.count[sj], sb.x)
    ok = ~np.isnan(dist)
    rows, sj, dist, point, weights, fnormal = rows[ok], sj[ok], dist[ok], point[ok], weights[ok], fnormal[ok]
    sub, bary = sub[ok], bary[ok]
    # the closest segment per node; every segment within TIE c of the closest is a tie,
    # won by the lowest segment index
    dmin = np.full(len(p), np.inf)
    np.minimum.at(dmin, rows, dist)
    eligible = dist <= dmin[rows] + TIE * c
    order = np.lexsort((sj, ~eligible, rows))
    first = np.ones(len(order), dtype=bool)
    first[1:] = rows[order][1:] != rows[order][:-1]
    pick = order[first]
    pick = pick[dist[pick] < c]
    if self_pass and len(pick):
        # already within contact distance at the start: part of the shape (no hit)
        d0 = project(nb.x0[idx[rows[pick]]], surf.nodes[sj[pick]], surf.count[sj[pick]], sb.x0)[0]
        pick = pick[~(d0 < c)]
    if len(pick) == 0:
        return empty
    node = idx[rows[pick]]
    return dict(node=node, seg=sj[pick], dist=dist[pick], point=point[pick],
                weights=weights[pick], fnormal=fnormal[pick], depth=c - dist[pick], c=c,
                sub=sub[pick], bary=bary[pick])


CREASE_COS = 0.866
NEWTON_ITERATIONS = 3
OUTSIDE_TOLERANCE = 0.25


def nodal_normals(b):
    """Area-weighted nodal normals: each triangle adds (x2-x1) x (x3-x1), each quad
    (x3-x1) x (x4-x2); unit length (zero where they cancel)."""
    n = np.zeros_like(b.x)
    if len(b.tris):
        t = b.tris
        f = cross(b.x[t[:, 1]] - b.x[t[:, 0]], b.x[t[:, 2]] - b.x[t[:, 0]])
        for k in range(3):
            np.add.at(n, t[:, k], f)
    if len(b.quads):
        q = b.quads
        f = cross(b.x[q[:, 2]] - b.x[q[:, 0]], b.x[q[:, 3]] - b.x[q[:, 1]])
        for k in range(4):
            np.add.at(n, q[:, k], f)
    ln = norm(n)
    return np.where((ln > 0.0)[:, None], n / np.where(ln > 0.0, ln, 1.0)[:, None], 0.0)


def _solve3(j0, j1, j2, r):
    """Rows of 3x3 systems [j0 j1 j2] d = r by Cramer's rule; det == 0 gives nan."""
    c12 = cross(j1, j2)
    det = dot(j0, c12)
    bad = (det == 0.0) | ~np.isfinite(det)
    det = np.where(bad, np.nan, det)
    return np.stack([dot(r, c12) / det, dot(j0, cross(r, j2)) / det, dot(j0, cross(j1, r)) / det], axis=1)


def _subtriangle(hits, sb, surf, nn):
    """Corners (A, B, C) of the (sub-)triangle holding the closest point, corner normals
    (from nn, the per-segment-node normals (h, 4, 3)) and the slots of B and C."""
    sn = surf.nodes[hits["seg"]]
    X = sb.x[sn]
    quad = surf.count[hits["seg"]] == 4
    k = np.where(quad, hits["sub"], 0)
    k1 = np.where(quad, (k + 1) % 4, 2)
    kb = np.where(quad, k, 1)
    r = np.arange(len(k))
    a = np.where(quad[:, None], (X[:, 0] + X[:, 1] + X[:, 2] + X[:, 3]) * 0.25, X[:, 0])
    na = np.where(quad[:, None], (nn[:, 0] + nn[:, 1] + nn[:, 2] + nn[:, 3]) * 0.25, nn[:, 0])
    return a, X[r, kb], X[r, k1], na, nn[r, kb], nn[r, k1], kb, k1, quad, X


def _weights(u, v, kb, k1, quad):
    w0 = 1.0 - u - v
    w = np.zeros((len(u), 4))
    r = np.arange(len(u))
    w[quad] = (0.25 * w0[quad])[:, None]
    w[~quad, 0] = w0[~quad]
    w[r, kb] += u
    w[r, k1] += v
    return w


def _inside(u, v):
    t = OUTSIDE_TOLERANCE
    return (u >= -t) & (v >= -t) & (u + v <= 1.0 + t) & np.isfinite(u) & np.isfinite(v)


def smoothed_normal(hits, nb, sb, surf, n_cp):
    """theory-contact.md "Normal: smoothed over facets": the direction and the reaction
    weights of every hit (projection along the interpolated nodal normal, then the
    common normal with the node's own normal; the closest point where either fails)."""
    c = hits["c"]
    p = nb.x[hits["node"]]
    seg = hits["seg"]
    sn = surf.nodes[seg]
    X = sb.x[sn]
    quad = surf.count[seg] == 4
    # the segment's own normal and the corner normals (crease: the segment's)
    fs = np.where(quad[:, None], cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1]),
                  cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]))
    ls = norm(fs)
    ns = np.where((ls > 0.0)[:, None], fs / np.where(ls > 0.0, ls, 1.0)[:, None], 0.0)
    nsb = nodal_normals(sb)[sn]
    # a segment with a corner beyond the crease angle is not smoothed (closest point)
    smooth = np.all(dot(nsb, ns[:, None, :]) >= CREASE_COS, axis=1)
    nn = nsb
    a, b, cc, na, nbb, nc, kb, k1, quad, X = _subtriangle(hits, sb, surf, nn)
    eu, ev, mu, mv = b - a, cc - a, nbb - na, nc - na
    u, v = hits["bary"][:, 1].copy(), hits["bary"][:, 2].copy()
    n0 = na + mu * u[:, None] + mv * v[:, None]
    n2 = dot(n0, n0)
    smooth &= hits["dist"] > 1e-9 * c
    ok = smooth & (n2 > 0.0) & np.isfinite(n2)
    lam = dot(p - hits["point"], n0) / np.where(n2 > 0.0, n2, 1.0)
    for _ in range(NEWTON_ITERATIONS):
        n = na + mu * u[:, None] + mv * v[:, None]
        f = a + eu * u[:, None] + ev * v[:, None] + n * lam[:, None] - p
        d = _solve3(eu + mu * lam[:, None], ev + mv * lam[:, None], n, f)
        u, v, lam = u - d[:, 0], v - d[:, 1], lam - d[:, 2]
    ok &= _inside(u, v)
    w = _weights(np.where(ok, u, 0.0), np.where(ok, v, 0.0), kb, k1, quad)
    pt = (X * w[:, :, None]).sum(axis=1)
    d = p - pt
    ld = norm(d)
    ok &= (ld > 1e-9 * c) & np.isfinite(ld) & (dot(d, p - hits["point"]) > 0.0)
    n_seg = np.where(ok[:, None], d / np.where(ld > 0.0, ld, 1.0)[:, None], n_cp)
    w_seg = np.where(ok[:, None], w, hits["weights"])
    # the common normal with the node's own normal
    own = nodal_normals(nb)[hits["node"]]
    sgn = dot(own, n_seg)
    ok2 = smooth & (np.abs(sgn) >= CREASE_COS)
    m = n_seg + np.where((sgn > 0.0)[:, None], own, -own)
    lm = norm(m)
    ok2 &= lm > 0.0
    m = m / np.where(lm > 0.0, lm, 1.0)[:, None]
    sol = _solve3(eu, ev, m, p - a)
    u2, v2 = sol[:, 0], sol[:, 1]
    ok2 &= _inside(u2, v2)
    w2 = _weights(np.where(ok2, u2, 0.0), np.where(ok2, v2, 0.0), kb, k1, quad)
    pt2 = (X * w2[:, :, None]).sum(axis=1)
    d2 = p - pt2
    l2 = norm(d2)
    ok2 &= (l2 > 0.0) & np.isfinite(l2) & (dot(d2, n_seg) > 0.0)
    n_out = np.where(ok2[:, None], d2 / np.where(l2 > 0.0, l2, 1.0)[:, None], n_seg)
    w_out = np.where(ok2[:, None], w2, w_seg)
    return n_out, w_out


def pushes(hits, nb, sb, surf, cfg, dt_ref):
    """Penalty forces of the hits: f_n = k (-g) - c_d v_n, kept where > 0."""
    if hits is None:
        return None
    c = hits["c"]
    node = hits["node"]
    p = nb.x[node]
    d = p - hits["point"]
    dist = hits["dist"]
    n = np.where((dist > 1e-9 * c)[:, None], d / np.where(dist > 0.0, dist, 1.0)[:, None],
                 np.where((dot(d, hits["fnormal"]) < 0.0)[:, None], -hits["fnormal"], hits["fnormal"]))
    n, weights = smoothed_normal(hits, nb, sb, surf, n)
    seg = hits["seg"]
    m_star = np.minimum(nb.mass[node], surf.seg_mass[seg])
    s = cfg["penalty_scale"]
    if cfg["penalty"] == "soft":
        k = s * m_star / (dt_ref * dt_ref)
    else:
        k = s * surf.k_unit[seg]
    fn = k * hits["depth"]
    xi = cfg["damping_ratio"]
    if xi > 0.0:
        w = weights
        sn = surf.nodes[seg]
        vs = (sb.v[sn] * w[:, :, None]).sum(axis=1)
        vn = dot(nb.v[node] - vs, n)
        fn = fn - 2.0 * xi * np.sqrt(k * m_star) * vn
    keep = (fn > 0.0) & np.isfinite(fn)
    if not np.any(keep):
        return None
    return dict(node=node[keep], seg=seg[keep], weights=weights[keep],
                depth=hits["depth"][keep], fn=fn[keep], force=n[keep] * fn[keep, None])


def _apply(nb, sb, surf, pu):
    np.add.at(nb.f_contact, pu["node"], pu["force"])
    sn = surf.nodes[pu["seg"]]
    cnt = surf.count[pu["seg"]]
    for q in range(4):
        m = cnt > q
        np.add.at(sb.f_contact, sn[m, q], -pu["force"][m] * pu["weights"][m, q:q + 1])


def _element_form_dt(cfg, nb_surf, surf):
    m_over_k = min(nb_surf.min_mass * surf.inv_k, surf.mass_per_k) / cfg["penalty_scale"]
    return math.sqrt(2.0 * m_over_k)


def candidate_pairs(boxes, pad_of):
    """Pairs (a < b) whose inflated boxes overlap (boundaries included), sorted.
    boxes: list of (id, lo, hi); pad_of(id) the inflation."""
    out = []
    inf = [(i, lo - pad_of(i), hi + pad_of(i)) for i, lo, hi in boxes
           if np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))]
    for ia in range(len(inf)):
        a, alo, ahi = inf[ia]
        for ib in range(len(inf)):
            b, blo, bhi = inf[ib]
            if a < b and np.all(alo <= bhi) and np.all(blo <= ahi):
                out.append((a, b))
    return sorted(set(out))


class ContactStage:
    """Per group: the surfaces (built once per body) and the pass."""

    def __init__(self, cfg):
        self.cfg = cfg
        self.surfaces = {}
        self.geometries = {}
        self.stats = []

    def geometry(self, b):
        g = self.geometries.get(b.id)
        if g is None:
            from .contact_segments import Geometry
            g = self.geometries[b.id] = Geometry(b)
        return g

    def surface(self, b):
        s = self.surfaces.get(b.id)
        if s is None:
            s = self.surfaces[b.id] = Surface(b)
        return s

    def run(self, bodies, element_dt):
        """Contact forces at the current positions into f_contact; returns the contact
        step limit per body (+inf unless the element penalty is used)."""
        cfg = self.cfg
        dt = [math.inf] * len(bodies)
        self.stats = []
        for b in bodies:
            b.f_contact = np.zeros((len(b.x), 3)) if (b.contact and cfg["enabled"]) else None
        if not cfg["enabled"]:
            return dt
        index = {b.id: k for k, b in enumerate(bodies) if b.contact}
        boxes = [(b.id, b.x.min(axis=0), b.x.max(axis=0)) for b in bodies if b.contact]
        th = {b.id: b.thickness for b in bodies}
        m = cfg["margin"]
        pairs = candidate_pairs(boxes, lambda i: 0.5 * (th[i] + (m if m > 0.0 else th[i])))
        pairs += [(b.id, b.id) for b in bodies if b.contact and b.self_contact]
        pairs.sort()
        for ida, idb in pairs:
            ia, ib = index[ida], index[idb]
            a, b = bodies[ia], bodies[ib]
            sa, sb = self.surface(a), self.surface(b)
            if cfg["penalty"] == "element":
                d = min(_element_form_dt(cfg, sa, sb), _element_form_dt(cfg, sb, sa))
                dt[ia] = min(dt[ia], d)
                dt[ib] = min(dt[ib], d)
            self_pair = ia == ib
            pair_dt = min(element_dt[ia], element_dt[ib])
            if cfg["penalty"] == "soft" and not (math.isfinite(pair_dt) and pair_dt > 0.0):
                continue
            if cfg.get("speed_rule", "limit_dt") == "limit_dt" and not self_pair:
                v = closing_speed(a, b)
                if v > 0.0:
                    d = CLOSING_FRACTION * 0.5 * (a.thickness + b.thickness) / v
                    dt[ia] = min(dt[ia], d)
                    dt[ib] = min(dt[ib], d)
                    pair_dt = min(pair_dt, d)
            dt_ref = REFERENCE_SAFETY * pair_dt
            if cfg.get("pass", "nodes") == "segments" and not self_pair:
                # the segment pass (contact_segments.py) and the stiffening law's step
                from .contact_segments import segment_pair, law_step
                st = segment_pair(a, b, self.geometry(a), self.geometry(b), cfg, dt_ref)
                c = 0.5 * (a.thickness + b.thickness)
                d = law_step(cfg["penalty_scale"], st["max_penetration"] / c, pair_dt)
                if d is not None:
                    dt[ia] = min(dt[ia], d)
                    dt[ib] = min(dt[ib], d)
                self.stats.append(st)
                continue
            first = pushes(search(a, b, sb, self_pair), a, b, sb, cfg, dt_ref)
            second = None if self_pair else pushes(search(b, a, sa, False), b, a, sa, cfg, dt_ref)
            st = dict(a=ida, b=idb, active=0, max_penetration=0.0, normal_force=0.0)
            for pu, nb_, sb_, surf in ((first, a, b, sb), (second, b, a, sa)):
                if pu is None:
                    continue
                _apply(nb_, sb_, surf, pu)
                st["active"] += len(pu["node"])
                st["max_penetration"] = max(st["max_penetration"], float(pu["depth"].max()))
                for f in pu["fn"]:
                    st["normal_force"] += float(f)
            st["max_penetration_ratio"] = st["max_penetration"] / min(a.thickness, b.thickness)
            self.stats.append(st)
        return dt


def check_moves(bodies, cfg, moves, h, step):
    """The tunnelling guard: a contact body whose node moved more than half its margin
    in one step stops the run."""
    if not cfg["enabled"]:
        return
    for b, mv in zip(bodies, moves):
        budget = 0.5 * margin_for(cfg, b)
        if b.contact and mv > budget:
            raise Fault(f"step {step}: body {b.id} tunnelling: moved {mv:e} m, budget {budget:e} m")
