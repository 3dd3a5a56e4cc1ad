//! Contact segments (element faces) and the closest-point projection of a node onto
//! them. Triangles: exact closest point (interior, edges, vertices). Quads: split into
//! four triangles around the centroid (no preferred diagonal, exact for plane quads,
//! symmetric for warped ones); the centroid's weight is shared equally by the corners.

use crate::body::Body;
use crate::Vec3;

/// One face of a body: a triangle (`count` 3, `nodes[3]` unused) or a quad.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    pub nodes: [u32; 4],
    pub count: u8,
}

impl Segment {
    pub fn nodes(&self) -> &[u32] {
        &self.nodes[..self.count as usize]
    }
}

/// The segments of a body: its triangles, then its quads (the element order).
pub fn segments(body: &Body) -> Vec<Segment> {
    let tris = body.def.tris.iter().map(|e| Segment {
        nodes: [e.nodes[0], e.nodes[1], e.nodes[2], e.nodes[2]],
        count: 3,
    });
    let quads = body.def.quads.iter().map(|e| Segment {
        nodes: e.nodes,
        count: 4,
    });
    tris.chain(quads).collect()
}

/// Closest point of a segment to a node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Distance node - closest point.
    pub dist: f64,
    /// Closest point, exactly sum_k weights[k] x_k.
    pub point: Vec3,
    /// Shape-function values of the segment's nodes at the closest point (sum 1).
    pub weights: [f64; 4],
    /// Unit normal of the (sub-)triangle that holds the closest point (used only when
    /// the node lies on the mid-surface and the direction to it is undefined).
    pub face_normal: Vec3,
    /// The (sub-)triangle that holds the closest point (0 for a triangle, k = 0..3 for
    /// the quad's (centroid, x_k, x_{k+1})) and the closest point's barycentric weights
    /// on it (corner order as listed).
    pub sub: u8,
    pub bary: [f64; 3],
}

/// Closest point on triangle abc to p as barycentric weights (Ericson, Real-Time
/// Collision Detection, 5.1.5): vertex, edge and interior regions.
pub fn triangle_weights(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> [f64; 3] {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    [1.0 - v - w, v, w]
}

fn unit_normal(a: &Vec3, b: &Vec3, c: &Vec3) -> Vec3 {
    let n = (b - a).cross(&(c - a));
    let l = n.norm();
    if l > 0.0 {
        n / l
    } else {
        Vec3::z()
    }
}

/// A segment's corner positions (a triangle's fourth repeats its third) and a quad's
/// centroid, gathered once for the many points the segment pass projects on it.
#[derive(Debug, Clone, Copy)]
pub struct Corners {
    pub xs: [Vec3; 4],
    /// The quad's centroid (unused for a triangle).
    pub centroid: Vec3,
    pub count: u8,
}

impl Corners {
    pub fn of(seg: &Segment, x: &[Vec3]) -> Self {
        let xs = seg.nodes.map(|n| x[n as usize]);
        let centroid = if seg.count == 3 {
            Vec3::zeros()
        } else {
            (xs[0] + xs[1] + xs[2] + xs[3]) * 0.25
        };
        Corners {
            xs,
            centroid,
            count: seg.count,
        }
    }
}

/// `Projection` without the face normal (the segment pass does not read it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    pub dist: f64,
    pub point: Vec3,
    pub weights: [f64; 4],
    pub sub: u8,
    pub bary: [f64; 3],
}

