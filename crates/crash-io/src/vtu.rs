//! Writes one frame as a VTK XML UnstructuredGrid (.vtu): triangles stay VTK_TRIANGLE,
//! quads VTK_QUAD, f64 everywhere so values survive exactly (ascii uses the shortest
//! round-trip form; binary is base64 of the raw little-endian bytes).

use crate::frame::{Frame, FrameBody};
use base64::Engine;
use crash_core::Vec3;
use std::io::{self, Write};

pub const VTK_TRIANGLE: u8 = 5;
pub const VTK_QUAD: u8 = 9;

/// How data arrays are stored inside the XML. ParaView reads both.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Encoding {
    /// Human-readable text; about twice the size of base64.
    Ascii,
    /// Inline base64 of the raw bytes with a UInt64 byte-count header.
    #[default]
    Base64,
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

/// A typed array to write.
enum Values<'a> {
    F64(Box<dyn Iterator<Item = f64> + 'a>),
    I64(Box<dyn Iterator<Item = i64> + 'a>),
    U8(Box<dyn Iterator<Item = u8> + 'a>),
}

impl Values<'_> {
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::I64(_) => "Int64",
            Values::U8(_) => "UInt8",
        }
    }
}

fn vec3s<'a>(it: impl Iterator<Item = &'a Vec3> + 'a) -> Values<'a> {
    Values::F64(Box::new(it.flat_map(|p| [p.x, p.y, p.z])))
}

fn triples<'a>(it: impl Iterator<Item = &'a [f64; 3]> + 'a) -> Values<'a> {
    Values::F64(Box::new(it.flat_map(|p| *p)))
}

