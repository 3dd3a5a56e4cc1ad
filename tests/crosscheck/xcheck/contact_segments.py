"""The segment contact pass of docs/theory-contact.md ("Segment pass", "Depth"; scene key
contact.pass = "segments"): quadrature points on each body's curved segments (the facet
plus the quadratic bulge of the corner normals) against the other body's curved
segments, each body slave once with half the weight; the potential k_a c^2 psi(-g_a/c)
of the stiffening law per point and its exact gradient (through the points, the closest
point's weights and the corner normals, whose loads are pulled back to nodes); damping
along the same gradient; the law's step limit.

The search is complete and simple: every master segment whose node box lies within the
reach r = c + max(0.25 c, H_m) of a point is a candidate (found over node boxes, H_m the
largest bulge bound of the master's segments), and crash's rule picks the master: the
first candidate in index order, replaced only by one closer by more than TIE c. crash's
near sets, trees, strips and slabs are culls that give that rule's answer."""

import math

import numpy as np

from .vec import dot, cross, norm
from .contact import project, segment_nodes, CREASE_COS, TIE

SPACING = 1.0
MAX_PARTS = 24
BULGE_REACH = 0.25
X1 = 0.2
CAP = 0.95
SOFT_SCALE_LIMIT = 0.3


# ---- the stiffening law ("Depth") -------------------------------------------------
def _phi_raw(x):
    r = 1.0 - x
    return x / (r * r) + x * x * x / (X1 * X1)


def _tangent_raw(x):
    r = 1.0 - x
    return (1.0 + x) / (r * r * r) + 3.0 * x * x / (X1 * X1)


def law_force(x):
    """phi(x): the force of a point pressed x = -g/c deep, per k c (linear past CAP)."""
    xc = np.minimum(x, CAP)
    return np.where(x <= CAP, _phi_raw(xc), _phi_raw(CAP) + _tangent_raw(CAP) * (x - CAP))


def law_step(scale, x, pair_dt):
    """The pair's step when the law stiffens its deepest point (x deep) past the soft
    limit: pair_dt sqrt(0.3 / (s phi'(x))); None below it."""
    s_eff = scale * _tangent_raw(min(x, CAP))
    return pair_dt * math.sqrt(SOFT_SCALE_LIMIT / s_eff) if s_eff > SOFT_SCALE_LIMIT else None


# ---- per body: segments, sub-triangles, curved data -------------------------------
def _unit(v):
    ln = norm(v)
    ok = ln > 0.0
    return np.where(ok[..., None], v / np.where(ok, ln, 1.0)[..., None], 0.0), ln


class Geometry:
    """A body's segments (triangles, then quads; a triangle's slot 3 repeats node 2),
    its sub-triangles (seg, k) with their weight derivatives and initial areas, the
    segments incident to each node, the areal mass (all node masses / initial area) and
    the mean segment area (the finer surface is the slave)."""

    def __init__(self, body):
        nt, nq = len(body.tris), len(body.quads)
        self.ns = nt + nq
        self.tri = np.arange(self.ns) < nt
        nodes = segment_nodes(body)
        self.nodes = nodes
        self.count = np.where(self.tri, 3, 4)
        self.nn = len(body.x)
        X0 = body.x0[nodes]
        area = np.where(self.tri, 0.5 * norm(cross(X0[:, 1] - X0[:, 0], X0[:, 2] - X0[:, 0])),
                        0.5 * norm(cross(X0[:, 2] - X0[:, 0], X0[:, 3] - X0[:, 1])))
        total = math.fsum(area)
        self.areal_mass = math.fsum(body.mass) / total if total > 0.0 else 0.0
        self.mean_area = total / max(self.ns, 1)
        # sub-triangles: a triangle's one, a quad's four (centroid, x_k, x_k+1)
        seg = np.concatenate([np.nonzero(self.tri)[0], np.repeat(np.nonzero(~self.tri)[0], 4)])
        k = np.concatenate([np.zeros(nt, dtype=np.int64), np.tile(np.arange(4), nq)])
        order = np.lexsort((k, seg))
        self.sub_seg, self.sub_k = seg[order], k[order]
        self.dw_du, self.dw_dv, self.base = self._weight_derivatives(self.sub_seg, self.sub_k)
        A, B, C = self.corners(body.x0, self.sub_seg, self.sub_k)
        self.sub_area0 = 0.5 * norm(cross(B - A, C - A))

    def _weight_derivatives(self, seg, k):
        n = len(seg)
        tri = self.tri[seg]
        du = np.full((n, 4), -0.25)
        dv = np.full((n, 4), -0.25)
        r = np.arange(n)
        du[r, k] += 1.0
        dv[r, (k + 1) % 4] += 1.0
        du[tri] = (-1.0, 1.0, 0.0, 0.0)
        dv[tri] = (-1.0, 0.0, 1.0, 0.0)
        base = np.where(tri[:, None], np.array([1.0, 0.0, 0.0, 0.0]), 0.25)
        return du, dv, base

    def corners(self, x, seg, k):
        """(A, B, C) of the sub-triangles (seg, k) at positions x."""
        X = x[self.nodes[seg]]
        tri = self.tri[seg]
        r = np.arange(len(seg))
        cen = (X[:, 0] + X[:, 1] + X[:, 2] + X[:, 3]) * 0.25
        A = np.where(tri[:, None], X[:, 0], cen)
        B = np.where(tri[:, None], X[:, 1], X[r, k])
        C = np.where(tri[:, None], X[:, 2], X[r, (k + 1) % 4])
        return A, B, C


