"""Meshes: the plate and icosphere generators and the Gmsh 4.1 ASCII reader.

A mesh is (nodes (n, 3) float, tris (nt, 3) int, quads (nq, 4) int). The generators
follow the recipes written down in docs/crosscheck.md ("Generated meshes"): node and
element order matter, because the comparison matches crash's output node by node.
"""

import math

import numpy as np


def plate(lx, ly, nx, ny, kind):
    """Rectangle lx x ly in the xy plane, centred, nx x ny cells. Nodes row by row
    (x fastest); quads (i,j) -> [a, b, c, d] counter-clockwise; triangles split cell
    (i, j) along a-c when i + j is even ([a,b,c], [a,c,d]), else along b-d
    ([a,b,d], [b,c,d])."""
    i = np.arange(nx + 1, dtype=float)
    j = np.arange(ny + 1, dtype=float)
    xs = lx * (i / nx - 0.5)
    ys = ly * (j / ny - 0.5)
    nodes = np.zeros(((nx + 1) * (ny + 1), 3))
    nodes[:, 0] = np.tile(xs, ny + 1)
    nodes[:, 1] = np.repeat(ys, nx + 1)
    tris, quads = [], []
    for jj in range(ny):
        for ii in range(nx):
            a = jj * (nx + 1) + ii
            b = a + 1
            c = a + nx + 2
            d = a + nx + 1
            if kind == "quad":
                quads.append([a, b, c, d])
            elif (ii + jj) % 2 == 0:
                tris += [[a, b, c], [a, c, d]]
            else:
                tris += [[a, b, d], [b, c, d]]
    return nodes, _ints(tris, 3), _ints(quads, 4)


def _ints(rows, n):
    return np.array(rows, dtype=np.int64).reshape(-1, n)


_ICO_T = (1.0 + math.sqrt(5.0)) / 2.0
_ICO_NODES = [
    (-1.0, _ICO_T, 0.0), (1.0, _ICO_T, 0.0), (-1.0, -_ICO_T, 0.0), (1.0, -_ICO_T, 0.0),
    (0.0, -1.0, _ICO_T), (0.0, 1.0, _ICO_T), (0.0, -1.0, -_ICO_T), (0.0, 1.0, -_ICO_T),
    (_ICO_T, 0.0, -1.0), (_ICO_T, 0.0, 1.0), (-_ICO_T, 0.0, -1.0), (-_ICO_T, 0.0, 1.0),
]
_ICO_TRIS = [
    [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
    [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
    [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
    [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
]


def _normalize(p):
    n = math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
    return (p[0] / n, p[1] / n, p[2] / n)


def icosphere(radius, level):
    """Subdivided icosahedron (docs/crosscheck.md): unit-sphere nodes, each level splits
    every triangle [a, b, c] into [a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca];
    a new midpoint node is appended (normalised mean of its edge's ends) the first time
    its edge is met, visiting the triangles in order and their edges ab, bc, ca. Then
    the nodes are numbered in the order the triangles first use them (crash's
    Mesh::number_nodes_by_first_use)."""
    nodes = [_normalize(p) for p in _ICO_NODES]
    tris = [list(t) for t in _ICO_TRIS]
    for _ in range(level):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            k = mid.get(key)
            if k is None:
                pa, pb = nodes[a], nodes[b]
                nodes.append(_normalize(((pa[0] + pb[0]) * 0.5, (pa[1] + pb[1]) * 0.5,
                                         (pa[2] + pb[2]) * 0.5)))
                k = len(nodes) - 1
                mid[key] = k
            return k

        nxt = []
        for a, b, c in tris:
            ab = midpoint(a, b)
            bc = midpoint(b, c)
            ca = midpoint(c, a)
            nxt += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        tris = nxt
    new_id, order = {}, []
    for n in [n for t in tris for n in t] + list(range(len(nodes))):
        if n not in new_id:
            new_id[n] = len(order)
            order.append(n)
    nodes = [nodes[n] for n in order]
    tris = [[new_id[n] for n in t] for t in tris]
    return np.array(nodes) * radius, _ints(tris, 3), _ints([], 4)


class MshError(Exception):
    pass


def read_msh(path):
    """Gmsh format 4.1 ASCII: $Nodes and $Elements; types 2 (triangle) and 3 (quad) are
    kept, 15, 1 and 8 skipped, anything else refused. Nodes used by no surface element
    are dropped; kept nodes stay in file order; triangles (file order) then quads."""
    sections = {}
    cur = None
    with open(path) as f:
        for raw in f:
            line = raw.strip()
            if line.startswith("$End"):
                cur = None
            elif line.startswith("$"):
                cur = line[1:]
                sections[cur] = []
            elif cur is not None:
                sections[cur].extend(line.split())
    fmt = sections.get("MeshFormat")
    if not fmt or fmt[0] != "4.1" or fmt[1] != "0":
        raise MshError(f"{path}: only Gmsh format 4.1 ASCII is read")
    toks = sections["Nodes"]
    k = 0

    def nxt():
        nonlocal k
        k += 1
        return toks[k - 1]

    blocks = int(nxt())
    nxt(); nxt(); nxt()
    tags, pos = [], []
    for _ in range(blocks):
        dim = int(nxt()); nxt(); parametric = int(nxt()); n = int(nxt())
        extra = min(dim, 2) if parametric == 1 else 0
        tags += [int(nxt()) for _ in range(n)]
        for _ in range(n):
            pos.append((float(nxt()), float(nxt()), float(nxt())))
            for _ in range(extra):
                nxt()
    index = {t: i for i, t in enumerate(tags)}
    toks = sections["Elements"]
    k = 0
    blocks = int(nxt())
    nxt(); nxt(); nxt()
    tris, quads = [], []
    skipped = {15: 1, 1: 2, 8: 3}
    for _ in range(blocks):
        nxt(); nxt(); kind = int(nxt()); n = int(nxt())
        if kind == 2:
            per = 3
        elif kind == 3:
            per = 4
        elif kind in skipped:
            per = skipped[kind]
        else:
            raise MshError(f"{path}: element type {kind} is not read")
        for _ in range(n):
            nxt()
            ids = [index[int(nxt())] for _ in range(per)]
            if kind == 2:
                tris.append(ids)
            elif kind == 3:
                quads.append(ids)
    used = np.zeros(len(pos), dtype=bool)
    for e in tris + quads:
        used[e] = True
    new_id = np.cumsum(used) - 1
    nodes = np.array(pos, dtype=float)[used]
    t = new_id[_ints(tris, 3)] if tris else _ints([], 3)
    q = new_id[_ints(quads, 4)] if quads else _ints([], 4)
    return nodes, t.astype(np.int64), q.astype(np.int64)
