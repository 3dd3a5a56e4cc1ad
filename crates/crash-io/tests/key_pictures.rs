//! Pictures that show what happened: key moments picked from the force history, the
//! contact zone located from nodal forces, the section cut, one colour scale per
//! picture, the history plots' axes, matsum.csv, and `render_run` over a synthetic
//! bounce (series, contacts.csv, energy.csv, matsum.csv).

mod common;

use common::{stepped_group, test_dir};
use crash_core::shapes::{icosphere, plate, ElementKind};
use crash_core::{Body, EnergyTotals, Stabilization, Vec3};
use crash_io::history::{ContactHistory, ContactRow};
use crash_io::matsum_read::{read_matsum_csv, MATSUM_CSV, MATSUM_HEADER};
use crash_io::render::contact_zone::contact_zone;
use crash_io::render::histories::{body_energy_plot, contact_force_plot};
use crash_io::render::image::WHITE;
use crash_io::render::lines::{fit_axes, Line};
use crash_io::render::load_png;
use crash_io::render::moments::{key_moments, panels, ForceSeries, KeyMoments, Reason};
use crash_io::render::scale::Scale;
use crash_io::render::scene::{format_number, frame_scale};
use crash_io::render::section::{cut_frame, render_section, Plane, Section};
use crash_io::render::zone_views::view_from_below;
use crash_io::{render_run, Colouring, EnergyHistory, Frame, Image, RenderOptions, SeriesWriter};

#[test]
fn key_moments_of_synthetic_histories_are_the_known_indices() {
    // A single bounce: touches at 3, peaks at 5, back to zero at 8, a second touch at 10.
    let bounce = [0.0, 0.0, 0.0, 1.0, 3.0, 7.0, 5.0, 2.0, 0.0, 0.0, 4.0, 0.0];
    assert_eq!(
        key_moments(&bounce),
        KeyMoments {
            first_contact: Some(3),
            peak: Some(5),
            separation: Some(8)
        }
    );
    // Chatter before the peak does not count as separation; the first of equal peaks.
    let chatter = [0.0, 2.0, 0.0, 1.0, 5.0, 3.0, 5.0, 0.0];
    assert_eq!(
        key_moments(&chatter),
        KeyMoments {
            first_contact: Some(1),
            peak: Some(4),
            separation: Some(7)
        }
    );
    // Still in contact at the end: no separation. NaN is no force.
    let pressed = [f64::NAN, 0.0, 1.0, 2.0, 2.5];
    assert_eq!(
        key_moments(&pressed),
        KeyMoments {
            first_contact: Some(2),
            peak: Some(4),
            separation: None
        }
    );
    assert_eq!(key_moments(&[0.0; 5]), KeyMoments::default());
}

#[test]
fn force_series_sums_pairs_and_counts_steps_without_rows_as_zero() {
    let row = |time, a, b, force| ContactRow {
        time,
        a,
        b,
        force,
        penetration: 0.0,
    };
    let rows = [
        row(0.2, 0, 1, 3.0),
        row(0.2, 1, 2, 4.0),
        row(0.35, 0, 1, 1.0),
    ];
    let s = ForceSeries::from_rows(&[0.0, 0.1, 0.2, 0.3], &rows);
    assert_eq!(s.time, vec![0.0, 0.1, 0.2, 0.3, 0.35]);
    assert_eq!(s.total, vec![0.0, 0.0, 7.0, 0.0, 1.0]);
}

#[test]
fn panels_are_the_frames_nearest_the_moments_and_share_a_frame() {
    // Records every 0.1 s, frames every 1 s: contact from 1.2 s, peak at 2.9 s, zero
    // again from 3.6 s.
    let time: Vec<f64> = (0..=50).map(|k| k as f64 * 0.1).collect();
    let total: Vec<f64> = time
        .iter()
        .map(|&t| {
            if (1.15..3.55).contains(&t) {
                10.0 - (t - 2.9f64).abs()
            } else {
                0.0
            }
        })
        .collect();
    let frames = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    let p = panels(&frames, &ForceSeries { time, total });
    let got: Vec<(usize, Vec<Reason>)> = p.iter().map(|p| (p.frame, p.reasons.clone())).collect();
    assert_eq!(
        got,
        vec![
            (0, vec![Reason::Start]),
            (1, vec![Reason::FirstContact]),
            (3, vec![Reason::PeakForce]),
            (4, vec![Reason::Separation]),
            (5, vec![Reason::End]),
        ]
    );
    assert!((p[1].moment_time - 1.2).abs() < 1e-12 && (p[2].moment_time - 2.9).abs() < 1e-12);
    // With frames at 0 and 3 only, contact and peak fall on shared frames.
    let two = panels(
        &[0.0, 3.0],
        &ForceSeries {
            time: vec![0.0, 1.0, 2.9, 3.0],
            total: vec![0.0, 1.0, 9.0, 0.0],
        },
    );
    assert_eq!(two[0].reasons, vec![Reason::Start, Reason::FirstContact]);
    assert_eq!(two[1].label(), "peak contact force, separation, end");
}

