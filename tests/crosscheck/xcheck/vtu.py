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


def read_vtu(path):
    root = ET.parse(path).getroot()
    out = {}
    for section in ("PointData", "CellData", "Points", "Cells", "FieldData"):
        for sec in root.iter(section):
            for da in sec.iter("DataArray"):
                name = da.get("Name")
                dt = _TYPES[da.get("type")]
                text = (da.text or "").strip()
                if da.get("format") == "binary":
                    raw = base64.b64decode(text)
                    n = int(np.frombuffer(raw[:8], dtype="<u8")[0])
                    a = np.frombuffer(raw[8:8 + n], dtype=dt)
                else:
                    a = np.array(text.split(), dtype=float).astype(dt)
                k = int(da.get("NumberOfComponents", "1"))
                out[(section, name)] = a.reshape(-1, k) if k > 1 else a
    return out


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    head = rows[0]
    data = [[float(v) for v in r] for r in rows[1:] if len(r) == len(head)]
    return head, np.array(data).reshape(-1, len(head))
