//! A shell body: one mesh, one section, its nodal state, constraints and loads.

use crate::curve::{TimeCurve, NO_CURVE};
use crate::element::{HourglassState, QuadElem, ShellState, Slot, Stabilization, TriElem};
use crate::error::CoreError;
use crate::material::Section;
use crate::mesh::Mesh;
use crate::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Fixed-DOF bits: translations x, y, z then rotations x, y, z.
pub mod dof {
    pub const X: u8 = 1;
    pub const Y: u8 = 2;
    pub const Z: u8 = 4;
    pub const RX: u8 = 8;
    pub const RY: u8 = 16;
    pub const RZ: u8 = 32;
    pub const TRANSLATIONS: u8 = 7;
    pub const ROTATIONS: u8 = 56;
    pub const ALL: u8 = 63;
}

/// No velocity program: a constrained DOF is held at zero velocity.
pub const NO_PROGRAM: u16 = u16::MAX;

/// Prescribed (kinematic) nodal velocity, ramped linearly from zero over `ramp` seconds
/// (ramp = 0: applied from the start, including the initial velocity), or scaled by
/// the body's load curve `curve` (then `ramp` is not used). With `displacement` the
/// vectors are a displacement [m] and a rotation [rad] scaled by the curve (or ramp):
/// d(t) = velocity * f(t), and each step moves the node by d(t_{n+1}) - d(t_n).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VelocityProgram {
    pub velocity: Vec3,
    pub angular: Vec3,
    pub ramp: f64,
    /// Index into `BodyDef::curves`, or `NO_CURVE`.
    pub curve: u32,
    /// A prescribed displacement (LS-DYNA VAD = 2) rather than a velocity.
    #[serde(default)]
    pub displacement: bool,
}

impl VelocityProgram {
    /// A program ramped from zero over `ramp` seconds.
    pub fn ramped(velocity: Vec3, angular: Vec3, ramp: f64) -> Self {
        Self {
            velocity,
            angular,
            ramp,
            curve: NO_CURVE,
            displacement: false,
        }
    }

    /// Velocity and angular velocity at t (`curves`: the body's); for a displacement,
    /// the rate of its curve (or ramp) just after t.
    pub fn at(&self, t: f64, curves: &[TimeCurve]) -> (Vec3, Vec3) {
        let s = if self.displacement {
            match curves.get(self.curve as usize) {
                Some(c) if self.curve != NO_CURVE => c.slope(t),
                _ if self.ramp > 0.0 && t < self.ramp && t >= 0.0 => 1.0 / self.ramp,
                _ => 0.0,
            }
        } else {
            scale(t, 0.0, self.ramp, self.curve, curves)
        };
        (self.velocity * s, self.angular * s)
    }

    /// The half-step velocity of the step of length h from t: a velocity program's
    /// value at t + h/2; a displacement's change over the step divided by h, so that
    /// the central-difference positions follow d(t_n) at every step without drift.
    pub fn over_step(&self, t: f64, h: f64, curves: &[TimeCurve]) -> (Vec3, Vec3) {
        if self.displacement {
            let f = |t: f64| scale(t, 0.0, self.ramp, self.curve, curves);
            let s = (f(t + h) - f(t)) / h;
            (self.velocity * s, self.angular * s)
        } else {
            self.at(t + 0.5 * h, curves)
        }
    }
}

/// The factor of a program or load at t: its curve's value, else its ramp.
#[inline]
pub fn scale(t: f64, t0: f64, t1: f64, curve: u32, curves: &[TimeCurve]) -> f64 {
    match curves.get(curve as usize) {
        Some(c) if curve != NO_CURVE => c.value(t),
        _ => ramp_factor(t, t0, t1),
    }
}

/// Linear ramp from 0 at `t0` to 1 at `t1` (a step at t0 when t1 <= t0).
pub fn ramp_factor(t: f64, t0: f64, t1: f64) -> f64 {
    if t1 <= t0 {
        if t >= t0 {
            1.0
        } else {
            0.0
        }
    } else {
        ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
    }
}

