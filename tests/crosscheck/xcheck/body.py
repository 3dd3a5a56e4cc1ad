"""A shell body: mesh, section, lumped masses (theory.md section 3), constraints, loads,
and the central-difference update with its energy terms (theory.md sections 5 and 6)."""

import math

import numpy as np

from . import elements
from .vec import dot, cross, norm


class DOF:
    ALL = 63
    TRANSLATIONS = 7
    ROTATIONS = 56


SHEAR_CORRECTION = 5.0 / 6.0
DT_SHAPE = 0.8
ROT_INERTIA_TRI = 0.5
ROT_INERTIA_QUAD = 0.1875
COLLAPSE_RATIO = 1e-3
# stabilisation coefficients (theory.md 2.2, 2.3)
R_DRILL = 0.1
R_HG_M = 0.05
R_HG_W = 0.05
R_HG_TH = 0.05


class Fault(Exception):
    """A physical stop (theory.md section 7, theory-contact.md guards)."""


class Material:
    def __init__(self, density, young, poisson, kelvin):
        self.density = density
        self.young = young
        self.poisson = poisson
        self.kelvin = kelvin


def element_dt(body, length):
    """theory.md section 4: 0.8 L / c (sqrt(1 + xi^2) - xi), xi = alpha c / L."""
    dt = DT_SHAPE * length / body.wave_speed
    if body.material.kelvin != 0.0:
        xi = body.material.kelvin * body.wave_speed / length
        dt = dt * (np.sqrt(1.0 + xi * xi) - xi)
    return dt


def ramp(t, t0, t1):
    """0 before t0, 1 after t1, linear between (a step at t0 when t1 <= t0)."""
    if t1 <= t0:
        return 1.0 if t >= t0 else 0.0
    return min(max((t - t0) / (t1 - t0), 0.0), 1.0)


