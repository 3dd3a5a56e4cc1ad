"""The one-point triangle and BLT quad of docs/theory.md section 2, vectorised over the
elements of a body: membrane (total Lagrangian, 2.1), plate part in rate form (bending,
transverse shear, drilling, 2.2), quad hourglass control (2.3), the element time step
lengths (4) and Kelvin damping (1)."""

from types import SimpleNamespace

import numpy as np

from .vec import dot, cross

HG = np.array([1.0, -1.0, 1.0, -1.0])


def _tri_frame(X):
    """e1 along 1->2, e3 normal, local (a, c, d) and twice the area."""
    r2 = X[:, 1] - X[:, 0]
    r3 = X[:, 2] - X[:, 0]
    n = cross(r2, r3)
    two_area = np.sqrt(dot(n, n))
    e3 = n / two_area[:, None]
    a = np.sqrt(dot(r2, r2))
    e1 = r2 / a[:, None]
    e2 = cross(e3, e1)
    c = dot(r3, e1)
    d = dot(r3, e2)
    return e1, e2, e3, a, c, d, two_area


def _tri_gradients(a, c, d):
    ad = a * d
    z = np.zeros_like(a)
    bx = np.stack([-d / ad, d / ad, z], axis=1)
    by = np.stack([(c - a) / ad, -c / ad, a / ad], axis=1)
    return bx, by


def _quad_frame(X):
    """BLT frame: e3 normal to the diagonals, e1 the projection of x2 - x1; local
    coordinates relative to the centroid."""
    n = cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
    e3 = n / np.sqrt(dot(n, n))[:, None]
    r = X[:, 1] - X[:, 0]
    r = r - e3 * dot(r, e3)[:, None]
    e1 = r / np.sqrt(dot(r, r))[:, None]
    e2 = cross(e3, e1)
    cen = (X[:, 0] + X[:, 1] + X[:, 2] + X[:, 3]) * 0.25
    rel = X - cen[:, None, :]
    xl = dot(rel, e1[:, None, :])
    yl = dot(rel, e2[:, None, :])
    return e1, e2, e3, xl, yl


def _quad_gradients(xl, yl):
    """bx = [y24, y31, y42, y13]/(2A), by = [x42, x13, x24, x31]/(2A),
    2A = x31 y42 - x42 y31."""
    x31 = xl[:, 2] - xl[:, 0]
    x42 = xl[:, 3] - xl[:, 1]
    y31 = yl[:, 2] - yl[:, 0]
    y42 = yl[:, 3] - yl[:, 1]
    two_a = x31 * y42 - x42 * y31
    bx = np.stack([-y42, y31, y42, -y31], axis=1) / two_a[:, None]
    by = np.stack([x42, -x31, -x42, x31], axis=1) / two_a[:, None]
    return bx, by, 0.5 * two_a


def _green(f1, f2):
    return np.stack([0.5 * (dot(f1, f1) - 1.0), 0.5 * (dot(f2, f2) - 1.0), dot(f1, f2)], axis=1)


def _plane(k, nu, e):
    """C e scaled by k, engineering strain (xx, yy, 2xy)."""
    return np.stack([k * (e[:, 0] + nu * e[:, 1]), k * (nu * e[:, 0] + e[:, 1]),
                     k * 0.5 * (1.0 - nu) * e[:, 2]], axis=1)


def reference(body):
    """Reference gradients b0, initial areas A0, quad E0, gamma and hourglass
    stiffnesses (theory.md 2, 2.1, 2.3)."""
    ref = SimpleNamespace()
    x = body.x0
    if len(body.tris):
        X = x[body.tris]
        _, _, _, a, c, d, two_area = _tri_frame(X)
        ref.tri_bx0, ref.tri_by0 = _tri_gradients(a, c, d)
        ref.tri_area0 = 0.5 * two_area
    else:
        ref.tri_area0 = np.zeros(0)
    if len(body.quads):
        X = x[body.quads]
        _, _, _, xl, yl = _quad_frame(X)
        bx0, by0, area0 = _quad_gradients(xl, yl)
        ref.quad_bx0, ref.quad_by0, ref.quad_area0 = bx0, by0, area0
        hx = (HG[None, :] * xl).sum(axis=1)
        hy = (HG[None, :] * yl).sum(axis=1)
        ref.gamma = 0.25 * (HG[None, :] - hx[:, None] * bx0 - hy[:, None] * by0)
        f1 = (X * bx0[:, :, None]).sum(axis=1)
        f2 = (X * by0[:, :, None]).sum(axis=1)
        ref.e0 = _green(f1, f2)
        bb = (bx0 * bx0 + by0 * by0).sum(axis=1)
        from .body import R_HG_M, R_HG_W, R_HG_TH
        ref.k_m = R_HG_M * body.k_membrane * area0 * bb
        ref.k_w = R_HG_W * body.k_bending * area0 * bb * bb
        ref.k_th = R_HG_TH * body.k_bending * area0 * bb
    else:
        ref.quad_area0 = np.zeros(0)
    return ref


