//! Mesh generators for the standard shapes (plates, spheres, cylinders, boxes).
//! Each returns a `Mesh` centred at the origin; scenes place and rotate them.

use crate::mesh::Mesh;
use crate::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Element family of a generated surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ElementKind {
    Tri,
    Quad,
}

/// Rectangle lx x ly in the xy plane, nx x ny cells, centred at the origin. Triangles
/// split each cell along alternating diagonals (no preferred direction).
pub fn plate(lx: f64, ly: f64, nx: usize, ny: usize, kind: ElementKind) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=ny {
        for i in 0..=nx {
            m.nodes.push(Vec3::new(
                lx * (i as f64 / nx as f64 - 0.5),
                ly * (j as f64 / ny as f64 - 0.5),
                0.0,
            ));
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            match kind {
                ElementKind::Quad => m.quads.push([a, b, c, d]),
                ElementKind::Tri => {
                    if (i + j) % 2 == 0 {
                        m.tris.push([a, b, c]);
                        m.tris.push([a, c, d]);
                    } else {
                        m.tris.push([a, b, d]);
                        m.tris.push([b, c, d]);
                    }
                }
            }
        }
    }
    m
}

/// The element benchmarks' body (shell_step, the plate_step example): a 1 m x 1 m steel
/// plate, 2 mm thick, of nx x ny cells, with a wavy transverse velocity
/// 0.1 sin(7x) cos(5y) m/s so that every element deforms.
pub fn bench_plate(nx: usize, ny: usize, kind: ElementKind) -> crate::Body {
    let section = crate::Section::new(crate::Material::steel(), 0.002);
    let stab = crate::Stabilization::default();
    let mut b = crate::Body::new(0, "plate", &plate(1.0, 1.0, nx, ny, kind), section, stab)
        .expect("a valid plate");
    for i in 0..b.state.x.len() {
        let p = b.def.x0[i];
        b.state.v[i] = Vec3::new(0.0, 0.0, 0.1 * (7.0 * p.x).sin() * (5.0 * p.y).cos());
    }
    b
}

/// Sphere of the given radius: a subdivided icosahedron (near-uniform triangles,
/// 20 * 4^level elements), outward normals. The triangles come out in subdivision
/// order (each base face's children together, recursively), and the nodes are numbered
/// in the order the triangles first use them, so that a run of elements and the run of
/// nodes they touch cover one patch of the sphere: threads that take halves of both
/// then share only the patches' rim (docs/performance.md, "Locality").
pub fn icosphere(radius: f64, level: u32) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut nodes: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(tris.len() * 4);
        let mut midpoint = |a: u32, b: u32, nodes: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                nodes.push(((nodes[a as usize] + nodes[b as usize]) * 0.5).normalize());
                (nodes.len() - 1) as u32
            })
        };
        for &[a, b, c] in &tris {
            let ab = midpoint(a, b, &mut nodes);
            let bc = midpoint(b, c, &mut nodes);
            let ca = midpoint(c, a, &mut nodes);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let mut m = Mesh {
        nodes: nodes.into_iter().map(|p| p * radius).collect(),
        tris,
        quads: Vec::new(),
    };
    m.number_nodes_by_first_use();
    m
}

/// Open cylinder (tube) along z: n_around x n_along cells, centred at the origin.
pub fn cylinder(
    radius: f64,
    length: f64,
    n_around: usize,
    n_along: usize,
    kind: ElementKind,
) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=n_along {
        let z = length * (j as f64 / n_along as f64 - 0.5);
        for i in 0..n_around {
            let a = std::f64::consts::TAU * i as f64 / n_around as f64;
            m.nodes
                .push(Vec3::new(radius * a.cos(), radius * a.sin(), z));
        }
    }
    let id = |i: usize, j: usize| (j * n_around + i % n_around) as u32;
    for j in 0..n_along {
        for i in 0..n_around {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            match kind {
                ElementKind::Quad => m.quads.push([a, b, c, d]),
                ElementKind::Tri => {
                    m.tris.push([a, b, c]);
                    m.tris.push([a, c, d]);
                }
            }
        }
    }
    m
}

