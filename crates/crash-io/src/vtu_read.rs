//! Reads back a .vtu written by crash into a `Frame`, for `crash render` and tests: the
//! appended raw data of today's files (zlib-compressed or not, Float64 or Float32) and
//! the inline ascii or base64 arrays of older ones. Body names are not stored in the .vtu
//! and come back empty; initial positions come back as x - displacement. The cells'
//! `worker`, `group` and `part` come back as the placement and, for a split body, the
//! part cells.

use crate::error::{AtPath, IoError};
use crate::frame::{Frame, FrameBody, PartCells, Placement};
use crate::vtu::{names, VTK_QUAD, VTK_TRIANGLE};
use base64::Engine;
use crash_core::Vec3;
use roxmltree::{Document, Node};
use std::collections::BTreeMap;
use std::path::Path;

/// Decoded array values, floats and integers kept apart so integers stay exact.
#[derive(Debug)]
enum Array {
    F(Vec<f64>),
    I(Vec<i64>),
}

impl Array {
    fn floats(self) -> Vec<f64> {
        match self {
            Array::F(v) => v,
            Array::I(v) => v.into_iter().map(|x| x as f64).collect(),
        }
    }
    fn ints(self) -> Vec<i64> {
        match self {
            Array::I(v) => v,
            Array::F(v) => v.into_iter().map(|x| x as i64).collect(),
        }
    }
}

#[derive(Clone, Copy)]
struct Reader<'a> {
    path: &'a Path,
    header64: bool,
    /// The bytes after the `_` of `<AppendedData encoding="raw">`, if any.
    appended: Option<&'a [u8]>,
    /// `compressor="vtkZLibDataCompressor"`.
    zlib: bool,
}

impl Reader<'_> {
    fn err(&self, what: impl Into<String>) -> IoError {
        IoError::format(self.path, what)
    }

    fn decode(&self, node: Node) -> Result<Array, IoError> {
        let name = node.attribute("Name").unwrap_or("?");
        let ty = node.attribute("type").unwrap_or("Float64");
        let text = node.text().unwrap_or("");
        match node.attribute("format").unwrap_or("ascii") {
            "ascii" => {
                let toks = text.split_ascii_whitespace();
                if ty.starts_with("Float") {
                    toks.map(|t| t.parse::<f64>())
                        .collect::<Result<_, _>>()
                        .map(Array::F)
                        .map_err(|e| self.err(format!("array {name}: {e}")))
                } else {
                    toks.map(|t| t.parse::<i64>())
                        .collect::<Result<_, _>>()
                        .map(Array::I)
                        .map_err(|e| self.err(format!("array {name}: {e}")))
                }
            }
            "binary" => {
                let clean: String = text.split_ascii_whitespace().collect();
                let bytes = base64::engine::general_purpose::STANDARD
                    .decode(clean)
                    .map_err(|e| self.err(format!("array {name}: base64: {e}")))?;
                let hb = if self.header64 { 8 } else { 4 };
                let data = bytes
                    .get(hb..)
                    .ok_or_else(|| self.err(format!("array {name}: no header")))?;
                self.binary(name, ty, data)
            }
            "appended" => {
                let offset: usize = node
                    .attribute("offset")
                    .and_then(|o| o.trim().parse().ok())
                    .ok_or_else(|| self.err(format!("array {name}: no valid offset")))?;
                let data = self.appended_array(name, offset)?;
                self.binary(name, ty, &data)
            }
            f => Err(self.err(format!("array {name}: format '{f}' is not supported"))),
        }
    }

    /// Header word `k` of the array at `at` in the appended data.
    fn word(&self, name: &str, data: &[u8], at: usize) -> Result<u64, IoError> {
        let hb = if self.header64 { 8 } else { 4 };
        let b = data
            .get(at..at + hb)
            .ok_or_else(|| self.err(format!("array {name}: appended data is truncated")))?;
        Ok(if self.header64 {
            u64::from_le_bytes(b.try_into().unwrap_or_default())
        } else {
            u32::from_le_bytes(b.try_into().unwrap_or_default()) as u64
        })
    }

    /// The raw bytes of the array at `offset` in the appended data (decompressed).
    fn appended_array(&self, name: &str, offset: usize) -> Result<Vec<u8>, IoError> {
        let data = self
            .appended
            .ok_or_else(|| self.err(format!("array {name}: appended, but no AppendedData")))?;
        let hb = if self.header64 { 8 } else { 4 };
        let slice = |from: usize, len: u64| -> Result<&[u8], IoError> {
            usize::try_from(len)
                .ok()
                .and_then(|l| data.get(from..from.checked_add(l)?))
                .ok_or_else(|| self.err(format!("array {name}: appended data is truncated")))
        };
        if !self.zlib {
            let n = self.word(name, data, offset)?;
            return Ok(slice(offset + hb, n)?.to_vec());
        }
        let nblocks = self.word(name, data, offset)?;
        let block = self.word(name, data, offset + hb)?;
        let last = self.word(name, data, offset + 2 * hb)?;
        let nb = usize::try_from(nblocks)
            .ok()
            .filter(|&n| n <= data.len())
            .ok_or_else(|| self.err(format!("array {name}: bad block count {nblocks}")))?;
        let mut at = offset + (3 + nb) * hb;
        let mut out = Vec::new();
        for k in 0..nb {
            let csize = self.word(name, data, offset + (3 + k) * hb)?;
            let mut z = flate2::read::ZlibDecoder::new(slice(at, csize)?);
            let before = out.len();
            std::io::Read::read_to_end(&mut z, &mut out)
                .map_err(|e| self.err(format!("array {name}: block {k}: zlib: {e}")))?;
            let want = if k + 1 == nb && last != 0 {
                last
            } else {
                block
            };
            if (out.len() - before) as u64 != want {
                return Err(self.err(format!(
                    "array {name}: block {k} holds {} bytes, {want} expected",
                    out.len() - before
                )));
            }
            at += csize as usize;
        }
        Ok(out)
    }

    fn binary(&self, name: &str, ty: &str, d: &[u8]) -> Result<Array, IoError> {
        fn chunks<const N: usize, T>(d: &[u8], f: impl Fn([u8; N]) -> T) -> Vec<T> {
            d.chunks_exact(N)
                .map(|c| {
                    let mut a = [0u8; N];
                    a.copy_from_slice(c);
                    f(a)
                })
                .collect()
        }
        Ok(match ty {
            "Float64" => Array::F(chunks(d, f64::from_le_bytes)),
            "Float32" => Array::F(chunks(d, |b| f32::from_le_bytes(b) as f64)),
            "Int64" => Array::I(chunks(d, i64::from_le_bytes)),
            "UInt64" => Array::I(chunks(d, |b| u64::from_le_bytes(b) as i64)),
            "Int32" => Array::I(chunks(d, |b| i32::from_le_bytes(b) as i64)),
            "UInt32" => Array::I(chunks(d, |b| u32::from_le_bytes(b) as i64)),
            "UInt8" => Array::I(d.iter().map(|&b| b as i64).collect()),
            "Int8" => Array::I(d.iter().map(|&b| b as i8 as i64).collect()),
            _ => return Err(self.err(format!("array {name}: type {ty} is not supported"))),
        })
    }

    /// Named arrays under the child element `section` of `parent`.
    fn arrays(&self, parent: Node, section: &str) -> Result<BTreeMap<String, Array>, IoError> {
        let mut out = BTreeMap::new();
        if let Some(s) = parent.children().find(|c| c.has_tag_name(section)) {
            for (k, a) in s
                .children()
                .filter(|c| c.has_tag_name("DataArray"))
                .enumerate()
            {
                let name = a
                    .attribute("Name")
                    .map_or_else(|| format!("#{k}"), String::from);
                out.insert(name, self.decode(a)?);
            }
        }
        Ok(out)
    }
}