fn sphere_body(id: u32, r: f64, level: u32, centre: Vec3) -> Body {
    let mut m = icosphere(r, level);
    m.transform(&nalgebra::Matrix3::identity(), centre);
    Body::new(
        id,
        "sphere",
        &m,
        common::steel(0.001),
        Stabilization::default(),
    )
    .expect("sphere")
}

#[test]
fn section_of_a_sphere_through_its_centre_is_a_circle_of_its_radius() {
    let (r, c) = (0.1, Vec3::new(0.3, -0.2, 0.5));
    let b = sphere_body(0, r, 4, c);
    let frame = Frame::capture(0.0, 0, &[&b]);
    let plane = Plane {
        point: c,
        normal: Vec3::new(0.0, 1.0, 0.0),
    };
    let segs = cut_frame(&frame, &plane, None);
    // An inscribed polygon of the great circle: its perimeter is a little under 2 pi r.
    let perimeter: f64 = segs.iter().map(|s| (s.b - s.a).norm()).sum();
    let circle = std::f64::consts::TAU * r;
    assert!(
        perimeter < circle && perimeter > 0.995 * circle,
        "{perimeter} vs {circle}"
    );
    let d: Vec<f64> = segs
        .iter()
        .flat_map(|s| [s.a, s.b])
        .map(|p| (p - c).norm())
        .collect();
    // Crossings lie on edges between nodes on the sphere: within the sag of the
    // longest edge L below r, r - sqrt(r^2 - L^2 / 4).
    let fb = &frame.bodies[0];
    let longest = fb
        .tris
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(i, j)| (fb.x[i as usize] - fb.x[j as usize]).norm())
        .fold(0.0, f64::max);
    let sag = r - (r * r - longest * longest / 4.0).sqrt();
    assert!(sag < 2e-3 * r, "fine mesh: sag {sag}");
    for (k, s) in segs.iter().enumerate() {
        assert!(plane.distance(&s.a).abs() < 1e-12 && plane.distance(&s.b).abs() < 1e-12);
        assert!(
            d[2 * k] <= r + 1e-12 && d[2 * k] >= r - sag - 1e-12,
            "{} vs {r}, sag {sag}",
            d[2 * k]
        );
    }
    // A closed curve: every end point is the end of exactly two segments.
    let key = |p: Vec3| [p.x, p.y, p.z].map(|v| (v * 1e9).round() as i64);
    let mut ends: Vec<[i64; 3]> = segs.iter().flat_map(|s| [key(s.a), key(s.b)]).collect();
    ends.sort_unstable();
    for w in ends.chunk_by(|a, b| a == b) {
        assert_eq!(w.len(), 2, "open end at {:?}", w[0]);
    }
    // In pixels: 600 px for 0.3 m, so the circle is 2 r x 2000 px/m = 400 px wide on the
    // centre row (within the 2.5 px line).
    let section = Section {
        plane,
        up: Vec3::z(),
        centre: c,
        mark: c,
        half_width: 0.15,
    };
    let (img, _) = render_section(&frame, &section, 600, 600, None);
    let bluish = |x: u32, y: u32| {
        let p = img.get(x, y);
        p[2] as i32 > p[0] as i32 + 40
    };
    let row: Vec<u32> = (0..600).filter(|&x| bluish(x, 300)).collect();
    let (x0, x1) = (row[0], row[row.len() - 1]);
    assert!(
        ((x1 - x0) as f64 - 400.0).abs() <= 4.0,
        "circle {x0}..{x1} on the centre row"
    );
    let col: Vec<u32> = (0..600).filter(|&y| bluish(300, y)).collect();
    let (y0, y1) = (col[0], col[col.len() - 1]);
    assert!(((y1 - y0) as f64 - 400.0).abs() <= 4.0, "circle {y0}..{y1}");
}