def _membrane(body, X, V, bx0, by0, area0, e0, h):
    """Total-Lagrangian membrane (2.1) with Kelvin damping: global nodal forces
    (ne, N, 3), stored energy, and the Kelvin part of the nodal forces (ne, N, 3; zero
    without damping), A0 F S_d b0_I."""
    f1 = (X * bx0[:, :, None]).sum(axis=1)
    f2 = (X * by0[:, :, None]).sum(axis=1)
    e = _green(f1, f2)
    if e0 is not None:
        e = e - e0
    nu = body.material.poisson
    s = _plane(body.k_membrane, nu, e)
    energy = 0.5 * area0 * (s * e).sum(axis=1)

    def nodal(s):
        p1 = (f1 * s[:, 0:1] + f2 * s[:, 2:3]) * area0[:, None]
        p2 = (f1 * s[:, 2:3] + f2 * s[:, 1:2]) * area0[:, None]
        return p1[:, None, :] * bx0[:, :, None] + p2[:, None, :] * by0[:, :, None]

    sd = np.zeros_like(s)
    alpha = body.material.kelvin
    if alpha > 0.0:
        d1 = (V * bx0[:, :, None]).sum(axis=1)
        d2 = (V * by0[:, :, None]).sum(axis=1)
        ed = np.stack([dot(f1, d1), dot(f2, d2), dot(f1, d2) + dot(d1, f2)], axis=1)
        sd = alpha * _plane(body.k_membrane, nu, ed)
    return nodal(s + sd), energy, nodal(sd)


def _plate(body, sl, bx, by, area, cw, cx, cy, vl, wl, h):
    """Rate-form plate part (2.2) of the elements `sl` (a slice of the body's element
    state): updates M, Q, tau; returns local nodal forces/moments (ne, N, 6), the stored
    energy and the Kelvin part of the nodal forces/moments (ne, N, 6; zero without
    damping: the same maps applied to M_d, Q_d, no drilling)."""
    N = bx.shape[1]
    wx, wy, wz = wl[:, :, 0], wl[:, :, 1], wl[:, :, 2]
    vx, vy, vz = vl[:, :, 0], vl[:, :, 1], vl[:, :, 2]
    kr = np.stack([(bx * wy).sum(axis=1), -(by * wx).sum(axis=1),
                   (by * wy - bx * wx).sum(axis=1)], axis=1)
    g = np.stack([(cw[:, :, s] * vz + cx[:, :, s] * wx + cy[:, :, s] * wy).sum(axis=1)
                  for s in range(2)], axis=1)
    drill_rate = wz.mean(axis=1) - 0.5 * (bx * vy - by * vx).sum(axis=1)
    nu = body.material.poisson
    M = body.M[sl] + h * _plane(body.k_bending, nu, kr)
    Q = body.Q[sl] + h * body.k_shear * g
    tau = body.tau[sl] + h * body.k_drill * drill_rate
    body.M[sl], body.Q[sl], body.tau[sl] = M, Q, tau
    D = body.k_bending
    energy = area * (
        (M[:, 0] ** 2 + M[:, 1] ** 2 - 2.0 * nu * M[:, 0] * M[:, 1] + 2.0 * (1.0 + nu) * M[:, 2] ** 2)
        / (2.0 * D * (1.0 - nu * nu))
        + (Q[:, 0] ** 2 + Q[:, 1] ** 2) / (2.0 * body.k_shear)
        + tau * tau / (2.0 * body.k_drill))
    A = area[:, None]

    def nodal(M, Q, tau):
        out = np.zeros(bx.shape + (6,))
        out[:, :, 3] = A * (-by * M[:, 1:2] - bx * M[:, 2:3])
        out[:, :, 4] = A * (bx * M[:, 0:1] + by * M[:, 2:3])
        out[:, :, 2] = A * (Q[:, 0:1] * cw[:, :, 0] + Q[:, 1:2] * cw[:, :, 1])
        out[:, :, 3] += A * (Q[:, 0:1] * cx[:, :, 0] + Q[:, 1:2] * cx[:, :, 1])
        out[:, :, 4] += A * (Q[:, 0:1] * cy[:, :, 0] + Q[:, 1:2] * cy[:, :, 1])
        td = (area * tau)[:, None]
        out[:, :, 5] = td / N
        out[:, :, 0] = 0.5 * td * by
        out[:, :, 1] = -0.5 * td * bx
        return out

    Md, Qd = np.zeros_like(M), np.zeros_like(Q)
    alpha = body.material.kelvin
    if alpha > 0.0:
        Md = alpha * _plane(body.k_bending, nu, kr)
        Qd = alpha * body.k_shear * g
    return nodal(M + Md, Q + Qd, tau), energy, nodal(Md, Qd, np.zeros_like(tau))


