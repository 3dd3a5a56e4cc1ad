"""Reading back a run directory (crash's or the harness's): frames.pvd, the VTU arrays
(appended raw data, zlib-compressed in VTK's block format or not; inline binary base64
with a UInt64 header; ascii), energy.csv, contacts.csv."""

import base64
import csv
import os
import xml.etree.ElementTree as ET
import zlib

import numpy as np

_TYPES = {"Float64": "<f8", "Int64": "<i8", "UInt8": "u1", "Float32": "<f4", "Int32": "<i4"}


def read_pvd(run):
    root = ET.parse(os.path.join(run, "frames.pvd")).getroot()
    return [(float(d.get("timestep")), os.path.join(run, d.get("file"))) for d in root.iter("DataSet")]


def _parse(path):
    """The XML root and the appended raw bytes (after the '_' marker) or None."""
    with open(path, "rb") as f:
        raw = f.read()
    at = raw.find(b"<AppendedData")
    if at < 0:
        return ET.fromstring(raw), None
    end = raw.index(b">", at)
    if b'encoding="raw"' not in raw[at:end]:
        raise ValueError(f"{path}: only raw appended data is read")
    mark = raw.index(b"_", end) + 1
    return ET.fromstring(raw[:at] + b"</VTKFile>"), raw[mark:]


def _appended(da, data, zlib_blocks):
    """Bytes of an appended array: [nbytes] + bytes, or VTK's compressed block format
    [nblocks, blocksize, lastsize, csize...] + zlib blocks (UInt64 header words)."""
    at = int(da.get("offset"))
    word = lambda k: int(np.frombuffer(data[at + 8 * k:at + 8 * k + 8], dtype="<u8")[0])
    if not zlib_blocks:
        return data[at + 8:at + 8 + word(0)]
    n = word(0)
    sizes = [word(3 + k) for k in range(n)]
    pos = at + 8 * (3 + n)
    out = []
    for c in sizes:
        out.append(zlib.decompress(data[pos:pos + c]))
        pos += c
    return b"".join(out)


def _array(da, data=None, zlib_blocks=False):
    dt = _TYPES[da.get("type")]
    text = (da.text or "").strip()
    if da.get("format") == "appended":
        a = np.frombuffer(_appended(da, data, zlib_blocks), dtype=dt)
    elif da.get("format") == "binary":
        raw = base64.b64decode(text)
        n = int(np.frombuffer(raw[:8], dtype="<u8")[0])
        a = np.frombuffer(raw[8:8 + n], dtype=dt)
    else:
        a = np.array(text.split(), dtype=float).astype(dt)
    k = int(da.get("NumberOfComponents", "1"))
    return a.reshape(-1, k) if k > 1 else a


def read_vtu(path):
    """All pieces of a .vtu merged into one (crash and the harness write one piece for
    all bodies; older crash files one per body): arrays concatenated in piece order, connectivity and
    offsets shifted to the merged numbering."""
    root, data = _parse(path)
    if root.get("header_type", "UInt32") != "UInt64" and data is not None:
        raise ValueError(f"{path}: appended data with a {root.get('header_type')} header")
    compressed = root.get("compressor") == "vtkZLibDataCompressor"
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
                    a = _array(da, data, compressed)
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
