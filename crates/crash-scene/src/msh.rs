//! Gmsh `.msh` version 4.1 ASCII reader for surface meshes (3-node triangles and 4-node
//! quads). Points and lines are skipped; anything else is refused with its line.

use crash_core::{Mesh, Vec3};
use std::collections::HashMap;
use thiserror::Error;

/// A malformed mesh file, at a 1-based line of that file.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("line {line}: {message}")]
pub struct MshError {
    pub line: usize,
    pub message: String,
}

/// An imported surface: the mesh (only nodes used by its elements, in file order) and,
/// per element (triangles first, then quads, as in `Mesh`), its Gmsh tag and line.
#[derive(Debug, Clone, PartialEq)]
pub struct MshSurface {
    pub mesh: Mesh,
    pub element_tags: Vec<(u64, usize)>,
    pub node_tags: Vec<u64>,
}

fn err(line: usize, message: impl Into<String>) -> MshError {
    MshError {
        line,
        message: message.into(),
    }
}

/// Whitespace-separated tokens of one section, each with its line number.
struct Tokens<'a> {
    toks: Vec<(&'a str, usize)>,
    at: usize,
    section: &'a str,
    end_line: usize,
}

impl<'a> Tokens<'a> {
    fn next(&mut self, what: &str) -> Result<(&'a str, usize), MshError> {
        let t = self.toks.get(self.at).copied().ok_or_else(|| {
            err(
                self.end_line,
                format!("${} ends early: expected {what}", self.section),
            )
        })?;
        self.at += 1;
        Ok(t)
    }
    fn uint(&mut self, what: &str) -> Result<(u64, usize), MshError> {
        let (t, l) = self.next(what)?;
        t.parse::<u64>()
            .map(|v| (v, l))
            .map_err(|_| err(l, format!("expected {what} (an integer >= 0), found `{t}`")))
    }
    fn count(&mut self, what: &str) -> Result<usize, MshError> {
        let (v, l) = self.uint(what)?;
        // a count larger than the file could hold is corrupt, not a reason to allocate
        if v as usize > self.toks.len() {
            return Err(err(
                l,
                format!("{what} = {v} is more than this section holds"),
            ));
        }
        Ok(v as usize)
    }
    fn float(&mut self, what: &str) -> Result<f64, MshError> {
        let (t, l) = self.next(what)?;
        match t.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(err(
                l,
                format!("expected {what} (a finite number), found `{t}`"),
            )),
        }
    }
}

/// One `$Name ... $EndName` block: its name, first content line and lines.
struct Section<'a> {
    name: &'a str,
    lines: Vec<(usize, &'a str)>,
    end_line: usize,
}

fn sections(text: &str) -> Result<Vec<Section<'_>>, MshError> {
    let mut out = Vec::new();
    let mut cur: Option<Section<'_>> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if let Some(name) = l.strip_prefix("$End") {
            match cur.take() {
                Some(mut s) if s.name == name => {
                    s.end_line = line;
                    out.push(s);
                }
                Some(s) => return Err(err(line, format!("${} closed by `{l}`", s.name))),
                None => return Err(err(line, format!("`{l}` outside any section"))),
            }
        } else if let Some(name) = l.strip_prefix('$') {
            if let Some(s) = &cur {
                return Err(err(
                    line,
                    format!("`{l}` inside ${} (missing $End{})", s.name, s.name),
                ));
            }
            cur = Some(Section {
                name,
                lines: Vec::new(),
                end_line: line,
            });
        } else if let Some(s) = &mut cur {
            s.lines.push((line, l));
        } else if !l.is_empty() {
            return Err(err(line, format!("`{l}` outside any section")));
        }
    }
    if let Some(s) = cur {
        return Err(err(
            text.lines().count(),
            format!("${} is never closed", s.name),
        ));
    }
    Ok(out)
}

fn tokens<'a>(s: &Section<'a>) -> Tokens<'a> {
    Tokens {
        toks: s
            .lines
            .iter()
            .flat_map(|&(n, l)| l.split_whitespace().map(move |t| (t, n)))
            .collect(),
        at: 0,
        section: s.name,
        end_line: s.end_line,
    }
}

fn check_format(s: &Section<'_>) -> Result<(), MshError> {
    let mut t = tokens(s);
    let (version, line) = t.next("the format version")?;
    if version != "4.1" {
        return Err(err(
            line,
            format!("format version {version}: only 4.1 is read (Gmsh: File > Export, Version 4 ASCII, or -format msh41)"),
        ));
    }
    let (kind, line) = t.uint("the file type")?;
    if kind != 0 {
        return Err(err(line, "binary .msh files are not read: export as ASCII"));
    }
    Ok(())
}

/// The $Nodes section: tags and positions in file order, and tag -> index.
struct Nodes {
    tags: Vec<u64>,
    pos: Vec<Vec3>,
    index: HashMap<u64, usize>,
}

