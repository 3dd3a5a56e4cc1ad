//! Pictures: decode, size, not blank, plausible coverage, round spheres; energy plot and
//! contact sheet; `render_run` over a written series.

mod common;

use common::{stepped_group, test_dir};
use crash_core::shapes::icosphere;
use crash_core::{Body, EnergyTotals, Stabilization, Vec3};
use crash_io::render::image::WHITE;
use crash_io::render::load_png;
use crash_io::{
    contact_sheet, energy_plot, render_frame, render_run, Camera, Colouring, EnergyHistory,
    EnergyRow, Frame, Image, RenderOptions, SeriesWriter, View,
};

/// Pixel bounding box (x0, y0, x1, y1) and count of non-background pixels in a region.
fn coverage(img: &Image, w: u32, h: u32) -> (u32, u32, u32, u32, usize) {
    let (mut x0, mut y0, mut x1, mut y1, mut n) = (u32::MAX, u32::MAX, 0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            if img.get(x, y) != WHITE {
                n += 1;
                x0 = x0.min(x);
                y0 = y0.min(y);
                x1 = x1.max(x);
                y1 = y1.max(y);
            }
        }
    }
    (x0, y0, x1, y1, n)
}

fn sphere_frame() -> Frame {
    let m = icosphere(0.1, 3);
    let b = Body::new(
        0,
        "ball",
        &m,
        common::steel(0.001),
        Stabilization::default(),
    )
    .expect("ball");
    Frame::capture(0.0, 0, &[&b])
}

#[test]
fn sphere_renders_as_a_round_blob_filling_the_view() {
    let dir = test_dir("pictures_sphere");
    let opts = RenderOptions {
        width: 640,
        height: 480,
        time_label: false,
        ..RenderOptions::default()
    };
    let img = render_frame(&sphere_frame(), &opts);
    let path = dir.join("sphere.png");
    img.save_png(&path).expect("save");
    let back = load_png(&path).expect("decode");
    assert_eq!((back.width, back.height), (640, 480));
    assert_eq!(back, img);
    let (x0, y0, x1, y1, n) = coverage(&back, 640, 480);
    let (w, h) = ((x1 - x0 + 1) as f64, (y1 - y0 + 1) as f64);
    assert!((w / h - 1.0).abs() < 0.1, "aspect {w} x {h}");
    // Fitted to the view: the disc spans most of the height (margin 6%).
    assert!(h > 0.85 * 480.0 && h <= 480.0, "height {h}");
    // A disc covers pi/4 of its bounding box.
    let fill = n as f64 / (w * h);
    assert!(
        (fill - std::f64::consts::FRAC_PI_4).abs() < 0.05,
        "fill {fill}"
    );
    assert!(
        back.distinct_colours() > 20,
        "shaded: {}",
        back.distinct_colours()
    );
}

#[test]
fn stress_picture_has_legend_and_many_colours() {
    let dir = test_dir("pictures_stress");
    let (clock, g) = stepped_group(40);
    let refs: Vec<&Body> = g.bodies.iter().collect();
    let frame = Frame::capture(clock.time, clock.step, &refs);
    let by_body = render_frame(&frame, &RenderOptions::default());
    by_body.save_png(dir.join("by_body.png")).expect("save");
    let stress = render_frame(
        &frame,
        &RenderOptions {
            colour: Colouring::ByVonMises { range: None },
            ..RenderOptions::default()
        },
    );
    stress.save_png(dir.join("stress.png")).expect("save");
    assert_eq!((stress.width, stress.height), (800, 600));
    let (_, _, _, _, n) = coverage(&by_body, 800, 600);
    let frac = n as f64 / (800.0 * 600.0);
    assert!(frac > 0.1 && frac < 0.9, "bodies cover {frac}");
    assert!(stress.distinct_colours() > 100);
    // The legend bar runs from blue (bottom) to red (top) at the right edge.
    let col = stress.width - crash_io::render::scale::legend_width(600) + 18;
    let top = stress.get(col, 100);
    let bottom = stress.get(col, 600 - 32);
    assert!(top[0] > 100 && top[2] < 60, "top of legend is red: {top:?}");
    assert!(
        bottom[2] > 80 && bottom[0] < 90,
        "bottom of legend is blue: {bottom:?}"
    );
}

