//! The .vtu/.pvd series: the appended (zlib) format decoded by hand and read back by our
//! own reader in f64 and f32; the background writer; older inline files. (The
//! independent reader is meshio: tests/crosscheck/vtu_meshio.py. vtkio 0.6 cannot read
//! appended raw data: its XML parser takes a '<' byte in the data for a tag.)

mod common;

use common::{stepped_group, test_dir};
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, Material, Section, Stabilization};
use crash_io::block_cache::{BlockCache, REMEASURE};
use crash_io::vtu::write_vtu;
use crash_io::vtu_encode::{FrameEncoder, Spill, BLOCK};
use crash_io::{read_pvd, read_vtu, BackgroundSeries, Frame, Precision, SeriesWriter, VtuFormat};

fn frame_at(steps: usize) -> Frame {
    let (clock, g) = stepped_group(steps);
    // Reverse the body order: a master gathers bodies in any order.
    let refs: Vec<&crash_core::Body> = g.bodies.iter().rev().collect();
    Frame::capture(clock.time, clock.step, &refs)
}

fn formats() -> [(VtuFormat, &'static str); 4] {
    let f = |precision, compress| VtuFormat {
        precision,
        compress,
    };
    [
        (f(Precision::F64, true), "f64_zlib"),
        (f(Precision::F64, false), "f64_raw"),
        (f(Precision::F32, true), "f32_zlib"),
        (f(Precision::F32, false), "f32_raw"),
    ]
}

/// What a value becomes in a file of this precision.
fn stored(v: f64, p: Precision) -> f64 {
    match p {
        Precision::F64 => v,
        Precision::F32 => v as f32 as f64,
    }
}

#[test]
fn own_reader_round_trips_f64_exactly_and_f32_to_f32_rounding() {
    let frame = frame_at(15);
    for (fmt, name) in formats() {
        let dir = test_dir(&format!("own_reader_{name}"));
        let mut w = SeriesWriter::create(&dir).expect("create").with_format(fmt);
        let back = read_vtu(&w.write(&frame).expect("write")).expect("read");
        let p = fmt.precision;
        let v3 = |v: &[crash_core::Vec3]| -> Vec<f64> {
            v.iter()
                .flat_map(|q| [q.x, q.y, q.z])
                .map(|c| stored(c, p))
                .collect()
        };
        let flat = |v: &[f64]| -> Vec<f64> { v.iter().map(|&c| stored(c, p)).collect() };
        let t3 =
            |v: &[[f64; 3]]| -> Vec<f64> { v.iter().flatten().map(|&c| stored(c, p)).collect() };
        let bits = |v: Vec<f64>| -> Vec<u64> { v.into_iter().map(f64::to_bits).collect() };
        assert_eq!(back.time.to_bits(), frame.time.to_bits(), "{name}");
        assert_eq!(back.step, frame.step);
        assert_eq!(back.bodies.len(), 2);
        for (a, b) in back.bodies.iter().zip(&frame.bodies) {
            // integers exact in every format
            assert_eq!(a.id, b.id);
            assert_eq!((&a.tris, &a.quads), (&b.tris, &b.quads), "{name}");
            assert_eq!(a.thickness, stored(b.thickness, p));
            // floats: the same bits (f64) or the nearest f32 of each value (f32)
            assert_eq!(bits(v3(&a.x)), bits(v3(&b.x)), "{name}: positions");
            assert_eq!(bits(v3(&a.v)), bits(v3(&b.v)), "{name}: velocities");
            assert_eq!(bits(v3(&a.f_contact)), bits(v3(&b.f_contact)), "{name}");
            assert_eq!(bits(flat(&a.von_mises_top)), bits(flat(&b.von_mises_top)));
            assert_eq!(
                bits(flat(&a.von_mises_bottom)),
                bits(flat(&b.von_mises_bottom))
            );
            assert_eq!(bits(t3(&a.n)), bits(t3(&b.n)), "{name}: membrane");
            assert_eq!(bits(t3(&a.m)), bits(t3(&b.m)), "{name}: bending");
            // x0 comes back as x - u, u rounded once, then the subtraction
            let eps = match p {
                Precision::F64 => 2.0 * f64::EPSILON,
                Precision::F32 => 2.0 * f32::EPSILON as f64,
            };
            for (q, r) in a.x0.iter().zip(&b.x0) {
                assert!(
                    (q - r).norm() <= eps * (1.0 + r.norm()),
                    "{name}: {q} vs {r}"
                );
            }
        }
    }
}

/// The header words (UInt64) at `at`.
fn words(data: &[u8], at: usize, n: usize) -> Vec<u64> {
    (0..n)
        .map(|k| u64::from_le_bytes(data[at + 8 * k..at + 8 * k + 8].try_into().expect("8")))
        .collect()
}

/// The attribute `key` of the first `<DataArray ... Name="name"` tag in `xml`.
fn attr_of(xml: &str, name: &str, key: &str) -> String {
    let tag = xml
        .split("<DataArray")
        .find(|t| t.contains(&format!(r#"Name="{name}""#)))
        .unwrap_or_else(|| panic!("no array {name}"));
    tag.split(&format!(r#"{key}=""#))
        .nth(1)
        .and_then(|s| s.split('"').next())
        .unwrap_or_else(|| panic!("{name} has no {key}"))
        .to_string()
}

/// A frame whose arrays span several blocks (the plate alone has 10 201 nodes).
fn big_frame() -> Frame {
    let p = Body::new(
        0,
        "plate",
        &plate(0.4, 0.4, 100, 100, ElementKind::Quad),
        Section::new(Material::steel(), 0.002),
        Stabilization::default(),
    )
    .expect("plate");
    let mut f = Frame::capture(0.5, 7, &[&p]);
    for (k, x) in f.bodies[0].x.iter_mut().enumerate() {
        x.z += 1e-3 * (k as f64 * 0.37).sin();
    }
    f
}

#[test]
fn compressed_arrays_follow_vtk_block_format_and_decode_independently() {
    let frame = big_frame();
    let b = &frame.bodies[0];
    let mut bytes = Vec::new();
    write_vtu(&mut bytes, &frame, VtuFormat::default()).expect("write");
    let at = bytes
        .windows(13)
        .position(|w| w == b"<AppendedData")
        .expect("appended");
    let xml = std::str::from_utf8(&bytes[..at]).expect("utf8");
    assert!(xml.contains(r#"header_type="UInt64""#));
    assert!(xml.contains(r#"compressor="vtkZLibDataCompressor""#));
    assert!(std::str::from_utf8(&bytes[at..at + 30])
        .expect("tag")
        .starts_with(r#"<AppendedData encoding="raw">"#));
    assert_eq!(xml.matches("<Piece").count(), 1, "all bodies in one piece");
    let mark = at + bytes[at..].iter().position(|&c| c == b'_').expect("_") + 1;
    let data = &bytes[mark..];
    assert!(bytes.ends_with(b"\n  </AppendedData>\n</VTKFile>\n"));

    // Decode the displacement by hand: [nblocks, blocksize, last, csizes..] + zlib blocks.
    let off: usize = attr_of(xml, "displacement", "offset")
        .parse()
        .expect("offset");
    assert_eq!(attr_of(xml, "displacement", "type"), "Float64");
    let raw_len = 24 * b.x.len();
    let h = words(data, off, 3);
    let nblocks = raw_len.div_ceil(BLOCK);
    assert!(nblocks >= 3, "the test array spans several blocks");
    assert_eq!(
        h,
        vec![nblocks as u64, BLOCK as u64, (raw_len % BLOCK) as u64]
    );
    let sizes = words(data, off + 24, nblocks);
    let mut pos = off + 24 + 8 * nblocks;
    let mut raw = Vec::new();
    for &c in &sizes {
        let mut z = flate2::read::ZlibDecoder::new(&data[pos..pos + c as usize]);
        std::io::Read::read_to_end(&mut z, &mut raw).expect("zlib");
        pos += c as usize;
    }
    assert_eq!(raw.len(), raw_len);
    // the next array starts right after this one
    let next: usize = attr_of(xml, "velocity", "offset").parse().expect("offset");
    assert_eq!(next, pos);
    for (k, (x, x0)) in b.x.iter().zip(&b.x0).enumerate() {
        let got = f64::from_le_bytes(raw[24 * k + 16..24 * k + 24].try_into().expect("8"));
        assert_eq!(got.to_bits(), (x.z - x0.z).to_bits());
    }
    // connectivity and types stay integers
    assert_eq!(attr_of(xml, "connectivity", "type"), "Int64");
    assert_eq!(attr_of(xml, "types", "type"), "UInt8");

    // Float32: the float arrays (and only they) change type; the file shrinks.
    let mut small = Vec::new();
    let f32z = VtuFormat {
        precision: Precision::F32,
        compress: true,
    };
    write_vtu(&mut small, &frame, f32z).expect("write f32");
    let xml32 = String::from_utf8_lossy(&small[..small.len().min(4000)]).to_string();
    for name in [
        "displacement",
        "velocity",
        "von_mises_top",
        "membrane_N",
        "Points",
    ] {
        assert_eq!(attr_of(&xml32, name, "type"), "Float32", "{name}");
    }
    assert_eq!(attr_of(&xml32, "offsets", "type"), "Int64");
    let mut plain = Vec::new();
    let raw64 = VtuFormat {
        precision: Precision::F64,
        compress: false,
    };
    write_vtu(&mut plain, &frame, raw64).expect("write raw");
    assert!(small.len() < bytes.len() && bytes.len() < plain.len());
}

/// The compressed size of array `name` in the .vtu file `bytes`, and its raw size.
fn sizes_of(bytes: &[u8], name: &str) -> (u64, u64) {
    let at = bytes
        .windows(13)
        .position(|w| w == b"<AppendedData")
        .expect("appended");
    let xml = std::str::from_utf8(&bytes[..at]).expect("utf8");
    let mark = at + bytes[at..].iter().position(|&c| c == b'_').expect("_") + 1;
    let off: usize = attr_of(xml, name, "offset").parse().expect("offset");
    let h = words(&bytes[mark..], off, 3);
    let raw = (h[0] - 1) * h[1] + if h[2] == 0 { h[1] } else { h[2] };
    (
        words(&bytes[mark..], off + 24, h[0] as usize).iter().sum(),
        raw,
    )
}

#[test]
fn a_series_through_the_block_cache_reads_back_every_value_and_stores_noisy_arrays() {
    let mut frame = big_frame();
    let dir = test_dir("block_cache");
    let mut w = SeriesWriter::create(&dir).expect("create");
    let mut stored_seen = false;
    for k in 0..REMEASURE + 3 {
        // velocities like a vibrating plate's: their low bits do not compress
        for (i, v) in frame.bodies[0].v.iter_mut().enumerate() {
            let s = |c: f64| ((i as f64 + c) * (k as f64 + 1.3)).sin() * 1e-3;
            *v = crash_core::Vec3::new(s(0.1), s(0.2), s(0.3));
        }
        for x in &mut frame.bodies[0].x {
            x.z += 1e-7;
        }
        frame.step = k;
        frame.time = k as f64 * 1e-6;
        let path = w.write(&frame).expect("write");
        let back = read_vtu(&path).expect("read");
        let (a, b) = (&back.bodies[0], &frame.bodies[0]);
        let bits = |v: &[crash_core::Vec3]| -> Vec<u64> {
            v.iter()
                .flat_map(|q| [q.x, q.y, q.z])
                .map(f64::to_bits)
                .collect()
        };
        assert_eq!(bits(&a.x), bits(&b.x), "frame {k}: positions");
        assert_eq!(bits(&a.v), bits(&b.v), "frame {k}: velocities");
        assert_eq!((&a.tris, &a.quads), (&b.tris, &b.quads), "frame {k}: cells");
        let (z, raw) = sizes_of(&std::fs::read(&path).expect("read"), "velocity");
        // from the second frame on, the noisy velocities are stored (raw plus the zlib
        // framing: a few bytes per block; level 1 makes them 5% larger than raw),
        // except in the frame after every REMEASURE-th
        let stored = raw <= z && z <= raw + 16 * raw.div_ceil(BLOCK as u64);
        assert_eq!(stored, k > 0 && k != REMEASURE, "frame {k}: {z} of {raw}");
        stored_seen |= stored;
        // the connectivity, from the cache after the first frame, compresses as ever
        let (cz, craw) = sizes_of(&std::fs::read(&path).expect("read"), "connectivity");
        assert!(cz * 3 < craw, "frame {k}: connectivity {cz} of {craw}");
    }
    assert!(stored_seen);
}

#[test]
fn a_spill_file_gives_the_same_bytes_as_memory_and_is_removed() {
    let frame = big_frame();
    let dir = test_dir("spill_file");
    let spill_path = dir.join("f.spill");
    for fmt in [VtuFormat::default(), formats()[3].0] {
        let mut in_mem = Vec::new();
        write_vtu(&mut in_mem, &frame, fmt).expect("memory");
        let mut enc = FrameEncoder::new(
            frame.time,
            frame.step,
            fmt,
            Spill::with_file_after(spill_path.clone(), 1000),
            BlockCache::default(),
        );
        for b in &frame.bodies {
            enc.body(b).expect("body");
        }
        assert!(spill_path.exists(), "past 1000 bytes the spill is a file");
        let mut via_file = Vec::new();
        enc.finish(&mut via_file).expect("finish");
        assert!(in_mem == via_file, "same bytes through the spill file");
        assert!(!spill_path.exists(), "spill file removed");
    }
}

#[test]
fn background_writer_writes_the_same_files_as_the_direct_writer() {
    let mut frame = frame_at(4);
    let (d1, d2) = (test_dir("bg_direct"), test_dir("bg_thread"));
    let fmt = formats()[2].0;
    let mut direct = SeriesWriter::create(&d1).expect("create").with_format(fmt);
    let mut bg =
        BackgroundSeries::start(SeriesWriter::create(&d2).expect("create")).expect("start");
    bg.set_format(fmt);
    for k in 0..5 {
        frame.time = k as f64 * 1e-5;
        frame.step = k;
        direct.write(&frame).expect("direct");
        bg.begin_frame(frame.time, frame.step).expect("begin");
        for b in &frame.bodies {
            bg.frame_body(b.clone()).expect("body");
        }
        bg.end_frame().expect("end");
    }
    bg.flush().expect("flush");
    assert_eq!(bg.entries().len(), 5);
    bg.finish().expect("finish");
    for k in 0..5 {
        let f = format!("frames/frame_{k:06}.vtu");
        let (a, b) = (
            std::fs::read(d1.join(&f)).expect("a"),
            std::fs::read(d2.join(&f)).expect("b"),
        );
        assert!(a == b, "{f} differs");
    }
    assert_eq!(
        read_pvd(&d2.join("frames.pvd")).expect("pvd"),
        read_pvd(&d1.join("frames.pvd")).expect("pvd")
    );
}

/// The writer thread runs below the step loop's priority (nice `WRITER_NICE` or
/// lower, read back from /proc for the thread named crash-frames).
#[cfg(target_os = "linux")]
#[test]
fn the_frame_writer_runs_below_the_step_loops_priority() {
    let dir = test_dir("bg_nice");
    let bg = BackgroundSeries::start(SeriesWriter::create(&dir).expect("create")).expect("start");
    let nice = |stat: &str| -> Option<i32> {
        // the fields after the command's closing parenthesis; nice is field 19 of stat
        let rest = &stat[stat.rfind(')')? + 2..];
        rest.split_whitespace().nth(16)?.parse().ok()
    };
    let mut found = None;
    for _ in 0..100 {
        found = std::fs::read_dir("/proc/self/task")
            .expect("/proc")
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .find(|p| {
                std::fs::read_to_string(p.join("comm")).is_ok_and(|c| c.trim() == "crash-frames")
            })
            .and_then(|p| std::fs::read_to_string(p.join("stat")).ok())
            .and_then(|s| nice(&s));
        if found.is_some_and(|n| n >= crash_io::frame_writer::WRITER_NICE) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(
        found.is_some_and(|n| n >= crash_io::frame_writer::WRITER_NICE),
        "writer thread's nice value: {found:?}"
    );
    drop(bg);
}

#[test]
fn background_writer_error_names_the_file_and_keeps_the_frames_before() {
    let frame = frame_at(2);
    let dir = test_dir("bg_error");
    let mut bg =
        BackgroundSeries::start(SeriesWriter::create(&dir).expect("create")).expect("start");
    // the second frame's temporary file cannot be created: a directory has its name
    std::fs::create_dir_all(dir.join("frames/frame_000001.vtu.tmp")).expect("blocker");
    for k in 0..2 {
        bg.begin_frame(k as f64, k).expect("begin");
        for b in &frame.bodies {
            bg.frame_body(b.clone()).expect("body");
        }
        bg.end_frame().expect("end");
    }
    let e = bg.flush().expect_err("the writer failed").to_string();
    assert!(
        e.contains("frame_000001.vtu"),
        "the error names the file: {e}"
    );
    let again = bg.begin_frame(2.0, 2).expect_err("stopped").to_string();
    assert!(again.contains("frame_000001.vtu"), "{again}");
    assert!(bg.finish().is_err());
    let list = read_pvd(&dir.join("frames.pvd")).expect("pvd");
    assert_eq!(list.len(), 1, "only the complete frame is listed");
    assert!(dir.join("frames/frame_000000.vtu").exists());
    assert!(
        !dir.join("frames/frame_000001.vtu").exists(),
        "no torn frame"
    );
    read_vtu(&dir.join("frames/frame_000000.vtu")).expect("the kept frame reads");
}

#[test]
fn older_inline_ascii_and_base64_frames_still_read() {
    use base64::Engine;
    let dir = test_dir("old_format");
    let b64 = |bytes: Vec<u8>| {
        let mut v = (bytes.len() as u64).to_le_bytes().to_vec();
        v.extend(bytes);
        base64::engine::general_purpose::STANDARD.encode(v)
    };
    let f64s = |v: &[f64]| b64(v.iter().flat_map(|x| x.to_le_bytes()).collect());
    // one triangle, body 4, written as crash wrote frames before appended data
    let pts = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.5];
    let text = format!(
        r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">
  <UnstructuredGrid>
    <FieldData>
      <DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="ascii">2.5e-3</DataArray>
      <DataArray type="Int64" Name="step" NumberOfTuples="1" format="ascii">9</DataArray>
    </FieldData>
    <Piece NumberOfPoints="3" NumberOfCells="1">
      <PointData>
        <DataArray type="Float64" Name="displacement" NumberOfComponents="3" format="ascii">0 0 0 0 0 0 0 0 0.5</DataArray>
        <DataArray type="Float64" Name="velocity" NumberOfComponents="3" format="binary">{}</DataArray>
        <DataArray type="Float64" Name="contact_force" NumberOfComponents="3" format="ascii">0 0 0 0 0 0 0 0 0</DataArray>
        <DataArray type="Int64" Name="body_id" format="ascii">4 4 4</DataArray>
      </PointData>
      <CellData>
        <DataArray type="Float64" Name="von_mises_top" format="ascii">1e6</DataArray>
        <DataArray type="Float64" Name="von_mises_bottom" format="ascii">2e6</DataArray>
        <DataArray type="Float64" Name="membrane_N" NumberOfComponents="3" format="ascii">1 2 3</DataArray>
        <DataArray type="Float64" Name="bending_M" NumberOfComponents="3" format="ascii">4 5 6</DataArray>
        <DataArray type="Float64" Name="thickness" format="ascii">0.001</DataArray>
        <DataArray type="Int64" Name="body_id" format="ascii">4</DataArray>
      </CellData>
      <Points>
        <DataArray type="Float64" Name="Points" NumberOfComponents="3" format="binary">{}</DataArray>
      </Points>
      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">0 1 2</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">3</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">5</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
"#,
        f64s(&[0.0, 0.0, -1.0, 0.0, 0.0, -1.0, 0.0, 0.0, -2.0]),
        f64s(&pts)
    );
    let path = dir.join("old.vtu");
    std::fs::write(&path, text).expect("write");
    let f = read_vtu(&path).expect("read");
    assert_eq!((f.time, f.step, f.bodies.len()), (2.5e-3, 9, 1));
    let b = &f.bodies[0];
    assert_eq!(
        (b.id, b.thickness, b.tris.clone()),
        (4, 0.001, vec![[0, 1, 2]])
    );
    assert_eq!(b.x[2], crash_core::Vec3::new(0.0, 1.0, 0.5));
    assert_eq!(b.x0[2], crash_core::Vec3::new(0.0, 1.0, 0.0));
    assert_eq!(b.v[2].z, -2.0);
    assert_eq!((b.von_mises_bottom[0], b.m[0][2]), (2e6, 6.0));
}

#[test]
fn pvd_lists_every_frame_with_its_time() {
    let dir = test_dir("pvd_list");
    let mut w = SeriesWriter::create(&dir).expect("create");
    let mut frame = frame_at(2);
    let times = [0.0, 1.5e-5, 3.0e-5, 4.5e-5];
    for &t in &times {
        frame.time = t;
        w.write(&frame).expect("write");
    }
    let text = std::fs::read_to_string(dir.join("frames.pvd")).expect("pvd");
    // Independent check on the text: one DataSet line per frame, times exact.
    let lines: Vec<&str> = text.lines().filter(|l| l.contains("<DataSet")).collect();
    assert_eq!(lines.len(), times.len());
    for (k, (l, t)) in lines.iter().zip(times).enumerate() {
        let ts = l
            .split("timestep=\"")
            .nth(1)
            .and_then(|s| s.split('"').next())
            .expect("timestep");
        assert_eq!(ts.parse::<f64>().expect("number"), t);
        assert!(l.contains(&format!("file=\"frames/frame_{k:06}.vtu\"")));
        assert!(dir.join(format!("frames/frame_{k:06}.vtu")).exists());
    }
    assert!(text.trim_end().ends_with("</VTKFile>"));
    assert_eq!(read_pvd(&dir.join("frames.pvd")).expect("read").len(), 4);
}

#[test]
fn reopen_keeps_frames_up_to_restart_time_and_continues_numbering() {
    let dir = test_dir("pvd_reopen");
    let mut frame = frame_at(1);
    {
        let mut w = SeriesWriter::create(&dir).expect("create");
        for k in 0..5 {
            frame.time = k as f64 * 1e-4;
            w.write(&frame).expect("write");
        }
    }
    let mut w = SeriesWriter::reopen(&dir, 2e-4).expect("reopen");
    assert_eq!(w.entries().len(), 3, "frames at 0, 1e-4 and 2e-4 kept");
    assert!(
        !dir.join("frames/frame_000003.vtu").exists(),
        "dropped frame removed"
    );
    assert!(!dir.join("frames/frame_000004.vtu").exists());
    frame.time = 2.5e-4;
    let p = w.write(&frame).expect("write");
    assert!(
        p.ends_with("frames/frame_000003.vtu"),
        "numbering continues: {p:?}"
    );
    let list = read_pvd(&dir.join("frames.pvd")).expect("pvd");
    let times: Vec<f64> = list.iter().map(|e| e.time).collect();
    assert_eq!(times, vec![0.0, 1e-4, 2e-4, 2.5e-4]);
    // A frame at an already listed time replaces it (restart that re-writes its frame).
    frame.time = 2.5e-4;
    w.write(&frame).expect("write again");
    let list = read_pvd(&dir.join("frames.pvd")).expect("pvd");
    assert_eq!(list.len(), 4);
    assert_eq!(list[3].file, "frames/frame_000004.vtu");
    assert!(!dir.join("frames/frame_000003.vtu").exists());
}

#[test]
fn create_removes_frames_of_an_earlier_series() {
    let dir = test_dir("pvd_create_again");
    let mut frame = frame_at(1);
    let mut w = SeriesWriter::create(&dir).expect("create");
    for k in 0..3 {
        frame.time = k as f64;
        w.write(&frame).expect("write");
    }
    let w = SeriesWriter::create(&dir).expect("create again");
    assert!(w.entries().is_empty());
    assert!(read_pvd(&dir.join("frames.pvd")).expect("pvd").is_empty());
    assert!(!dir.join("frames/frame_000002.vtu").exists());
}

#[test]
fn frame_capture_sorts_bodies_by_id_whatever_the_gather_order() {
    let (clock, g) = stepped_group(3);
    let a = Frame::capture(clock.time, clock.step, &[&g.bodies[0], &g.bodies[1]]);
    let b = Frame::capture(clock.time, clock.step, &[&g.bodies[1], &g.bodies[0]]);
    assert_eq!(a, b);
    assert_eq!(
        a.bodies.iter().map(|b| b.id).collect::<Vec<_>>(),
        vec![1, 3]
    );
    let sphere = &a.bodies[0];
    assert_eq!(sphere.von_mises_top.len(), sphere.tris.len());
    assert_eq!(sphere.f_contact.len(), sphere.x.len());
}
