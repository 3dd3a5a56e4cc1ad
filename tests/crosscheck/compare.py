"""Compare two run directories (docs/output.md): crash's and the harness's, or the
harness's on two rank counts. Prints one line per comparison:

  PASS|FAIL  <label>: <quantity> <measured> (tolerance <tol>)

and returns the number of failures. Quantities:
  steps      number of energy records and frames, and their times (relative 1e-12)
  mesh       cells identical, initial positions (x - displacement) equal to 1e-14 of the size
  positions  max |x_a - x_b| over every node of every frame / largest |displacement| (ref)
  membrane N, bending M   the frames' element resultants / their largest value (ref): the
             deformation itself, which rigid motion cannot hide (N: 100 x the position
             tolerance, as it is the positions' Green strain, amplified by ~1/strain)
  energy     max |E_a - E_b| over every record and column / largest energy of the run (ref);
             the balance_error column (already relative) compared absolutely
  contact    max |F_a - F_b| of contacts.csv normal forces (rows matched by record time and
             pair, a missing row counting as 0) / largest normal force (ref); and the nodal
             contact_force of every frame / largest nodal contact force (ref); the
             max_penetration column likewise
"""

import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from xcheck.vtu import read_pvd, read_vtu, read_csv  # noqa: E402

ENERGY_COLS = ["kinetic", "internal", "hourglass", "contact", "damping", "external_work"]


class Report:
    def __init__(self, label):
        self.label = label
        self.failed = 0
        self.passed = 0
        self.values = {}

    def check(self, what, value, tol, note=""):
        ok = bool(value <= tol) and value == value
        self.values[what] = value
        self.passed += ok
        self.failed += not ok
        extra = f" ({note})" if note else ""
        print(f"{'PASS' if ok else 'FAIL'}  {self.label}: {what} {value:.3e} (tolerance {tol:.0e}){extra}",
              flush=True)
        return ok


