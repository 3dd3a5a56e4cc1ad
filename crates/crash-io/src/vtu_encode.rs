//! Encodes a frame, body by body, into a .vtu with VTK "appended raw" data.
//!
//! The XML must come before the data and give each array's byte offset, which is known
//! only once every body is in. So each array is cut into blocks of `BLOCK` bytes as its
//! values arrive; a full block is compressed (zlib, VTK's `vtkZLibDataCompressor`) and
//! staged in a `Spill` (memory, then a temporary file beyond `SPILL_MEMORY`), and at the
//! end the XML is written, then every array's header and blocks copied from the spill.
//! Memory stays bounded whatever the model size: one block per array plus the spill's
//! memory part.
//!
//! A compressed array is `[nblocks, blocksize, last_blocksize, csize_1..csize_n]`
//! (UInt64) then the compressed blocks; `last_blocksize` is the uncompressed size of a
//! partial last block (0 when every block is full). An uncompressed array is `[nbytes]`
//! then the bytes.

use crate::block_cache::BlockCache;
use crate::frame::FrameBody;
use crate::vtu::{names, section_attributes, Base, Precision, Section, Values, VtuFormat, ARRAYS};
use flate2::{write::ZlibEncoder, Compression};
use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::PathBuf;

/// Uncompressed bytes per block (a multiple of 8, so no value straddles two blocks).
pub const BLOCK: usize = 1 << 16;
/// Staged data kept in memory before the spill moves to its file.
pub const SPILL_MEMORY: usize = 16 << 20;

/// zlib level of the Float32 arrays that change every frame. zlib-rs's level 1 (its
/// quick mode) left the showcase's Float32 positions, displacements, von Mises stresses
/// and membrane forces within 10 % of their raw size, so they were stored; level 2
/// shrinks them by 11-25 % (the whole 5 ms showcase with `precision = "f32"`: 65.0 MB
/// against 75.1 MB; docs/output.md, docs/performance.md session 35).
const LEVEL_F32: u32 = 2;
/// zlib level of the other arrays that change every frame (Float64, Int64). On Float64
/// level 1 keeps most of level 2's gain at half its time or less: the floor's positions
/// 0.849 against 0.767 of their size in 4.0 against 10.3 ms a frame, displacements
/// 0.844 against 0.766 in 4.0 against 7.2 ms (docs/performance.md, session 37). The
/// writer's CPU is taken from the step loop when every core steps (two domains, the
/// cluster's master beside its workers).
const LEVEL_OTHER: u32 = 1;
/// zlib level of the arrays that rarely change (`ArrayDef::steady`): compressed once and
/// kept (`BlockCache`), so the best level costs once.
const STEADY_LEVEL: u32 = 9;

/// Where compressed blocks wait until the XML is written.
#[derive(Debug)]
pub struct Spill {
    mem: Vec<u8>,
    /// The temporary file to use once `mem` would outgrow `SPILL_MEMORY` (None: memory
    /// only), and the open file once it is used.
    path: Option<PathBuf>,
    file: Option<BufWriter<File>>,
    len: u64,
    /// Bytes kept in memory before the file is used.
    memory: usize,
}

impl Spill {
    /// Everything in memory (tests, `write_vtu`).
    pub fn in_memory() -> Self {
        Self {
            mem: Vec::new(),
            path: None,
            file: None,
            len: 0,
            memory: usize::MAX,
        }
    }

    /// Memory first (`SPILL_MEMORY` bytes), then `path` (removed again when the spill
    /// is dropped).
    pub fn with_file(path: PathBuf) -> Self {
        Self::with_file_after(path, SPILL_MEMORY)
    }

    /// Memory for the first `memory` bytes, then `path`.
    pub fn with_file_after(path: PathBuf, memory: usize) -> Self {
        let mut s = Self::in_memory();
        s.path = Some(path);
        s.memory = memory;
        s
    }

    /// Append `bytes`; returns where they start.
    fn append(&mut self, bytes: &[u8]) -> io::Result<u64> {
        let at = self.len;
        if self.file.is_none() {
            if let Some(p) = self
                .path
                .as_ref()
                .filter(|_| self.mem.len() + bytes.len() > self.memory)
            {
                let file = std::fs::OpenOptions::new()
                    .read(true)
                    .write(true)
                    .create(true)
                    .truncate(true)
                    .open(p)?;
                let mut f = BufWriter::new(file);
                f.write_all(&self.mem)?;
                self.mem = Vec::new();
                self.file = Some(f);
            }
        }
        match &mut self.file {
            Some(f) => f.write_all(bytes)?,
            None => self.mem.extend_from_slice(bytes),
        }
        self.len += bytes.len() as u64;
        Ok(at)
    }