#[test]
fn contact_sheet_is_a_grid_of_cells_with_one_camera() {
    let dir = test_dir("pictures_sheet");
    let mut frames = Vec::new();
    for k in 0..5 {
        let mut f = sphere_frame();
        for p in &mut f.bodies[0].x {
            *p += Vec3::new(0.0, 0.0, -0.1 * k as f64);
        }
        f.time = k as f64 * 1e-3;
        frames.push(f);
    }
    let cell = RenderOptions {
        width: 300,
        height: 200,
        ..RenderOptions::default()
    };
    let sheet = contact_sheet(&frames, 3, &cell);
    sheet.save_png(dir.join("sheet.png")).expect("save");
    assert_eq!((sheet.width, sheet.height), (900, 400));
    // Same camera: the sphere moves down from cell to cell. Centroid of its (bluish)
    // pixels per cell; labels are black and the grid grey, so they do not count.
    let centroid_y = |k: u32| {
        let (cx, cy) = ((k % 3) * 300, (k / 3) * 200);
        let (mut sum, mut n) = (0.0, 0usize);
        for y in 0..200 {
            for x in 0..300 {
                let p = sheet.get(cx + x, cy + y);
                if p[2] as i32 > p[0] as i32 + 30 {
                    sum += y as f64;
                    n += 1;
                }
            }
        }
        assert!(n > 500, "cell {k} shows the sphere ({n} px)");
        sum / n as f64
    };
    let ys: Vec<f64> = (0..5).map(centroid_y).collect();
    let steps: Vec<f64> = ys.windows(2).map(|w| w[1] - w[0]).collect();
    // Equal world steps give equal picture steps (orthographic, one camera).
    for d in &steps {
        assert!((d - steps[0]).abs() < 1.5 && *d > 5.0, "centroids {ys:?}");
    }
    // The sixth cell of the grid stays empty.
    assert_eq!(sheet.get(2 * 300 + 150, 200 + 100), WHITE);
}

fn energy_rows() -> Vec<EnergyRow> {
    // A bounce: kinetic turns into internal energy and back, a little is dissipated.
    (0..=400)
        .map(|k| {
            let t = k as f64 * 1e-5;
            let s = (std::f64::consts::PI * t / 4e-3).sin().powi(2);
            let damping = 0.05 * t / 4e-3;
            EnergyRow {
                time: t,
                energy: EnergyTotals {
                    kinetic: (1.0 - damping) * (1.0 - s),
                    internal: (1.0 - damping) * 0.9 * s,
                    hourglass: 0.02 * s,
                    contact: 0.08 * s,
                    damping,
                    external: 0.0,
                    balance_error: 0.0,
                    run_error: 0.0,
                },
            }
        })
        .collect()
}

#[test]
fn energy_plot_draws_every_series_with_axes() {
    let dir = test_dir("pictures_energy");
    let img = energy_plot(&energy_rows(), 1000, 600);
    img.save_png(dir.join("energy.png")).expect("save");
    assert_eq!((img.width, img.height), (1000, 600));
    let has = |c: [u8; 3]| img.rgb.chunks_exact(3).filter(|p| *p == c).count();
    for c in [
        [31, 119, 180],
        [255, 127, 14],
        [148, 103, 189],
        [214, 39, 40],
        [140, 86, 75],
    ] {
        assert!(has(c) > 50, "series colour {c:?} drawn ({})", has(c));
    }
    assert!(has([0, 0, 0]) > 500, "axes, labels and the total line");
}