def compare(ref, run, label, tol_pos, tol_energy, tol_contact, tol_time=1e-12):
    r = Report(label)
    he, ea = read_csv(os.path.join(ref, "energy.csv"))
    hb, eb = read_csv(os.path.join(run, "energy.csv"))
    if ea.shape != eb.shape:
        r.check("steps", float("inf"), 0, f"{len(ea)} vs {len(eb)} energy records")
        return r
    tmax = max(abs(ea[:, 0]).max(), 1e-300)
    pa, pb = read_pvd(ref), read_pvd(run)
    if len(pa) != len(pb):
        r.check("steps", float("inf"), 0, f"{len(pa)} vs {len(pb)} frames")
        return r
    dt_err = max(abs(ea[:, 0] - eb[:, 0]).max(), max(abs(a[0] - b[0]) for a, b in zip(pa, pb))) / tmax
    r.check("steps", dt_err, tol_time, f"{len(ea) - 1} steps, {len(pa)} frames, record times")

    # energies
    cols = [he.index(c) for c in ENERGY_COLS]
    scale = np.abs(ea[:, cols]).max()
    de = np.abs(ea[:, cols] - eb[:, cols]).max() / scale
    worst = ENERGY_COLS[int(np.argmax(np.abs(ea[:, cols] - eb[:, cols]).max(axis=0)))]
    r.check("energy", de, tol_energy, f"largest energy {scale:.4g} J, worst column {worst}")
    # each column against its own largest value (columns above 1e-3 of the largest energy)
    own = []
    for c, name in zip(cols, ENERGY_COLS):
        m = np.abs(ea[:, c]).max()
        if m > 1e-3 * scale:
            own.append((np.abs(ea[:, c] - eb[:, c]).max() / m, name))
    worst_own = max(own)
    r.check("energy per column", worst_own[0], tol_energy, f"worst {worst_own[1]}, each against its own largest value")
    bi = he.index("balance_error")
    r.check("balance_error", np.abs(ea[:, bi] - eb[:, bi]).max(), tol_energy)

    # frames: mesh, positions, nodal contact forces
    frames_a = [read_vtu(f) for _, f in pa]
    frames_b = [read_vtu(f) for _, f in pb]
    fa0, fb0 = frames_a[0], frames_b[0]
    same = all(np.array_equal(fa0[("Cells", k)], fb0[("Cells", k)]) for k in ("connectivity", "offsets", "types"))
    x0a = fa0[("Points", "Points")] - fa0[("PointData", "displacement")]
    x0b = fb0[("Points", "Points")] - fb0[("PointData", "displacement")]
    size = np.abs(x0a).max()
    r.check("mesh", (np.abs(x0a - x0b).max() / size) if same and x0a.shape == x0b.shape else float("inf"),
            1e-14, "cells identical" if same else "cells differ")
    if not same or x0a.shape != x0b.shape:
        return r
    dmax = max(np.linalg.norm(f[("PointData", "displacement")], axis=1).max() for f in frames_a)
    dx = max(np.abs(a[("Points", "Points")] - b[("Points", "Points")]).max() for a, b in zip(frames_a, frames_b))
    r.check("positions", dx / dmax, tol_pos, f"largest displacement {dmax:.4g} m")

    # element resultants of the frames: the deformation itself, whatever the rigid motion
    # (N comes from the Green strain of the positions, (f.f - 1)/2: position round-off
    # reaches it amplified by ~1/strain, hence 100 x the position tolerance)
    for key, name, tol in ((("CellData", "membrane_N"), "membrane N", 100.0 * tol_pos),
                           (("CellData", "bending_M"), "bending M", tol_pos)):
        smax = max(np.abs(f[key]).max() for f in frames_a)
        ds = max(np.abs(a[key] - b[key]).max() for a, b in zip(frames_a, frames_b))
        r.check(name, ds / smax if smax > 0 else ds, tol, f"largest |{name.split()[1]}| {smax:.4g}, frames")

    fmax = max(np.abs(f[("PointData", "contact_force")]).max() for f in frames_a)
    ca = os.path.join(ref, "contacts.csv")
    if fmax > 0.0 or (os.path.exists(ca) and len(read_csv(ca)[1])):
        dfc = max(np.abs(a[("PointData", "contact_force")] - b[("PointData", "contact_force")]).max()
                  for a, b in zip(frames_a, frames_b))
        r.check("nodal contact forces", dfc / fmax if fmax > 0 else dfc, tol_contact,
                f"largest nodal force {fmax:.4g} N, frames only")
        _, ra = read_csv(ca)
        _, rb = read_csv(os.path.join(run, "contacts.csv"))

        # rows are keyed by record time; times agree to round-off, so index by the record
        times = ea[:, 0]
        key = lambda rows: {(int(np.argmin(np.abs(times - t))), int(a), int(b)): (f, p)
                            for t, a, b, f, p in rows}
        ta, tb = key(ra), key(rb)
        fscale = max(abs(v[0]) for v in ta.values()) if ta else 1.0
        diff = max(abs(ta.get(k, (0.0, 0.0))[0] - tb.get(k, (0.0, 0.0))[0]) for k in set(ta) | set(tb))
        only = len(set(ta) ^ set(tb))
        r.check("contact force history", diff / fscale, tol_contact,
                f"{len(ta)} rows, largest total force {fscale:.4g} N, {only} rows in one run only")
        pscale = max(abs(v[1]) for v in ta.values()) if ta else 1.0
        pdiff = max(abs(ta.get(k, (0.0, 0.0))[1] - tb.get(k, (0.0, 0.0))[1]) for k in set(ta) | set(tb))
        r.check("penetration history", pdiff / pscale, tol_contact,
                f"largest penetration {pscale:.4g} m")
    return r


def main():
    p = argparse.ArgumentParser()
    p.add_argument("ref")
    p.add_argument("run")
    p.add_argument("--label", default="run")
    p.add_argument("--positions", type=float, default=1e-8)
    p.add_argument("--energy", type=float, default=1e-8)
    p.add_argument("--contact", type=float, default=1e-6)
    a = p.parse_args()
    r = compare(a.ref, a.run, a.label, a.positions, a.energy, a.contact)
    print(f"RESULT {r.passed} {r.failed}")
    sys.exit(1 if r.failed else 0)


if __name__ == "__main__":
    main()
