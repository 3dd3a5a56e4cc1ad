//! What one frame's .vtu (VTK XML UnstructuredGrid) holds: the list of named arrays,
//! their types and how they are stored. Triangles stay VTK_TRIANGLE and quads VTK_QUAD;
//! all bodies of a frame form one `Piece` (points body after body, in id order).
//!
//! The arrays are stored as VTK "appended raw" data after the XML, zlib-compressed in
//! VTK's block format by default (`vtu_encode`); floats are Float64 (every bit kept) or
//! Float32 (`Precision::F32`, half the bytes), ids and connectivity stay integers.

use crate::block_cache::BlockCache;
use crate::frame::{Frame, FrameBody};
use crate::vtu_encode::{FrameEncoder, Spill};
use std::io::{self, Write};

pub const VTK_TRIANGLE: u8 = 5;
pub const VTK_QUAD: u8 = 9;

/// How wide the float arrays are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Precision {
    /// Float64: values survive bit for bit.
    #[default]
    F64,
    /// Float32: half the bytes; values rounded to the nearest f32.
    F32,
}

impl Precision {
    /// The scene keyword ("f64" or "f32").
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "f64" => Some(Self::F64),
            "f32" => Some(Self::F32),
            _ => None,
        }
    }
}

/// How a frame's arrays are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VtuFormat {
    pub precision: Precision,
    /// zlib-compress the appended data (VTK's `vtkZLibDataCompressor` block format).
    pub compress: bool,
}

impl Default for VtuFormat {
    fn default() -> Self {
        Self {
            precision: Precision::F64,
            compress: true,
        }
    }
}

/// Point- and cell-data names (ParaView shows these).
pub mod names {
    pub const DISPLACEMENT: &str = "displacement";
    pub const VELOCITY: &str = "velocity";
    pub const CONTACT_FORCE: &str = "contact_force";
    pub const BODY_ID: &str = "body_id";
    pub const VM_TOP: &str = "von_mises_top";
    pub const VM_BOTTOM: &str = "von_mises_bottom";
    pub const MEMBRANE: &str = "membrane_N";
    pub const BENDING: &str = "bending_M";
    pub const THICKNESS: &str = "thickness";
    pub const TIME: &str = "TimeValue";
    pub const STEP: &str = "step";
}

/// Where an array goes in the .vtu.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    PointData,
    CellData,
    Points,
    Cells,
}

impl Section {
    pub fn tag(self) -> &'static str {
        match self {
            Section::PointData => "PointData",
            Section::CellData => "CellData",
            Section::Points => "Points",
            Section::Cells => "Cells",
        }
    }
}

/// The values of one array for one body. Floats are written at the frame's precision.
pub enum Values<'a> {
    F64(Box<dyn Iterator<Item = f64> + 'a>),
    I64(Box<dyn Iterator<Item = i64> + 'a>),
    U8(Box<dyn Iterator<Item = u8> + 'a>),
}

impl std::fmt::Debug for Values<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Values::F64(_) => "Values::F64",
            Values::I64(_) => "Values::I64",
            Values::U8(_) => "Values::U8",
        })
    }
}

/// Where a body starts in the frame's piece: its first point and its first
/// connectivity entry (connectivity and offsets count from the piece's start).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Base {
    pub point: i64,
    pub conn: i64,
}

/// One named array of the frame: its place, width and how to get a body's values.
#[derive(Clone, Copy)]
pub struct ArrayDef {
    pub section: Section,
    pub name: &'static str,
    pub components: usize,
    pub values: fn(&FrameBody, Base) -> Values<'_>,
    /// Rarely changes between frames: its compressed blocks are kept for the next
    /// frame (`BlockCache`).
    pub steady: bool,
}

impl std::fmt::Debug for ArrayDef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.section.tag(), self.name)
    }
}

const fn def(
    section: Section,
    name: &'static str,
    components: usize,
    values: fn(&FrameBody, Base) -> Values<'_>,
) -> ArrayDef {
    ArrayDef {
        section,
        name,
        components,
        values,
        steady: false,
    }
}

/// `d`, marked as rarely changing between frames.
const fn steady(d: ArrayDef) -> ArrayDef {
    ArrayDef { steady: true, ..d }
}

fn f64s<'a>(it: impl Iterator<Item = f64> + 'a) -> Values<'a> {
    Values::F64(Box::new(it))
}

fn vec3s(v: &[crash_core::Vec3]) -> Values<'_> {
    f64s(v.iter().flat_map(|p| [p.x, p.y, p.z]))
}

fn per_element<T: Copy + 'static>(b: &FrameBody, v: T) -> impl Iterator<Item = T> + '_ {
    std::iter::repeat_n(v, b.element_count())
}

