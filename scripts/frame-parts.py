#!/usr/bin/env python3
"""Where a split run's parts lie: per body, worker and part of one output frame, the
element count, the box of the element centroids and how many elements touch a node
with a contact force. Reads crash's appended, zlib-compressed VTU frames with the
standard library only (no numpy, no meshio).

Usage: python3 scripts/frame-parts.py OUT/frames/frame_000001.vtu
(docs/performance.md, "Session 41": the cut of the split showcase.)"""
import array
import collections
import re
import struct
import sys
import zlib

CODES = {"Float64": "d", "Float32": "f", "Int64": "q", "Int32": "i", "UInt32": "I", "UInt8": "B"}


def read(path):
    """Every appended DataArray of the file by name (the points as "Points"; a second
    array of one name gets a trailing "_"), as (values, components)."""
    raw = open(path, "rb").read()
    i = raw.index(b"<AppendedData")
    start = raw.index(b"_", i) + 1
    arrays = {}
    for m in re.finditer(r"<DataArray([^>]*)/>", raw[:i].decode()):
        at = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1)))
        if "offset" not in at:
            continue
        off = int(at["offset"]) + start
        blocks = struct.unpack_from("<Q", raw, off)[0]
        sizes = struct.unpack_from("<%dQ" % blocks, raw, off + 24)
        p, data = off + 24 + 8 * blocks, b""
        for s in sizes:
            data += zlib.decompress(raw[p:p + s])
            p += s
        values = array.array(CODES[at["type"]])
        values.frombytes(data)
        key = at.get("Name", "Points")
        while key in arrays:
            key += "_"
        arrays[key] = (values, int(at.get("NumberOfComponents", "1")))
    return arrays


def main(path):
    a = read(path)
    pts, con, offs = a["Points"][0], a["connectivity"][0], a["offsets"][0]
    body, worker, part = a["body_id_"][0], a["worker"][0], a["part"][0]
    force = a["contact_force"][0]
    rows = collections.defaultdict(list)
    prev = 0
    for e, end in enumerate(offs):
        nodes = con[prev:end]
        prev = end
        c = [sum(pts[3 * n + k] for n in nodes) / len(nodes) for k in range(3)]
        touched = any(force[3 * n + k] != 0.0 for n in nodes for k in range(3))
        rows[(body[e], worker[e], part[e])].append((c, touched))
    print("body worker part elements x[min,max] y[min,max] z[min,max] touching")
    for key in sorted(rows):
        r = rows[key]
        box = " ".join(
            "[%.4f,%.4f]" % (min(c[k] for c, _ in r), max(c[k] for c, _ in r)) for k in range(3)
        )
        print(*key, len(r), box, sum(t for _, t in r))


if __name__ == "__main__":
    main(sys.argv[1])