#[test]
fn render_run_writes_snapshots_sheet_and_energy_plot() {
    let dir = test_dir("render_run");
    let mut series = SeriesWriter::create(&dir).expect("series");
    let mut energy = EnergyHistory::create(dir.join("energy.csv")).expect("csv");
    let (mut clock, mut g) = stepped_group(0);
    let mut reports = g.start().expect("start");
    for k in 0..=40 {
        if k % 8 == 0 {
            let refs: Vec<&Body> = g.bodies.iter().collect();
            series
                .write(&Frame::capture(clock.time, clock.step, &refs))
                .expect("frame");
        }
        let e = EnergyTotals::sum(reports.iter().map(|r| &r.energy));
        energy.write(clock.time, &e).expect("row");
        let h = 0.9
            * reports
                .iter()
                .map(|r| r.stable_dt)
                .fold(f64::INFINITY, f64::min);
        reports = g.advance(&clock, h).expect("step");
        clock = clock.after(h);
    }
    energy.flush().expect("flush");
    let written = render_run(&dir).expect("render");
    let names: Vec<String> = written
        .iter()
        .map(|p| p.file_name().expect("name").to_string_lossy().into_owned())
        .collect();
    // Six snapshots, the sheet, the energies (totals: no matsum.csv) and the balance; no
    // contact, so no contact views and no contact-force plot.
    assert_eq!(names.len(), 6 + 3, "{names:?}");
    for n in ["sheet.png", "energies.png", "energy.png"] {
        assert!(names.contains(&n.to_string()), "{n} in {names:?}");
    }
    for p in &written {
        let img = load_png(p).expect("decodes");
        assert!(img.distinct_colours() > 10, "{p:?} is not blank");
    }
    let snap = load_png(&written[0]).expect("snapshot");
    assert_eq!((snap.width, snap.height), (800, 600));
    let sheet = load_png(dir.join("pictures/sheet.png")).expect("sheet");
    // No contact: the start and the end only.
    assert_eq!((sheet.width, sheet.height), (2 * 480, 360));
}

#[test]
fn explicit_camera_is_used_as_given() {
    let f = sphere_frame();
    let auto = View::fit_frames([&f]).expect("view");
    let far = auto.widen(2.0);
    let opts = RenderOptions {
        width: 400,
        height: 400,
        time_label: false,
        camera: Camera::View(far),
        ..RenderOptions::default()
    };
    let img = render_frame(&f, &opts);
    let (x0, _, x1, _, _) = coverage(&img, 400, 400);
    let near = render_frame(
        &f,
        &RenderOptions {
            camera: Camera::Auto,
            ..opts
        },
    );
    let (n0, _, n1, _, _) = coverage(&near, 400, 400);
    let ratio = (n1 - n0 + 1) as f64 / (x1 - x0 + 1) as f64;
    assert!(
        (ratio - 2.0).abs() < 0.05,
        "twice the view, half the size: {ratio}"
    );
}

#[test]
fn fine_mesh_picture_is_not_darkened_by_edges() {
    // A level-5 sphere (20480 triangles) is too fine for edge lines: its pixels keep the
    // shaded body colour (mean brightness near that of the edge-free picture).
    let m = icosphere(0.1, 5);
    let b = Body::new(
        0,
        "ball",
        &m,
        common::steel(0.001),
        Stabilization::default(),
    )
    .expect("ball");
    let f = Frame::capture(0.0, 0, &[&b]);
    let o = RenderOptions {
        width: 400,
        height: 300,
        ..RenderOptions::default()
    };
    let with = render_frame(&f, &o);
    let without = render_frame(&f, &RenderOptions { edges: false, ..o });
    with.save_png(test_dir("pictures_fine").join("fine.png"))
        .expect("save");
    let mean = |img: &Image| img.rgb.iter().map(|&v| v as f64).sum::<f64>() / img.rgb.len() as f64;
    assert!(
        (mean(&with) - mean(&without)).abs() < 0.5,
        "{} vs {}",
        mean(&with),
        mean(&without)
    );
}
