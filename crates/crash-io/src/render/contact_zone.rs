//! Where two bodies touch in a frame, from the nodal contact forces: the centre of
//! pressure, the contact normal, the zone's radius, and which body hides the zone from
//! below. The view from below and the section cut are placed from it.

use crate::frame::{Frame, FrameBody};
use crash_core::Vec3;

/// The contact zone of one body pair in one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactZone {
    /// The body left out of the view from below (the lower one of the pair, by centroid
    /// height z; the pair's second body on a tie).
    pub hidden: u32,
    /// The body the views show.
    pub kept: u32,
    /// Force-weighted centroid of the zone's nodes of both bodies [m].
    pub centre: Vec3,
    /// Unit direction of the contact force on `kept` (from `hidden` toward `kept`).
    pub normal: Vec3,
    /// Largest distance, across the normal, of a zone node carrying at least 1 % of
    /// the largest nodal contact force, from `centre` [m].
    pub radius: f64,
    /// Nodes in the zone (both bodies).
    pub nodes: usize,
}

/// Bounding box of a body's current positions (None if it has no nodes).
fn bounds(b: &FrameBody) -> Option<(Vec3, Vec3)> {
    let first = *b.x.first()?;
    Some(
        b.x.iter()
            .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p))),
    )
}

/// Nodes of `b` that carry a contact force and lie in `other`'s box grown by `margin`:
/// the nodes of this pair's zone (a body touching several others keeps them apart).
fn zone_nodes<'a>(
    b: &'a FrameBody,
    other: &FrameBody,
    margin: f64,
) -> impl Iterator<Item = (Vec3, Vec3)> + 'a {
    let (lo, hi) = bounds(other).map_or((Vec3::zeros(), -Vec3::repeat(1.0)), |(lo, hi)| {
        (lo - Vec3::repeat(margin), hi + Vec3::repeat(margin))
    });
    b.x.iter()
        .zip(&b.f_contact)
        .filter(move |(p, f)| {
            f.norm() > 0.0
                && f.norm().is_finite()
                && p.iter()
                    .zip(lo.iter().zip(hi.iter()))
                    .all(|(c, (l, h))| *c >= *l && *c <= *h)
        })
        .map(|(p, f)| (*p, *f))
}

fn centroid_z(b: &FrameBody) -> f64 {
    b.x.iter().map(|p| p.z).sum::<f64>() / b.x.len().max(1) as f64
}

/// Total magnitude of the nodal contact forces of a body.
fn force_sum(b: &FrameBody) -> f64 {
    b.f_contact
        .iter()
        .map(|f| f.norm())
        .filter(|v| v.is_finite())
        .sum()
}

/// The contact zone of bodies `pair` in `frame`; with `pair = None`, of the two bodies
/// carrying the largest contact forces. None when the pair carries no contact force.
pub fn contact_zone(frame: &Frame, pair: Option<(u32, u32)>) -> Option<ContactZone> {
    let (a, b) = match pair {
        Some((a, b)) => (
            frame.bodies.iter().find(|x| x.id == a)?,
            frame.bodies.iter().find(|x| x.id == b)?,
        ),
        None => {
            let mut by_force: Vec<&FrameBody> = frame.bodies.iter().collect();
            by_force.sort_by(|p, q| force_sum(q).total_cmp(&force_sum(p)).then(p.id.cmp(&q.id)));
            match by_force[..] {
                [p, q, ..] => (p, q),
                _ => return None,
            }
        }
    };
    // Penalty contact acts within a thickness of the shells' mid-surfaces.
    let margin = 2.0 * (a.thickness + b.thickness);
    let za: Vec<(Vec3, Vec3)> = zone_nodes(a, b, margin).collect();
    let zb: Vec<(Vec3, Vec3)> = zone_nodes(b, a, margin).collect();
    let w: f64 = za.iter().chain(&zb).map(|(_, f)| f.norm()).sum();
    if za.is_empty() && zb.is_empty() || w <= 0.0 || !w.is_finite() {
        return None;
    }
    let centre = za
        .iter()
        .chain(&zb)
        .fold(Vec3::zeros(), |c, (p, f)| c + p * f.norm())
        / w;
    // Force on a from b (points from b to a), measured on both sides.
    let fa = za.iter().fold(Vec3::zeros(), |s, (_, f)| s + f)
        - zb.iter().fold(Vec3::zeros(), |s, (_, f)| s + f);
    let (hidden, kept, n_kept) = if centroid_z(a) < centroid_z(b) {
        (a.id, b.id, -fa)
    } else {
        (b.id, a.id, fa)
    };
    let normal = if n_kept.norm() > 0.0 {
        n_kept.normalize()
    } else {
        Vec3::z()
    };
    let fmax = za
        .iter()
        .chain(&zb)
        .map(|(_, f)| f.norm())
        .fold(0.0, f64::max);
    let radius = za
        .iter()
        .chain(&zb)
        .filter(|(_, f)| f.norm() >= 0.01 * fmax)
        .map(|(p, _)| {
            let d = p - centre;
            (d - normal * d.dot(&normal)).norm()
        })
        .fold(0.0, f64::max);
    Some(ContactZone {
        hidden,
        kept,
        centre,
        normal,
        radius,
        nodes: za.len() + zb.len(),
    })
}

impl ContactZone {
    /// A unit vector across the normal: the world axis least aligned with the normal,
    /// made perpendicular to it (x for a vertical normal). The section plane holds the
    /// normal and this direction.
    pub fn across(&self) -> Vec3 {
        let n = self.normal;
        let axes = [Vec3::x(), Vec3::y(), Vec3::z()];
        let e = axes
            .iter()
            .min_by(|p, q| p.dot(&n).abs().total_cmp(&q.dot(&n).abs()))
            .copied()
            .unwrap_or(Vec3::x());
        (e - n * e.dot(&n)).normalize()
    }

    /// Normal of the section plane through the zone: across x normal, so that in the
    /// section picture `across` points right and the contact normal up.
    pub fn section_normal(&self) -> Vec3 {
        self.across().cross(&self.normal).normalize()
    }
}