fn take(map: &mut BTreeMap<String, Array>, name: &str, r: &Reader) -> Result<Array, IoError> {
    map.remove(name)
        .ok_or_else(|| r.err(format!("array '{name}' is missing")))
}

fn vecs(v: &[f64], range: std::ops::Range<usize>) -> Vec<Vec3> {
    range
        .map(|i| Vec3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]))
        .collect()
}

/// Split a .vtu into its XML (closed again without the appended section) and the
/// appended raw bytes after the `_` marker, if it has them.
fn split_appended(path: &Path, bytes: &[u8]) -> Result<(String, Option<usize>), IoError> {
    const TAG: &[u8] = b"<AppendedData";
    let Some(at) = bytes.windows(TAG.len()).position(|w| w == TAG) else {
        let text = std::str::from_utf8(bytes)
            .map_err(|e| IoError::format(path, format!("not UTF-8 text: {e}")))?;
        return Ok((text.to_string(), None));
    };
    let end = bytes[at..]
        .iter()
        .position(|&b| b == b'>')
        .map(|k| at + k)
        .ok_or_else(|| IoError::format(path, "AppendedData tag is not closed"))?;
    let tag = String::from_utf8_lossy(&bytes[at..end]);
    if !tag.contains(r#"encoding="raw""#) {
        return Err(IoError::format(
            path,
            format!("{tag}>: only raw appended data is supported"),
        ));
    }
    let mark = bytes[end..]
        .iter()
        .position(|&b| b == b'_')
        .map(|k| end + k + 1)
        .ok_or_else(|| IoError::format(path, "AppendedData has no '_' marker"))?;
    let xml = std::str::from_utf8(&bytes[..at])
        .map_err(|e| IoError::format(path, format!("XML part is not UTF-8: {e}")))?;
    Ok((format!("{xml}</VTKFile>"), Some(mark)))
}