fn read_nodes(s: &Section<'_>) -> Result<Nodes, MshError> {
    let mut t = tokens(s);
    let blocks = t.count("numEntityBlocks")?;
    let total = t.count("numNodes")?;
    t.uint("minNodeTag")?;
    t.uint("maxNodeTag")?;
    let mut tags = Vec::with_capacity(total);
    let mut pos = Vec::with_capacity(total);
    let mut index = HashMap::with_capacity(total);
    for _ in 0..blocks {
        let (dim, _) = t.uint("entityDim")?;
        t.uint("entityTag")?;
        let (parametric, _) = t.uint("parametric")?;
        let n = t.count("numNodesInBlock")?;
        let extra = if parametric == 1 {
            dim.min(2) as usize
        } else {
            0
        };
        let first = tags.len();
        for _ in 0..n {
            let (tag, line) = t.uint("a node tag")?;
            if index.insert(tag, tags.len()).is_some() {
                return Err(err(line, format!("node tag {tag} is defined twice")));
            }
            tags.push(tag);
        }
        for _ in 0..n {
            let p = Vec3::new(t.float("x")?, t.float("y")?, t.float("z")?);
            for _ in 0..extra {
                t.float("a parametric coordinate")?;
            }
            pos.push(p);
        }
        debug_assert_eq!(pos.len() - first, n);
    }
    if tags.len() != total {
        return Err(err(
            s.lines.first().map_or(s.end_line, |l| l.0),
            format!("header says {total} nodes, the blocks hold {}", tags.len()),
        ));
    }
    Ok(Nodes { tags, pos, index })
}

/// Nodes per element for the element types that are skipped (points, lines).
fn skipped_nodes(kind: u64) -> Option<usize> {
    match kind {
        15 => Some(1),
        1 => Some(2),
        8 => Some(3),
        _ => None,
    }
}

