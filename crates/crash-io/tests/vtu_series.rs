//! The .vtu/.pvd series read back by an independent reader (vtkio) and by our own.

mod common;

use common::{stepped_group, test_dir};
use crash_io::{read_pvd, read_vtu, Encoding, Frame, SeriesWriter};
use vtkio::model::{Attribute, CellType, DataSet, IOBuffer, Piece, VertexNumbers};

fn frame_at(steps: usize) -> Frame {
    let (clock, g) = stepped_group(steps);
    // Reverse the body order: a master gathers bodies in any order.
    let refs: Vec<&crash_core::Body> = g.bodies.iter().rev().collect();
    Frame::capture(clock.time, clock.step, &refs)
}

fn f64s(b: &IOBuffer) -> Vec<f64> {
    b.clone().cast_into::<f64>().expect("numeric buffer")
}

fn attr<'a>(list: &'a [Attribute], name: &str) -> &'a IOBuffer {
    list.iter()
        .find_map(|a| match a {
            Attribute::DataArray(d) if d.name == name => Some(&d.data),
            _ => None,
        })
        .unwrap_or_else(|| panic!("attribute {name} missing"))
}

fn check_with_vtkio(path: &std::path::Path, frame: &Frame) {
    let vtk = vtkio::Vtk::import(path).expect("vtkio reads the .vtu");
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid")
    };
    // one piece per body, in id order: sphere (id 1, triangles) first
    assert_eq!(pieces.len(), frame.bodies.len());
    assert_eq!(frame.bodies[0].id, 1);
    let piece = |k: usize| {
        let Piece::Inline(p) = &pieces[k] else {
            panic!("piece not inline")
        };
        p
    };
    for (k, b) in frame.bodies.iter().enumerate() {
        let p = piece(k);
        assert_eq!(p.num_points(), b.x.len());
        let (nt, nq) = (b.tris.len(), b.quads.len());
        assert_eq!(p.cells.types.len(), nt + nq);
        let tri = p
            .cells
            .types
            .iter()
            .filter(|t| **t == CellType::Triangle)
            .count();
        let quad = p
            .cells
            .types
            .iter()
            .filter(|t| **t == CellType::Quad)
            .count();
        assert_eq!((tri, quad), (nt, nq), "triangles and quads kept as such");
        let fc = f64s(attr(&p.data.point, "contact_force"));
        assert_eq!(fc.len(), 3 * b.x.len());
    }
    let (b0, b1) = (&frame.bodies[0], &frame.bodies[1]);
    let (p0, p1) = (piece(0), piece(1));
    assert_eq!(p0.cells.types[0], CellType::Triangle);
    assert_eq!(p1.cells.types[b1.quads.len() - 1], CellType::Quad);

    // Exact values: points, a connectivity entry of the second body, stresses, ids.
    let (pts0, pts1) = (f64s(&p0.points), f64s(&p1.points));
    let n0 = b0.x.len();
    for (pts, i, q) in [
        (&pts0, 0usize, b0.x[0]),
        (&pts0, n0 - 1, b0.x[n0 - 1]),
        (&pts1, 5, b1.x[5]),
    ] {
        assert_eq!(
            [pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]],
            [q.x, q.y, q.z]
        );
    }
    let VertexNumbers::XML {
        connectivity,
        offsets,
    } = &p1.cells.cell_verts
    else {
        panic!("xml cells")
    };
    assert_eq!(offsets[0] as usize, 4);
    let q0: Vec<u64> = b1.quads[0].iter().map(|&n| n as u64).collect();
    assert_eq!(&connectivity[0..4], &q0[..]);
    let vm0 = f64s(attr(&p0.data.cell, "von_mises_top"));
    assert_eq!(vm0[7], b0.von_mises_top[7]);
    let vm1 = f64s(attr(&p1.data.cell, "von_mises_top"));
    assert_eq!(vm1[3], b1.von_mises_top[3]);
    assert!(b1.von_mises_top[3] > 0.0, "the plate is stressed");
    let vb = f64s(attr(&p1.data.cell, "von_mises_bottom"));
    assert_eq!(vb[3], b1.von_mises_bottom[3]);
    let mm = f64s(attr(&p1.data.cell, "bending_M"));
    assert_eq!(mm[3 * 2 + 1], b1.m[2][1]);
    let (th0, th1) = (
        f64s(attr(&p0.data.cell, "thickness")),
        f64s(attr(&p1.data.cell, "thickness")),
    );
    assert_eq!((th0[0], th1[0]), (0.001, 0.002));
    let (c0, c1) = (
        f64s(attr(&p0.data.cell, "body_id")),
        f64s(attr(&p1.data.cell, "body_id")),
    );
    assert_eq!((c0[0], c1[0]), (1.0, 3.0));
    let pid = f64s(attr(&p1.data.point, "body_id"));
    assert_eq!(pid[0], 3.0);
    let u = f64s(attr(&p1.data.point, "displacement"));
    assert_eq!(u[2], b1.x[0].z - b1.x0[0].z);
    assert!(u[2] != 0.0, "the plate has moved");
    let v = f64s(attr(&p0.data.point, "velocity"));
    assert_eq!(v[4], b0.v[1].y);
}

#[test]
fn vtu_read_by_vtkio_has_counts_types_and_exact_values_ascii_and_binary() {
    let frame = frame_at(20);
    for (enc, name) in [(Encoding::Ascii, "ascii"), (Encoding::Base64, "binary")] {
        let dir = test_dir(&format!("vtkio_{name}"));
        let mut w = SeriesWriter::create(&dir)
            .expect("create")
            .with_encoding(enc);
        let path = w.write(&frame).expect("write");
        let text = std::fs::read_to_string(&path).expect("read");
        assert!(text.contains(&format!("format=\"{name}\"")));
        check_with_vtkio(&path, &frame);
    }
}

#[test]
fn own_reader_round_trips_a_frame_exactly() {
    let frame = frame_at(15);
    for enc in [Encoding::Ascii, Encoding::Base64] {
        let dir = test_dir(&format!("own_reader_{enc:?}"));
        let mut w = SeriesWriter::create(&dir)
            .expect("create")
            .with_encoding(enc);
        let back = read_vtu(&w.write(&frame).expect("write")).expect("read");
        assert_eq!(back.time.to_bits(), frame.time.to_bits());
        assert_eq!(back.step, frame.step);
        assert_eq!(back.bodies.len(), 2);
        for (a, b) in back.bodies.iter().zip(&frame.bodies) {
            assert_eq!((a.id, a.thickness), (b.id, b.thickness));
            assert_eq!((&a.x, &a.v, &a.f_contact), (&b.x, &b.v, &b.f_contact));
            assert_eq!((&a.tris, &a.quads), (&b.tris, &b.quads));
            assert_eq!(
                (&a.von_mises_top, &a.von_mises_bottom),
                (&b.von_mises_top, &b.von_mises_bottom)
            );
            assert_eq!((&a.n, &a.m), (&b.n, &b.m));
            // x0 comes back as x - (x - x0): equal to rounding.
            for (p, q) in a.x0.iter().zip(&b.x0) {
                assert!((p - q).norm() <= 1e-15 * (1.0 + q.norm()));
            }
        }
    }
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
