"""The distributed time loop (docs/architecture-cluster.md, "One step"), on MPI ranks.

Rank 0 keeps the time loop, the energy ledger, the MEIM and the placement, and is also
worker 0; every rank integrates the groups placed on it. Per step: rank 0 broadcasts the
control message (migrations, frame request, stop) and the step length -- the barrier --
and gathers every rank's body reports (point-to-point messages in rank order; waiting
ranks poll with short sleeps). Bodies move between ranks (their whole state, pickled exact
float64 arrays) when the groups change. Every rank builds every body's definition from
the scene file; only the owner's copy has a live state."""

import math
import sys
import time as wall

import numpy as np

from . import scene as scenes
from .body import Fault
from .contact import margin_for, candidate_pairs
from .elements import _green, _plane
from .group import Group
from .meim import Meim, assign
from .output import Writer

TIME_EPS = 1e-12
RUNAWAY_PERSIST = 3
DT_FLOOR = 1e-3
MARGIN_FACTOR = 2.0
SPLIT_AFTER = 50


class Ledger:
    """theory.md 6: E_0, the running largest energy, the balance error."""

    def __init__(self):
        self.e0 = None
        self.scale = 0.0
        self.max_abs = 0.0
        self.over = 0

    def update(self, reports, counts=True):
        """counts False: the record after a last step shortened to land on the end time
        (theory.md 6): it enters neither the largest energy nor the largest imbalance."""
        t = dict(kinetic=0.0, internal=0.0, hourglass=0.0, contact=0.0, damping=0.0, external=0.0)
        for r in reports:
            for k in t:
                t[k] += r["energy"][k]
        total = t["kinetic"] + t["internal"] + t["hourglass"] + t["contact"] + t["damping"] - t["external"]
        if self.e0 is None:
            self.e0 = total
        size = max(t["kinetic"] + t["internal"] + t["hourglass"] + t["damping"] + abs(t["contact"]),
                   abs(t["external"]), abs(self.e0))
        if counts:
            self.scale = max(self.scale, size)
        t["balance_error"] = (total - self.e0) / self.scale if self.scale > 0.0 else 0.0
        if counts:
            self.max_abs = max(self.max_abs, abs(total - self.e0))
        # the run's figure (theory.md 7): the one the energy guard judges
        t["run_error"] = self.max_abs / self.scale if self.scale > 0.0 else 0.0
        return t


class Worker:
    """The bodies and groups of one rank."""

    def __init__(self, sc):
        self.sc = sc
        self.defs = {b.id: b for b in sc.bodies}
        self.owned = set()
        self.groups = []
        self.clock = (0.0, 0, 0.0)   # time, step, h_prev

    def regroup(self, layout, rank):
        mine = [g for g, r in layout if r == rank]
        t, s, hp = self.clock
        self.groups = [Group([self.defs[i] for i in g], self.sc.gravity, self.sc.contact, t, s, hp)
                       for g in mine]
        self.owned = {i for g in mine for i in g}

    def start(self):
        reps, stats = [], []
        for g in self.groups:
            reps += g.start()
            stats += g.contact.stats
        return reps, stats

    def step(self, h):
        reps, stats = [], []
        for g in self.groups:
            reps += g.advance(h)
            stats += g.contact.stats
        t, s, _ = self.clock
        self.clock = (t + h, s + 1, h)
        return reps, stats

    def snapshot(self):
        out = []
        for i in sorted(self.owned):
            b = self.defs[i]
            out.append(dict(id=i, x=b.x.copy(), v=b.v.copy(),
                            f_contact=None if b.f_contact is None else b.f_contact.copy(),
                            M=b.M.copy()))
        return out


def frame_bodies(sc, snaps):
    """Frame data in id order (membrane N from the positions: output.md cell data)."""
    out = []
    for s in sorted(snaps, key=lambda s: s["id"]):
        b = sc.bodies[s["id"]]
        x = s["x"]
        Ns = []
        for nodes, bx0, by0, e0 in ((b.tris, getattr(b.ref, "tri_bx0", None), getattr(b.ref, "tri_by0", None), None),
                                    (b.quads, getattr(b.ref, "quad_bx0", None), getattr(b.ref, "quad_by0", None),
                                     getattr(b.ref, "e0", None))):
            if len(nodes) == 0:
                continue
            X = x[nodes]
            f1 = (X * bx0[:, :, None]).sum(axis=1)
            f2 = (X * by0[:, :, None]).sum(axis=1)
            e = _green(f1, f2)
            if e0 is not None:
                e = e - e0
            Ns.append(_plane(b.k_membrane, b.material.poisson, e))
        fc = s["f_contact"] if s["f_contact"] is not None else np.zeros_like(x)
        out.append(dict(id=b.id, thickness=b.thickness, x=x, x0=b.x0, v=s["v"], f_contact=fc,
                        tris=b.tris, quads=b.quads, N=np.concatenate(Ns), M=s["M"]))
    return out


