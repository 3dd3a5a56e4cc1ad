//! The memory a scene needs, estimated from its node and element counts before any mesh
//! is generated, and the memory the machine has (`MemAvailable` of /proc/meminfo).
//!
//! The per-node and per-element bytes are the sizes of the structures a run holds for
//! them (`size_of` of the core's types, so they follow any change there) times
//! `RUN_FACTOR`, the ratio of a whole `crash run`'s peak resident memory to those
//! structures. Measured (docs/scene-format.md, "Memory"): peak RSS of `crash run` on
//! 200 x 200 ... 800 x 800 plates with a sphere, 2-5 steps, two frames: 1510 B per
//! quad + node and 1900 B per node + 2 triangles, against structure sizes of 683 and
//! 795 B; the factor (snapshots for frames, contact search, output buffers) is 2.21 and
//! 2.39. `RUN_FACTOR` takes the larger, rounded up. The 104-byte `QuadElem` (was 168)
//! lowered the peak by 43 B per quad (same-sitting A/B, release build): 1467 B per quad
//! + node against 619 B of structures.

use crash_core::element::{HourglassState, QuadElem, ShellState, Slot, TriElem};
use crash_core::Vec3;
use std::mem::size_of;

/// Peak run memory over the structure sizes below (measured, see the module docs).
pub const RUN_FACTOR: f64 = 2.4;

/// Bytes of the per-node arrays of a body (positions, velocities, angular velocities,
/// reference positions, contact forces; masses and inertias; flags, programs, load and
/// gather indices) plus the mesh and the two placement copies the scene holds.
pub const NODE_BYTES: usize = 5 * size_of::<Vec3>()
    + 2 * size_of::<f64>()
    + size_of::<u8>()
    + size_of::<u16>()
    + 2 * size_of::<u32>()
    + 3 * size_of::<Vec3>();

/// Bytes per triangle: element, resultant state, three force slots and gather entries,
/// the mesh connectivity.
pub const TRI_BYTES: usize = size_of::<TriElem>()
    + size_of::<ShellState>()
    + 3 * size_of::<Slot>()
    + 3 * size_of::<u32>()
    + size_of::<[u32; 3]>();

/// Bytes per quad: as a triangle, plus the hourglass state and a fourth node.
pub const QUAD_BYTES: usize = size_of::<QuadElem>()
    + size_of::<ShellState>()
    + size_of::<HourglassState>()
    + 4 * size_of::<Slot>()
    + 4 * size_of::<u32>()
    + size_of::<[u32; 4]>();

/// Node and element counts of a body (or a whole scene).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    pub nodes: usize,
    pub tris: usize,
    pub quads: usize,
    /// Extra force slots of Kelvin-damped bodies (their elements keep the Kelvin part
    /// of each nodal force apart: one more slot per element node).
    pub kelvin_slots: usize,
}

impl Counts {
    pub fn elements(&self) -> usize {
        self.tris.saturating_add(self.quads)
    }

    pub fn add(&mut self, o: Counts) {
        self.nodes = self.nodes.saturating_add(o.nodes);
        self.tris = self.tris.saturating_add(o.tris);
        self.quads = self.quads.saturating_add(o.quads);
        self.kelvin_slots = self.kelvin_slots.saturating_add(o.kelvin_slots);
    }

    /// These counts for a body with Kelvin damping.
    pub fn with_kelvin(self) -> Counts {
        Counts {
            kelvin_slots: self
                .tris
                .saturating_mul(3)
                .saturating_add(self.quads.saturating_mul(4)),
            ..self
        }
    }

    /// Estimated peak bytes of a run holding these.
    pub fn bytes(&self) -> f64 {
        RUN_FACTOR
            * (self.nodes as f64 * NODE_BYTES as f64
                + self.tris as f64 * TRI_BYTES as f64
                + self.quads as f64 * QUAD_BYTES as f64
                + self.kelvin_slots as f64 * size_of::<Slot>() as f64)
    }
}

/// `MemAvailable` of /proc/meminfo in bytes (None where there is no such file).
pub fn available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&text)
}

fn parse_meminfo(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let mut it = line.split_whitespace().skip(1);
    let value: u64 = it.next()?.parse().ok()?;
    let unit = match it.next() {
        Some("kB") | Some("KB") => 1024,
        None => 1,
        Some(_) => return None,
    };
    value.checked_mul(unit)
}

/// Bytes as `12.3 GB` (decimal units, as `free -h` and the kernel's kB are read by most).
pub fn human(bytes: f64) -> String {
    const UNITS: [&str; 5] = ["B", "kB", "MB", "GB", "TB"];
    let mut v = bytes;
    let mut u = 0;
    while v >= 1000.0 && u + 1 < UNITS.len() {
        v /= 1000.0;
        u += 1;
    }
    format!("{v:.1} {}", UNITS[u])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meminfo_is_read_in_kilobytes() {
        let t = "MemTotal:       32000000 kB\nMemFree:   100 kB\nMemAvailable:   23526520 kB\n";
        assert_eq!(parse_meminfo(t), Some(23_526_520 * 1024));
        assert_eq!(parse_meminfo("MemTotal: 1 kB\n"), None);
    }

    #[test]
    fn estimate_matches_the_measured_runs() {
        // measured peak RSS per quad + node and per node + 2 triangles (module docs)
        let quad = Counts {
            nodes: 1,
            quads: 1,
            ..Counts::default()
        }
        .bytes();
        let tri = Counts {
            nodes: 1,
            tris: 2,
            ..Counts::default()
        }
        .bytes();
        assert!((1467.0..1467.0 * 1.25).contains(&quad), "{quad}");
        assert!((1900.0..1900.0 * 1.25).contains(&tri), "{tri}");
        assert_eq!(human(3.2e10), "32.0 GB");
    }

    #[test]
    fn a_kelvin_damped_body_counts_one_more_slot_per_element_node() {
        let c = Counts {
            nodes: 10,
            tris: 2,
            quads: 3,
            ..Counts::default()
        };
        let extra = c.with_kelvin().bytes() - c.bytes();
        let want = RUN_FACTOR * (2 * 3 + 3 * 4) as f64 * size_of::<Slot>() as f64;
        assert!((extra - want).abs() < 1e-6, "{extra} vs {want}");
    }
}
