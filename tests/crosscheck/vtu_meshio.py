"""ParaView-readability check of crash's frames with an independent reader (meshio, PyPI):
run a scene with `[outputs] precision = "f64"` and `"f32"`, open the last frame of each
with meshio and compare it with what crash's own reader finds (the `vtu_dump` example of
crash-io, JSON): point and cell counts, triangles and quads, positions and von Mises
stresses exactly, displacements to the round-off of crash's reader (it keeps x0 = x - u),
and the f32 frame against the f64 one to f32 rounding. A file meshio cannot read fails.

    python vtu_meshio.py CRASH VTU_DUMP SCENE OUT [--end-time T]

Prints PASS/FAIL lines and, last, "RESULT n_failed".
"""

import argparse
import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np

failed = 0


def check(ok, text):
    global failed
    print(("PASS" if ok else "FAIL") + "  vtu meshio: " + text)
    if not ok:
        failed += 1
    return ok


def last_frame(run):
    root = ET.parse(os.path.join(run, "frames.pvd")).getroot()
    files = [d.get("file") for d in root.iter("DataSet")]
    return os.path.join(run, files[-1]) if files else None


def run_one(args, precision):
    with open(args.scene) as f:
        text = f.read()
    if "[outputs]" in text:
        sys.exit(f"{args.scene} has an [outputs] table already; pick a scene without one")
    scene = os.path.join(args.out, f"scene-{precision}.toml")
    os.makedirs(args.out, exist_ok=True)
    with open(scene, "w") as f:
        f.write(text + f'\n[outputs]\nprecision = "{precision}"\n')
    run = os.path.join(args.out, precision)
    cmd = [args.crash, "run", scene, "--out", run, "--threads", "1", "--no-pictures",
           "--quiet", "--end-time", args.end_time]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if not check(p.returncode == 0, f"{precision}: crash run exit {p.returncode}"):
        print(p.stderr[-2000:])
        return None
    frame = last_frame(run)
    if not check(frame is not None, f"{precision}: frames.pvd lists frames"):
        return None
    try:
        m = meshio.read(frame)
    except Exception as e:  # any failure to read is the failure this check is for
        check(False, f"{precision}: meshio cannot read {frame}: {e!r}")
        return None
    check(True, f"{precision}: meshio reads {frame}")
    d = subprocess.run([args.dump, frame], capture_output=True, text=True)
    if not check(d.returncode == 0, f"{precision}: crash's reader (vtu_dump) reads it: {d.stderr.strip()}"):
        return None
    ours = json.loads(d.stdout)
    ncells = sum(len(c.data) for c in m.cells)
    kinds = {c.type: 0 for c in m.cells}
    for c in m.cells:
        kinds[c.type] += len(c.data)
    check(len(m.points) == ours["points"] and ours["points"] > 0,
          f"{precision}: {len(m.points)} points (crash's reader {ours['points']})")
    check(ncells == ours["cells"], f"{precision}: {ncells} cells (crash's reader {ours['cells']})")
    check(kinds.get("triangle", 0) == ours["triangles"] and kinds.get("quad", 0) == ours["quads"],
          f"{precision}: {kinds} (crash's reader {ours['triangles']} triangles, {ours['quads']} quads)")
    want = np.float32 if precision == "f32" else np.float64
    u = m.point_data["displacement"]
    check(u.dtype == want, f"{precision}: displacement stored as {u.dtype}")
    check(np.array_equal(m.points.astype(np.float64).ravel(), np.array(ours["points_xyz"])),
          f"{precision}: positions equal bit for bit")
    vm = np.concatenate([a for a in m.cell_data["von_mises_top"]]).astype(np.float64)
    check(np.array_equal(vm, np.array(ours["von_mises_top"])),
          f"{precision}: von_mises_top equal bit for bit")
    ou = np.array(ours["displacement"])
    # crash's reader returns x - (x - u): equal to u up to the round-off of |x|
    tol = 4 * np.finfo(np.float64).eps * np.abs(m.points).max()
    du = np.abs(u.astype(np.float64).ravel() - ou).max()
    check(du <= tol and np.abs(ou).max() > 0,
          f"{precision}: displacement differs by {du:.3g} m (tolerance {tol:.3g}, largest {np.abs(ou).max():.3g} m)")
    return u.astype(np.float64), float(m.field_data.get("TimeValue", [np.nan])[0])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("crash")
    ap.add_argument("dump")
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--end-time", default="1e-4")
    args = ap.parse_args()
    a = run_one(args, "f64")
    b = run_one(args, "f32")
    if a is not None and b is not None:
        (u64, t64), (u32, t32) = a, b
        scale = np.abs(u64).max()
        # the runs are the same (the state hash does not depend on the file format)
        err = np.abs(u32 - u64).max()
        check(t64 == t32 and err <= 2.0 ** -24 * scale,
              f"f32 frame against f64: largest difference {err:.3g} m (f32 rounding of {scale:.3g} m: {2.0 ** -24 * scale:.3g})")
    print(f"RESULT {failed}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