def _face_vectors(g, X):
    return np.where(g.tri[:, None], cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]),
                    cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1]))


def _node_sums(g, F):
    """Per node, the sum of its incident segments' vectors F in crash's order
    (triangles before quads, then corner slot, then segment)."""
    out = np.zeros((g.nn, 3))
    for kind, corners in ((g.tri, 3), (~g.tri, 4)):
        for k in range(corners):
            np.add.at(out, g.nodes[kind, k], F[kind])
    return out


class Curved:
    """A body's curved data at the current positions: face vectors and unit normals,
    nodal normals (sums and units), corner normals (nodal, or the segment's own past the
    30 degree crease), whether each corner took its nodal normal, the bulge coefficients
    b_ij and each segment's bound min(sum |b_ij| / 4, 3/8 max |b_ij|)."""

    def __init__(self, g, x):
        X = x[g.nodes]
        self.X = X
        self.F = _face_vectors(g, X)
        self.ns_unit, self.ls = _unit(self.F)
        self.Fn = _node_sums(g, self.F)
        self.nn_unit, self.ln = _unit(self.Fn)
        N4 = self.nn_unit[g.nodes]
        nodal = dot(N4, self.ns_unit[:, None, :]) >= CREASE_COS
        nodal[g.tri, 3] = False
        self.nodal = nodal
        self.normals = np.where(nodal[:, :, None], N4, self.ns_unit[:, None, :])
        b = np.zeros((g.ns, 4, 4))
        for i in range(4):
            for j in range(i + 1, 4):
                e = X[:, j] - X[:, i]
                v = 0.5 * dot(e, self.normals[:, j] - self.normals[:, i])
                if j == 3:
                    v = np.where(g.tri, 0.0, v)
                b[:, i, j] = v
                b[:, j, i] = v
        self.b = b
        pairs = [np.abs(b[:, i, j]) for i in range(4) for j in range(i + 1, 4)]
        # the smaller of sum |b_ij| / 4 (w_i w_j <= 1/4) and max |b_ij| 3/8 (sum over
        # pairs of w_i w_j <= (1 - 1/k) / 2 <= 3/8)
        self.bound = np.minimum(0.25 * sum(pairs), 0.375 * np.max(pairs, axis=0))
        self.lo = X.min(axis=1)
        self.hi = X.max(axis=1)
        self._dF = None

    def rates(self, g, v):
        """Per node and per segment, the rate of the face-vector sums under velocities v."""
        if self._dF is None:
            X, V = self.X, v[g.nodes]
            self._dF = np.where(
                g.tri[:, None],
                cross(V[:, 1] - V[:, 0], X[:, 2] - X[:, 0]) + cross(X[:, 1] - X[:, 0], V[:, 2] - V[:, 0]),
                cross(V[:, 2] - V[:, 0], X[:, 3] - X[:, 1]) + cross(X[:, 2] - X[:, 0], V[:, 3] - V[:, 1]))
            self._dFn = _node_sums(g, self._dF)
        return self._dFn, self._dF