/// Read a Gmsh 4.1 ASCII file into a surface mesh.
pub fn read_msh(text: &str) -> Result<MshSurface, MshError> {
    let secs = sections(text)?;
    let find = |name: &str| secs.iter().find(|s| s.name == name);
    let fmt =
        find("MeshFormat").ok_or_else(|| err(1, "no $MeshFormat section: not a Gmsh .msh file"))?;
    check_format(fmt)?;
    let nodes = find("Nodes").ok_or_else(|| err(fmt.end_line, "no $Nodes section"))?;
    let elems = find("Elements").ok_or_else(|| err(nodes.end_line, "no $Elements section"))?;
    let Nodes {
        tags: node_tags,
        pos,
        index,
    } = read_nodes(nodes)?;

    let mut t = tokens(elems);
    let blocks = t.count("numEntityBlocks")?;
    t.count("numElements")?;
    t.uint("minElementTag")?;
    t.uint("maxElementTag")?;
    let mut tris: Vec<([usize; 3], u64, usize)> = Vec::new();
    let mut quads: Vec<([usize; 4], u64, usize)> = Vec::new();
    for _ in 0..blocks {
        t.uint("entityDim")?;
        t.uint("entityTag")?;
        let (kind, kline) = t.uint("elementType")?;
        let n = t.count("numElementsInBlock")?;
        let per = match kind {
            2 => 3,
            3 => 4,
            9 | 10 | 16 | 20 | 21 | 22 | 23 | 24 | 25 => {
                return Err(err(kline, format!("element type {kind} is a second- or higher-order surface element: export first-order elements (Mesh.ElementOrder = 1)")))
            }
            4..=7 | 11..=14 | 17..=19 | 29..=33 => {
                return Err(err(kline, format!("element type {kind} is a volume element: crash bodies are shell surfaces (mesh the surfaces only, 2D)")))
            }
            k => match skipped_nodes(k) {
                Some(p) => p,
                None => return Err(err(kline, format!("element type {kind} is not supported: only 3-node triangles (2) and 4-node quads (3) are read"))),
            },
        };
        for _ in 0..n {
            let (tag, line) = t.uint("an element tag")?;
            let mut ids = [0usize; 4];
            for slot in ids.iter_mut().take(per.min(4)) {
                let (nt, l) = t.uint("a node tag")?;
                *slot = *index.get(&nt).ok_or_else(|| {
                    err(
                        l,
                        format!("element {tag} refers to node {nt}, which $Nodes does not define"),
                    )
                })?;
            }
            for _ in 4..per {
                t.uint("a node tag")?;
            }
            match kind {
                2 => tris.push(([ids[0], ids[1], ids[2]], tag, line)),
                3 => quads.push((ids, tag, line)),
                _ => {}
            }
        }
    }
    if tris.is_empty() && quads.is_empty() {
        return Err(err(
            elems.end_line,
            "no triangles or quads: the file holds no surface to build a shell from",
        ));
    }
    // keep only nodes that elements use (geometry points and volume nodes have no mass)
    let mut used = vec![false; pos.len()];
    for (e, _, _) in &tris {
        e.iter().for_each(|&n| used[n] = true);
    }
    for (e, _, _) in &quads {
        e.iter().for_each(|&n| used[n] = true);
    }
    let mut new_id = vec![u32::MAX; pos.len()];
    let mut mesh = Mesh::default();
    let mut kept_tags = Vec::new();
    for (i, &u) in used.iter().enumerate() {
        if u {
            new_id[i] = mesh.nodes.len() as u32;
            mesh.nodes.push(pos[i]);
            kept_tags.push(node_tags[i]);
        }
    }
    let mut element_tags = Vec::with_capacity(tris.len() + quads.len());
    for (e, tag, line) in &tris {
        mesh.tris.push(e.map(|n| new_id[n]));
        element_tags.push((*tag, *line));
    }
    for (e, tag, line) in &quads {
        mesh.quads.push(e.map(|n| new_id[n]));
        element_tags.push((*tag, *line));
    }
    Ok(MshSurface {
        mesh,
        element_tags,
        node_tags: kept_tags,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square: two triangles (tags 10, 11) and one quad (tag 12) to the right,
    /// a geometry point (node 100, unused) and a line element that must be skipped.
    pub const SMALL: &str = "$MeshFormat
4.1 0 8
$EndMeshFormat
$Entities
1 0 1 0
$EndEntities
$Nodes
3 7 1 100
0 1 0 1
100
5 5 5
2 1 0 4
1
2
3
4
0 0 0
1 0 0
1 1 0
0 1 0
2 2 1 2
5
6
2 0 0 0.5 0
2 1 0 0.5 1
$EndNodes
$Elements
3 4 10 13
1 1 1 1
13 1 2
2 1 2 2
10 1 2 3
11 1 3 4
2 2 3 1
12 2 5 6 3
$EndElements
";

    #[test]
    fn small_file_gives_two_triangles_one_quad_and_drops_unused_nodes() {
        let s = read_msh(SMALL).expect("valid");
        assert_eq!(s.mesh.tris.len(), 2);
        assert_eq!(s.mesh.quads.len(), 1);
        assert_eq!(
            s.mesh.nodes.len(),
            6,
            "node 100 is used by no surface element"
        );
        assert_eq!(s.node_tags, vec![1, 2, 3, 4, 5, 6]);
        assert_eq!(
            s.element_tags.iter().map(|e| e.0).collect::<Vec<_>>(),
            vec![10, 11, 12]
        );
        // element 12 is written on line 35
        assert_eq!(s.element_tags[2].1, 35);
        // parametric coordinates skipped: node 5 is at (2, 0, 0)
        assert_eq!(s.mesh.nodes[4], Vec3::new(2.0, 0.0, 0.0));
        assert!((s.mesh.area() - 2.0).abs() < 1e-15);
        s.mesh.validate("m").expect("valid mesh");
    }

    #[test]
    fn undefined_node_is_reported_on_its_line() {
        let bad = SMALL.replace("12 2 5 6 3", "12 2 5 6 99");
        let e = read_msh(&bad).expect_err("node 99 undefined");
        assert_eq!(e.line, 35);
        assert!(e.message.contains("node 99"), "{e}");
    }

    #[test]
    fn version_2_and_binary_files_are_refused_with_a_hint() {
        let e = read_msh(&SMALL.replace("4.1 0 8", "2.2 0 8")).expect_err("v2");
        assert_eq!(e.line, 2);
        assert!(e.message.contains("only 4.1"), "{e}");
        let e = read_msh(&SMALL.replace("4.1 0 8", "4.1 1 8")).expect_err("binary");
        assert!(e.message.contains("binary"), "{e}");
    }

    #[test]
    fn volume_elements_are_refused() {
        let bad = SMALL.replace("2 2 3 1\n12 2 5 6 3", "3 1 4 1\n12 1 2 3 5");
        let e = read_msh(&bad).expect_err("tet");
        assert_eq!(e.line, 34);
        assert!(e.message.contains("volume element"), "{e}");
    }

    #[test]
    fn truncated_section_and_bad_numbers_are_located() {
        let e = read_msh(&SMALL.replace("1 1 0\n", "1 x 0\n")).expect_err("x");
        assert_eq!(e.line, 19);
        assert!(e.message.contains("`x`"), "{e}");
        let e = read_msh(&SMALL.replace("$EndElements\n", "")).expect_err("unclosed");
        assert!(e.message.contains("never closed"), "{e}");
        let e = read_msh(&SMALL.replace("12 2 5 6 3\n", "12 2 5\n")).expect_err("short");
        assert!(e.message.contains("ends early"), "{e}");
    }
}
