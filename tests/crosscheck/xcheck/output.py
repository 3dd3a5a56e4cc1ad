"""The run directory of docs/output.md: energy.csv, contacts.csv, frames.pvd and
frames/frame_NNNNNN.vtu (VTK XML UnstructuredGrid, Float64 / Int64, inline base64 with a
UInt64 header), floats in the shortest round-trip form."""

import base64
import os
from decimal import Decimal

import numpy as np

ENERGY_HEADER = "time,kinetic,internal,hourglass,contact,damping,external_work,balance_error"
CONTACTS_HEADER = "time,body_a,body_b,normal_force,max_penetration"


def fmt(x):
    """Rust's `{:e}` of an f64: shortest round-trip digits, e.g. 1.5e-5, 0e0."""
    x = float(x)
    if x != x:
        return "NaN"
    if x in (float("inf"), float("-inf")):
        return "inf" if x > 0 else "-inf"
    sign, digits, exp = Decimal(repr(x)).as_tuple()
    digits = list(digits)
    while len(digits) > 1 and digits[-1] == 0:
        digits.pop()
        exp += 1
    if digits == [0]:
        return ("-" if sign else "") + "0e0"
    e = exp + len(digits) - 1
    mant = str(digits[0]) + ("." + "".join(map(str, digits[1:])) if len(digits) > 1 else "")
    return ("-" if sign else "") + f"{mant}e{e}"


class Writer:
    def __init__(self, out):
        self.out = out
        os.makedirs(os.path.join(out, "frames"), exist_ok=True)
        self.energy = open(os.path.join(out, "energy.csv"), "w")
        self.energy.write(ENERGY_HEADER + "\n")
        self.contacts = open(os.path.join(out, "contacts.csv"), "w")
        self.contacts.write(CONTACTS_HEADER + "\n")
        self.frames = []

    def energy_row(self, time, e):
        vals = [time, e["kinetic"], e["internal"], e["hourglass"], e["contact"], e["damping"],
                e["external"], e["balance_error"]]
        self.energy.write(",".join(fmt(v) for v in vals) + "\n")

    def contact_rows(self, time, stats):
        for s in stats:
            if s["active"] > 0:
                self.contacts.write(f"{fmt(time)},{s['a']},{s['b']},{fmt(s['normal_force'])},"
                                    f"{fmt(s['max_penetration'])}\n")

    def frame(self, time, step, bodies):
        name = f"frames/frame_{len(self.frames):06d}.vtu"
        path = os.path.join(self.out, name)
        with open(path + ".tmp", "w") as f:
            write_vtu(f, time, step, bodies)
        os.replace(path + ".tmp", path)
        self.frames.append((time, name))
        with open(os.path.join(self.out, "frames.pvd.tmp"), "w") as f:
            f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" '
                    'byte_order="LittleEndian">\n  <Collection>\n')
            for t, n in self.frames:
                f.write(f'    <DataSet timestep="{fmt(t)}" group="" part="0" file="{n}"/>\n')
            f.write("  </Collection>\n</VTKFile>\n")
        os.replace(os.path.join(self.out, "frames.pvd.tmp"), os.path.join(self.out, "frames.pvd"))
        self.energy.flush()
        self.contacts.flush()

    def close(self):
        self.energy.close()
        self.contacts.close()


def _array(f, name, values, components, kind="Float64"):
    a = np.ascontiguousarray(values, dtype={"Float64": "<f8", "Int64": "<i8", "UInt8": "u1"}[kind])
    raw = a.tobytes()
    head = np.array([len(raw)], dtype="<u8").tobytes()
    comp = f' NumberOfComponents="{components}"' if components > 1 else ""
    f.write(f'        <DataArray type="{kind}" Name="{name}"{comp} format="binary">\n')
    f.write(base64.b64encode(head + raw).decode() + "\n")
    f.write("        </DataArray>\n")


def write_vtu(f, time, step, bodies):
    """bodies: dicts in id order with id, thickness, x, x0, v, f_contact, tris, quads,
    N, M (per element, triangles first)."""
    np_ = sum(len(b["x"]) for b in bodies)
    nc = sum(len(b["tris"]) + len(b["quads"]) for b in bodies)
    f.write('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
            'byte_order="LittleEndian" header_type="UInt64">\n  <UnstructuredGrid>\n'
            '    <FieldData>\n')
    f.write(f'      <DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="ascii">{fmt(time)}</DataArray>\n')
    f.write(f'      <DataArray type="Int64" Name="step" NumberOfTuples="1" format="ascii">{step}</DataArray>\n')
    f.write('    </FieldData>\n')
    f.write(f'    <Piece NumberOfPoints="{np_}" NumberOfCells="{nc}">\n')
    f.write('      <PointData Scalars="body_id" Vectors="displacement">\n')
    cat = lambda key: np.concatenate([np.asarray(b[key]).reshape(-1, 3) for b in bodies])
    _array(f, "displacement", cat("x") - cat("x0"), 3)
    _array(f, "velocity", cat("v"), 3)
    _array(f, "contact_force", cat("f_contact"), 3)
    _array(f, "body_id", np.concatenate([np.full(len(b["x"]), b["id"]) for b in bodies]), 1, "Int64")
    f.write('      </PointData>\n      <CellData Scalars="von_mises_top">\n')
    top, bottom = [], []
    for b in bodies:
        t = b["thickness"]
        N, M = b["N"], b["M"]
        for sign, out in ((1.0, top), (-1.0, bottom)):
            s = N / t + sign * 6.0 * M / (t * t)
            out.append(np.sqrt(s[:, 0] * s[:, 0] - s[:, 0] * s[:, 1] + s[:, 1] * s[:, 1] + 3.0 * s[:, 2] * s[:, 2]))
    _array(f, "von_mises_top", np.concatenate(top), 1)
    _array(f, "von_mises_bottom", np.concatenate(bottom), 1)
    _array(f, "membrane_N", np.concatenate([b["N"] for b in bodies]), 3)
    _array(f, "bending_M", np.concatenate([b["M"] for b in bodies]), 3)
    ne = [len(b["tris"]) + len(b["quads"]) for b in bodies]
    _array(f, "thickness", np.concatenate([np.full(n, b["thickness"]) for n, b in zip(ne, bodies)]), 1)
    _array(f, "body_id", np.concatenate([np.full(n, b["id"]) for n, b in zip(ne, bodies)]), 1, "Int64")
    f.write('      </CellData>\n      <Points>\n')
    _array(f, "Points", cat("x"), 3)
    f.write('      </Points>\n      <Cells>\n')
    conn, offsets, types = [], [], []
    base = 0
    end = 0
    for b in bodies:
        for cells, k, typ in ((b["tris"], 3, 5), (b["quads"], 4, 9)):
            if len(cells):
                conn.append(np.asarray(cells).reshape(-1) + base)
                end_here = end + k * np.arange(1, len(cells) + 1)
                offsets.append(end_here)
                end = int(end_here[-1])
                types.append(np.full(len(cells), typ))
        base += len(b["x"])
    _array(f, "connectivity", np.concatenate(conn), 1, "Int64")
    _array(f, "offsets", np.concatenate(offsets), 1, "Int64")
    _array(f, "types", np.concatenate(types), 1, "UInt8")
    f.write('      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n')