/// Closest point of a segment (corners `k`) to `p`: the bits of `project`. A quad's
/// sub-triangle whose squared distance exceeds the best's skips its square root (sqrt
/// is monotone, so it could not be strictly closer).
pub fn closest(p: &Vec3, k: &Corners) -> Closest {
    let xs = &k.xs;
    if k.count == 3 {
        let w = triangle_weights(p, &xs[0], &xs[1], &xs[2]);
        let point = xs[0] * w[0] + xs[1] * w[1] + xs[2] * w[2];
        return Closest {
            dist: (p - point).norm(),
            point,
            weights: [w[0], w[1], w[2], 0.0],
            sub: 0,
            bary: w,
        };
    }
    let c = k.centroid;
    let mut best = Closest {
        dist: f64::INFINITY,
        point: c,
        weights: [0.25; 4],
        sub: 0,
        bary: [1.0, 0.0, 0.0],
    };
    let mut best_sq = f64::INFINITY;
    for s in 0..4 {
        let (a, b) = (xs[s], xs[(s + 1) % 4]);
        // a sub-triangle whose box lies farther than the best so far (its squared gap
        // above best_sq by more than round-off) would be skipped below anyway: its
        // projection is not computed (the same answer, ties to the first included)
        if s > 0 {
            let bx = (c.inf(&a).inf(&b), c.sup(&a).sup(&b));
            if point_gap2(p, &bx) > best_sq * (1.0 + 1e-12) {
                continue;
            }
        }
        let w = triangle_weights(p, &c, &a, &b);
        let mut weights = [0.25 * w[0]; 4];
        weights[s] += w[1];
        weights[(s + 1) % 4] += w[2];
        let point =
            xs[0] * weights[0] + xs[1] * weights[1] + xs[2] * weights[2] + xs[3] * weights[3];
        let sq = (p - point).norm_squared();
        if s > 0 && sq > best_sq {
            continue;
        }
        let dist = sq.sqrt();
        // strict comparison: the first sub-triangle wins ties (deterministic)
        if s == 0 || dist < best.dist {
            best_sq = sq;
            best = Closest {
                dist,
                point,
                weights,
                sub: s as u8,
                bary: w,
            };
        }
    }
    best
}

/// Squared gap of a point and a box.
pub(crate) fn point_gap2(p: &Vec3, b: &(Vec3, Vec3)) -> f64 {
    ((b.0 - p).sup(&Vec3::zeros()) + (p - b.1).sup(&Vec3::zeros())).norm_squared()
}

/// Closest point of segment `seg` (positions `x`) to `p`.
pub fn project(p: &Vec3, seg: &Segment, x: &[Vec3]) -> Projection {
    let k = Corners::of(seg, x);
    let cl = closest(p, &k);
    let xs = &k.xs;
    let face_normal = if seg.count == 3 {
        unit_normal(&xs[0], &xs[1], &xs[2])
    } else {
        let s = cl.sub as usize;
        unit_normal(&k.centroid, &xs[s], &xs[(s + 1) % 4])
    };
    Projection {
        dist: cl.dist,
        point: cl.point,
        weights: cl.weights,
        face_normal,
        sub: cl.sub,
        bary: cl.bary,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(p: &Vec3, seg: &Segment, x: &[Vec3]) -> f64 {
        // dense sampling of the (sub-)triangles
        let n = 200;
        let xs = seg.nodes.map(|i| x[i as usize]);
        let tris: Vec<[Vec3; 3]> = if seg.count == 3 {
            vec![[xs[0], xs[1], xs[2]]]
        } else {
            let c = (xs[0] + xs[1] + xs[2] + xs[3]) * 0.25;
            (0..4).map(|k| [c, xs[k], xs[(k + 1) % 4]]).collect()
        };
        let mut best = f64::INFINITY;
        for t in &tris {
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let q = t[0] * (1.0 - u - v) + t[1] * u + t[2] * v;
                    best = best.min((p - q).norm());
                }
            }
        }
        best
    }

    #[test]
    fn projection_matches_dense_sampling_in_every_region() {
        let x = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.1),
            Vec3::new(1.1, 0.9, 0.0),
            Vec3::new(-0.1, 1.0, 0.05),
        ];
        let tri = Segment {
            nodes: [0, 1, 2, 2],
            count: 3,
        };
        let quad = Segment {
            nodes: [0, 1, 2, 3],
            count: 4,
        };
        // points over interior, beyond edges and beyond vertices, both sides
        for i in 0..7 {
            for j in 0..7 {
                for z in [-0.3, 0.02, 0.4] {
                    let p = Vec3::new(-0.6 + 0.35 * i as f64, -0.6 + 0.35 * j as f64, z);
                    for seg in [&tri, &quad] {
                        let pr = project(&p, seg, &x);
                        let b = brute(&p, seg, &x);
                        // sampling is 1/200 of the size: the exact value is a bit below
                        assert!(
                            pr.dist <= b + 1e-12 && pr.dist > b - 0.01,
                            "{p:?} {} {b}",
                            pr.dist
                        );
                        let s: f64 = pr.weights.iter().sum();
                        assert!((s - 1.0).abs() < 1e-14);
                        assert!(pr.weights.iter().all(|&w| w >= -1e-15));
                    }
                }
            }
        }
    }
}
