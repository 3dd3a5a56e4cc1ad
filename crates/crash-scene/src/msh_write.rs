//! Gmsh `.msh` 4.1 ASCII writer: the inverse of `msh::read_msh` for the surfaces it
//! returns. Reading the text back gives the same surface, bit for bit (numbers are
//! written in Rust's shortest round-trip form; nodes, triangles and quads keep their
//! order and tags). `crash convert` writes a keyword deck's parts with it.

use crate::msh::MshSurface;
use std::fmt::Write;

/// Write `s` to `out` (a `String`, or a hasher).
pub fn write(s: &MshSurface, out: &mut impl Write) {
    // writing to a String or to the hash adaptor cannot fail
    let _ = write_inner(s, out);
}

fn write_inner(s: &MshSurface, out: &mut impl Write) -> std::fmt::Result {
    let m = &s.mesh;
    out.write_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")?;
    let nn = m.nodes.len();
    let tag = |i: usize| s.node_tags.get(i).copied().unwrap_or(i as u64 + 1);
    let (lo, hi) = (0..nn)
        .map(tag)
        .fold((u64::MAX, 0), |(a, b), t| (a.min(t), b.max(t)));
    let lo = if nn == 0 { 0 } else { lo };
    writeln!(out, "$Nodes\n1 {nn} {lo} {hi}\n2 1 0 {nn}")?;
    for i in 0..nn {
        writeln!(out, "{}", tag(i))?;
    }
    for p in &m.nodes {
        writeln!(out, "{:?} {:?} {:?}", p.x, p.y, p.z)?;
    }
    out.write_str("$EndNodes\n")?;
    let nt = m.tris.len();
    let ne = nt + m.quads.len();
    let etag = |e: usize| s.element_tags.get(e).map_or(e as u64 + 1, |t| t.0);
    let (elo, ehi) = (0..ne)
        .map(etag)
        .fold((u64::MAX, 0), |(a, b), t| (a.min(t), b.max(t)));
    let elo = if ne == 0 { 0 } else { elo };
    let blocks = usize::from(nt > 0) + usize::from(!m.quads.is_empty());
    writeln!(out, "$Elements\n{blocks} {ne} {elo} {ehi}")?;
    if nt > 0 {
        writeln!(out, "2 1 2 {nt}")?;
        for (e, t) in m.tris.iter().enumerate() {
            let n = t.map(|k| tag(k as usize));
            writeln!(out, "{} {} {} {}", etag(e), n[0], n[1], n[2])?;
        }
    }
    if !m.quads.is_empty() {
        writeln!(out, "2 1 3 {}", m.quads.len())?;
        for (e, q) in m.quads.iter().enumerate() {
            let n = q.map(|k| tag(k as usize));
            writeln!(out, "{} {} {} {} {}", etag(nt + e), n[0], n[1], n[2], n[3])?;
        }
    }
    out.write_str("$EndElements\n")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msh::read_msh;
    use crash_core::{Mesh, Vec3};

    #[test]
    fn written_surface_reads_back_identically() {
        let mesh = Mesh {
            nodes: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(0.1, -0.0, 1e-20),
                Vec3::new(1.0 / 3.0, 2.5e17, -7.25),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(2.0, 0.5, 0.0),
            ],
            tris: vec![[0, 1, 2]],
            quads: vec![[1, 4, 2, 3]],
        };
        let s = MshSurface {
            mesh,
            element_tags: vec![(70, 0), (9, 0)],
            node_tags: vec![11, 12, 13, 5, 100],
        };
        let mut text = String::new();
        write(&s, &mut text);
        let back = read_msh(&text).expect("reads back");
        assert_eq!(back.mesh, s.mesh);
        assert_eq!(back.node_tags, s.node_tags);
        let tags: Vec<u64> = back.element_tags.iter().map(|t| t.0).collect();
        assert_eq!(tags, vec![70, 9]);
        assert!(back.mesh.nodes[1].y.is_sign_negative());
    }
}
