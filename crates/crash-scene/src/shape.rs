//! A body's surface in its own frame: generated shapes (crash_core::shapes) or an
//! imported Gmsh surface, with every size and count checked.
//!
//! `plan` checks a body's shape and counts its nodes and elements without generating
//! anything (an imported file is read and parsed: its size is capped), so that the
//! scene's memory is estimated before the meshes are allocated; `Planned::generate`
//! then makes the mesh.

use crate::context::Ctx;
use crate::error::{ErrorKind, SceneError};
use crate::files;
use crate::memory::Counts;
use crate::msh::{read_msh, MshSurface};
use crate::schema::BodySpec;
use crash_core::hash::Fnv;
use crash_core::shapes::{self, ElementKind};
use crash_core::Mesh;
use std::collections::BTreeMap;
use std::path::Path;

/// Largest element count of one body: beyond it a typo (an extra zero) would exhaust
/// memory instead of producing an error.
pub const MAX_ELEMENTS: usize = 20_000_000;
/// Highest icosphere level (20 * 4^8 = 1.3 million triangles).
pub const MAX_LEVEL: i64 = 8;
/// Edge of the unit-circumradius icosahedron; a level-l icosphere's mean edge is
/// about R * this / 2^l.
const ICOSAHEDRON_EDGE: f64 = 1.051_462_224_238_267_2;

/// An imported mesh: where it came from, each element's tag and line there, and each
/// node's tag (in `Mesh` order).
#[derive(Debug, Clone, Default)]
pub struct MeshSource {
    pub display: String,
    pub element_tags: Vec<(u64, usize)>,
    pub node_tags: Vec<u64>,
    /// Elements written in other files than `display` (a keyword deck and its
    /// includes): the files, and per element the index of its file. The lines of
    /// `element_tags` are then lines of those files.
    pub written: Option<(Vec<String>, Vec<u32>)>,
}

impl MeshSource {
    /// `file:line` where element `e` (Mesh order) is written, and its tag.
    pub fn element_origin(&self, e: usize) -> Option<(String, usize, u64)> {
        let &(tag, line) = self.element_tags.get(e)?;
        let file = match &self.written {
            Some((files, of)) => files.get(*of.get(e)? as usize)?.clone(),
            None => self.display.clone(),
        };
        Some((file, line, tag))
    }
}

/// A mesh file given in memory instead of on disk (the meshes of a converted keyword
/// deck), under the name the scene's `mesh.file` uses. Its bytes for the scene hash
/// are those `crash convert` writes (`msh_write::write`).
#[derive(Debug, Clone)]
pub struct MeshInput {
    pub surface: MshSurface,
    /// See `MeshSource::written`.
    pub written: Option<(Vec<String>, Vec<u32>)>,
}

/// Mesh files given in memory, by name.
pub type MeshInputs = BTreeMap<String, MeshInput>;

/// A body's surface before placement.
#[derive(Debug, Clone)]
pub struct Shape {
    pub mesh: Mesh,
    /// Key path of the shape table, e.g. `bodies[0].plate`.
    pub key: String,
    /// Short description for summaries, e.g. `plate 0.4 x 0.4 m, 40 x 40 quad`.
    pub describe: String,
    pub source: Option<MeshSource>,
}

fn positive(ctx: &Ctx, key: &str, v: f64, unit: &str) -> Result<f64, SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(ctx.invalid(key, format!("must be finite and > 0 ({unit})")))
    }
}

fn count(ctx: &Ctx, key: &str, v: i64, min: i64) -> Result<usize, SceneError> {
    if v >= min {
        Ok(v as usize)
    } else {
        Err(ctx.invalid(key, format!("must be an integer >= {min}")))
    }
}

/// Cells needed to cover `length` with cells no longer than `size`.
fn cells_for(length: f64, size: f64, min: usize) -> usize {
    ((length / size - 1e-9).ceil().max(min as f64)).min(1e12) as usize
}