def _tri_shear(a, c, d):
    """Coefficients of v_z, omega_x, omega_y of node I in the centroid shear (2.2,
    "Transverse shear of the triangle"): edges 1->2, 2->3, 3->1 with vectors (a, 0),
    (c - a, d), (-c, -d); h_e = u_e - mean(u); g_x = h_1/a, g_y = -(h_3 + (c/a) h_1)/d."""
    ne = len(a)
    third = 1.0 / 3.0
    # K[s][e]: coefficient of u_e in g_s
    kx = np.stack([(1 - third) / a, -third / a, -third / a], axis=1)
    ca = c / a
    ky = -np.stack([-third + ca * (1 - third), -third - ca * third, (1 - third) - ca * third], axis=1) / d[:, None]
    K = np.stack([kx, ky], axis=2)         # (ne, edge, s)
    ex = np.stack([a, c - a, -c], axis=1)  # edge vectors, local x
    ey = np.stack([np.zeros(ne), d, -d], axis=1)
    cw = np.zeros((ne, 3, 2))
    cx = np.zeros((ne, 3, 2))
    cy = np.zeros((ne, 3, 2))
    for e, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
        k = K[:, e, :]
        cw[:, i] -= k
        cw[:, j] += k
        hx = 0.5 * k * ex[:, e:e + 1]
        hy = 0.5 * k * ey[:, e:e + 1]
        cy[:, i] += hx
        cy[:, j] += hx
        cx[:, i] -= hy
        cx[:, j] -= hy
    return cw, cx, cy


def _to_global(e1, e2, e3, lo):
    """Local (ne, N, 3) components -> global."""
    return (lo[:, :, 0:1] * e1[:, None, :] + lo[:, :, 1:2] * e2[:, None, :]
            + lo[:, :, 2:3] * e3[:, None, :])


def _local(p, e1, e2, e3):
    return np.stack([dot(p, e1[:, None, :]), dot(p, e2[:, None, :]), dot(p, e3[:, None, :])], axis=2)