/// Closed box surface lx x ly x lz with about `n` cells along the longest side,
/// outward normals, centred at the origin.
pub fn cuboid(lx: f64, ly: f64, lz: f64, n: usize, kind: ElementKind) -> Mesh {
    let longest = lx.max(ly).max(lz);
    let cells = |l: f64| ((l / longest * n as f64).round() as usize).max(1);
    let (nx, ny, nz) = (cells(lx), cells(ly), cells(lz));
    let mut index: HashMap<(i64, i64, i64), u32> = HashMap::new();
    let mut m = Mesh::default();
    // integer lattice keys make shared edges between faces share nodes exactly
    let mut node = |i: usize, j: usize, k: usize, m: &mut Mesh| -> u32 {
        *index
            .entry((i as i64, j as i64, k as i64))
            .or_insert_with(|| {
                m.nodes.push(Vec3::new(
                    lx * (i as f64 / nx as f64 - 0.5),
                    ly * (j as f64 / ny as f64 - 0.5),
                    lz * (k as f64 / nz as f64 - 0.5),
                ));
                (m.nodes.len() - 1) as u32
            })
    };
    // each face: (fixed axis, fixed value index, u axis count, v axis count, outward sign)
    let dims = [nx, ny, nz];
    for axis in 0..3 {
        let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0usize, 1] {
            let fixed = side * dims[axis];
            for a in 0..dims[ua] {
                for b in 0..dims[va] {
                    let mut corner = |da: usize, db: usize, m: &mut Mesh| {
                        let mut ijk = [0usize; 3];
                        ijk[axis] = fixed;
                        ijk[ua] = a + da;
                        ijk[va] = b + db;
                        node(ijk[0], ijk[1], ijk[2], m)
                    };
                    let mut q = [
                        corner(0, 0, &mut m),
                        corner(1, 0, &mut m),
                        corner(1, 1, &mut m),
                        corner(0, 1, &mut m),
                    ];
                    if side == 0 {
                        q.reverse();
                    }
                    match kind {
                        ElementKind::Quad => m.quads.push(q),
                        ElementKind::Tri => {
                            m.tris.push([q[0], q[1], q[2]]);
                            m.tris.push([q[0], q[2], q[3]]);
                        }
                    }
                }
            }
        }
    }
    m
}

/// Equiangular cubed sphere of radius r: each face of a cube carries n x n cells whose
/// edges subtend equal angles (a face coordinate a in [-1, 1] maps to tan(pi a / 4)),
/// projected onto the sphere; 6 n^2 quads (or 12 n^2 triangles, each quad split), 6 n^2
/// + 2 nodes, outward normals.
pub fn cubed_sphere(r: f64, n: usize, kind: ElementKind) -> Mesh {
    let mut m = cuboid(2.0, 2.0, 2.0, n, kind);
    for p in &mut m.nodes {
        let q = p.map(|a| (std::f64::consts::FRAC_PI_4 * a).tan());
        *p = q * (r / q.norm());
    }
    m
}

