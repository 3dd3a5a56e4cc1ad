"""Scene files (docs/scene-format.md), the subset the cross-check reads: global keys,
[contact], materials (E, nu or the Lame pair, kelvin), bodies with plate, sphere or mesh
shapes, rotation, position, velocity, angular velocity, mass damping, contact flags,
fix, prescribe and load tables. Cylinders and boxes are refused."""

import math
import os
import tomllib

import numpy as np

from . import mesh as meshes
from .body import Body, Material, DOF, element_dt

DEFAULT_SAFETY = 0.9
DEFAULT_ENERGY_LIMIT = 0.05   # globals.rs / driver.rs: the scene's energy_limit
DEFAULT_FRAMES = 100.0
SELECT_TOL = 1e-9
ICOSAHEDRON_EDGE = 1.0514622242382672


class SceneError(Exception):
    pass


class Scene:
    """A built scene: bodies (ids 0.. in file order) and run parameters."""

    def __init__(self):
        self.name = ""
        self.end_time = 0.0
        self.safety = DEFAULT_SAFETY
        self.energy_limit = DEFAULT_ENERGY_LIMIT
        self.gravity = np.zeros(3)
        self.output_interval = 0.0
        self.contact = {}
        self.margin_derived = False
        self.bodies = []


def _vec(v, default=(0.0, 0.0, 0.0)):
    if v is None:
        v = default
    if len(v) != 3:
        raise SceneError(f"expected [x, y, z], got {v!r}")
    return np.array([float(c) for c in v])


def _material(spec):
    rho = float(spec["density"])
    kelvin = float(spec.get("kelvin", 0.0))
    if "young" in spec:
        return Material(rho, float(spec["young"]), float(spec["poisson"]), kelvin)
    l1, l2 = float(spec["lambda1"]), float(spec["lambda2"])
    young = l2 * (3.0 * l1 + 2.0 * l2) / (l1 + l2)
    poisson = l1 / (2.0 * (l1 + l2))
    return Material(rho, young, poisson, kelvin)


def _cells_for(length, size, lo):
    return int(max(math.ceil(length / size - 1e-9), lo))


def _shape(spec, scene_dir):
    kind = spec.get("element")
    if "plate" in spec:
        p = spec["plate"]
        lx, ly = float(p["size"][0]), float(p["size"][1])
        if "cells" in p:
            nx, ny = int(p["cells"][0]), int(p["cells"][1])
        else:
            h = float(p["element_size"])
            nx, ny = _cells_for(lx, h, 1), _cells_for(ly, h, 1)
        return meshes.plate(lx, ly, nx, ny, kind or "quad")
    if "sphere" in spec:
        s = spec["sphere"]
        r = float(s["radius"])
        if kind == "quad":
            raise SceneError("a sphere is meshed with triangles")
        if "level" in s:
            level = int(s["level"])
        else:
            h = float(s["element_size"])
            level = next(l for l in range(9) if r * ICOSAHEDRON_EDGE / float(1 << l) <= h)
        return meshes.icosphere(r, level)
    if "mesh" in spec:
        m = spec["mesh"]
        nodes, tris, quads = meshes.read_msh(os.path.join(scene_dir, m["file"]))
        nodes = nodes * float(m.get("scale", 1.0))
        if kind == "tri" and len(quads):
            extra = []
            for q in quads:
                extra += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
            tris = np.concatenate([tris, np.array(extra, dtype=np.int64)])
            quads = np.zeros((0, 4), dtype=np.int64)
        elif kind == "quad" and len(tris):
            raise SceneError("a mesh holding triangles cannot become quads")
        return nodes, tris, quads
    raise SceneError("the cross-check reads plate, sphere and mesh shapes only")


def _rotation(rot):
    """Right-handed rotation by `angle` degrees about `axis` (Rodrigues' matrix)."""
    if rot is None:
        return np.eye(3)
    a = _vec(rot["axis"])
    u = a / math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
    ang = math.radians(float(rot["angle"]))
    if ang == 0.0:
        return np.eye(3)
    s, c = math.sin(ang), math.cos(ang)
    ux, uy, uz = u
    omc = 1.0 - c
    return np.array([
        [ux * ux + (1.0 - ux * ux) * c, ux * uy * omc - uz * s, ux * uz * omc + uy * s],
        [ux * uy * omc + uz * s, uy * uy + (1.0 - uy * uy) * c, uy * uz * omc - ux * s],
        [ux * uz * omc - uy * s, uy * uz * omc + ux * s, uz * uz + (1.0 - uz * uz) * c],
    ])


def _bounds(x):
    return x.min(axis=0), x.max(axis=0)


def _select(sel, local, glob):
    picked = np.zeros(len(local), dtype=bool)
    _pick(sel, local, glob, picked)
    out = np.nonzero(picked)[0]
    if len(out) == 0:
        raise SceneError(f"selector {sel!r} picks no node")
    return out


def _pick(sel, local, glob, out):
    if isinstance(sel, list):
        for s in sel:
            _pick(s, local, glob, out)
    elif isinstance(sel, str):
        if sel == "all":
            out[:] = True
            return
        axis = "xyz".index(sel[0])
        lo, hi = _bounds(local)
        tol = SELECT_TOL * max(float(np.linalg.norm(hi - lo)), 5e-324)
        target = hi[axis] if sel[1] == "+" else lo[axis]
        out |= np.abs(local[:, axis] - target) <= tol
    else:
        lo, hi = _vec(sel["min"]), _vec(sel["max"])
        blo, bhi = _bounds(glob)
        tol = SELECT_TOL * max(float(np.linalg.norm(bhi - blo)), 5e-324)
        out |= np.all((glob >= lo - tol) & (glob <= hi + tol), axis=1)