/// A plate (id 0) at z = 0 and a sphere (id 1) resting on it at (0.03, -0.02), with
/// contact forces on the nodes within `rc` of the touching point.
fn pressed_frame(rc: f64) -> Frame {
    let touch = Vec3::new(0.03, -0.02, 0.0);
    let pm = plate(0.4, 0.4, 40, 40, ElementKind::Quad);
    let p = Body::new(
        0,
        "plate",
        &pm,
        common::steel(0.002),
        Stabilization::default(),
    )
    .expect("plate");
    let s = sphere_body(1, 0.1, 4, touch + Vec3::new(0.0, 0.0, 0.1015));
    let mut f = Frame::capture(1e-3, 10, &[&p, &s]);
    for (b, sign) in f.bodies.iter_mut().zip([-1.0, 1.0]) {
        for (x, fc) in b.x.iter().zip(b.f_contact.iter_mut()) {
            let d = (x - touch).xy().norm();
            if d < rc && x.z < 0.01 {
                *fc = Vec3::new(0.0, 0.0, sign * (1.0 - d / rc));
            }
        }
    }
    f
}

#[test]
fn contact_zone_is_centred_where_the_forces_act() {
    let f = pressed_frame(0.03);
    let z = contact_zone(&f, Some((0, 1))).expect("zone");
    assert_eq!(
        (z.hidden, z.kept),
        (0, 1),
        "the plate is below and left out"
    );
    assert!(
        (z.centre.xy() - Vec3::new(0.03, -0.02, 0.0).xy()).norm() < 2e-3,
        "{:?}",
        z.centre
    );
    assert!(
        (z.normal - Vec3::z()).norm() < 1e-9,
        "force on the sphere is up"
    );
    // Nodes up to rc (less one plate cell of 10 mm) carry at least 1 % of the peak force.
    assert!(z.radius > 0.019 && z.radius < 0.03, "radius {}", z.radius);
    let unnamed = contact_zone(&f, None).expect("zone of the two bodies with forces");
    assert!((unnamed.centre - z.centre).norm() < 1e-12);
    // Without forces there is no zone.
    let mut none = f.clone();
    none.bodies
        .iter_mut()
        .for_each(|b| b.f_contact.iter_mut().for_each(|v| *v = Vec3::zeros()));
    assert_eq!(contact_zone(&none, None), None);
    // From below with the plate left out, the sphere is a disc filling its view.
    let img = view_from_below(&f, &z, 500, 400);
    let plot_w = 500 - crash_io::render::scale::legend_width(400);
    let (mut n, mut x0, mut x1, mut y0, mut y1) = (0usize, u32::MAX, 0, u32::MAX, 0);
    for y in 70..400 {
        for x in 0..plot_w {
            if img.get(x, y) != WHITE {
                n += 1;
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
    }
    let (w, h) = ((x1 - x0 + 1) as f64, (y1 - y0 + 1) as f64);
    assert!(
        (w / h - 1.0).abs() < 0.05,
        "a disc, not the square plate: {w} x {h}"
    );
    let fill = n as f64 / (w * h);
    assert!(
        (fill - std::f64::consts::FRAC_PI_4).abs() < 0.05,
        "fill {fill}"
    );
}

#[test]
fn each_picture_states_its_own_colour_scale() {
    let frames: Vec<Frame> = [10, 40]
        .iter()
        .map(|&n| {
            let (clock, g) = stepped_group(n);
            let refs: Vec<&Body> = g.bodies.iter().collect();
            Frame::capture(clock.time, clock.step, &refs)
        })
        .collect();
    let range = |f: &Frame, id: Option<u32>| {
        let v: Vec<f64> = f
            .bodies
            .iter()
            .filter(|b| id.is_none_or(|i| b.id == i))
            .flat_map(|b| (0..b.element_count()).map(move |e| b.von_mises_max(e)))
            .collect();
        (
            v.iter().copied().fold(f64::INFINITY, f64::min),
            v.iter().copied().fold(0.0, f64::max),
        )
    };
    let opts = RenderOptions {
        colour: Colouring::ByVonMises { range: None },
        ..RenderOptions::default()
    };
    let scales: Vec<Scale> = frames
        .iter()
        .map(|f| frame_scale(f, &opts).expect("scale"))
        .collect();
    for (f, s) in frames.iter().zip(&scales) {
        assert_eq!((s.min, s.max), range(f, None));
        let [title, max, min] = s.texts();
        assert_eq!(title, "von Mises [MPa]");
        assert_eq!(
            max,
            format!("max {}", format_number(range(f, None).1 / 1e6))
        );
        assert_eq!(
            min,
            format!("min {}", format_number(range(f, None).0 / 1e6))
        );
    }
    assert_ne!(
        scales[0].max, scales[1].max,
        "one scale per picture, not per run"
    );
    // A body left out does not count toward the scale.
    let hidden = RenderOptions {
        hidden: Some(3),
        ..opts
    };
    let s = frame_scale(&frames[1], &hidden).expect("scale");
    assert_eq!((s.min, s.max), range(&frames[1], Some(1)));
    // The bar on the picture runs blue (min, bottom) to red (max, top).
    let img = crash_io::render_frame(&frames[1], &opts);
    let x = 800 - crash_io::render::scale::legend_width(600) + 8 + 10;
    let (top, bottom) = (img.get(x, 100), img.get(x, 600 - 32));
    assert!(top[0] > 100 && top[2] < 60, "top red: {top:?}");
    assert!(bottom[2] > 80 && bottom[0] < 90, "bottom blue: {bottom:?}");
}

#[test]
fn plot_axes_cover_the_data() {
    let lines = vec![
        Line {
            name: "a".into(),
            colour: [0, 0, 0],
            points: vec![(0.5, 2.0), (1.5, -3.0), (f64::NAN, 99.0)],
        },
        Line {
            name: "b".into(),
            colour: [0, 0, 0],
            points: vec![(2.5, 7.0)],
        },
    ];
    let a = fit_axes(&lines);
    assert_eq!(a.x, (0.5, 2.5));
    assert!(a.y.0 <= -3.0 && a.y.1 >= 7.0 && a.y.1 < 7.6, "{:?}", a.y);
    let series = ForceSeries {
        time: vec![0.0, 1e-4, 2e-4, 3e-4],
        total: vec![0.0, 500.0, 1500.0, 0.0],
    };
    let row = |time, force| ContactRow {
        time,
        a: 0,
        b: 1,
        force,
        penetration: 0.0,
    };
    let rows = [row(1e-4, 500.0), row(2e-4, 1500.0)];
    let names = [(0, "plate".to_string()), (1, "sphere".to_string())];
    let (img, axes) = contact_force_plot(&series, &rows, &names, 900, 500);
    assert_eq!(axes.x, (0.0, 0.3), "ms");
    assert!(axes.y.0 == 0.0 && axes.y.1 >= 1500.0, "{:?}", axes.y);
    assert!(img.distinct_colours() > 10);
}

fn write_matsum(path: &std::path::Path, rows: &[(u64, f64, &str, f64)]) {
    let mut s = format!("{MATSUM_HEADER}\n");
    for (step, t, body, ke) in rows {
        s += &format!(
            "{step},{t:e},{body},{ke:e},{:e},0,{:e}\n",
            1.0 - ke,
            0.01 * t
        );
    }
    std::fs::write(path, s).expect("fixture");
}

#[test]
fn matsum_is_read_and_bad_rows_name_the_line() {
    let dir = test_dir("matsum_read");
    let path = dir.join(MATSUM_CSV);
    write_matsum(
        &path,
        &[
            (0, 0.0, "sphere", 1.0),
            (0, 0.0, "\"plate, fixed\"", 0.0),
            (5, 1e-4, "sphere", 0.5),
        ],
    );
    let rows = read_matsum_csv(&path).expect("read");
    assert_eq!(rows.len(), 3);
    assert_eq!((rows[1].step, rows[1].body.as_str()), (0, "plate, fixed"));
    assert_eq!(
        (rows[2].time, rows[2].kinetic, rows[2].internal),
        (1e-4, 0.5, 0.5)
    );
    std::fs::write(
        &path,
        format!("{MATSUM_HEADER}\n0,0,sphere,1,0,0,0\n1,x,sphere,1,0,0,0\n"),
    )
    .expect("w");
    let e = read_matsum_csv(&path).expect_err("bad time").to_string();
    assert!(
        e.contains("matsum.csv") && e.contains("line 3, column 2"),
        "{e}"
    );
    std::fs::write(&path, "time,body,kinetic\n").expect("w");
    let e = read_matsum_csv(&path).expect_err("bad header").to_string();
    assert!(e.contains("line 1") && e.contains(MATSUM_HEADER), "{e}");
    // Per body in the body's picture colour.
    let names = [(0, "plate, fixed".to_string()), (1, "sphere".to_string())];
    let img = body_energy_plot(&rows, &names, 1200, 800);
    let has = |c: [u8; 3]| img.rgb.chunks_exact(3).filter(|p| *p == c).count();
    let (plate, sphere) = (
        crash_io::render::colour::body_colour(0),
        crash_io::render::colour::body_colour(1),
    );
    assert!(
        has(plate) > 50 && has(sphere) > 50,
        "{} {}",
        has(plate),
        has(sphere)
    );
}

#[test]
fn render_run_shows_the_key_moments_and_the_contact_zone() {
    let dir = test_dir("render_key_moments");
    // A sphere comes down onto a plate, presses (forces rise and fall) and leaves.
    let mut series = SeriesWriter::create(&dir).expect("series");
    let mut energy = EnergyHistory::create(dir.join("energy.csv")).expect("energy");
    let mut contacts = ContactHistory::create(dir.join("contacts.csv")).expect("contacts");
    let base = pressed_frame(0.03);
    let force = |k: usize| {
        if (3..=7).contains(&k) {
            1000.0 * (5.0 - (k as f64 - 5.0).abs())
        } else {
            0.0
        }
    };
    let mut matsum = vec![];
    for k in 0..=10usize {
        let t = k as f64 * 1e-4;
        let mut f = base.clone();
        (f.time, f.step) = (t, k as u64);
        for b in &mut f.bodies {
            b.f_contact.iter_mut().for_each(|v| *v *= force(k));
        }
        let lift = Vec3::new(0.0, 0.0, 0.002 * (k as f64 - 5.0).abs());
        f.bodies[1].x.iter_mut().for_each(|x| *x += lift);
        series.write(&f).expect("frame");
        energy
            .write(
                t,
                &EnergyTotals {
                    kinetic: 1.0,
                    ..EnergyTotals::default()
                },
            )
            .expect("e");
        if force(k) > 0.0 {
            contacts
                .write(&ContactRow {
                    time: t,
                    a: 0,
                    b: 1,
                    force: force(k),
                    penetration: 1e-6,
                })
                .expect("c");
        }
        matsum.push((k as u64, t, "sphere", 1.0 - force(k) / 5000.0));
        matsum.push((k as u64, t, "plate", 0.0));
    }
    energy.flush().expect("flush");
    contacts.flush().expect("flush");
    write_matsum(&dir.join(MATSUM_CSV), &matsum);
    let written = render_run(&dir).expect("render");
    let names: Vec<String> = written
        .iter()
        .map(|p| p.file_name().expect("name").to_string_lossy().into_owned())
        .collect();
    for n in [
        "sheet.png",
        "below.png",
        "section.png",
        "contact_force.png",
        "energies.png",
        "energy.png",
    ] {
        assert!(names.contains(&n.to_string()), "{n} in {names:?}");
    }
    assert_eq!(names.len(), 11 + 6);
    // Start (0), first contact (3), peak (5), separation (8), end (10) + below + section:
    // seven panels of 480 x 360, four columns.
    let sheet = load_png(dir.join("pictures/sheet.png")).expect("sheet");
    assert_eq!((sheet.width, sheet.height), (4 * 480, 2 * 360));
    let blank = |img: &Image, cx: u32, cy: u32| {
        (0..360).all(|y| (0..480).all(|x| img.get(cx + x, cy + y) == WHITE))
    };
    assert!(blank(&sheet, 3 * 480, 360), "the eighth cell is empty");
    for k in 0..7 {
        assert!(
            !blank(&sheet, (k % 4) * 480, (k / 4) * 360),
            "cell {k} drawn"
        );
    }
}