def bulge(b, w):
    """h(w) = sum_{i<j} w_i w_j b_ij and dh/dw (rows)."""
    dh = np.einsum("nij,nj->ni", b, w)
    return 0.5 * (w * dh).sum(axis=1), dh


def bulge_parts(X, normals, w, scale, count):
    """scale dh/dx at fixed weights: per corner a force through the edges (direct) and a
    load on each corner normal (on_normal)."""
    n = len(w)
    direct = np.zeros((n, 4, 3))
    on_normal = np.zeros((n, 4, 3))
    for k in range(4):
        for m in range(4):
            if m == k:
                continue
            ww = 0.5 * w[:, k] * w[:, m] * scale
            ww = np.where((k < count) & (m < count), ww, 0.0)[:, None]
            direct[:, k] += (normals[:, k] - normals[:, m]) * ww
            on_normal[:, k] += (X[:, k] - X[:, m]) * ww
    return direct, on_normal


def _spread(f, tri, k, out):
    """Per-corner vectors of (A, B, C) onto the segment's nodes (a quad's centroid A to
    its four corners equally)."""
    r = np.arange(len(k))
    t = tri[:, None]
    for q in range(3):
        out[:, q] += np.where(t, f[:, q], 0.0)
    quad = ~tri
    out[quad] += 0.25 * f[quad, 0][:, None, :]
    rq = r[quad]
    out[rq, k[quad]] += f[quad, 1]
    out[rq, (k[quad] + 1) % 4] += f[quad, 2]


def corner_gradients(A, B, C, du, dv, df, bary, rho):
    """Derivatives of f(w) (partials df) of the weights of a point's projection on the
    plane of (A, B, C) (barycentrics bary, x - P = rho) by the point (grad) and by the
    corners (A, B, C): vertex, edge and interior regions each by its own formula."""
    n = len(A)
    grad = np.zeros((n, 3))
    cg = np.zeros((n, 3, 3))
    zero = bary <= 0.0
    zeros = zero.sum(axis=1)
    Xs = np.stack([A, B, C], axis=1)
    W = np.stack([np.zeros_like(du), du, dv], axis=1)          # corner weight vectors
    r = np.arange(n)
    # on an edge from corner i to corner j
    e1 = zeros == 1
    if np.any(e1):
        z = np.argmax(zero, axis=1)
        i, j = (z + 1) % 3, (z + 2) % 3
        e = Xs[r, j] - Xs[r, i]
        ee = dot(e, e)
        ok = e1 & (ee > 0.0)
        t = bary[r, j]
        ft = (df * (W[r, j] - W[r, i])).sum(axis=1)
        s = np.where(ok, ft / np.where(ok, ee, 1.0), 0.0)[:, None]
        grad = np.where(ok[:, None], e * s, grad)
        ci = (-e * (1.0 - t)[:, None] - rho) * s
        cj = (-e * t[:, None] + rho) * s
        cg[r[ok], i[ok]] = ci[ok]
        cg[r[ok], j[ok]] = cj[ok]
    # interior
    e0 = zeros == 0
    if np.any(e0):
        a1, a2 = B - A, C - A
        p, q, rr = dot(a1, a1), dot(a1, a2), dot(a2, a2)
        det = p * rr - q * q
        ok = e0 & (det > 0.0)
        dd = np.where(ok, det, 1.0)
        g00, g01, g11 = rr / dd, -q / dd, p / dd
        g1 = a1 * g00[:, None] + a2 * g01[:, None]
        g2 = a1 * g01[:, None] + a2 * g11[:, None]
        u, v = bary[:, 1], bary[:, 2]
        fu = (df * du).sum(axis=1)
        fv = (df * dv).sum(axis=1)
        gr = g1 * fu[:, None] + g2 * fv[:, None]
        r1 = rho * (fu * g00 + fv * g01)[:, None]
        r2 = rho * (fu * g01 + fv * g11)[:, None]
        c = np.stack([-gr * (1.0 - u - v)[:, None] - r1 - r2, -gr * u[:, None] + r1,
                      -gr * v[:, None] + r2], axis=1)
        grad = np.where(ok[:, None], gr, grad)
        cg = np.where(ok[:, None, None], c, cg)
    return grad, cg