def _dofs(v):
    names = {"all": DOF.ALL, "translations": DOF.TRANSLATIONS, "rotations": DOF.ROTATIONS,
             "x": 1, "y": 2, "z": 4, "rx": 8, "ry": 16, "rz": 32}
    if v is None:
        return DOF.ALL
    if isinstance(v, str):
        return names[v]
    mask = 0
    for s in v:
        mask |= names[s]
    return mask


def _body(i, spec, materials, scene_dir):
    mat = materials[spec["material"]]
    nodes, tris, quads = _shape(spec, scene_dir)
    local = nodes.copy()
    rot = _rotation(spec.get("rotation"))
    pos = _vec(spec.get("position"))
    glob = np.array([rot @ p + pos for p in nodes]) if len(nodes) else nodes
    b = Body(i, spec["name"], glob, tris, quads, mat, float(spec["thickness"]))
    b.mass_damping = float(spec.get("mass_damping", 0.0))
    b.contact = bool(spec.get("contact", True))
    b.self_contact = bool(spec.get("self_contact", False))
    v = _vec(spec.get("velocity"))
    w = _vec(spec.get("angular_velocity"))
    com = (b.x * b.mass[:, None]).sum(axis=0) / b.mass.sum()
    b.set_rigid_velocity(v, w, com)
    for f in spec.get("fix", []):
        b.fix(_select(f["select"], local, glob), _dofs(f.get("dofs")))
    for p in spec.get("prescribe", []):
        b.prescribe(_select(p["select"], local, glob), _vec(p["velocity"]),
                    float(p.get("ramp", 0.0)))
    per_node = {}
    for ld in spec.get("load", []):
        sel = _select(ld["select"], local, glob)
        if "force" not in ld and "moment" not in ld:
            raise SceneError("a load needs force and/or moment")
        force = _vec(ld.get("force")) / len(sel)
        moment = _vec(ld.get("moment")) / len(sel)
        t0 = float(ld.get("start", 0.0))
        t1 = t0 + float(ld.get("ramp", 0.0))
        for n in sel:
            prev = per_node.get(int(n))
            if prev is None:
                per_node[int(n)] = [force.copy(), moment.copy(), t0, t1]
            elif prev[2] == t0 and prev[3] == t1:
                prev[0] = prev[0] + force
                prev[1] = prev[1] + moment
            else:
                raise SceneError("loads on one node must share start and ramp")
    b.set_loads(sorted(per_node.items()))
    return b


def default_margin(bodies, gravity, end_time, safety):
    """docs/scene-format.md, "Default margin"."""
    contact = [b for b in bodies if b.contact]
    if not contact:
        return 0.0
    h = min(b.min_length() for b in contact)
    dt = safety * min(element_dt(b, b.min_length()) for b in bodies)
    v = max(b.max_speed() for b in contact)
    g = math.sqrt(float(gravity @ gravity))
    v = v + g * end_time
    return 0.25 * h + 2.0 * v * dt * 10.0


def load(path, end_time=None, output_interval=None):
    with open(path, "rb") as f:
        spec = tomllib.load(f)
    s = Scene()
    s.name = spec.get("name", os.path.splitext(os.path.basename(path))[0])
    s.end_time = float(end_time if end_time is not None else spec["end_time"])
    s.safety = float(spec.get("dt_safety", DEFAULT_SAFETY))
    s.energy_limit = float(spec.get("energy_limit", DEFAULT_ENERGY_LIMIT))
    s.gravity = _vec(spec.get("gravity"))
    oi = output_interval if output_interval is not None else spec.get("output_interval")
    s.output_interval = float(oi) if oi is not None else s.end_time / DEFAULT_FRAMES
    c = spec.get("contact", {})
    s.contact = {
        "enabled": bool(c.get("enabled", True)),
        "margin": float(c.get("margin", 0.0)),
        "penalty": c.get("penalty", "soft"),
        "penalty_scale": float(c.get("penalty_scale", 0.1)),
        "damping_ratio": float(c.get("damping_ratio", 0.0)),
        "speed_rule": c.get("speed_rule", "limit_dt"),
        "pass": c.get("pass", "nodes"),
        "sides": c.get("sides", "auto"),
    }
    if s.contact["sides"] not in ("auto", "finer", "both"):
        raise ValueError(
            f"contact.sides: {s.contact['sides']!r} is not \"auto\", \"finer\" or \"both\"")
    if s.contact["pass"] not in ("nodes", "segments"):
        raise ValueError(f"contact.pass: {s.contact['pass']!r} is not \"nodes\" or \"segments\"")
    if s.contact["pass"] == "segments" and s.contact["penalty"] != "soft":
        raise ValueError("contact.pass = \"segments\" needs penalty = \"soft\"")
    materials = {k: _material(v) for k, v in spec.get("materials", {}).items()}
    scene_dir = os.path.dirname(os.path.abspath(path))
    s.bodies = [_body(i, b, materials, scene_dir) for i, b in enumerate(spec.get("bodies", []))]
    if "margin" not in c and s.contact["enabled"]:
        s.contact["margin"] = default_margin(s.bodies, s.gravity, s.end_time, s.safety)
        s.margin_derived = True
    return s