class Body:
    def __init__(self, bid, name, nodes, tris, quads, material, thickness):
        self.id = bid
        self.name = name
        self.material = material
        self.thickness = t = thickness
        E, nu = material.young, material.poisson
        self.plate_modulus = E / (1.0 - nu * nu)
        self.shear_modulus = E / (2.0 * (1.0 + nu))
        self.k_membrane = self.plate_modulus * t           # t E / (1 - nu^2)
        self.k_bending = self.plate_modulus * t ** 3 / 12.0  # D
        self.k_shear = SHEAR_CORRECTION * self.shear_modulus * t
        self.k_drill = R_DRILL * self.shear_modulus * t
        self.wave_speed = math.sqrt(self.plate_modulus / material.density)

        self.x0 = np.array(nodes, dtype=float).reshape(-1, 3)
        self.x = self.x0.copy()
        n = len(self.x0)
        self.v = np.zeros((n, 3))
        self.w = np.zeros((n, 3))
        self.tris = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
        self.quads = np.asarray(quads, dtype=np.int64).reshape(-1, 4)
        self.ref = elements.reference(self)
        # lumped masses (theory.md section 3), element order: triangles, then quads
        rho_t = material.density * t
        t2 = t * t / 12.0
        self.mass = np.zeros(n)
        self.inertia = np.zeros(n)
        for nodes_e, area0, f in ((self.tris, self.ref.tri_area0, ROT_INERTIA_TRI),
                                  (self.quads, self.ref.quad_area0, ROT_INERTIA_QUAD)):
            if len(nodes_e) == 0:
                continue
            k = nodes_e.shape[1]
            m = rho_t * area0 / k
            s = np.maximum(t2, f * area0)
            for c in range(k):
                np.add.at(self.mass, nodes_e[:, c], m)
                np.add.at(self.inertia, nodes_e[:, c], m * s)
        if np.any(self.mass <= 0.0):
            raise ValueError(f"body {name}: a node belongs to no element")
        self.fixed = np.zeros(n, dtype=np.int64)
        self.program = np.full(n, -1, dtype=np.int64)
        self.programs = []           # (velocity (3,), ramp)
        self.load_nodes = np.zeros(0, dtype=np.int64)
        self.load_force = np.zeros((0, 3))
        self.load_moment = np.zeros((0, 3))
        self.load_t = []             # (t0, t1) per load
        self.mass_damping = 0.0
        self.contact = True
        self.self_contact = False
        self.kinematic = False
        ne = len(self.tris) + len(self.quads)
        # rate-form state (theory.md 2.2, 2.3): M (Mxx, Myy, Mxy), Q (Qx, Qy), tau; quads' hourglass
        self.M = np.zeros((ne, 3))
        self.Q = np.zeros((ne, 2))
        self.tau = np.zeros(ne)
        self.hg_w = np.zeros(len(self.quads))
        self.hg_th = np.zeros((len(self.quads), 2))
        # gathered internal forces and moments of the last force pass
        self.f_int = np.zeros((n, 3))
        self.m_int = np.zeros((n, 3))
        # the Kelvin part of f_int, m_int (theory.md 6: booked as damping)
        self.f_d = np.zeros((n, 3))
        self.m_d = np.zeros((n, 3))
        self.f_contact = None
        self.energy = dict(kinetic=0.0, internal=0.0, hourglass=0.0, contact=0.0,
                           damping=0.0, external=0.0)
        self.internal_now = 0.0
        self.hourglass_now = 0.0

    # ---- set-up -------------------------------------------------------------------
    def set_rigid_velocity(self, v, omega, centre):
        self.v = v[None, :] + cross(np.broadcast_to(omega, self.x.shape), self.x - centre)
        self.w = np.tile(omega, (len(self.x), 1)).astype(float)

    def fix(self, nodes, mask):
        self.fixed[nodes] |= mask
        self.kinematic = bool(np.all(self.fixed == DOF.ALL))

    def prescribe(self, nodes, velocity, ramp_time):
        pid = len(self.programs)
        self.programs.append((np.array(velocity, dtype=float), ramp_time))
        v0 = velocity * ramp(0.0, 0.0, ramp_time)
        self.fixed[nodes] = DOF.ALL
        self.program[nodes] = pid
        self.v[nodes] = v0
        self.w[nodes] = 0.0
        self.kinematic = bool(np.all(self.fixed == DOF.ALL))

    def set_loads(self, items):
        self.load_nodes = np.array([k for k, _ in items], dtype=np.int64)
        self.load_force = np.array([v[0] for _, v in items]).reshape(-1, 3)
        self.load_moment = np.array([v[1] for _, v in items]).reshape(-1, 3)
        self.load_t = [(v[2], v[3]) for _, v in items]

    def program_velocity(self, t):
        """Prescribed velocity per node at time t (rows of nodes without a program: 0)."""
        pv = np.zeros((len(self.x), 3))
        for pid, (vel, rt) in enumerate(self.programs):
            pv[self.program == pid] = vel * ramp(t, 0.0, rt)
        return pv

    def apply_constraints(self, t):
        """Fixed DOFs to zero, prescribed DOFs to their program at t (the start)."""
        fx = self.fixed
        if not np.any(fx):
            return
        pv = self.program_velocity(t)
        for d in range(3):
            m = (fx & (1 << d)) != 0
            self.v[m, d] = pv[m, d]
            m = (fx & (8 << d)) != 0
            self.w[m, d] = 0.0

    # ---- derived ----------------------------------------------------------------
    def element_count(self):
        return len(self.tris) + len(self.quads)

    def lengths_now(self):
        """Characteristic lengths of docs/scene-format.md (2A/longest edge, A/longest
        diagonal with A = |d13 x d24|/2) at the current positions."""
        x = self.x
        out = []
        if len(self.tris):
            p = [x[self.tris[:, k]] for k in range(3)]
            area2 = norm(cross(p[1] - p[0], p[2] - p[0]))
            longest = np.maximum(np.maximum(norm(p[1] - p[0]), norm(p[2] - p[1])), norm(p[0] - p[2]))
            out.append(area2 / longest)
        if len(self.quads):
            p = [x[self.quads[:, k]] for k in range(4)]
            area = 0.5 * norm(cross(p[2] - p[0], p[3] - p[1]))
            diag = np.maximum(norm(p[2] - p[0]), norm(p[3] - p[1]))
            out.append(area / diag)
        return np.concatenate(out)

    def min_length(self):
        return float(self.lengths_now().min())

    def max_speed(self):
        s = float(norm(self.v).max()) if len(self.v) else 0.0
        for vel, _ in self.programs:
            s = max(s, float(norm(vel[None, :])[0]))
        return s

    def kinetic_energy(self):
        return float(np.sum(0.5 * (self.mass * dot(self.v, self.v) + self.inertia * dot(self.w, self.w))))

    # ---- one step ---------------------------------------------------------------
    def integrate(self, t, h_prev, h, gravity):
        """x_n -> x_{n+1}, v_{n-1/2} -> v_{n+1/2} (theory.md 5) and the energy record
        at t_{n+1/2} (theory.md 6). Returns (max move, box lo, box hi)."""
        hbar = 0.5 * (h_prev + h)
        t_half = t + 0.5 * h
        c = self.mass_damping
        dn = 1.0 - 0.5 * c * hbar
        dd = 1.0 / (1.0 + 0.5 * c * hbar)
        m = self.mass[:, None]
        inr = self.inertia[:, None]
        fe = gravity[None, :] * m
        me = np.zeros_like(fe)
        if len(self.load_nodes):
            sc = np.array([ramp(t, t0, t1) for t0, t1 in self.load_t])
            fe[self.load_nodes] += self.load_force * sc[:, None]
            me[self.load_nodes] += self.load_moment * sc[:, None]
        f = fe.copy()
        mom = me.copy()
        fcon = self.f_contact if self.f_contact is not None else np.zeros_like(f)
        f += fcon
        if not self.kinematic:
            f -= self.f_int
            mom -= self.m_int
        v_old, w_old = self.v, self.w
        v_new = (v_old * dn + f * (hbar / m)) * dd
        w_new = (w_old * dn + mom * (hbar / inr)) * dd
        free_v, free_w = v_new.copy(), w_new.copy()
        fx = self.fixed
        constrained = fx != 0
        if np.any(constrained):
            pv = self.program_velocity(t_half)
            for d in range(3):
                sel = (fx & (1 << d)) != 0
                v_new[sel, d] = pv[sel, d]
                sel = (fx & (8 << d)) != 0
                w_new[sel, d] = 0.0
        vn = (v_old + v_new) * 0.5
        wn = (w_old + w_new) * 0.5
        kinetic = np.sum(0.5 * (self.mass * dot(v_new, v_new) + self.inertia * dot(w_new, w_new)))
        external = np.sum(hbar * (dot(fe, vn) + dot(me, wn)))
        contact = np.sum(hbar * dot(fcon, vn))
        if self.kinematic:
            power = 0.0
        else:
            power = np.sum(dot(self.f_int - self.f_d, v_new) + dot(self.m_int - self.m_d, w_new))
        reaction = 0.0
        if np.any(constrained):
            k = constrained
            reaction = np.sum(dot(m[k] * (v_new[k] - free_v[k]) / dd, vn[k])
                              + dot(inr[k] * (w_new[k] - free_w[k]) / dd, wn[k]))
        damping = 0.0
        if c > 0.0:
            damping = np.sum(hbar * c * (self.mass * dot(vn, vn) + self.inertia * dot(wn, wn)))
        if not self.kinematic:
            damping += np.sum(hbar * (dot(self.f_d, vn) + dot(self.m_d, wn)))
        dx = v_new * h
        xn = self.x + dx
        moves = norm(dx)
        if not (np.all(np.isfinite(xn)) and np.all(np.isfinite(w_new))):
            raise Fault(f"non-finite velocity or position in body {self.id}")
        self.x, self.v, self.w = xn, v_new, w_new
        e = self.energy
        e["kinetic"] = float(kinetic)
        e["internal"] = self.internal_now + 0.5 * h * float(power)
        e["hourglass"] = self.hourglass_now
        e["external"] += float(external) + float(reaction)
        e["contact"] -= float(contact)
        e["damping"] += float(damping)
        return float(moves.max()), xn.min(axis=0), xn.max(axis=0)

    def internal_forces(self, h):
        """Element forces at the current positions (theory.md 2), updating the rate-form
        resultants with the half-step velocities over h. Returns the body's critical step
        (theory.md 4; +inf for a kinematic body)."""
        if self.kinematic:
            self.internal_now = 0.0
            self.hourglass_now = 0.0
            return math.inf
        r = elements.forces(self, h)
        self.f_int, self.m_int = r.f, r.m
        self.f_d, self.m_d = r.fd, r.md
        if np.any(r.ratio < COLLAPSE_RATIO) or np.any(np.isnan(r.ratio)):
            raise Fault(f"element collapsed in body {self.id}")
        if r.corners is not None and np.any(~(r.corners > 0.0)):
            raise Fault(f"quad inverted in body {self.id}")
        internal = float(np.sum(r.internal))
        hourglass = float(np.sum(r.hourglass))
        if not (math.isfinite(internal) and math.isfinite(hourglass)):
            raise Fault(f"non-finite internal energy in body {self.id}")
        self.internal_now = internal
        self.hourglass_now = hourglass
        return float(np.min(element_dt(self, r.length)))

    # ---- migration: the whole state, exact bits ------------------------------------
    STATE = ("x", "v", "w", "M", "Q", "tau", "hg_w", "hg_th", "f_int", "m_int", "f_d", "m_d",
             "f_contact", "energy", "internal_now", "hourglass_now")

    def state(self):
        return {k: getattr(self, k) for k in self.STATE}

    def set_state(self, s):
        for k in self.STATE:
            setattr(self, k, s[k])