class Master:
    """Rank 0's part: time loop, ledger, dt, MEIM, placement, output."""

    def __init__(self, sc, nranks, out):
        self.sc = sc
        self.nranks = nranks
        self.writer = Writer(out)
        self.ledger = Ledger()
        ids = [b.id for b in sc.bodies]
        self.meim = Meim(ids, SPLIT_AFTER)
        cfg = sc.contact
        self.in_meim = {b.id: (cfg["enabled"] and b.contact) for b in sc.bodies}
        self.extra = {b.id: 0.5 * (MARGIN_FACTOR - 1.0) * margin_for(cfg, b) for b in sc.bodies}
        self.thick = {b.id: b.thickness for b in sc.bodies}
        self.cost = {b.id: 1.0 + (0.0 if b.kinematic else b.element_count())
                     + (len(b.x) if self.in_meim[b.id] else 0.0) for b in sc.bodies}
        self.rank_of = {}
        self.time = 0.0
        self.step = 0
        self.next_dt = 0.0
        self.dt0 = 0.0
        self.frames = 0
        self.last_frame_step = None
        self.migrations = []
        self.group_changes = 0

    def pairs(self, boxes):
        if not self.sc.contact["enabled"]:
            return []
        m = self.sc.contact["margin"]
        mb = [(i, lo - self.extra[i], hi + self.extra[i]) for i, lo, hi in boxes if self.in_meim[i]]
        return candidate_pairs(mb, lambda i: 0.5 * (self.thick[i] + (m if m > 0.0 else self.thick[i])))

    def place(self):
        groups = self.meim.groups
        to = assign(groups, self.cost, self.rank_of, self.nranks, 0.25, True)
        return [(g, r) for g, r in zip(groups, to)]

    def choose_dt(self, reports):
        crit = math.inf
        for r in reports:
            if r["dt"] < crit:
                crit = r["dt"]
        dt = self.sc.safety * crit
        if (self.dt0 > 0.0 and dt < DT_FLOOR * self.dt0) or not dt > 0.0:
            raise Fault(f"step {self.step}: time step collapsed to {dt:e}")
        return dt

    def runaway(self, e):
        """theory.md 7: the run's figure past the scene's energy_limit for more than
        RUNAWAY_PERSIST steps, or NaN."""
        if abs(e["run_error"]) <= self.sc.energy_limit:
            self.ledger.over = 0
        else:
            self.ledger.over += 1
        nan = e["balance_error"] != e["balance_error"] or e["run_error"] != e["run_error"]
        if self.ledger.over > RUNAWAY_PERSIST or nan:
            raise Fault(f"step {self.step}: energy runaway, balance error {e['run_error']:e}")

    def check_margin(self, reports):
        for r in reports:
            allowed = self.extra[r["id"]]
            if self.in_meim[r["id"]] and r["move"] > allowed:
                raise Fault(f"step {self.step}: body {r['id']} moved {r['move']:e} m in one step, "
                            f"more than the {allowed:e} m the interaction-graph margin allows")

    def frame_due(self, force):
        oi = self.sc.output_interval
        due = oi > 0.0 and self.time >= self.frames * oi * (1.0 - TIME_EPS)
        return (force or due) and self.last_frame_step != self.step

    def frame_done(self):
        self.last_frame_step = self.step
        oi = self.sc.output_interval
        while oi > 0.0 and self.frames * oi <= self.time * (1.0 + TIME_EPS):
            self.frames += 1

    def finished(self):
        return self.time >= self.sc.end_time * (1.0 - TIME_EPS)


# Waiting ranks poll with short sleeps instead of MPI's busy wait, so that idle ranks
# leave the (shared) cores to the ranks that compute.
POLL_SLEEP = 5e-5
TAG_BCAST, TAG_GATHER, TAG_MOVE = 11, 12, 1000


def _wait(comm, source, tag):
    while not comm.iprobe(source=source, tag=tag):
        wall.sleep(POLL_SLEEP)


def bcast(comm, obj):
    """Rank 0's object to every rank (the per-step barrier)."""
    if comm.Get_rank() == 0:
        for r in range(1, comm.Get_size()):
            comm.send(obj, dest=r, tag=TAG_BCAST)
        return obj
    _wait(comm, 0, TAG_BCAST)
    return comm.recv(source=0, tag=TAG_BCAST)


def gather(comm, obj):
    """Every rank's object to rank 0, in rank order (None elsewhere)."""
    if comm.Get_rank() != 0:
        comm.send(obj, dest=0, tag=TAG_GATHER)
        return None
    out = [obj]
    for r in range(1, comm.Get_size()):
        _wait(comm, r, TAG_GATHER)
        out.append(comm.recv(source=r, tag=TAG_GATHER))
    return out


def _merge(gathered):
    reps, stats, faults = [], [], []
    for g in gathered:
        if g[0] == "fault":
            faults.append(g[1])
        else:
            reps += g[1]
            stats += g[2]
    return sorted(reps, key=lambda r: r["id"]), sorted(stats, key=lambda s: (s["a"], s["b"])), faults