def _triangle_normal_pullback(A, B, C, t):
    """(d n / d corners)^T t for the unit normal of (A, B, C)."""
    e1, e2 = B - A, C - A
    m = cross(e1, e2)
    n, ln = _unit(m)
    ok = ln > 0.0
    tt = t - n * dot(n, t)[:, None]
    l_ = np.where(ok, ln, 1.0)[:, None]
    db = np.where(ok[:, None], cross(e2, tt) / l_, 0.0)
    dc = np.where(ok[:, None], cross(tt, e1) / l_, 0.0)
    return np.stack([-(db + dc), db, dc], axis=1)


# ---- the points of one direction ---------------------------------------------------
_TEMPLATES = {}


def _template(n):
    """(u, v) of the centroids of a (sub-)triangle's n x n small triangles, strip by
    strip (u between i/n and (i+1)/n), as crash orders them."""
    t = _TEMPLATES.get(n)
    if t is None:
        out = []
        for i in range(n):
            for j in range(n - i):
                out.append(((i + 1.0 / 3.0) / n, (j + 1.0 / 3.0) / n))
                if i + j + 1 < n:
                    out.append(((i + 2.0 / 3.0) / n, (j + 2.0 / 3.0) / n))
        t = _TEMPLATES[n] = np.array(out)
    return t


def _box_gap(alo, ahi, blo, bhi):
    d = np.maximum(blo - ahi, 0.0) + np.maximum(alo - bhi, 0.0)
    return np.sqrt(dot(d, d))


def _points(g, cv, x, segs, c):
    """The quadrature points of the slave segments segs: slave segment, sub-triangle
    (A, B, C), unit normal, weights w, the point x_a, its bulge h_s and its area share."""
    subs = np.nonzero(np.isin(g.sub_seg, segs))[0]
    seg, k = g.sub_seg[subs], g.sub_k[subs]
    A, B, C = g.corners(x, seg, k)
    longest = np.maximum(np.maximum(norm(B - A), norm(C - B)), norm(A - C))
    with np.errstate(invalid="ignore"):
        n = np.nan_to_num(np.ceil(longest / (SPACING * c)), nan=0.0)
    n = np.clip(n, 1, MAX_PARTS).astype(np.int64)
    rows, us, vs, ns = [], [], [], []
    for m in np.unique(n):
        t = _template(int(m))
        r = np.nonzero(n == m)[0]
        rows.append(np.repeat(r, len(t)))
        us.append(np.tile(t[:, 0], len(r)))
        vs.append(np.tile(t[:, 1], len(r)))
        ns.append(np.full(len(r) * len(t), m))
    if not rows:
        return None
    r = np.concatenate(rows)
    u, v, n = np.concatenate(us), np.concatenate(vs), np.concatenate(ns)
    order = np.lexsort((np.arange(len(r)), r))     # sub-triangle order, then point order
    r, u, v, n = r[order], u[order], v[order], n[order]
    s = subs[r]
    du, dv = g.dw_du[s], g.dw_dv[s]
    w = g.base[s] + (u[:, None] * du + v[:, None] * dv)
    A, B, C = A[r], B[r], C[r]
    flat = A + (B - A) * u[:, None] + (C - A) * v[:, None]
    nsub, _ = _unit(cross(B - A, C - A))
    js = g.sub_seg[s]
    hs, _ = bulge(cv.b[js], w)
    xa = flat + nsub * hs[:, None]
    return dict(seg=js, k=g.sub_k[s], A=A, B=B, C=C, nsub=nsub, w=w, hs=hs, xa=xa,
                area=g.sub_area0[s] / (n * n).astype(float), du=du, dv=dv)