fn element_kind(
    ctx: &Ctx,
    key: &str,
    v: &Option<String>,
) -> Result<Option<ElementKind>, SceneError> {
    match v.as_deref() {
        None => Ok(None),
        Some("tri") => Ok(Some(ElementKind::Tri)),
        Some("quad") => Ok(Some(ElementKind::Quad)),
        Some(_) => Err(ctx.invalid(key, "must be \"tri\" or \"quad\"")),
    }
}

fn cap(ctx: &Ctx, key: &str, elements: usize) -> Result<(), SceneError> {
    // (per body; the whole scene's memory is checked against the machine in build)
    if elements > MAX_ELEMENTS {
        return Err(ctx.invalid(
            key,
            format!("gives {elements} elements, more than the {MAX_ELEMENTS} a body may have"),
        ));
    }
    Ok(())
}

fn kind_name(k: ElementKind) -> &'static str {
    match k {
        ElementKind::Tri => "tri",
        ElementKind::Quad => "quad",
    }
}

/// Exactly one of `cells` / `element_size` must be given.
fn one_of<'a, C>(
    ctx: &Ctx,
    key: &str,
    cells: &'a Option<C>,
    size: Option<f64>,
    cells_name: &str,
) -> Result<Result<&'a C, f64>, SceneError> {
    match (cells, size) {
        (Some(c), None) => Ok(Ok(c)),
        (None, Some(h)) => Ok(Err(positive(ctx, &format!("{key}.element_size"), h, "m")?)),
        (Some(_), Some(_)) => Err(ctx.invalid(
            &format!("{key}.element_size"),
            format!("give either {cells_name} or element_size, not both"),
        )),
        (None, None) => Err(ctx.missing(
            &format!("{key}.{cells_name}"),
            format!("give {cells_name} or element_size (m) to set the mesh density"),
        )),
    }
}

/// What `generate` will make.
#[derive(Debug, Clone)]
enum Gen {
    Plate(f64, f64, usize, usize, ElementKind),
    Sphere(f64, u32),
    Cubed(f64, usize, ElementKind),
    Cylinder(f64, f64, usize, usize, ElementKind),
    Cuboid([f64; 3], usize, ElementKind),
    Loaded(Mesh),
}

/// A checked shape whose mesh is not generated yet.
#[derive(Debug, Clone)]
pub struct Planned {
    pub key: String,
    pub describe: String,
    pub counts: Counts,
    pub source: Option<MeshSource>,
    gen: Gen,
}

impl Planned {
    pub fn generate(self) -> Shape {
        let mesh = match self.gen {
            Gen::Plate(lx, ly, nx, ny, k) => shapes::plate(lx, ly, nx, ny, k),
            Gen::Sphere(r, level) => shapes::icosphere(r, level),
            Gen::Cubed(r, n, k) => shapes::cubed_sphere(r, n, k),
            Gen::Cylinder(r, len, na, nl, k) => shapes::cylinder(r, len, na, nl, k),
            Gen::Cuboid(l, n, k) => shapes::cuboid(l[0], l[1], l[2], n, k),
            Gen::Loaded(m) => m,
        };
        Shape {
            mesh,
            key: self.key,
            describe: self.describe,
            source: self.source,
        }
    }
}

fn counts(nodes: usize, elements: usize, k: ElementKind) -> Counts {
    match k {
        ElementKind::Tri => Counts {
            nodes,
            tris: elements,
            ..Counts::default()
        },
        ElementKind::Quad => Counts {
            nodes,
            quads: elements,
            ..Counts::default()
        },
    }
}