/// A nodal force and moment (global axes), scaled by a ramp from `t0` to `t1`, or by
/// the body's load curve `curve` (then t0 and t1 are not used).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NodalLoad {
    pub node: u32,
    pub force: Vec3,
    pub moment: Vec3,
    pub t0: f64,
    pub t1: f64,
    /// Index into `BodyDef::curves`, or `NO_CURVE`.
    pub curve: u32,
}

impl NodalLoad {
    /// The factor of this load at t.
    #[inline]
    pub fn scale(&self, t: f64, curves: &[TimeCurve]) -> f64 {
        scale(t, self.t0, self.t1, self.curve, curves)
    }
}

/// Energy record of one body. After a step from t_n to t_{n+1} it holds the values at
/// t_{n+1/2}: kinetic energy of v_{n+1/2}, the shadow internal energy
/// E(x_n) + h/2 f_int(x_n) . v_{n+1/2} (see integrate.rs), and the work and dissipation
/// summed up to then.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct BodyEnergy {
    pub kinetic: f64,
    pub internal: f64,
    pub hourglass: f64,
    /// Work absorbed by contact (minus the work contact forces did on this body).
    pub contact: f64,
    /// Dissipated by Kelvin and mass damping.
    pub damping: f64,
    /// Work of loads, gravity and boundary reactions.
    pub external: f64,
}

/// Rotational inertia of a node: m * max(t^2/12, f * A_e), f = ROT_INERTIA_QUAD or
/// ROT_INERTIA_TRI; the area term lifts the shear-rotation frequency below the membrane
/// one so rotations never set the time step (docs/theory.md, "Mass"). Triangles need a
/// larger factor: a corner node held by a single triangle measured
/// omega_max dt_e / 2 = 1.64 with f = 1/8 (tests/stability.rs covers such meshes).
/// Quads: 3/16, not 1/8: with 1/8 the shear-rotation mode of a freely precessing quad
/// plate grows (energy balance 1.5e-3 after 10 turns, 3.0e-5 with 3/16; tests/energy_hold.rs).
pub const ROT_INERTIA_QUAD: f64 = 3.0 / 16.0;
pub const ROT_INERTIA_TRI: f64 = 1.0 / 2.0;

/// What never changes during a run: mesh and reference element data, section,
/// supports, programs, loads and the lumped masses derived from them. Shared behind an
/// `Arc`: copies of a body (snapshots, migrations in one process) share one definition,
/// and a definition crosses the wire once per worker.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BodyDef {
    pub id: u32,
    pub name: String,
    pub section: Section,
    pub stab: Stabilization,
    /// Reference (initial) positions.
    pub x0: Vec<Vec3>,
    pub mass: Vec<f64>,
    pub inertia: Vec<f64>,
    pub fixed: Vec<u8>,
    pub program: Vec<u16>,
    pub programs: Vec<VelocityProgram>,
    pub loads: Vec<NodalLoad>,
    /// Index of the first load of each node in `loads` (sorted by node; u32::MAX: none).
    /// A node may carry several loads, each with its own ramp.
    pub load_of: Vec<u32>,
    /// Load curves of the programs and loads (`curve` indices).
    pub curves: Vec<TimeCurve>,
    /// Mass-proportional (global) damping coefficient c [1/s]: f = -c m v.
    pub mass_damping: f64,
    pub tris: Vec<TriElem>,
    pub quads: Vec<QuadElem>,
    /// Gather map: the force slots of node n are gather_slot[gather_start[n]..gather_start[n+1]].
    pub gather_start: Vec<u32>,
    pub gather_slot: Vec<u32>,
    /// Contact participates (has a contact surface).
    pub contact: bool,
    /// Self-contact of this body enabled.
    pub self_contact: bool,
    /// Every DOF of every node constrained: no internal forces are computed.
    pub kinematic: bool,
    /// A part of a split body (`partition`): its last `halo_nodes` nodes are copies of
    /// nodes another part owns, not integrated here (their state is copied from the
    /// owner after each update) and out of the kinetic energy and work sums. 0 for a
    /// whole body.
    #[serde(default)]
    pub halo_nodes: usize,
    /// A part of a split body: per element, true where another part is the element's
    /// owner (`Partition`). Such an element is computed here too (it touches an owned
    /// node) but its energies are counted by its owner only, so that the parts' energies
    /// add up to the whole body's. None for a whole body.
    #[serde(skip)]
    pub uncounted: Option<std::sync::Arc<[bool]>>,
    /// A contact view's sub-body (`partition::view`): the whole body's surface
    /// figures, which the segment pass reads (`Surface::figures`); None for a body that
    /// is its own whole.
    #[serde(skip)]
    pub whole_surface: Option<SurfaceFigures>,
}