def _masters(pts, cs, gm, cm, xm, reach, tie, c):
    """Each point's master by crash's rule over the masters whose node box lies within
    reach of it: (point rows, master segments, projections) of the points that have one
    within reach and off the master's mid-surface."""
    segs = np.unique(pts["seg"])
    grow = reach + cs.bound[segs]
    gap = _box_gap(cs.lo[segs][:, None, :], cs.hi[segs][:, None, :], cm.lo[None], cm.hi[None])
    si, mj = np.nonzero(gap < grow[:, None])
    if len(si) == 0:
        return None
    # the point x candidate pairs: every master of its slave segment, box within reach
    pos = np.searchsorted(segs, pts["seg"])
    start = np.searchsorted(si, np.arange(len(segs)), side="left")
    cnt = np.searchsorted(si, np.arange(len(segs)), side="right") - start
    pc = cnt[pos]
    rows = np.repeat(np.arange(len(pos)), pc)
    off = np.arange(pc.sum()) - np.repeat(np.cumsum(pc) - pc, pc)
    mseg = mj[np.repeat(start[pos], pc) + off]
    p = pts["xa"][rows]
    d = np.maximum(cm.lo[mseg] - p, 0.0) + np.maximum(p - cm.hi[mseg], 0.0)
    keep = np.sqrt(dot(d, d)) < reach
    rows, mseg = rows[keep], mseg[keep]
    if len(rows) == 0:
        return None
    dist, point, weights, _, sub, bary = project(pts["xa"][rows], gm.nodes[mseg], gm.count[mseg], xm)
    # the rule: candidates in index order; the first is the best, a later one replaces
    # it only when closer by more than TIE c
    order = np.lexsort((mseg, rows))
    rows, mseg = rows[order], mseg[order]
    dist, point, weights, sub, bary = dist[order], point[order], weights[order], sub[order], bary[order]
    first = np.searchsorted(rows, rows, side="left")
    rank = np.arange(len(rows)) - first
    best = np.full(len(pos), -1)
    bestd = np.full(len(pos), np.inf)
    for q in range(int(rank.max()) + 1):
        at = np.nonzero((rank == q) & ~np.isnan(dist))[0]
        rr = rows[at]
        better = (best[rr] < 0) | (dist[at] < bestd[rr] - tie)
        best[rr[better]] = at[better]
        bestd[rr[better]] = dist[at[better]]
    pick = best[best >= 0]
    pick = pick[(dist[pick] < reach) & (dist[pick] > 1e-9 * c)]
    if len(pick) == 0:
        return None
    return dict(row=rows[pick], seg=mseg[pick], dist=dist[pick], point=point[pick],
                weights=weights[pick], sub=sub[pick], bary=bary[pick])


def _normal_rate(of_node, which, cv, g, v):
    """d n / dt of corner normals: nodal (of_node) or the segment's own."""
    dFn, dF = cv.rates(g, v)
    F = np.where(of_node[:, None], cv.Fn[np.where(of_node, which, 0)], cv.F[np.where(of_node, 0, which)])
    dFx = np.where(of_node[:, None], dFn[np.where(of_node, which, 0)], dF[np.where(of_node, 0, which)])
    n, ln = _unit(F)
    ok = ln > 0.0
    return np.where(ok[:, None], (dFx - n * dot(n, dFx)[:, None]) / np.where(ok, ln, 1.0)[:, None], 0.0)