/// Check the shape of body `i` and count its mesh; imported files (read from `dir`, or
/// taken from `inputs`) are fed to `hash`.
pub fn plan(
    ctx: &Ctx,
    dir: &Path,
    i: usize,
    b: &BodySpec,
    hash: &mut Fnv,
    inputs: &MeshInputs,
) -> Result<Planned, SceneError> {
    let base = format!("bodies[{i}]");
    let given: Vec<&str> = [
        ("plate", b.plate.is_some()),
        ("sphere", b.sphere.is_some()),
        ("cylinder", b.cylinder.is_some()),
        ("box", b.cuboid.is_some()),
        ("mesh", b.mesh.is_some()),
    ]
    .iter()
    .filter(|s| s.1)
    .map(|s| s.0)
    .collect();
    if given.len() > 1 {
        return Err(ctx.key_error(
            ErrorKind::Invalid,
            &format!("{base}.{}", given[1]),
            format!(
                "body \"{}\" has two shapes ({} and {}): give exactly one",
                b.name, given[0], given[1]
            ),
        ));
    }
    let ekey = format!("{base}.element");
    let kind = element_kind(ctx, &ekey, &b.element)?;
    let mut source = None;
    let (key, gen, describe, counts) = if let Some(p) = &b.plate {
        let key = format!("{base}.plate");
        let lx = positive(ctx, &format!("{key}.size[0]"), p.size[0], "m")?;
        let ly = positive(ctx, &format!("{key}.size[1]"), p.size[1], "m")?;
        let (nx, ny) = match one_of(ctx, &key, &p.cells, p.element_size, "cells")? {
            Ok(c) => (
                count(ctx, &format!("{key}.cells[0]"), c[0], 1)?,
                count(ctx, &format!("{key}.cells[1]"), c[1], 1)?,
            ),
            Err(h) => (cells_for(lx, h, 1), cells_for(ly, h, 1)),
        };
        let k = kind.unwrap_or(ElementKind::Quad);
        let per = if k == ElementKind::Tri { 2 } else { 1 };
        let elements = nx.saturating_mul(ny).saturating_mul(per);
        cap(ctx, &key, elements)?;
        let d = format!("plate {lx} x {ly} m, {nx} x {ny} {}", kind_name(k));
        let nodes = (nx + 1) * (ny + 1);
        (
            key,
            Gen::Plate(lx, ly, nx, ny, k),
            d,
            counts(nodes, elements, k),
        )
    } else if let Some(s) = &b.sphere {
        let key = format!("{base}.sphere");
        let r = positive(ctx, &format!("{key}.radius"), s.radius, "m")?;
        if let Some(n) = s.cubed {
            if s.level.is_some() || s.element_size.is_some() {
                return Err(ctx.invalid(
                    &format!("{key}.cubed"),
                    "give either cubed (a cubed sphere) or level/element_size (an icosphere), not both",
                ));
            }
            let n = count(ctx, &format!("{key}.cubed"), n, 1)?;
            let k = kind.unwrap_or(ElementKind::Quad);
            let per = if k == ElementKind::Tri { 2 } else { 1 };
            let elements = n.saturating_mul(n).saturating_mul(6 * per);
            cap(ctx, &key, elements)?;
            let d = format!("cubed sphere R {r} m, 6 x {n} x {n} {}", kind_name(k));
            let c = counts(6 * n * n + 2, elements, k);
            (key, Gen::Cubed(r, n, k), d, c)
        } else {
            if kind == Some(ElementKind::Quad) {
                return Err(ctx.invalid(
                    &ekey,
                    "an icosphere is meshed with triangles: use \"tri\", omit element, or give cubed = N for a cubed sphere of quads",
                ));
            }
            let level = match one_of(ctx, &key, &s.level, s.element_size, "level")? {
                Ok(&l) => {
                    if !(0..=MAX_LEVEL).contains(&l) {
                        return Err(ctx.invalid(
                            &format!("{key}.level"),
                            format!(
                                "must be an integer in [0, {MAX_LEVEL}] (20 * 4^level triangles)"
                            ),
                        ));
                    }
                    l as u32
                }
                Err(h) => {
                    let l = (0..=MAX_LEVEL as u32)
                        .find(|&l| r * ICOSAHEDRON_EDGE / f64::from(1u32 << l) <= h);
                    l.ok_or_else(|| {
                    ctx.invalid(
                        &format!("{key}.element_size"),
                        format!("is too small for radius {r} m: level {MAX_LEVEL} (edge {:.3e} m) is the finest", r * ICOSAHEDRON_EDGE / f64::from(1u32 << MAX_LEVEL)),
                    )
                })?
                }
            };
            let tris = 20usize << (2 * level);
            let d = format!("sphere R {r} m, level {level} ({tris} tri)");
            // Euler: V = F / 2 + 2 for a closed triangulated sphere
            let c = counts(tris / 2 + 2, tris, ElementKind::Tri);
            (key, Gen::Sphere(r, level), d, c)
        }
    } else if let Some(c) = &b.cylinder {
        let key = format!("{base}.cylinder");
        let r = positive(ctx, &format!("{key}.radius"), c.radius, "m")?;
        let len = positive(ctx, &format!("{key}.length"), c.length, "m")?;
        let (na, nl) = match one_of(ctx, &key, &c.cells, c.element_size, "cells")? {
            Ok(n) => (
                count(ctx, &format!("{key}.cells[0]"), n[0], 3)?,
                count(ctx, &format!("{key}.cells[1]"), n[1], 1)?,
            ),
            Err(h) => (
                cells_for(std::f64::consts::TAU * r, h, 3),
                cells_for(len, h, 1),
            ),
        };
        let k = kind.unwrap_or(ElementKind::Quad);
        let per = if k == ElementKind::Tri { 2 } else { 1 };
        let elements = na.saturating_mul(nl).saturating_mul(per);
        cap(ctx, &key, elements)?;
        let d = format!("tube R {r} m, length {len} m, {na} x {nl} {}", kind_name(k));
        let c = counts(na * (nl + 1), elements, k);
        (key, Gen::Cylinder(r, len, na, nl, k), d, c)
    } else if let Some(x) = &b.cuboid {
        let key = format!("{base}.box");
        let mut l = [0.0; 3];
        for (d, v) in l.iter_mut().enumerate() {
            *v = positive(ctx, &format!("{key}.size[{d}]"), x.size[d], "m")?;
        }
        let longest = l[0].max(l[1]).max(l[2]);
        let n = match one_of(ctx, &key, &x.cells, x.element_size, "cells")? {
            Ok(&n) => count(ctx, &format!("{key}.cells"), n, 1)?,
            Err(h) => cells_for(longest, h, 1),
        };
        let k = kind.unwrap_or(ElementKind::Quad);
        let per = if k == ElementKind::Tri { 2 } else { 1 };
        let faces = l
            .iter()
            .map(|&s| ((s / longest * n as f64).round()).max(1.0))
            .collect::<Vec<_>>();
        let cells = 2.0 * (faces[0] * faces[1] + faces[1] * faces[2] + faces[2] * faces[0]);
        let total = cells * per as f64;
        cap(ctx, &key, total.min(1e15) as usize)?;
        // Euler: V = F + 2 for a closed quad surface (triangles split the quads)
        let c = counts(cells as usize + 2, total as usize, k);
        let d = format!(
            "box {} x {} x {} m, {n} cells on the longest side, {}",
            l[0],
            l[1],
            l[2],
            kind_name(k)
        );
        (key, Gen::Cuboid(l, n, k), d, c)
    } else if let Some(m) = &b.mesh {
        let key = format!("{base}.mesh");
        let fkey = format!("{key}.file");
        let scale = positive(ctx, &format!("{key}.scale"), m.scale.unwrap_or(1.0), "-")?;
        let (surf, written) = match inputs.get(&m.file) {
            Some(input) => {
                crate::msh_write::write(&input.surface, &mut FnvWriter(hash));
                (input.surface.clone(), input.written.clone())
            }
            None => (read_file(ctx, dir, &fkey, &m.file, hash)?, None),
        };
        let node_tags = surf.node_tags;
        let mut written = written;
        let mut mesh = surf.mesh;
        let mut tags = surf.element_tags;
        for p in &mut mesh.nodes {
            *p *= scale;
        }
        if kind == Some(ElementKind::Tri) && !mesh.quads.is_empty() {
            // split every quad along its 0-2 diagonal; both halves keep the quad's tag
            let nt = mesh.tris.len();
            let quad_tags = tags.split_off(nt);
            let quad_files = written.as_mut().map(|w| w.1.split_off(nt));
            for (j, (q, t)) in mesh.quads.drain(..).zip(quad_tags).enumerate() {
                mesh.tris.push([q[0], q[1], q[2]]);
                mesh.tris.push([q[0], q[2], q[3]]);
                tags.push(t);
                tags.push(t);
                if let (Some(w), Some(f)) = (written.as_mut(), quad_files.as_ref()) {
                    w.1.push(f[j]);
                    w.1.push(f[j]);
                }
            }
        } else if kind == Some(ElementKind::Quad) && !mesh.tris.is_empty() {
            return Err(ctx.invalid(&ekey, format!("{} holds triangles, which cannot become quads: omit element (keep the file's elements) or use \"tri\"", m.file)));
        }
        cap(ctx, &key, mesh.element_count())?;
        let d = format!(
            "mesh {} ({} tri, {} quad)",
            m.file,
            mesh.tris.len(),
            mesh.quads.len()
        );
        source = Some(MeshSource {
            display: m.file.clone(),
            element_tags: tags,
            node_tags,
            written,
        });
        let c = Counts {
            nodes: mesh.nodes.len(),
            tris: mesh.tris.len(),
            quads: mesh.quads.len(),
            ..Counts::default()
        };
        (key, Gen::Loaded(mesh), d, c)
    } else {
        return Err(ctx.missing(
            &format!("{base}.shape"),
            format!("body \"{}\" has no shape: add exactly one of the tables plate, sphere, cylinder, box, mesh", b.name),
        ));
    };
    Ok(Planned {
        key,
        describe,
        counts,
        source,
        gen,
    })
}