/// A whole body's contact surface figures from its definition (initial positions, all
/// its elements): what the segment pass reads, the same in every mode however the body
/// is split or viewed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceFigures {
    /// All node masses over the sum of the segments' initial areas [kg/m^2] (the
    /// pass's stiffness).
    pub areal_mass: f64,
    /// The segments' mean initial area [m^2] (the finer surface is the slave).
    pub mean_area: f64,
}

/// What a step changes: nodal motion, element resultants and force slots, contact
/// forces, energies. Snapshots, migrations and checkpoints carry this.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyState {
    /// Current positions x_n, half-step velocities v_{n-1/2} (v_0 before the first step),
    /// angular velocities.
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub w: Vec<Vec3>,
    /// Resultant state: triangles first, then quads.
    pub shell: Vec<ShellState>,
    pub hourglass: Vec<HourglassState>,
    /// Per-element force slots (tri: 3, quad: 4), gathered per node in a fixed order.
    /// With Kelvin damping a second set of as many follows (`BodyDef::slot_count`): the
    /// Kelvin part of each slot's force, which the integration books as dissipation
    /// with the time levels of the other work terms (docs/theory.md section 6). Kept in
    /// this vector so that snapshots, migrations and checkpoints carry it unchanged.
    pub slots: Vec<Slot>,
    /// The forces carried as node sums (`summed`: one thread, a body beyond the cache):
    /// each node's summed slots, then with Kelvin damping each node's summed Kelvin part.
    /// While not empty the slots are not current: whatever takes the state out of its
    /// group takes it settled (`Body::settle`, `Body::settled_state`).
    #[serde(skip)]
    pub node_sums: Vec<Slot>,
    /// Contact forces on nodes (written by the contact stage, zero otherwise).
    pub f_contact: Vec<Vec3>,
    pub energy: BodyEnergy,
    /// Internal and hourglass energy of the current configuration (last force pass).
    pub internal_now: f64,
    pub hourglass_now: f64,
}

/// A body: its shared definition and its own state.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Body {
    pub def: Arc<BodyDef>,
    pub state: BodyState,
    /// `BodyDef::total_mass` of the definition it was taken of (`total_mass`): the
    /// integration's momentum figures and the closing speed read it every step, and a
    /// serial sum over the nodes was a serial part of the step. Holding the `Weak`
    /// keeps that definition's address from being reused, so the sum is never read for
    /// another; `def_mut` clears it before the definition can change.
    #[serde(skip)]
    mass_sum: std::sync::OnceLock<(std::sync::Weak<BodyDef>, f64)>,
}