def _direction(S, M, c, kappa, mu, xi, loads):
    """One direction of the pass: slave S's points against master M (S, M: (body,
    geometry, curved)). Returns the pushes (node forces on both, statistics); the loads
    on the normals go into loads[S body id], loads[M body id] (per node, per segment)."""
    (sb, gs, cs), (mb, gm, cm) = S, M
    xs, xm = sb.x, mb.x
    hm_max = float(cm.bound.max()) if gm.ns else 0.0
    reach = c + max(BULGE_REACH * c, hm_max)
    # slave segments within reach (plus their own bulge) of the master's node box
    grow = reach + cs.bound
    lo, hi = xm.min(axis=0), xm.max(axis=0)
    near = np.nonzero(_box_gap(cs.lo, cs.hi, lo[None], hi[None]) < grow)[0]
    if len(near) == 0:
        return None
    pts = _points(gs, cs, xs, near, c)
    if pts is None:
        return None
    hit = _masters(pts, cs, gm, cm, xm, reach, TIE * c, c)
    if hit is None:
        return None
    r, j = hit["row"], hit["seg"]
    P = {k: val[r] for k, val in pts.items()}
    js, ksub = P["seg"], P["k"]
    xa = P["xa"]
    # the master's (sub-)triangle, the side, the master's bulge and the gap
    mtri = gm.tri[j]
    msub = np.where(mtri, 0, hit["sub"])
    mA, mB, mC = gm.corners(xm, j, msub)
    mdu, mdv, _ = gm._weight_derivatives(j, msub)
    rho = xa - hit["point"]
    dist = hit["dist"]
    direc = rho / dist[:, None]
    mn, _ = _unit(cross(mB - mA, mC - mA))
    side = np.where(dot(direc, mn) >= 0.0, 1.0, -1.0)
    hm, dhm = bulge(cm.b[j], hit["weights"])
    gap = dist - side * hm - c
    on = gap < 0.0
    if not np.any(on):
        return None
    sel = np.nonzero(on)[0]
    j, js, ksub, msub, mtri = j[sel], js[sel], ksub[sel], msub[sel], mtri[sel]
    P = {k: val[sel] for k, val in P.items()}
    mA, mB, mC, mdu, mdv = mA[sel], mB[sel], mC[sel], mdu[sel], mdv[sel]
    rho, direc, side, dhm, gap = rho[sel], direc[sel], side[sel], dhm[sel], gap[sel]
    weights, bary = hit["weights"][sel], hit["bary"][sel]
    # the exact gradient of g: by the slave point, by the master's corner nodes
    gw, cg = corner_gradients(mA, mB, mC, mdu, mdv, dhm, bary, rho)
    grad = direc - gw * side[:, None]
    gmf = -direc[:, None, :] * weights[:, :, None]
    _spread(cg * -side[:, None, None], mtri, msub, gmf)
    mcount = gm.count[j]
    direct, m_tau = bulge_parts(cm.X[j], cm.normals[j], weights, -side, mcount)
    gmf += direct
    # the slave point: with its facet, along the facet's normal by h_s, and with h_s
    w = P["w"]
    gsf = grad[:, None, :] * w[:, :, None]
    pb = _triangle_normal_pullback(P["A"], P["B"], P["C"], grad)
    stri = gs.tri[js]
    _spread(pb * P["hs"][:, None, None], stri, ksub, gsf)
    scount = gs.count[js]
    direct, s_tau = bulge_parts(cs.X[js], cs.normals[js], w, dot(grad, P["nsub"]), scount)
    gsf += direct
    # the stiffening law, damping
    k = kappa * P["area"]
    phi = k * c * law_force(-gap / c)
    snodes, mnodes = gs.nodes[js], gm.nodes[j]
    if xi > 0.0:
        gdot = np.zeros(len(phi))
        for q in range(4):
            for (g_, cv, b_, nodes, seg, f, tau, count) in (
                    (gs, cs, sb, snodes, js, gsf, s_tau, scount),
                    (gm, cm, mb, mnodes, j, gmf, m_tau, mcount)):
                of_node = cv.nodal[seg, q]
                which = np.where(of_node, nodes[:, q], seg)
                rate = _normal_rate(of_node, which, cv, g_, b_.v)
                term = dot(f[:, q], b_.v[nodes[:, q]]) + dot(tau[:, q], rate)
                gdot += np.where(q < count, term, 0.0)
        phi = phi - 2.0 * xi * np.sqrt(k * (mu * P["area"])) * gdot
    ok = (phi > 0.0) & np.isfinite(phi)
    if not np.any(ok):
        return None
    # loads on the normals (a corner's nodal normal, or on a crease its segment's)
    for (body, cv, nodes, seg, tau, count) in ((sb, cs, snodes, js, s_tau, scount),
                                               (mb, cm, mnodes, j, m_tau, mcount)):
        tn, ts = loads[body.id]
        for q in range(4):
            use = ok & (q < count)
            t = tau[:, q] * phi[:, None]
            nod = use & cv.nodal[seg, q]
            np.add.at(tn, nodes[nod, q], t[nod])
            crease = use & ~cv.nodal[seg, q]
            np.add.at(ts, seg[crease], t[crease])
    phi = phi[ok]
    return dict(snodes=snodes[ok], scount=scount[ok], sf=gsf[ok] * phi[:, None, None],
                mnodes=mnodes[ok], mcount=mcount[ok], mf=gmf[ok] * phi[:, None, None],
                normal_force=phi * norm(grad[ok]), depth=-gap[ok])


def _add(body, nodes, count, f):
    for q in range(4):
        m = count > q
        np.add.at(body.f_contact, nodes[m, q], f[m, q])