    /// Copy `len` bytes from `at` to `out`.
    fn copy(
        &mut self,
        at: u64,
        len: u64,
        out: &mut dyn Write,
        buf: &mut Vec<u8>,
    ) -> io::Result<()> {
        match &mut self.file {
            None => out.write_all(&self.mem[at as usize..(at + len) as usize]),
            Some(f) => {
                f.flush()?;
                let file = f.get_mut();
                file.seek(SeekFrom::Start(at))?;
                buf.resize(len as usize, 0);
                file.read_exact(buf)?;
                out.write_all(buf)
            }
        }
    }
}

impl Drop for Spill {
    fn drop(&mut self) {
        if let (Some(_), Some(p)) = (self.file.take(), &self.path) {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// One array being cut into blocks.
#[derive(Debug)]
struct ArrayStream {
    buf: Vec<u8>,
    /// (where in the spill, stored size) of each block, in order.
    blocks: Vec<(u64, u64)>,
    raw_len: u64,
    float32: bool,
    type_name: &'static str,
    /// Index in `ARRAYS`, and whether its blocks go through the `BlockCache`.
    index: usize,
    steady: bool,
    /// zlib level of its blocks (`STEADY_LEVEL`, `LEVEL_F32` or `LEVEL_OTHER`).
    level: u32,
}

/// A frame being encoded.
#[derive(Debug)]
pub struct FrameEncoder {
    time: f64,
    step: u64,
    format: VtuFormat,
    streams: Vec<ArrayStream>,
    spill: Spill,
    base: Base,
    cells: u64,
    scratch: Vec<u8>,
    cache: BlockCache,
}

impl FrameEncoder {
    /// `cache`: the blocks kept from the series' previous frame (`finish` gives it back).
    pub fn new(
        time: f64,
        step: u64,
        format: VtuFormat,
        mut spill: Spill,
        mut cache: BlockCache,
    ) -> Self {
        if spill.len == 0 {
            spill.mem = cache.take_spare();
        }
        // each array's type, from its values for a body without nodes or elements
        let empty = FrameBody::default();
        let streams = ARRAYS
            .iter()
            .enumerate()
            .map(|(index, def)| {
                let (type_name, float32) =
                    match ((def.values)(&empty, Base::default()), format.precision) {
                        (Values::F64(_), Precision::F64) => ("Float64", false),
                        (Values::F64(_), Precision::F32) => ("Float32", true),
                        (Values::I64(_), _) => ("Int64", false),
                        (Values::U8(_), _) => ("UInt8", false),
                    };
                ArrayStream {
                    buf: Vec::with_capacity(BLOCK),
                    blocks: Vec::new(),
                    raw_len: 0,
                    float32,
                    type_name,
                    index,
                    steady: def.steady,
                    level: if def.steady {
                        STEADY_LEVEL
                    } else if float32 {
                        LEVEL_F32
                    } else {
                        LEVEL_OTHER
                    },
                }
            })
            .collect();
        Self {
            time,
            step,
            format,
            streams,
            spill,
            base: Base::default(),
            cells: 0,
            scratch: Vec::new(),
            cache,
        }
    }

    /// The next body (bodies in id order).
    pub fn body(&mut self, b: &FrameBody) -> io::Result<()> {
        for (def, s) in ARRAYS.iter().zip(&mut self.streams) {
            let values = (def.values)(b, self.base);
            let mut out = Out {
                spill: &mut self.spill,
                scratch: &mut self.scratch,
                cache: &mut self.cache,
                compress: self.format.compress,
            };
            let mut put = |s: &mut ArrayStream, bytes: &[u8]| -> io::Result<()> {
                s.buf.extend_from_slice(bytes);
                if s.buf.len() >= BLOCK {
                    out.store_block(s)?;
                }
                Ok(())
            };
            match values {
                Values::F64(it) if s.float32 => {
                    for v in it {
                        put(s, &(v as f32).to_le_bytes())?;
                    }
                }
                Values::F64(it) => {
                    for v in it {
                        put(s, &v.to_le_bytes())?;
                    }
                }
                Values::I64(it) => {
                    for v in it {
                        put(s, &v.to_le_bytes())?;
                    }
                }
                Values::U8(it) => {
                    for v in it {
                        put(s, &[v])?;
                    }
                }
            }
        }
        let conn: usize = 3 * b.tris.len() + 4 * b.quads.len();
        self.base.point += b.x.len() as i64;
        self.base.conn += conn as i64;
        self.cells += b.element_count() as u64;
        Ok(())
    }

    /// Write the whole .vtu to `out`: XML, then the appended data from the spill.
    /// Gives back the block cache for the series' next frame.
    pub fn finish(mut self, out: &mut dyn Write) -> io::Result<BlockCache> {
        let mut o = Out {
            spill: &mut self.spill,
            scratch: &mut self.scratch,
            cache: &mut self.cache,
            compress: self.format.compress,
        };
        for s in &mut self.streams {
            if !s.buf.is_empty() {
                o.store_block(s)?;
            }
        }
        let headers: Vec<Vec<u8>> = self
            .streams
            .iter()
            .map(|s| header(s, self.format.compress))
            .collect();
        self.write_xml(out, &headers)?;
        // the '_' right after the tag: some readers (vtkio) take the data from there
        write!(out, r#"  <AppendedData encoding="raw">_"#)?;
        let mut buf = Vec::new();
        for (s, h) in self.streams.iter().zip(&headers) {
            out.write_all(h)?;
            for &(at, len) in &s.blocks {
                self.spill.copy(at, len, out, &mut buf)?;
            }
        }
        writeln!(out)?;
        writeln!(out, "  </AppendedData>")?;
        writeln!(out, "</VTKFile>")?;
        self.cache.end_frame();
        self.cache.keep_spare(std::mem::take(&mut self.spill.mem));
        Ok(self.cache)
    }

    fn write_xml(&self, w: &mut dyn Write, headers: &[Vec<u8>]) -> io::Result<()> {
        use names::*;
        let compressor = if self.format.compress {
            r#" compressor="vtkZLibDataCompressor""#
        } else {
            ""
        };
        writeln!(w, r#"<?xml version="1.0"?>"#)?;
        writeln!(
            w,
            r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64"{compressor}>"#
        )?;
        writeln!(w, "  <UnstructuredGrid>")?;
        writeln!(w, "    <FieldData>")?;
        writeln!(
            w,
            r#"      <DataArray type="Float64" Name="{TIME}" NumberOfTuples="1" format="ascii">{:e}</DataArray>"#,
            self.time
        )?;
        writeln!(
            w,
            r#"      <DataArray type="Int64" Name="{STEP}" NumberOfTuples="1" format="ascii">{}</DataArray>"#,
            self.step
        )?;
        writeln!(w, "    </FieldData>")?;
        writeln!(
            w,
            r#"    <Piece NumberOfPoints="{}" NumberOfCells="{}">"#,
            self.base.point, self.cells
        )?;
        // byte offset of each array in the appended data
        let mut offsets = Vec::with_capacity(self.streams.len());
        let mut at = 0u64;
        for (s, h) in self.streams.iter().zip(headers) {
            offsets.push(at);
            at += h.len() as u64 + s.blocks.iter().map(|b| b.1).sum::<u64>();
        }
        for section in [
            Section::PointData,
            Section::CellData,
            Section::Points,
            Section::Cells,
        ] {
            writeln!(
                w,
                "      <{}{}>",
                section.tag(),
                section_attributes(section)
            )?;
            for ((def, s), off) in ARRAYS.iter().zip(&self.streams).zip(&offsets) {
                if def.section != section {
                    continue;
                }
                write!(
                    w,
                    r#"        <DataArray type="{}" Name="{}""#,
                    s.type_name, def.name
                )?;
                if def.components > 1 {
                    write!(w, r#" NumberOfComponents="{}""#, def.components)?;
                }
                writeln!(w, r#" format="appended" offset="{off}"/>"#)?;
            }
            writeln!(w, "      </{}>", section.tag())?;
        }
        writeln!(w, "    </Piece>")?;
        writeln!(w, "  </UnstructuredGrid>")
    }
}

/// Where full blocks go: compressed (or taken from the cache) into the spill.
struct Out<'a> {
    spill: &'a mut Spill,
    scratch: &'a mut Vec<u8>,
    cache: &'a mut BlockCache,
    compress: bool,
}

impl Out<'_> {
    /// Move the stream's buffered bytes to the spill as one block.
    fn store_block(&mut self, s: &mut ArrayStream) -> io::Result<()> {
        let k = s.blocks.len();
        let cached = if self.compress && s.steady {
            self.cache.get(s.index, k, &s.buf)
        } else {
            None
        };
        let stored = match cached {
            Some(z) => z,
            None if self.compress && self.cache.level(s.index, s.level) == 0 => {
                stored_zlib(&s.buf, self.scratch);
                &self.scratch[..]
            }
            None if self.compress => {
                // the arm above took the arrays the cache stores: this one's level is its own
                self.scratch.clear();
                let level = Compression::new(s.level);
                let mut z = ZlibEncoder::new(std::mem::take(self.scratch), level);
                z.write_all(&s.buf)?;
                *self.scratch = z.finish()?;
                if !s.steady {
                    self.cache
                        .measured(s.index, s.buf.len(), self.scratch.len());
                }
                if s.steady {
                    self.cache.put(s.index, k, &s.buf, self.scratch);
                }
                &self.scratch[..]
            }
            None => &s.buf[..],
        };
        let at = self.spill.append(stored)?;
        s.blocks.push((at, stored.len() as u64));
        s.raw_len += s.buf.len() as u64;
        s.buf.clear();
        Ok(())
    }
}

/// `raw` as a zlib stream of stored (uncompressed) deflate blocks into `out`: what zlib
/// writes at level 0, without a deflate state. Creating one per 64 KiB block (about
/// 300 KiB allocated and a 128 KiB hash table cleared each time) cost the background
/// writer more than copying the bytes, for the arrays it stores (block_cache::POOR).
pub(crate) fn stored_zlib(raw: &[u8], out: &mut Vec<u8>) {
    // deflate's stored blocks hold at most 65 535 bytes
    const MAX: usize = 0xffff;
    out.clear();
    out.reserve(raw.len() + 6 + 5 * raw.len().div_ceil(MAX).max(1));
    // CMF: deflate with a 32 KiB window; FLG: no dictionary, level "fastest", and
    // (CMF * 256 + FLG) a multiple of 31
    out.extend_from_slice(&[0x78, 0x01]);
    let mut pieces = raw.chunks(MAX).peekable();
    if pieces.peek().is_none() {
        out.extend_from_slice(&[1, 0, 0, 0xff, 0xff]);
    }
    while let Some(p) = pieces.next() {
        let last = pieces.peek().is_none();
        let len = p.len() as u16;
        out.push(u8::from(last)); // BFINAL, BTYPE = 00 (stored), byte-aligned
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(p);
    }
    let mut adler = simd_adler32::Adler32::new();
    adler.write(raw);
    out.extend_from_slice(&adler.finish().to_be_bytes());
}

/// The array's header (UInt64 values, little endian).
fn header(s: &ArrayStream, compress: bool) -> Vec<u8> {
    let words: Vec<u64> = if compress {
        let last = s.raw_len % BLOCK as u64;
        [s.blocks.len() as u64, BLOCK as u64, last]
            .into_iter()
            .chain(s.blocks.iter().map(|b| b.1))
            .collect()
    } else {
        vec![s.raw_len]
    };
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use flate2::read::ZlibDecoder;

    #[test]
    fn stored_zlib_streams_inflate_to_their_input() {
        // empty, one byte, one stored block exactly, one byte more, several blocks
        for n in [0usize, 1, 65_535, 65_536, 200_003] {
            let raw: Vec<u8> = (0..n).map(|i| (i * 7 + i / 251) as u8).collect();
            let mut z = Vec::new();
            stored_zlib(&raw, &mut z);
            let mut back = Vec::new();
            ZlibDecoder::new(&z[..])
                .read_to_end(&mut back)
                .expect("a valid zlib stream");
            assert_eq!(back, raw, "{n} bytes");
            // the data, 5 bytes per stored block, a 2-byte header and a 4-byte checksum
            assert_eq!(z.len(), n + 6 + 5 * n.div_ceil(65_535).max(1), "{n} bytes");
        }
    }
}