/// Read one .vtu file into a frame.
pub fn read_vtu(path: &Path) -> Result<Frame, IoError> {
    let bytes = std::fs::read(path).at(path)?;
    let (text, mark) = split_appended(path, &bytes)?;
    let doc = Document::parse(&text).map_err(|e| IoError::format(path, format!("XML: {e}")))?;
    let root = doc.root_element();
    let r = Reader {
        path,
        header64: root.attribute("header_type") == Some("UInt64"),
        appended: mark.map(|m| &bytes[m..]),
        zlib: match root.attribute("compressor") {
            None => false,
            Some("vtkZLibDataCompressor") => true,
            Some(c) => {
                return Err(IoError::format(
                    path,
                    format!("compressor {c} is not supported (vtkZLibDataCompressor is)"),
                ))
            }
        },
    };
    if r.zlib && mark.is_none() {
        return Err(r.err("compressed inline arrays are not supported (appended raw data is)"));
    }
    if root.attribute("type") != Some("UnstructuredGrid") {
        return Err(r.err("not an UnstructuredGrid .vtu file"));
    }
    let grid = root
        .children()
        .find(|c| c.has_tag_name("UnstructuredGrid"))
        .ok_or_else(|| r.err("no UnstructuredGrid element"))?;
    let mut field = r.arrays(grid, "FieldData")?;
    let time = field
        .remove(names::TIME)
        .map(|a| a.floats())
        .and_then(|v| v.first().copied());
    let step = field
        .remove(names::STEP)
        .map(|a| a.ints())
        .and_then(|v| v.first().copied());
    let mut frame_bodies = Vec::new();
    for piece in grid.children().filter(|c| c.has_tag_name("Piece")) {
        frame_bodies.extend(piece_bodies(&r, piece)?);
    }
    if frame_bodies.is_empty() && grid.children().all(|c| !c.has_tag_name("Piece")) {
        return Err(r.err("no Piece element"));
    }
    Ok(Frame::from_bodies(
        time.unwrap_or(0.0),
        step.unwrap_or(0).max(0) as u64,
        frame_bodies,
    ))
}

