//! The whole bodies of a split group from its parts (`SharedGroup::assemble`), for
//! frames, checkpoints and merging a split back: owned nodes from their owners,
//! element data from a part that holds the element, energies summed over the parts.

use super::report::add_energy;
use super::SharedGroup;
use crate::body::{Body, BodyEnergy, BodyState};
use crate::error::CoreError;
use crate::Vec3;

impl SharedGroup {
    /// The full states of the parts computed here (for the assembly of whole bodies).
    pub fn own_states(&self) -> Vec<(u32, u32, BodyState)> {
        let mut out = Vec::new();
        for (i, s) in self.split.splits.iter().enumerate() {
            for (q, p) in s.parts.iter().enumerate() {
                if self.mine(i, q) {
                    out.push((self.ids[i], q as u32, p.body.state.clone()));
                }
            }
        }
        out
    }

    /// Take the other holders' part states (every part not computed here, full
    /// states) and assemble the whole bodies from all parts: owned nodes from their
    /// owners, element data from a part that holds the element (every such part has
    /// the same bits), energies summed over the parts.
    pub fn assemble(&mut self, others: Vec<(u32, u32, BodyState)>) -> Result<Vec<Body>, CoreError> {
        for (id, q, st) in others {
            let bad = |what: &str| CoreError::Other {
                body: format!("body {id}"),
                what: format!("part {q}: {what}"),
            };
            let i = self
                .ids
                .iter()
                .position(|&x| x == id)
                .ok_or_else(|| bad("not in this split group"))?;
            let q = q as usize;
            if q >= self.split.mine[i].len() || self.mine(i, q) {
                return Err(bad("not expected here"));
            }
            let p = &mut self.split.splits[i].parts[q];
            p.body = Body::from_parts(p.body.def.clone(), st)?;
        }
        let mut out = Vec::with_capacity(self.ids.len());
        for (s, whole) in self.split.splits.iter().zip(&self.split.whole) {
            let mut b = whole.clone();
            let d = b.def.clone();
            let nt = d.tris.len();
            let first_slot = |e: usize| if e < nt { 3 * e } else { 3 * nt + 4 * (e - nt) };
            let corners = |e: usize| if e < nt { 3 } else { 4 };
            let half = d.gather_slot.len();
            let (mut energy, mut inow, mut hnow) = (BodyEnergy::default(), 0.0, 0.0);
            let w = &mut b.state;
            // every element's slots come from its owner part below (`summed`)
            w.node_sums.clear();
            let contact = s.parts.iter().any(|p| !p.body.state.f_contact.is_empty());
            if contact {
                w.f_contact.resize(w.x.len(), Vec3::zeros());
            } else {
                w.f_contact.clear();
            }
            for p in &s.parts {
                let ps = &p.body.state;
                for (k, &n) in p.node[..p.owned].iter().enumerate() {
                    let n = n as usize;
                    (w.x[n], w.v[n], w.w[n]) = (ps.x[k], ps.v[k], ps.w[k]);
                    if contact {
                        w.f_contact[n] = ps.f_contact.get(k).copied().unwrap_or_default();
                    }
                }
                let phalf = p.body.def.gather_slot.len();
                let halves = ps.slots.len() / phalf.max(1);
                if w.slots.len() < halves * half {
                    w.slots.resize(halves * half, [0.0; 6]);
                }
                let mut local_slot = 0;
                for (le, &e) in p.element.iter().enumerate() {
                    let e = e as usize;
                    w.shell[e] = ps.shell[le];
                    if e >= nt {
                        let lq = le - p.body.def.tris.len();
                        if let (Some(t), Some(s)) =
                            (w.hourglass.get_mut(e - nt), ps.hourglass.get(lq))
                        {
                            *t = *s;
                        }
                    }
                    let c = corners(e);
                    for hf in 0..halves {
                        let a = hf * half + first_slot(e);
                        let la = hf * phalf + local_slot;
                        w.slots[a..a + c].copy_from_slice(&ps.slots[la..la + c]);
                    }
                    local_slot += c;
                }
                energy = add_energy(energy, ps.energy);
                inow += ps.internal_now;
                hnow += ps.hourglass_now;
            }
            w.energy = energy;
            w.internal_now = inow;
            w.hourglass_now = hnow;
            out.push(b);
        }
        Ok(out)
    }
}