def forces(body, h):
    """All element forces of a body at its current state. Returns gathered nodal forces
    and moments (global), their Kelvin part (global, gathered the same way), per-element
    energies, lengths, area ratios and quad corner orientations."""
    x, v, w = body.x, body.v, body.w
    ref = body.ref
    nt, nq = len(body.tris), len(body.quads)
    slot_f, slot_d, slot_nodes = [], [], []
    internal, hourglass, length, ratio = [], [], [], []
    corners = None
    if nt:
        X, V, W = x[body.tris], v[body.tris], w[body.tris]
        e1, e2, e3, a, c, d, two_area = _tri_frame(X)
        fm, em, dm = _membrane(body, X, V, ref.tri_bx0, ref.tri_by0, ref.tri_area0, None, h)
        bx, by = _tri_gradients(a, c, d)
        cw, cx, cy = _tri_shear(a, c, d)
        vl, wl = _local(V, e1, e2, e3), _local(W, e1, e2, e3)
        lo, ep, dp = _plate(body, slice(0, nt), bx, by, 0.5 * two_area, cw, cx, cy, vl, wl, h)
        f = fm + _to_global(e1, e2, e3, lo[:, :, 0:3])
        m = _to_global(e1, e2, e3, lo[:, :, 3:6])
        slot_f.append(np.concatenate([f, m], axis=2).reshape(-1, 6))
        fd = dm + _to_global(e1, e2, e3, dp[:, :, 0:3])
        md = _to_global(e1, e2, e3, dp[:, :, 3:6])
        slot_d.append(np.concatenate([fd, md], axis=2).reshape(-1, 6))
        slot_nodes.append(body.tris.reshape(-1))
        internal.append(em + ep)
        hourglass.append(np.zeros(nt))
        r23 = X[:, 2] - X[:, 1]
        r2 = X[:, 1] - X[:, 0]
        r3 = X[:, 2] - X[:, 0]
        longest = np.sqrt(np.maximum(np.maximum(dot(r2, r2), dot(r3, r3)), dot(r23, r23)))
        length.append(two_area / longest)
        ratio.append(0.5 * two_area / ref.tri_area0)
    if nq:
        X, V, W = x[body.quads], v[body.quads], w[body.quads]
        e1, e2, e3, xl, yl = _quad_frame(X)
        bx, by, area = _quad_gradients(xl, yl)
        nxt = [1, 2, 3, 0]
        prv = [3, 0, 1, 2]
        corners = ((xl[:, nxt] - xl) * (yl[:, prv] - yl) - (yl[:, nxt] - yl) * (xl[:, prv] - xl))
        fm, em, dm = _membrane(body, X, V, ref.quad_bx0, ref.quad_by0, ref.quad_area0, ref.e0, h)
        gam = ref.gamma
        # in-plane hourglass, total form
        q = (X * gam[:, :, None]).sum(axis=1)
        qt = q - e3 * dot(q, e3)[:, None]
        fq = qt * ref.k_m[:, None]
        ehg = 0.5 * ref.k_m * dot(qt, qt)
        vl, wl = _local(V, e1, e2, e3), _local(W, e1, e2, e3)
        # out-of-plane and rotational hourglass, rate form
        body.hg_w = body.hg_w + h * ref.k_w * (gam * vl[:, :, 2]).sum(axis=1)
        body.hg_th = body.hg_th + h * ref.k_th[:, None] * np.stack(
            [(gam * wl[:, :, 0]).sum(axis=1), (gam * wl[:, :, 1]).sum(axis=1)], axis=1)
        ehg = ehg + body.hg_w ** 2 / (2.0 * ref.k_w) + (body.hg_th ** 2).sum(axis=1) / (2.0 * ref.k_th)
        cw = np.stack([bx, by], axis=2)
        cx = np.zeros((nq, 4, 2))
        cx[:, :, 1] = -0.25
        cy = np.zeros((nq, 4, 2))
        cy[:, :, 0] = 0.25
        lo, ep, dp = _plate(body, slice(nt, nt + nq), bx, by, area, cw, cx, cy, vl, wl, h)
        lo[:, :, 2] += gam * body.hg_w[:, None]
        lo[:, :, 3] += gam * body.hg_th[:, 0:1]
        lo[:, :, 4] += gam * body.hg_th[:, 1:2]
        f = fm + fq[:, None, :] * gam[:, :, None] + _to_global(e1, e2, e3, lo[:, :, 0:3])
        m = _to_global(e1, e2, e3, lo[:, :, 3:6])
        slot_f.append(np.concatenate([f, m], axis=2).reshape(-1, 6))
        fd = dm + _to_global(e1, e2, e3, dp[:, :, 0:3])
        md = _to_global(e1, e2, e3, dp[:, :, 3:6])
        slot_d.append(np.concatenate([fd, md], axis=2).reshape(-1, 6))
        slot_nodes.append(body.quads.reshape(-1))
        internal.append(em + ep)
        hourglass.append(ehg)
        d13 = X[:, 2] - X[:, 0]
        d24 = X[:, 3] - X[:, 1]
        length.append(area / np.sqrt(np.maximum(dot(d13, d13), dot(d24, d24))))
        ratio.append(area / ref.quad_area0)
    # gather per node in element order (triangles, then quads)
    sf = np.concatenate(slot_f)
    sd = np.concatenate(slot_d)
    sn = np.concatenate(slot_nodes)
    n = len(x)
    g = np.stack([np.bincount(sn, weights=sf[:, k], minlength=n) for k in range(6)], axis=1)
    gd = np.stack([np.bincount(sn, weights=sd[:, k], minlength=n) for k in range(6)], axis=1)
    return SimpleNamespace(
        f=g[:, 0:3], m=g[:, 3:6], fd=gd[:, 0:3], md=gd[:, 3:6],
        internal=np.concatenate(internal), hourglass=np.concatenate(hourglass),
        length=np.concatenate(length), ratio=np.concatenate(ratio), corners=corners)
