"""Cut the raw arrays out of a frame written with `compression = "none"` into
OUT/NAME.TYPE files (one per DataArray of the appended data)."""
import os
import re
import struct
import sys

frame, out = sys.argv[1], sys.argv[2]
d = open(frame, "rb").read()
at = d.index(b"<AppendedData")
xml = d[:at].decode()
start = d.index(b"_", at) + 1
os.makedirs(out, exist_ok=True)
for m in re.finditer(r"<DataArray([^>]*)>", xml):
    a = m.group(1)
    name, off, ty = (re.search(k + r'="([^"]*)"', a) for k in ("Name", "offset", "type"))
    if not off:
        continue
    o = start + int(off.group(1))
    n = struct.unpack("<Q", d[o:o + 8])[0]
    open(os.path.join(out, f"{name.group(1)}.{ty.group(1)}"), "wb").write(d[o + 8:o + 8 + n])
    print(name.group(1), ty.group(1), n)