impl Body {
    /// Build a body: validates the mesh, precomputes element reference data, lumped
    /// masses and the gather map.
    pub fn new(
        id: u32,
        name: &str,
        mesh: &Mesh,
        section: Section,
        stab: Stabilization,
    ) -> Result<Self, CoreError> {
        section.material.validate()?;
        if !(section.thickness.is_finite() && section.thickness > 0.0) {
            return Err(CoreError::Thickness {
                body: name.into(),
                value: section.thickness,
            });
        }
        mesh.validate(name)?;
        let nn = mesh.nodes.len();
        let x = mesh.nodes.clone();
        let tris: Vec<TriElem> = mesh
            .tris
            .iter()
            .map(|t| TriElem::new(*t, &t.map(|n| x[n as usize])))
            .collect();
        let quads: Vec<QuadElem> = mesh
            .quads
            .iter()
            .map(|q| QuadElem::new(*q, &q.map(|n| x[n as usize])))
            .collect();
        let rho_t = section.material.density * section.thickness;
        let t2 = section.thickness * section.thickness / 12.0;
        let mut mass = vec![0.0; nn];
        let mut inertia = vec![0.0; nn];
        let mut lump = |nodes: &[u32], area: f64, factor: f64| {
            let m = rho_t * area / nodes.len() as f64;
            let s = t2.max(factor * area);
            for &n in nodes {
                mass[n as usize] += m;
                inertia[n as usize] += m * s;
            }
        };
        for e in &tris {
            lump(&e.nodes, e.area0, ROT_INERTIA_TRI);
        }
        for e in &quads {
            lump(&e.nodes, e.area0, ROT_INERTIA_QUAD);
        }
        // Gather map: node -> slots, in element order (fixed, thread-independent).
        let mut count = vec![0u32; nn + 1];
        let slot_nodes: Vec<u32> = tris
            .iter()
            .flat_map(|e| e.nodes)
            .chain(quads.iter().flat_map(|e| e.nodes))
            .collect();
        for &n in &slot_nodes {
            count[n as usize + 1] += 1;
        }
        for i in 0..nn {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut gather_slot = vec![0u32; slot_nodes.len()];
        for (s, &n) in slot_nodes.iter().enumerate() {
            gather_slot[fill[n as usize] as usize] = s as u32;
            fill[n as usize] += 1;
        }
        for (i, m) in mass.iter().enumerate() {
            if *m <= 0.0 {
                return Err(CoreError::Other {
                    body: name.into(),
                    what: format!("node {i} belongs to no element (it would have no mass)"),
                });
            }
        }
        let ne = tris.len() + quads.len();
        let nslots = slot_nodes.len() * if section.material.kelvin > 0.0 { 2 } else { 1 };
        Ok(Self {
            state: BodyState {
                v: vec![Vec3::zeros(); nn],
                w: vec![Vec3::zeros(); nn],
                x: x.clone(),
                shell: vec![ShellState::default(); ne],
                hourglass: vec![HourglassState::default(); quads.len()],
                slots: vec![[0.0; 6]; nslots],
                node_sums: Vec::new(),
                f_contact: Vec::new(),
                energy: BodyEnergy::default(),
                internal_now: 0.0,
                hourglass_now: 0.0,
            },
            def: Arc::new(BodyDef {
                id,
                name: name.into(),
                section,
                stab,
                x0: x,
                mass,
                inertia,
                fixed: vec![0; nn],
                program: vec![NO_PROGRAM; nn],
                programs: Vec::new(),
                loads: Vec::new(),
                load_of: vec![u32::MAX; nn],
                curves: Vec::new(),
                mass_damping: 0.0,
                gather_start: count,
                gather_slot,
                tris,
                quads,
                contact: false,
                self_contact: false,
                kinematic: false,
                halo_nodes: 0,
                uncounted: None,
                whole_surface: None,
            }),
            mass_sum: Default::default(),
        })
    }

    /// The body's id (its definition's).
    pub fn id(&self) -> u32 {
        self.def.id
    }

    /// The definition, for changes while a body is being built (copies it first if it
    /// is shared: never on the stepping path).
    pub fn def_mut(&mut self) -> &mut BodyDef {
        self.mass_sum = Default::default();
        Arc::make_mut(&mut self.def)
    }

    /// Put a definition and a state back together, checking that they fit.
    pub fn from_parts(def: Arc<BodyDef>, state: BodyState) -> Result<Self, CoreError> {
        let nn = def.x0.len();
        let ne = def.tris.len() + def.quads.len();
        let nslots = 3 * def.tris.len() + 4 * def.quads.len();
        // the Kelvin half may be missing (Kelvin damping given after the body was built:
        // the next force pass adds it) or stale (damping taken away, e.g. `modal`)
        let fits = state.x.len() == nn
            && state.v.len() == nn
            && state.w.len() == nn
            && state.shell.len() == ne
            && state.hourglass.len() == def.quads.len()
            && (state.slots.len() == nslots || state.slots.len() == 2 * nslots)
            && (state.f_contact.is_empty() || state.f_contact.len() == nn);
        if !fits {
            return Err(CoreError::Other {
                body: def.name.clone(),
                what: format!(
                    "a state of {} nodes / {} elements does not fit the definition ({nn} nodes, {ne} elements)",
                    state.x.len(),
                    state.shell.len()
                ),
            });
        }
        Ok(Self {
            def,
            state,
            mass_sum: Default::default(),
        })
    }

    pub fn node_count(&self) -> usize {
        self.state.x.len()
    }

    pub fn element_count(&self) -> usize {
        self.def.element_count()
    }

    /// `BodyDef::total_mass`, summed once per definition (the same bits; a definition
    /// put in `def` after the first sum is summed at every call).
    pub fn total_mass(&self) -> f64 {
        let of = |w: &std::sync::Weak<BodyDef>| std::ptr::eq(w.as_ptr(), Arc::as_ptr(&self.def));
        match self.mass_sum.get() {
            Some((w, m)) if of(w) => *m,
            Some(_) => self.def.total_mass(),
            None => {
                let m = self.def.total_mass();
                let _ = self.mass_sum.set((Arc::downgrade(&self.def), m));
                m
            }
        }
    }

    /// Rigid initial motion: v_I = v + omega x (x_I - centre), w_I = omega.
    pub fn set_rigid_velocity(&mut self, v: Vec3, omega: Vec3, centre: Vec3) {
        let s = &mut self.state;
        for i in 0..s.x.len() {
            s.v[i] = v + omega.cross(&(s.x[i] - centre));
            s.w[i] = omega;
        }
    }

    /// Mass-weighted centre of the current positions.
    pub fn centre_of_mass(&self) -> Vec3 {
        let mut c = Vec3::zeros();
        for (p, m) in self.state.x.iter().zip(&self.def.mass) {
            c += p * *m;
        }
        c / self.total_mass()
    }

    /// Constrain DOFs of a node to zero velocity (bits of `dof`).
    pub fn fix(&mut self, node: usize, mask: u8) {
        let d = self.def_mut();
        d.fixed[node] |= mask;
        d.refresh_kinematic();
    }

    /// Add a load curve; returns its index for `VelocityProgram::curve` and
    /// `NodalLoad::curve` (an invalid table is refused).
    pub fn add_curve(&mut self, c: TimeCurve) -> Result<u32, CoreError> {
        if !c.is_valid() {
            return Err(CoreError::Other {
                body: self.def.name.clone(),
                what: "a load curve needs finite points with increasing times".into(),
            });
        }
        let d = self.def_mut();
        d.curves.push(c);
        Ok(d.curves.len() as u32 - 1)
    }

    /// Prescribe the velocity of the given nodes (all six DOFs follow the program).
    pub fn prescribe(&mut self, nodes: &[usize], program: VelocityProgram) {
        let d = self.def_mut();
        let id = d.programs.len() as u16;
        d.programs.push(program);
        for &n in nodes {
            d.fixed[n] = dof::ALL;
            d.program[n] = id;
        }
        d.refresh_kinematic();
        let (v, w) = program.at(0.0, &self.def.curves);
        for &n in nodes {
            self.state.v[n] = v;
            self.state.w[n] = w;
        }
    }

    /// Add a nodal load (several loads on one node add up).
    pub fn add_load(&mut self, load: NodalLoad) {
        let d = self.def_mut();
        d.loads.push(load);
        d.loads.sort_by_key(|l| l.node);
        d.load_of.iter_mut().for_each(|l| *l = u32::MAX);
        for (k, l) in d.loads.iter().enumerate().rev() {
            d.load_of[l.node as usize] = k as u32;
        }
    }

    /// Zero all DOFs whose bits are fixed and apply programs at time t (used at start).
    pub fn apply_constraints(&mut self, t: f64) {
        let (d, s) = (&*self.def, &mut self.state);
        for i in 0..s.x.len() {
            let f = d.fixed[i];
            if f == 0 {
                continue;
            }
            let (pv, pw) = match d.program[i] {
                NO_PROGRAM => (Vec3::zeros(), Vec3::zeros()),
                p => d.programs[p as usize].at(t, &d.curves),
            };
            for k in 0..3 {
                if f & (1 << k) != 0 {
                    s.v[i][k] = pv[k];
                }
                if f & (8 << k) != 0 {
                    s.w[i][k] = pw[k];
                }
            }
        }
    }

    /// Translational + rotational kinetic energy of the current (half-step) velocities.
    pub fn kinetic_energy_now(&self) -> f64 {
        let (d, s) = (&*self.def, &self.state);
        let mut e = 0.0;
        // a part's halo nodes are counted by their owner
        for i in 0..s.x.len().saturating_sub(d.halo_nodes) {
            e += 0.5 * (d.mass[i] * s.v[i].norm_squared() + d.inertia[i] * s.w[i].norm_squared());
        }
        e
    }

    /// Linear momentum sum m v.
    pub fn linear_momentum(&self) -> Vec3 {
        let mut p = Vec3::zeros();
        for (v, m) in self.state.v.iter().zip(&self.def.mass) {
            p += v * *m;
        }
        p
    }

    /// Angular momentum about the origin: sum m x x v + I w (positions at the same time
    /// level as v when called between steps: x_{n+1} with v_{n+1/2} is exactly conserved
    /// by central differences).
    pub fn angular_momentum(&self) -> Vec3 {
        let (d, s) = (&*self.def, &self.state);
        let mut l = Vec3::zeros();
        for i in 0..s.x.len() {
            l += s.x[i].cross(&s.v[i]) * d.mass[i] + s.w[i] * d.inertia[i];
        }
        l
    }
}

impl BodyDef {
    pub fn node_count(&self) -> usize {
        self.x0.len()
    }

