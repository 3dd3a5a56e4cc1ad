//! Forces carried as node sums (`crash_core::summed`: on one thread, for a body beyond
//! the last-level cache, the element stage adds each chunk's slots into a sum per node
//! and the node loop reads the sums). Each node's sum takes the gather's additions in
//! the gather's order, so a run gives the same bits either way; a settled state (each
//! sum in its node's first slot, -0.0 in the others) is gathered slot by slot to the
//! same sums, by the whole body or by the parts of a split; a run may change between
//! the two forms at any step. One test: it sets the process-wide mode.

mod common;

use common::mixed_damped_plate;
use crash_core::hash::state_hash;
use crash_core::partition::{partition_body, Split};
use crash_core::summed::set_summed_slots;
use crash_core::{Body, BodyEnergy, Clock, Group, Vec3};

const STEPS: usize = 60;
const SAFETY: f64 = 0.9;

/// A run in progress: the group, its clock and its next stable step.
struct Stepping {
    g: Group,
    clock: Clock,
    dt: f64,
}

impl Stepping {
    fn start(b: &Body, gravity: Vec3) -> Self {
        let mut g = Group::new(vec![b.clone()], gravity);
        let dt = g.start().expect("start")[0].stable_dt;
        Self {
            g,
            clock: Clock::default(),
            dt,
        }
    }

    /// `n` steps, the state hash after each and the energies at the end.
    fn steps(&mut self, n: usize) -> (Vec<u64>, [u64; 5]) {
        let mut hashes = Vec::new();
        for _ in 0..n {
            let h = SAFETY * self.dt;
            self.dt = self.g.advance(&self.clock, h).expect("stable")[0].stable_dt;
            self.clock = self.clock.after(h);
            hashes.push(state_hash(&self.g.bodies));
        }
        (hashes, bits(&self.g.bodies[0].state.energy))
    }
}

fn bits(e: &BodyEnergy) -> [u64; 5] {
    [e.kinetic, e.internal, e.hourglass, e.damping, e.external].map(f64::to_bits)
}

#[test]
fn summed_force_slots_step_the_same_bits_as_gathered_slots() {
    // triangles and quads, Kelvin and mass damping, a clamped edge, a driven edge, spin
    let (b, gravity) = mixed_damped_plate();
    let half = STEPS / 2;

    set_summed_slots(Some(false));
    let mut plain = Stepping::start(&b, gravity);
    let (first, _) = plain.steps(half);
    let at_half = plain_copy(&plain);
    let (second, plain_energy) = plain.steps(STEPS - half);
    assert!(plain.g.bodies[0].state.node_sums.is_empty());

    set_summed_slots(Some(true));
    let mut summed = Stepping::start(&b, gravity);
    let (s_first, _) = summed.steps(half);
    assert!(
        !summed.g.bodies[0].state.node_sums.is_empty(),
        "the mode was not taken"
    );
    assert_eq!(s_first, first, "summed slots, first half");
    // the sums settled into the slots, gathered slot by slot (a state that left the
    // group), and split into parts
    let mut rebuilt = plain_copy(&summed);
    let copy = rebuilt.g.bodies[0].settled_state();
    rebuilt.g.bodies[0].settle();
    assert!(
        rebuilt.g.bodies[0].state == copy,
        "settle and settled_state"
    );
    let split_second = split_steps(&summed.g.bodies[0], &summed, gravity, STEPS - half);
    let (s_second, s_energy) = summed.steps(STEPS - half);
    assert_eq!(s_second, second, "summed slots, second half");
    assert_eq!(s_energy, plain_energy, "summed slots: energies");

    set_summed_slots(Some(false));
    let (r_second, r_energy) = rebuilt.steps(STEPS - half);
    assert_eq!(r_second, second, "settled sums gathered slot by slot");
    assert_eq!(r_energy, plain_energy);
    assert_eq!(split_second, second, "settled sums split into parts");

    // a state of the usual form taken on summed from the middle of a run
    set_summed_slots(Some(true));
    let mut taken = at_half;
    let (t_second, t_energy) = taken.steps(STEPS - half);
    assert!(!taken.g.bodies[0].state.node_sums.is_empty());
    assert_eq!(t_second, second, "usual form continued summed");
    assert_eq!(t_energy, plain_energy);
    set_summed_slots(None);
}

/// The state hash after each of `n` steps of `b`, split into 3 parts, from `at`'s clock.
fn split_steps(b: &Body, at: &Stepping, gravity: Vec3, n: usize) -> Vec<u64> {
    let p = partition_body(&b.def, 3).expect("partition");
    let mut split = Split::new(b, &p).expect("split");
    let mut whole = b.clone();
    let (mut clock, mut dt) = (at.clock, at.dt);
    let mut hashes = Vec::new();
    for _ in 0..n {
        let h = SAFETY * dt;
        split.integrate(&clock, h, gravity).expect("stable");
        split.exchange();
        dt = split.forces(h, clock.after(h).step).expect("stable");
        clock = clock.after(h);
        split.gather_into(&mut whole);
        hashes.push(state_hash([&whole]));
    }
    hashes
}

fn plain_copy(s: &Stepping) -> Stepping {
    Stepping {
        g: s.g.clone(),
        clock: s.clock,
        dt: s.dt,
    }
}