def main(scene_path, out, end_time=None, comm=None):
    from mpi4py import MPI
    comm = comm or MPI.COMM_WORLD
    rank, nranks = comm.Get_rank(), comm.Get_size()
    sc = scenes.load(scene_path, end_time=end_time)
    worker = Worker(sc)
    master = Master(sc, nranks, out) if rank == 0 else None
    t_start = wall.time()
    status = 0

    # ---- start: groups of the initial boxes, placement, first force pass ----
    layout = None
    if rank == 0:
        boxes = [(b.id, b.x.min(axis=0), b.x.max(axis=0)) for b in sc.bodies]
        master.meim.update(0, master.pairs(boxes))
        layout = master.place()
        for g, r in layout:
            for i in g:
                master.rank_of[i] = r
    layout = bcast(comm, layout)
    worker.regroup(layout, rank)
    try:
        mine = ("ok",) + worker.start()
    except Fault as f:
        mine = ("fault", str(f))
    gathered = gather(comm, mine)
    ctrl = None
    if rank == 0:
        reps, stats, faults = _merge(gathered)
        try:
            if faults:
                raise Fault(faults[0])
            e = master.ledger.update(reps)
            master.next_dt = master.choose_dt(reps)
            master.dt0 = master.next_dt
            master.writer.energy_row(0.0, e)
            master.writer.contact_rows(0.0, stats)
            ctrl = dict(stop=False, frame=True, moves=None, layout=None)
        except Fault as f:
            print(f"crosscheck: {f}", file=sys.stderr)
            status = 1
            ctrl = dict(stop=True, frame=False, moves=None, layout=None)
    while True:
        ctrl = bcast(comm, ctrl)
        # migration: the whole state of each moved body, exact bits
        if ctrl["moves"]:
            reqs = []
            for i, (src, dst) in sorted(ctrl["moves"].items()):
                if src == rank:
                    reqs.append(comm.isend(worker.defs[i].state(), dest=dst, tag=TAG_MOVE + i))
            for i, (src, dst) in sorted(ctrl["moves"].items()):
                if dst == rank:
                    _wait(comm, src, TAG_MOVE + i)
                    worker.defs[i].set_state(comm.recv(source=src, tag=TAG_MOVE + i))
            for q in reqs:
                q.wait()
        if ctrl["layout"] is not None:
            worker.regroup(ctrl["layout"], rank)
        if ctrl["frame"]:
            snaps = gather(comm, worker.snapshot())
            if rank == 0:
                master.writer.frame(master.time, master.step,
                                    frame_bodies(sc, [s for part in snaps for s in part]))
                master.frame_done()
        if ctrl["stop"]:
            break
        # ---- one step: the control message above was the barrier ----
        h = None
        short = False
        if rank == 0:
            h = master.next_dt
            left = sc.end_time - master.time
            if left < h and left > 0.0:
                h = left
                short = True
        h = bcast(comm, h)
        try:
            mine = ("ok",) + worker.step(h)
        except Fault as f:
            mine = ("fault", str(f))
        gathered = gather(comm, mine)
        if rank != 0:
            continue
        reps, stats, faults = _merge(gathered)
        master.time += h
        master.step += 1
        ctrl = dict(stop=False, frame=False, moves=None, layout=None)
        try:
            if faults:
                raise Fault(faults[0])
            e = master.ledger.update(reps, counts=not short)
            master.runaway(e)
            master.next_dt = master.choose_dt(reps)
            master.check_margin(reps)
            master.writer.energy_row(master.time, e)
            master.writer.contact_rows(master.time, stats)
            boxes = [(r["id"], r["lo"], r["hi"]) for r in reps]
            if master.meim.update(master.step, master.pairs(boxes)):
                master.group_changes += 1
                layout = master.place()
                moves = {}
                for g, r in layout:
                    for i in g:
                        if master.rank_of[i] != r:
                            moves[i] = (master.rank_of[i], r)
                            master.migrations.append((master.step, i, master.rank_of[i], r))
                        master.rank_of[i] = r
                ctrl["moves"] = moves
                ctrl["layout"] = layout
            done = master.finished()
            ctrl["frame"] = master.frame_due(done)
            ctrl["stop"] = done
        except Fault as f:
            print(f"crosscheck: {f}", file=sys.stderr)
            status = 1
            ctrl["stop"] = True     # like crash: the frames written so far stay, no new one
            ctrl["frame"] = False
    if rank == 0:
        master.writer.close()
        summary = dict(steps=master.step, time=master.time, ranks=nranks,
                       wall_time_s=wall.time() - t_start, group_changes=master.group_changes,
                       migrations=master.migrations, margin=sc.contact["margin"],
                       max_energy_balance_error=(master.ledger.max_abs / master.ledger.scale
                                                 if master.ledger.scale > 0 else 0.0))
        import json
        with open(f"{out}/summary.json", "w") as f:
            json.dump(summary, f, indent=1)
    status = bcast(comm, status)
    return status
