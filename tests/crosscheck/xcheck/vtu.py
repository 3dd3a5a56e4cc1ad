"""Reading back a run directory (crash's or the harness's): frames.pvd, the VTU arrays
(binary base64 with a UInt64 header, or ascii), energy.csv, contacts.csv."""

import base64
import csv
import os
import xml.etree.ElementTree as ET

import numpy as np

_TYPES = {"Float64": "<f8", "Int64": "<i8", "UInt8": "u1", "Float32": "<f4", "Int32": "<i4"}


def read_pvd(run):
    root = ET.parse(os.path.join(run, "frames.pvd")).getroot()
    return [(float(d.get("timestep")), os.path.join(run, d.get("file"))) for d in root.iter("DataSet")]


def _array(da):
    dt = _TYPES[da.get("type")]
    text = (da.text or "").strip()
    if da.get("format") == "binary":
        raw = base64.b64decode(text)
        n = int(np.frombuffer(raw[:8], dtype="<u8")[0])
        a = np.frombuffer(raw[8:8 + n], dtype=dt)
    else:
        a = np.array(text.split(), dtype=float).astype(dt)
    k = int(da.get("NumberOfComponents", "1"))
    return a.reshape(-1, k) if k > 1 else a


def read_vtu(path):
    """All pieces of a .vtu merged into one (crash writes one piece per body, the
    harness one for all bodies): arrays concatenated in piece order, connectivity and
    offsets shifted to the merged numbering."""
    root = ET.parse(path).getroot()
    out = {}
    for sec in root.iter("FieldData"):
        for da in sec.iter("DataArray"):
            out[("FieldData", da.get("Name"))] = _array(da)
    parts = {}
    points = cells = 0
    for piece in root.iter("Piece"):
        for section in ("PointData", "CellData", "Points", "Cells"):
            for sec in piece.iter(section):
                for da in sec.iter("DataArray"):
                    name = da.get("Name")
                    a = _array(da)
                    if (section, name) == ("Cells", "connectivity"):
                        a = a + points
                    elif (section, name) == ("Cells", "offsets"):
                        a = a + cells
                    parts.setdefault((section, name), []).append(a)
        points += int(piece.get("NumberOfPoints"))
        conn = parts.get(("Cells", "connectivity"))
        cells = int(sum(len(c) for c in conn)) if conn else 0
    for key, arrays in parts.items():
        out[key] = np.concatenate(arrays)
    return out


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    head = rows[0]
    data = [[float(v) for v in r] for r in rows[1:] if len(r) == len(head)]
    return head, np.array(data).reshape(-1, len(head))
