"""The one-step pipeline of a group of bodies (theory.md 5, theory-contact.md "Where
contact sits in a step"): integrate -> tunnelling guard -> element forces -> contact."""

import numpy as np

from .contact import ContactStage, check_moves


class Group:
    def __init__(self, bodies, gravity, cfg, time, step, h_prev):
        self.bodies = sorted(bodies, key=lambda b: b.id)
        self.gravity = gravity
        self.cfg = cfg
        self.time = time
        self.step = step
        self.h_prev = h_prev
        self.contact = ContactStage(cfg)

    def _report(self, b, dt, lo, hi, move):
        return dict(id=b.id, energy=dict(b.energy), dt=dt, lo=lo, hi=hi, move=move)

    def _contact(self, reports):
        limits = self.contact.run(self.bodies, [r["dt"] for r in reports])
        for r, d in zip(reports, limits):
            r["dt"] = min(r["dt"], d)

    def start(self):
        out = []
        for b in self.bodies:
            b.apply_constraints(0.0)
            dt = b.internal_forces(0.0)
            b.energy["internal"] = b.internal_now
            b.energy["hourglass"] = b.hourglass_now
            b.energy["kinetic"] = b.kinetic_energy()
            out.append(self._report(b, dt, b.x.min(axis=0), b.x.max(axis=0), 0.0))
        self._contact(out)
        return out

    def advance(self, h):
        res = [b.integrate(self.time, self.h_prev, h, self.gravity) for b in self.bodies]
        self.time += h
        self.step += 1
        self.h_prev = h
        check_moves(self.bodies, self.cfg, [r[0] for r in res], h, self.step)
        out = []
        for b, (move, lo, hi) in zip(self.bodies, res):
            dt = b.internal_forces(h)
            out.append(self._report(b, dt, lo, hi, move))
        self._contact(out)
        return out