/// The bodies of one `Piece` (crash writes one per body; a piece holding several bodies,
/// as older files do, is split by the point body ids).
fn piece_bodies(r: &Reader, piece: Node) -> Result<Vec<FrameBody>, IoError> {
    let r = *r;
    let count = |a: &str| -> Result<usize, IoError> {
        piece
            .attribute(a)
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| r.err(format!("Piece has no valid {a}")))
    };
    let (np, nc) = (count("NumberOfPoints")?, count("NumberOfCells")?);
    let mut pd = r.arrays(piece, "PointData")?;
    let mut cd = r.arrays(piece, "CellData")?;
    let mut pts = r.arrays(piece, "Points")?;
    let mut cells = r.arrays(piece, "Cells")?;
    let x = pts.pop_first().map(|(_, a)| a.floats()).unwrap_or_default();
    let u = take(&mut pd, names::DISPLACEMENT, &r)?.floats();
    let v = take(&mut pd, names::VELOCITY, &r)?.floats();
    let fc = take(&mut pd, names::CONTACT_FORCE, &r)?.floats();
    let pid = take(&mut pd, names::BODY_ID, &r)?.ints();
    let vt = take(&mut cd, names::VM_TOP, &r)?.floats();
    let vb = take(&mut cd, names::VM_BOTTOM, &r)?.floats();
    let nm = take(&mut cd, names::MEMBRANE, &r)?.floats();
    let bm = take(&mut cd, names::BENDING, &r)?.floats();
    let th = take(&mut cd, names::THICKNESS, &r)?.floats();
    let cid = take(&mut cd, names::BODY_ID, &r)?.ints();
    // where elements were computed (written by crash since the cluster; optional)
    let mut placed = |name: &str| -> Option<Vec<i64>> {
        cd.remove(name).map(|a| a.ints()).filter(|a| a.len() == nc)
    };
    let (worker, group, part) = (placed("worker"), placed("group"), placed("part"));
    let conn = take(&mut cells, "connectivity", &r)?.ints();
    let offsets = take(&mut cells, "offsets", &r)?.ints();
    let types = take(&mut cells, "types", &r)?.ints();
    for (name, len, want) in [
        ("Points", x.len(), 3 * np),
        (names::DISPLACEMENT, u.len(), 3 * np),
        (names::VELOCITY, v.len(), 3 * np),
        (names::CONTACT_FORCE, fc.len(), 3 * np),
        ("point body_id", pid.len(), np),
        (names::VM_TOP, vt.len(), nc),
        (names::VM_BOTTOM, vb.len(), nc),
        (names::MEMBRANE, nm.len(), 3 * nc),
        (names::BENDING, bm.len(), 3 * nc),
        (names::THICKNESS, th.len(), nc),
        ("cell body_id", cid.len(), nc),
        ("offsets", offsets.len(), nc),
        ("types", types.len(), nc),
    ] {
        if len != want {
            return Err(r.err(format!("array {name} has {len} values, {want} expected")));
        }
    }

    // Points of one body are contiguous; cells refer to them.
    let mut bodies = Vec::new();
    let mut start = 0usize;
    while start < np {
        let id = pid[start];
        let mut end = start;
        while end < np && pid[end] == id {
            end += 1;
        }
        let mut b = FrameBody {
            id: u32::try_from(id).map_err(|_| r.err(format!("body id {id} out of range")))?,
            name: String::new(),
            thickness: 0.0,
            x: vecs(&x, start..end),
            x0: Vec::new(),
            v: vecs(&v, start..end),
            // angular velocities are not written to .vtu files
            w: Vec::new(),
            tris: Vec::new(),
            quads: Vec::new(),
            von_mises_top: Vec::new(),
            von_mises_bottom: Vec::new(),
            n: Vec::new(),
            m: Vec::new(),
            f_contact: vecs(&fc, start..end),
            placement: None,
            parts: None,
            pending: None,
        };
        let uu = vecs(&u, start..end);
        b.x0 = b.x.iter().zip(&uu).map(|(x, u)| x - u).collect();
        bodies.push((b, start, end, Vec::new(), Vec::new()));
        start = end;
    }
    let slot_of: BTreeMap<i64, usize> = bodies
        .iter()
        .enumerate()
        .map(|(k, s)| (s.0.id as i64, k))
        .collect();
    let mut prev = 0usize;
    for c in 0..nc {
        let off = usize::try_from(offsets[c]).map_err(|_| r.err("negative offset"))?;
        let nodes = conn
            .get(prev..off)
            .ok_or_else(|| r.err(format!("cell {c}: offsets out of range")))?;
        prev = off;
        let k = *slot_of
            .get(&cid[c])
            .ok_or_else(|| r.err(format!("cell {c}: body {} has no points", cid[c])))?;
        let slot = &mut bodies[k];
        let (lo, hi) = (slot.1 as i64, slot.2 as i64);
        let mut local = [0u32; 4];
        for (k, &n) in nodes.iter().take(4).enumerate() {
            if n < lo || n >= hi {
                return Err(r.err(format!(
                    "cell {c}: node {n} is not a point of body {}",
                    cid[c]
                )));
            }
            local[k] = (n - lo) as u32;
        }
        match (types[c] as u8, nodes.len()) {
            (VTK_TRIANGLE, 3) => slot.3.push((c, [local[0], local[1], local[2]])),
            (VTK_QUAD, 4) => slot.4.push((c, local)),
            (t, k) => {
                return Err(r.err(format!(
                    "cell {c}: type {t} with {k} nodes is not supported"
                )))
            }
        }
    }
    let frame_bodies: Vec<FrameBody> = bodies
        .into_iter()
        .map(|(mut b, _, _, tris, quads)| {
            let order: Vec<usize> = tris
                .iter()
                .map(|t| t.0)
                .chain(quads.iter().map(|q| q.0))
                .collect();
            b.tris = tris.into_iter().map(|t| t.1).collect();
            b.quads = quads.into_iter().map(|q| q.1).collect();
            b.thickness = order.first().map_or(0.0, |&c| th[c]);
            b.von_mises_top = order.iter().map(|&c| vt[c]).collect();
            b.von_mises_bottom = order.iter().map(|&c| vb[c]).collect();
            b.n = order
                .iter()
                .map(|&c| [nm[3 * c], nm[3 * c + 1], nm[3 * c + 2]])
                .collect();
            b.m = order
                .iter()
                .map(|&c| [bm[3 * c], bm[3 * c + 1], bm[3 * c + 2]])
                .collect();
            let at = |a: &Option<Vec<i64>>, c: usize| a.as_ref().map_or(-1, |a| a[c]);
            if let Some(&c) = order.first() {
                if let (Ok(worker), Ok(group)) =
                    (u32::try_from(at(&worker, c)), u32::try_from(at(&group, c)))
                {
                    b.placement = Some(Placement { worker, group });
                }
            }
            // a split body: some element in a part other than 0
            if order.iter().any(|&c| at(&part, c) > 0) {
                let of = |a: &Option<Vec<i64>>| -> Vec<u32> {
                    order.iter().map(|&c| at(a, c).max(0) as u32).collect()
                };
                b.parts = Some(PartCells {
                    worker: of(&worker),
                    part: of(&part),
                });
            }
            b
        })
        .collect();
    Ok(frame_bodies)
}
