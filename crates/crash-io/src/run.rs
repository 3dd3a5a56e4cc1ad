//! `crash render OUT_DIR`: pictures of a finished (or interrupted) run from its files.

use crate::error::{AtPath, IoError};
use crate::history::{read_energy_csv, ENERGY_CSV};
use crate::render::camera::Fit;
use crate::render::energy_plot;
use crate::render::scene::{render_frame, Camera, Colouring, RenderOptions};
use crate::render::sheet::sheet_from_cells;
use crate::series::{read_pvd, PVD_FILE};
use crate::vtu_read::read_vtu;
use std::path::{Path, PathBuf};

/// Sub-directory of the output directory that receives the pictures.
pub const PICTURES_DIR: &str = "pictures";
/// Frames on the contact sheet (evenly spread over the series).
pub const SHEET_FRAMES: usize = 6;
pub const SHEET_COLS: usize = 3;

/// Indices of `n` frames spread evenly over `len` (first and last included).
fn spread(len: usize, n: usize) -> Vec<usize> {
    if len <= n {
        return (0..len).collect();
    }
    let mut v: Vec<usize> = (0..n)
        .map(|k| ((k * (len - 1)) as f64 / (n - 1) as f64).round() as usize)
        .collect();
    v.dedup();
    v
}

/// Read the series in `out_dir` and write, under `out_dir/pictures/`: one von Mises
/// snapshot per frame (`frame_NNNNNN.png`), `sheet.png` (bodies coloured by id) and
/// `energy.png` (when energy.csv exists). All pictures share one camera and one stress
/// scale. Returns the paths written.
pub fn render_run(out_dir: impl AsRef<Path>) -> Result<Vec<PathBuf>, IoError> {
    let dir = out_dir.as_ref();
    let entries = read_pvd(&dir.join(PVD_FILE))?;
    let pics = dir.join(PICTURES_DIR);
    std::fs::create_dir_all(&pics).at(&pics)?;
    let mut written = Vec::new();

    // Pass 1: common camera and stress scale (frames are read twice to bound memory).
    let mut fit = Fit::three_quarter();
    let mut vm_max = 0.0f64;
    for e in &entries {
        let f = read_vtu(&dir.join(&e.file))?;
        vm_max = vm_max.max(f.max_von_mises());
        fit.add_frame(&f);
    }
    let camera = fit.view().map_or(Camera::Auto, Camera::View);
    let snap = RenderOptions {
        colour: Colouring::ByVonMises {
            max: (vm_max > 0.0).then_some(vm_max),
        },
        camera,
        ..RenderOptions::default()
    };
    let cell = RenderOptions {
        width: 480,
        height: 360,
        camera,
        ..RenderOptions::default()
    };
    let on_sheet = spread(entries.len(), SHEET_FRAMES);
    let mut cells = Vec::new();

    // Pass 2: pictures.
    for (k, e) in entries.iter().enumerate() {
        let f = read_vtu(&dir.join(&e.file))?;
        let stem = Path::new(&e.file).file_stem().map_or_else(
            || format!("frame_{k:06}"),
            |s| s.to_string_lossy().into_owned(),
        );
        let path = pics.join(format!("{stem}.png"));
        render_frame(&f, &snap).save_png(&path)?;
        written.push(path);
        if on_sheet.contains(&k) {
            cells.push(render_frame(&f, &cell));
        }
    }
    if !cells.is_empty() {
        let path = pics.join("sheet.png");
        sheet_from_cells(&cells, SHEET_COLS).save_png(&path)?;
        written.push(path);
    }
    let csv = dir.join(ENERGY_CSV);
    if csv.exists() {
        let rows = read_energy_csv(&csv)?;
        let path = pics.join("energy.png");
        energy_plot(&rows, 1000, 600).save_png(&path)?;
        written.push(path);
    }
    Ok(written)
}