/// Spherical cap of radius r around the south pole (a mesh vertex sits exactly at
/// (0, 0, -r)): the triangles of an icosphere of the given level whose nodes all lie
/// below z = -r cos(theta). Returns the mesh and its rim nodes (boundary edges).
pub fn spherical_cap(r: f64, level: u32, theta: f64) -> (Mesh, Vec<usize>) {
    let mut m = icosphere(1.0, level);
    let a = m.nodes[0];
    let rot = nalgebra::Rotation3::rotation_between(&a, &Vec3::new(0.0, 0.0, -1.0))
        .unwrap_or_else(nalgebra::Rotation3::identity);
    for p in &mut m.nodes {
        *p = rot * *p;
    }
    let zcut = -theta.cos() + 1e-9;
    m.tris
        .retain(|t| t.iter().all(|&n| m.nodes[n as usize].z <= zcut));
    let used = m.number_nodes_by_first_use();
    m.nodes.truncate(used);
    for p in &mut m.nodes {
        *p *= r;
    }
    let mut edges = std::collections::BTreeMap::new();
    for t in &m.tris {
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            *edges.entry((a, b)).or_insert(0) += 1;
        }
    }
    let mut rim: Vec<usize> = edges
        .iter()
        .filter(|(_, &c)| c == 1)
        .flat_map(|(&(a, b), _)| [a as usize, b as usize])
        .collect();
    rim.sort_unstable();
    rim.dedup();
    (m, rim)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plate_area_is_exact_for_both_kinds() {
        for kind in [ElementKind::Tri, ElementKind::Quad] {
            let m = plate(2.0, 0.5, 8, 3, kind);
            assert!((m.area() - 1.0).abs() < 1e-12);
            m.validate("p").expect("valid");
        }
    }

    #[test]
    fn icosphere_threads_halves_share_only_a_rim() {
        // the elements of each half (as two threads take them) read nodes of the other
        // half only along the rim between the halves (performance.md, session 19):
        // level 5, 1 000 of 20 480 elements; numbered level by level, 11 305
        let m = icosphere(1.0, 5);
        let (ne, nn) = (m.tris.len(), m.nodes.len() as u32);
        let crossing = m
            .tris
            .iter()
            .enumerate()
            .filter(|(e, t)| t.iter().any(|&n| (n < nn / 2) != (*e < ne / 2)))
            .count();
        println!("{crossing} of {ne} elements read a node of the other half");
        assert!(crossing * 10 < ne, "{crossing} of {ne}");
    }

    #[test]
    fn icosphere_area_converges_to_sphere_area() {
        let m = icosphere(1.0, 4);
        let exact = 4.0 * std::f64::consts::PI;
        assert_eq!(m.tris.len(), 20 * 256);
        assert!((m.area() - exact).abs() / exact < 0.01);
        m.validate("s").expect("valid");
    }

    /// Nodes on the sphere, Euler's count, the area within the faceting error (second
    /// order in the cell size: n = 40 faceting is ~1e-3 below 4 pi R^2), outward faces.
    #[test]
    fn cubed_sphere_nodes_lie_on_the_sphere_and_its_area_converges() {
        let exact = 4.0 * std::f64::consts::PI * 0.01;
        for kind in [ElementKind::Quad, ElementKind::Tri] {
            let m = cubed_sphere(0.1, 40, kind);
            assert_eq!(m.nodes.len(), 6 * 40 * 40 + 2);
            let per = if kind == ElementKind::Tri { 2 } else { 1 };
            assert_eq!(m.quads.len() + m.tris.len(), 6 * 1600 * per);
            for p in &m.nodes {
                assert!((p.norm() - 0.1).abs() < 1e-15, "{p:?}");
            }
            let err = (exact - m.area()) / exact;
            assert!(err > 0.0 && err < 2e-3, "{kind:?}: area error {err}");
            for q in &m.quads {
                let c = (m.nodes[q[0] as usize] + m.nodes[q[2] as usize]) * 0.5;
                let n = (m.nodes[q[2] as usize] - m.nodes[q[0] as usize])
                    .cross(&(m.nodes[q[3] as usize] - m.nodes[q[1] as usize]));
                assert!(n.dot(&c) > 0.0);
            }
            m.validate("s").expect("valid");
        }
    }

    #[test]
    fn closed_surfaces_have_outward_normals() {
        for m in [
            icosphere(1.0, 2),
            cuboid(1.0, 2.0, 3.0, 6, ElementKind::Quad),
        ] {
            // divergence theorem: volume = sum over faces of (x . n) A / 3 > 0
            let mut vol = 0.0;
            for t in &m.tris {
                let p = t.map(|n| m.nodes[n as usize]);
                vol += p[0].dot(&(p[1] - p[0]).cross(&(p[2] - p[0]))) / 6.0;
            }
            for q in &m.quads {
                let p = q.map(|n| m.nodes[n as usize]);
                vol += p[0].dot(&(p[1] - p[0]).cross(&(p[2] - p[0]))) / 6.0;
                vol += p[0].dot(&(p[2] - p[0]).cross(&(p[3] - p[0]))) / 6.0;
            }
            assert!(vol > 0.0);
        }
        let b = cuboid(1.0, 2.0, 3.0, 6, ElementKind::Quad);
        let vol_expected = 6.0;
        let mut vol = 0.0;
        for q in &b.quads {
            let p = q.map(|n| b.nodes[n as usize]);
            vol += p[0].dot(&(p[1] - p[0]).cross(&(p[2] - p[0]))) / 6.0;
            vol += p[0].dot(&(p[2] - p[0]).cross(&(p[3] - p[0]))) / 6.0;
        }
        assert!((vol - vol_expected).abs() < 1e-9, "{vol}");
    }
}