    pub fn element_count(&self) -> usize {
        self.tris.len() + self.quads.len()
    }

    /// The nodes of element e (triangles first, then quads).
    pub fn element_nodes(&self, e: usize) -> &[u32] {
        let nt = self.tris.len();
        if e < nt {
            &self.tris[e].nodes
        } else {
            &self.quads[e - nt].nodes
        }
    }

    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Length of `BodyState::slots`: one slot per element node, twice that with Kelvin
    /// damping (the second half holds the Kelvin part of the forces).
    pub fn slot_count(&self) -> usize {
        let n = self.gather_slot.len();
        if self.section.material.kelvin > 0.0 {
            2 * n
        } else {
            n
        }
    }

    fn refresh_kinematic(&mut self) {
        self.kinematic = self.fixed.iter().all(|&f| f == dof::ALL);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::shapes::{plate, ElementKind};

    #[test]
    fn loads_on_one_node_add_up() {
        let m = plate(1.0, 1.0, 1, 1, ElementKind::Quad);
        let sec = Section::new(Material::new(1000.0, 1e9, 0.3, 0.0).expect("valid"), 0.01);
        let mut b = Body::new(0, "p", &m, sec, Stabilization::default()).expect("valid");
        let load = |node: u32, fz: f64| NodalLoad {
            node,
            force: Vec3::new(0.0, 0.0, fz),
            moment: Vec3::zeros(),
            t0: 0.0,
            t1: 0.0,
            curve: NO_CURVE,
        };
        b.add_load(load(2, 1.0));
        b.add_load(load(0, 5.0));
        b.add_load(load(2, 2.0));
        let clock = crate::integrate::StepClock {
            t: 0.0,
            h_prev: 0.0,
            h: 1e-6,
            step: 0,
        };
        let before = b.state.v.clone();
        b.integrate(&clock, Vec3::zeros()).expect("finite");
        // node 2 got 3 N, node 0 got 5 N, over hbar = h/2
        let a2 = (b.state.v[2].z - before[2].z) / 0.5e-6 * b.def.mass[2];
        let a0 = (b.state.v[0].z - before[0].z) / 0.5e-6 * b.def.mass[0];
        assert!(
            (a2 - 3.0).abs() < 1e-9 && (a0 - 5.0).abs() < 1e-9,
            "{a2} {a0}"
        );
    }
}