/// Feeds the bytes a writer produces to the scene hash (the in-memory meshes of a deck
/// hash as the files `crash convert` writes).
struct FnvWriter<'a>(&'a mut Fnv);

impl std::fmt::Write for FnvWriter<'_> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.bytes(s.as_bytes());
        Ok(())
    }
}

/// Bytes that reading a Gmsh file of n bytes may take at most, per byte (text, tokens
/// with their lines, nodes): files whose reading would not fit in the available memory
/// are refused before they are read.
pub const MSH_READ_FACTOR: u64 = 6;

/// Read and parse a Gmsh file named at `fkey`, its size capped.
fn read_file(
    ctx: &Ctx,
    dir: &Path,
    fkey: &str,
    name: &str,
    hash: &mut Fnv,
) -> Result<MshSurface, SceneError> {
    let path = dir.join(name);
    let bytes = files::read(&path, files::MAX_FILE_BYTES).map_err(|p| {
        let kind = match p {
            files::FileProblem::TooLarge(_) => ErrorKind::TooLarge,
            _ => ErrorKind::Read,
        };
        ctx.value_error(kind, fkey, p.describe(&path, files::MAX_FILE_BYTES))
    })?;
    hash.bytes(&bytes);
    let text = String::from_utf8(bytes).map_err(|_| {
        ctx.value_error(
            ErrorKind::MeshFile,
            fkey,
            format!("{name}: not a text file (binary .msh files are not read: export as ASCII)"),
        )
    })?;
    read_msh(&text).map_err(|e| {
        ctx.value_error(
            ErrorKind::MeshFile,
            fkey,
            format!("{name}:{}: {}", e.line, e.message),
        )
    })
}