/// Every array of a frame, in file order (within a section, in this order). A new
/// point or cell field is one line here; the reader and ParaView pick it up by name.
pub const ARRAYS: &[ArrayDef] = {
    use names::*;
    use Section::*;
    &[
        def(PointData, DISPLACEMENT, 3, |b, _| {
            f64s(b.x.iter().zip(&b.x0).flat_map(|(x, x0)| {
                let u = x - x0;
                [u.x, u.y, u.z]
            }))
        }),
        def(PointData, VELOCITY, 3, |b, _| vec3s(&b.v)),
        def(PointData, CONTACT_FORCE, 3, |b, _| vec3s(&b.f_contact)),
        steady(def(PointData, BODY_ID, 1, |b, _| {
            Values::I64(Box::new(std::iter::repeat_n(b.id as i64, b.x.len())))
        })),
        def(CellData, VM_TOP, 1, |b, _| {
            f64s(b.von_mises_top.iter().copied())
        }),
        def(CellData, VM_BOTTOM, 1, |b, _| {
            f64s(b.von_mises_bottom.iter().copied())
        }),
        def(CellData, MEMBRANE, 3, |b, _| {
            f64s(b.n.iter().flatten().copied())
        }),
        def(CellData, BENDING, 3, |b, _| {
            f64s(b.m.iter().flatten().copied())
        }),
        steady(def(CellData, THICKNESS, 1, |b, _| {
            f64s(per_element(b, b.thickness))
        })),
        steady(def(CellData, BODY_ID, 1, |b, _| {
            Values::I64(Box::new(per_element(b, b.id as i64)))
        })),
        // where the element was computed (-1: not known to the writer)
        steady(def(CellData, "worker", 1, |b, _| match &b.parts {
            Some(p) => Values::I64(Box::new(p.worker.iter().map(|&w| w as i64))),
            None => {
                let w = b.placement.map_or(-1, |p| p.worker as i64);
                Values::I64(Box::new(per_element(b, w)))
            }
        })),
        // the part of a body split over workers (0: whole; -1: not known to the writer)
        steady(def(CellData, "part", 1, |b, _| match &b.parts {
            Some(p) => Values::I64(Box::new(p.part.iter().map(|&q| q as i64))),
            None => {
                let q = b.placement.map_or(-1, |_| 0);
                Values::I64(Box::new(per_element(b, q)))
            }
        })),
        steady(def(CellData, "group", 1, |b, _| {
            let g = b.placement.map_or(-1, |p| p.group as i64);
            Values::I64(Box::new(per_element(b, g)))
        })),
        def(Points, "Points", 3, |b, _| vec3s(&b.x)),
        steady(def(Cells, "connectivity", 1, |b, base| {
            let tris = b.tris.iter().flatten();
            let quads = b.quads.iter().flatten();
            Values::I64(Box::new(
                tris.chain(quads).map(move |&n| base.point + n as i64),
            ))
        })),
        steady(def(Cells, "offsets", 1, |b, base| {
            let sizes = per_element_sizes(b);
            Values::I64(Box::new(sizes.scan(base.conn, |end, k| {
                *end += k;
                Some(*end)
            })))
        })),
        steady(def(Cells, "types", 1, |b, _| {
            let t = std::iter::repeat_n(VTK_TRIANGLE, b.tris.len());
            Values::U8(Box::new(
                t.chain(std::iter::repeat_n(VTK_QUAD, b.quads.len())),
            ))
        })),
    ]
};

/// Nodes per element, triangles first.
fn per_element_sizes(b: &FrameBody) -> impl Iterator<Item = i64> + '_ {
    std::iter::repeat_n(3i64, b.tris.len()).chain(std::iter::repeat_n(4i64, b.quads.len()))
}

/// The `Scalars`/`Vectors` attributes of a data section (ParaView's default colouring).
pub(crate) fn section_attributes(s: Section) -> &'static str {
    match s {
        Section::PointData => r#" Scalars="body_id" Vectors="displacement""#,
        Section::CellData => r#" Scalars="von_mises_top""#,
        _ => "",
    }
}

/// Write a whole `frame` as one .vtu document to `w` (the data staged in memory; the
/// run's series stages large frames in a file instead, `SeriesWriter`).
pub fn write_vtu(w: &mut dyn Write, frame: &Frame, format: VtuFormat) -> io::Result<()> {
    let mut enc = FrameEncoder::new(
        frame.time,
        frame.step,
        format,
        Spill::in_memory(),
        BlockCache::default(),
    );
    for b in &frame.bodies {
        enc.body(b)?;
    }
    enc.finish(w).map(drop)
}