fn data_array(
    w: &mut dyn Write,
    enc: Encoding,
    name: Option<&str>,
    components: usize,
    values: Values,
) -> io::Result<()> {
    write!(w, r#"        <DataArray type="{}""#, values.type_name())?;
    if let Some(n) = name {
        write!(w, r#" Name="{n}""#)?;
    }
    if components > 1 {
        write!(w, r#" NumberOfComponents="{components}""#)?;
    }
    match enc {
        Encoding::Ascii => {
            writeln!(w, r#" format="ascii">"#)?;
            let per_line = if components > 1 { components } else { 8 };
            let mut k = 0usize;
            let mut sep = |w: &mut dyn Write| -> io::Result<()> {
                k += 1;
                if k.is_multiple_of(per_line) {
                    writeln!(w)
                } else {
                    write!(w, " ")
                }
            };
            match values {
                Values::F64(it) => {
                    for v in it {
                        write!(w, "{v:e}")?;
                        sep(w)?;
                    }
                }
                Values::I64(it) => {
                    for v in it {
                        write!(w, "{v}")?;
                        sep(w)?;
                    }
                }
                Values::U8(it) => {
                    for v in it {
                        write!(w, "{v}")?;
                        sep(w)?;
                    }
                }
            }
            if !k.is_multiple_of(per_line) {
                writeln!(w)?;
            }
        }
        Encoding::Base64 => {
            write!(w, r#" format="binary">"#)?;
            // Uncompressed inline binary: one base64 stream of header + data.
            let mut bytes = vec![0u8; 8];
            match values {
                Values::F64(it) => it.for_each(|v| bytes.extend_from_slice(&v.to_le_bytes())),
                Values::I64(it) => it.for_each(|v| bytes.extend_from_slice(&v.to_le_bytes())),
                Values::U8(it) => it.for_each(|v| bytes.push(v)),
            }
            let n = (bytes.len() - 8) as u64;
            bytes[..8].copy_from_slice(&n.to_le_bytes());
            writeln!(w)?;
            writeln!(
                w,
                "{}",
                base64::engine::general_purpose::STANDARD.encode(&bytes)
            )?;
        }
    }
    writeln!(w, "        </DataArray>")
}

/// Write `frame` as a .vtu document: one `Piece` per body, so a frame can also be
/// written body by body as the bodies arrive (`write_vtu_header`, `write_vtu_piece`,
/// `write_vtu_footer`).
pub fn write_vtu(w: &mut dyn Write, frame: &Frame, enc: Encoding) -> io::Result<()> {
    write_vtu_header(w, frame.time, frame.step)?;
    for b in &frame.bodies {
        write_vtu_piece(w, b, enc)?;
    }
    write_vtu_footer(w)
}

/// The start of a .vtu document: the grid and its time and step.
pub fn write_vtu_header(w: &mut dyn Write, time: f64, step: u64) -> io::Result<()> {
    use names::*;
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        w,
        r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(w, "    <FieldData>")?;
    writeln!(
        w,
        r#"      <DataArray type="Float64" Name="{TIME}" NumberOfTuples="1" format="ascii">{:e}</DataArray>"#,
        time
    )?;
    writeln!(
        w,
        r#"      <DataArray type="Int64" Name="{STEP}" NumberOfTuples="1" format="ascii">{}</DataArray>"#,
        step
    )?;
    writeln!(w, "    </FieldData>")
}

/// The end of a .vtu document.
pub fn write_vtu_footer(w: &mut dyn Write) -> io::Result<()> {
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

/// One body as one `Piece`.
pub fn write_vtu_piece(w: &mut dyn Write, body: &FrameBody, enc: Encoding) -> io::Result<()> {
    use names::*;
    let bodies = std::slice::from_ref(body);
    let np = body.x.len();
    let nc = body.element_count();
    writeln!(
        w,
        r#"    <Piece NumberOfPoints="{np}" NumberOfCells="{nc}">"#
    )?;

    writeln!(
        w,
        r#"      <PointData Scalars="{BODY_ID}" Vectors="{DISPLACEMENT}">"#
    )?;
    let disp = bodies.iter().flat_map(|b| {
        b.x.iter()
            .zip(&b.x0)
            .flat_map(|(x, x0)| [x.x - x0.x, x.y - x0.y, x.z - x0.z])
    });
    data_array(w, enc, Some(DISPLACEMENT), 3, Values::F64(Box::new(disp)))?;
    data_array(
        w,
        enc,
        Some(VELOCITY),
        3,
        vec3s(bodies.iter().flat_map(|b| b.v.iter())),
    )?;
    let fc = vec3s(bodies.iter().flat_map(|b| b.f_contact.iter()));
    data_array(w, enc, Some(CONTACT_FORCE), 3, fc)?;
    let ids = bodies
        .iter()
        .flat_map(|b| std::iter::repeat_n(b.id as i64, b.x.len()));
    data_array(w, enc, Some(BODY_ID), 1, Values::I64(Box::new(ids)))?;
    writeln!(w, "      </PointData>")?;

    writeln!(w, r#"      <CellData Scalars="{VM_TOP}">"#)?;
    let f = |g: fn(&crate::frame::FrameBody) -> &Vec<f64>| {
        Values::F64(Box::new(
            bodies.iter().flat_map(move |b| g(b).iter().copied()),
        ))
    };
    data_array(w, enc, Some(VM_TOP), 1, f(|b| &b.von_mises_top))?;
    data_array(w, enc, Some(VM_BOTTOM), 1, f(|b| &b.von_mises_bottom))?;
    data_array(
        w,
        enc,
        Some(MEMBRANE),
        3,
        triples(bodies.iter().flat_map(|b| b.n.iter())),
    )?;
    data_array(
        w,
        enc,
        Some(BENDING),
        3,
        triples(bodies.iter().flat_map(|b| b.m.iter())),
    )?;
    let th = bodies
        .iter()
        .flat_map(|b| std::iter::repeat_n(b.thickness, b.element_count()));
    data_array(w, enc, Some(THICKNESS), 1, Values::F64(Box::new(th)))?;
    let ids = bodies
        .iter()
        .flat_map(|b| std::iter::repeat_n(b.id as i64, b.element_count()));
    data_array(w, enc, Some(BODY_ID), 1, Values::I64(Box::new(ids)))?;
    if let Some(p) = body.placement {
        for (name, v) in [("worker", p.worker), ("group", p.group)] {
            let vals = std::iter::repeat_n(v as i64, nc);
            data_array(w, enc, Some(name), 1, Values::I64(Box::new(vals)))?;
        }
    }
    writeln!(w, "      </CellData>")?;

    writeln!(w, "      <Points>")?;
    data_array(
        w,
        enc,
        Some("Points"),
        3,
        vec3s(bodies.iter().flat_map(|b| b.x.iter())),
    )?;
    writeln!(w, "      </Points>")?;

    writeln!(w, "      <Cells>")?;
    let mut conn = Vec::with_capacity(3 * nc);
    let mut offsets = Vec::with_capacity(nc);
    let mut types = Vec::with_capacity(nc);
    let mut base = 0i64;
    for b in bodies {
        for t in &b.tris {
            conn.extend(t.iter().map(|&n| base + n as i64));
            offsets.push(conn.len() as i64);
            types.push(VTK_TRIANGLE);
        }
        for q in &b.quads {
            conn.extend(q.iter().map(|&n| base + n as i64));
            offsets.push(conn.len() as i64);
            types.push(VTK_QUAD);
        }
        base += b.x.len() as i64;
    }
    data_array(
        w,
        enc,
        Some("connectivity"),
        1,
        Values::I64(Box::new(conn.into_iter())),
    )?;
    data_array(
        w,
        enc,
        Some("offsets"),
        1,
        Values::I64(Box::new(offsets.into_iter())),
    )?;
    data_array(
        w,
        enc,
        Some("types"),
        1,
        Values::U8(Box::new(types.into_iter())),
    )?;
    writeln!(w, "      </Cells>")?;
    writeln!(w, "    </Piece>")
}