def _pull_back(body, g, cv, tau_node, tau_seg):
    """The loads summed per normal pulled back to node forces: (d n / d x)^T tau for
    n = F / |F|, F the sum of the face vectors of the normal's segments."""
    n, ln = cv.nn_unit, cv.ln
    ok = ln > 0.0
    t_node = np.where(ok[:, None], (tau_node - n * dot(n, tau_node)[:, None])
                      / np.where(ok, ln, 1.0)[:, None], 0.0)
    ns, ls = cv.ns_unit, cv.ls
    ok = ls > 0.0
    t_seg = np.where(ok[:, None], (tau_seg - ns * dot(ns, tau_seg)[:, None])
                     / np.where(ok, ls, 1.0)[:, None], 0.0)
    T = t_seg + sum(np.where((q < g.count)[:, None], t_node[g.nodes[:, q]], 0.0) for q in range(4))
    live = np.nonzero(np.any(T != 0.0, axis=1))[0]
    if len(live) == 0:
        return
    X, T, tri = cv.X[live], T[live], g.tri[live]
    f = np.zeros((len(live), 4, 3))
    db = cross(X[:, 2] - X[:, 0], T)
    dc = cross(T, X[:, 1] - X[:, 0])
    qc = cross(X[:, 3] - X[:, 1], T)
    qd = cross(T, X[:, 2] - X[:, 0])
    t3 = tri[:, None]
    f[:, 0] = np.where(t3, -(db + dc), -qc)
    f[:, 1] = np.where(t3, db, -qd)
    f[:, 2] = np.where(t3, dc, qc)
    f[:, 3] = np.where(t3, 0.0, qd)
    _add(body, g.nodes[live], g.count[live], f)


def _tally(values):
    """crash's exact sum of forces on the quantum 2^-64 N (truncated toward zero)."""
    q = 2.0 ** 64
    return float(sum(int(v * q) for v in values)) / q


FINER = 0.99
# sides "auto": one way only where the finer mean segment area is below this fraction
# of the other's (crash: contact::ONE_SIDE_RATIO)
ONE_SIDE_RATIO = 0.7


def _slave_is_a(a, b):
    """The finer surface (mean initial segment area smaller by more than 1 %), else the
    lower id."""
    (ida, ga), (idb, gb) = a, b
    if ga.mean_area < FINER * gb.mean_area:
        return True
    if gb.mean_area < FINER * ga.mean_area:
        return False
    return ida < idb


def segment_pair(a, b, ga, gb, cfg, dt_ref):
    """The segment pass of a pair of different bodies: one way the slave's points (the
    finer surface, by mean initial segment area, else the lower id) against the master's
    curved surface, full weight; both ways a's points against b, then b's against a,
    half the weight each; forces into f_contact; the pair's statistics. Sides "finer":
    one way; "both": both ways; "auto": one way only where the finer mean area is below
    ONE_SIDE_RATIO of the other's."""
    sides = cfg.get("sides", "auto")
    lo, hi = sorted((ga.mean_area, gb.mean_area))
    both = sides == "both" or (sides == "auto" and not lo < ONE_SIDE_RATIO * hi)
    mu = min(ga.areal_mass, gb.areal_mass)
    kappa = (0.5 if both else 1.0) * cfg["penalty_scale"] * mu / (dt_ref * dt_ref)
    c = 0.5 * (a.thickness + b.thickness)
    xi = cfg["damping_ratio"]
    ca, cb = Curved(ga, a.x), Curved(gb, b.x)
    loads = {a.id: (np.zeros((ga.nn, 3)), np.zeros((ga.ns, 3))),
             b.id: (np.zeros((gb.nn, 3)), np.zeros((gb.ns, 3)))}
    a_slave = _slave_is_a((a.id, ga), (b.id, gb))
    first = second = None
    if both or a_slave:
        first = _direction((a, ga, ca), (b, gb, cb), c, kappa, mu, xi, loads)
    if both or not a_slave:
        second = _direction((b, gb, cb), (a, ga, ca), c, kappa, mu, xi, loads)
    st = dict(a=a.id, b=b.id, active=0, max_penetration=0.0, normal_force=0.0)
    forces = []
    for pu, sl, ms in ((first, a, b), (second, b, a)):
        if pu is None:
            continue
        _add(sl, pu["snodes"], pu["scount"], pu["sf"])
        _add(ms, pu["mnodes"], pu["mcount"], pu["mf"])
        st["active"] += len(pu["depth"])
        st["max_penetration"] = max(st["max_penetration"], float(pu["depth"].max()))
        forces.append(pu["normal_force"])
    for body, g, cv in ((a, ga, ca), (b, gb, cb)):
        _pull_back(body, g, cv, *loads[body.id])
    st["normal_force"] = _tally(np.concatenate(forces)) if forces else 0.0
    st["max_penetration_ratio"] = st["max_penetration"] / min(a.thickness, b.thickness)
    return st
