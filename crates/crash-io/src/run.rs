//! `crash render OUT_DIR`: pictures of a finished (or interrupted) run from its files.

use crate::error::{AtPath, IoError};
use crate::frame::Frame;
use crate::history::{read_contacts_csv, read_energy_csv, ContactRow, CONTACTS_CSV, ENERGY_CSV};
use crate::matsum_read::{read_matsum_csv, MATSUM_CSV};
use crate::render::camera::Fit;
use crate::render::contact_zone::contact_zone;
use crate::render::energy_plot;
use crate::render::histories::{body_energy_plot, contact_force_plot, total_energy_fallback_plot};
use crate::render::moments::{key_moments, panels, ForceSeries, Panel};
use crate::render::scene::{format_time, render_frame, Camera, Colouring, RenderOptions};
use crate::render::sheet::sheet_from_cells;
use crate::render::zone_views::{section_view, view_from_below};
use crate::series::{read_pvd, PVD_FILE};
use crate::vtu_read::read_vtu;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Sub-directory of the output directory that receives the pictures.
pub const PICTURES_DIR: &str = "pictures";
/// Size of one panel of the contact sheet [px].
pub const CELL: (u32, u32) = (480, 360);

/// What pass 1 takes of one frame.
struct FrameFacts {
    fit: Fit,
    time: f64,
    force: f64,
    names: Vec<(u32, String)>,
}

/// What pass 2 makes of one frame: the files written (its snapshot, and at the peak
/// the contact zone's views), its sheet panel and its zone panels.
struct FramePictures {
    written: Vec<PathBuf>,
    cell: Option<crate::render::Image>,
    zone: Vec<crate::render::Image>,
}

/// Sum of the magnitudes of a frame's nodal contact forces, halved (each contact force
/// acts on both bodies): the contact-force history when contacts.csv is missing.
fn frame_contact_force(f: &Frame) -> f64 {
    let s: f64 = f
        .bodies
        .iter()
        .flat_map(|b| b.f_contact.iter())
        .map(|v| v.norm())
        .filter(|v| v.is_finite())
        .sum();
    0.5 * s
}

/// The body pair with the largest force at `time` (contacts.csv), if any.
fn pair_at(rows: &[ContactRow], time: f64) -> Option<(u32, u32)> {
    rows.iter()
        .filter(|r| r.time == time && r.force.is_finite())
        .max_by(|p, q| p.force.total_cmp(&q.force))
        .map(|r| (r.a, r.b))
}

/// Read the series and histories in `out_dir` and write under `out_dir/pictures/`:
/// - `frame_NNNNNN.png`: one snapshot per frame, von Mises stress on its own scale;
/// - `sheet.png`: the frames nearest the key moments (start, first contact, peak
///   contact force, separation, end), each labelled, plus the view from below and the
///   section cut at the peak;
/// - `below.png`, `section.png`: the contact zone at the peak, full size;
/// - `contact_force.png`: force per body pair over time (contacts.csv);
/// - `energies.png`: energies per body (matsum.csv; else totals of energy.csv);
/// - `energy.png`: the energy balance (energy.csv).
///
/// Returns the paths written.
pub fn render_run(out_dir: impl AsRef<Path>) -> Result<Vec<PathBuf>, IoError> {
    let dir = out_dir.as_ref();
    let entries = read_pvd(&dir.join(PVD_FILE))?;
    let pics = dir.join(PICTURES_DIR);
    std::fs::create_dir_all(&pics).at(&pics)?;
    let mut written = Vec::new();
    let save = |img: crate::render::Image, name: &str| -> Result<PathBuf, IoError> {
        let path = pics.join(name);
        img.save_png(&path)?;
        Ok(path)
    };

    // Pass 1: common camera, frame times and contact forces, body names (frames are
    // read twice to bound memory). Frames in parallel (each read on its own), taken in
    // order: the same camera, times and names as one after the other.
    let firsts: Vec<FrameFacts> = entries
        .par_iter()
        .map(|e| {
            let f = read_vtu(&dir.join(&e.file))?;
            let mut fit = Fit::three_quarter();
            fit.add_frame(&f);
            Ok(FrameFacts {
                fit,
                time: f.time,
                force: frame_contact_force(&f),
                names: f.bodies.iter().map(|b| (b.id, b.name.clone())).collect(),
            })
        })
        .collect::<Result<_, IoError>>()?;
    let mut fit = Fit::three_quarter();
    let (mut times, mut frame_force) = (Vec::new(), Vec::new());
    let mut names: Vec<(u32, String)> = Vec::new();
    for facts in firsts {
        fit.merge(&facts.fit);
        times.push(facts.time);
        frame_force.push(facts.force);
        for (id, name) in facts.names {
            if !names.iter().any(|(i, _)| *i == id) {
                names.push((id, name));
            }
        }
    }
    let camera = fit.view().map_or(Camera::Auto, Camera::View);
    let energy_csv = dir.join(ENERGY_CSV);
    let energy = if energy_csv.exists() {
        Some(read_energy_csv(&energy_csv)?)
    } else {
        None
    };
    let contacts_csv = dir.join(CONTACTS_CSV);
    let contacts = if contacts_csv.exists() {
        Some(read_contacts_csv(&contacts_csv)?)
    } else {
        None
    };
    let series = match &contacts {
        Some(rows) => {
            let base: Vec<f64> = energy.iter().flatten().map(|r| r.time).collect();
            ForceSeries::from_rows(&base, rows)
        }
        None => ForceSeries {
            time: times.clone(),
            total: frame_force.clone(),
        },
    };
    let sheet_panels = panels(&times, &series);
    let km = key_moments(&series.total);
    let peak_pair = km
        .peak
        .and_then(|k| pair_at(contacts.as_deref().unwrap_or(&[]), series.time[k]));
    // The contact zone is shown at the frame nearest the peak if it holds contact
    // forces, else at the frame with the largest contact force.
    let peak_frame = sheet_panels
        .iter()
        .find(|p| {
            p.reasons
                .contains(&crate::render::moments::Reason::PeakForce)
        })
        .map(|p| p.frame)
        .filter(|&k| frame_force[k] > 0.0)
        .or_else(|| {
            (0..frame_force.len())
                .filter(|&k| frame_force[k] > 0.0)
                .max_by(|&a, &b| frame_force[a].total_cmp(&frame_force[b]).then(b.cmp(&a)))
        });

    // Pass 2: snapshots, sheet panels, contact-zone views.
    let snap = RenderOptions {
        colour: Colouring::ByVonMises { range: None },
        camera,
        ..RenderOptions::default()
    };
    // frames in parallel; what each gives is taken in frame order
    let per_frame: Vec<FramePictures> = entries
        .par_iter()
        .enumerate()
        .map(|(k, e)| {
            let f = read_vtu(&dir.join(&e.file))?;
            let stem = Path::new(&e.file).file_stem().map_or_else(
                || format!("frame_{k:06}"),
                |s| s.to_string_lossy().into_owned(),
            );
            let mut out = FramePictures {
                written: vec![save(render_frame(&f, &snap), &format!("{stem}.png"))?],
                cell: sheet_panels
                    .iter()
                    .find(|p| p.frame == k)
                    .map(|p| panel_cell(&f, p, camera)),
                zone: Vec::new(),
            };
            if peak_frame == Some(k) {
                if let Some(z) = contact_zone(&f, peak_pair) {
                    out.written
                        .push(save(view_from_below(&f, &z, 800, 600), "below.png")?);
                    out.written
                        .push(save(section_view(&f, &z, 800, 600), "section.png")?);
                    out.zone.push(view_from_below(&f, &z, CELL.0, CELL.1));
                    out.zone.push(section_view(&f, &z, CELL.0, CELL.1));
                }
            }
            Ok(out)
        })
        .collect::<Result<_, IoError>>()?;
    let mut cells: Vec<crate::render::Image> = Vec::new();
    let mut zone_cells: Vec<crate::render::Image> = Vec::new();
    for p in per_frame {
        written.extend(p.written);
        cells.extend(p.cell);
        zone_cells.extend(p.zone);
    }
    let mut all = cells;
    all.extend(zone_cells);
    if !all.is_empty() {
        // One row up to four panels, else two rows (at most four columns).
        let cols = if all.len() <= 4 {
            all.len()
        } else {
            all.len().div_ceil(2).min(4)
        };
        written.push(save(sheet_from_cells(&all, cols), "sheet.png")?);
    }
    if let Some(rows) = &contacts {
        written.push(save(
            contact_force_plot(&series, rows, &names, 1000, 500).0,
            "contact_force.png",
        )?);
    }
    let matsum = dir.join(MATSUM_CSV);
    if matsum.exists() {
        let rows = read_matsum_csv(&matsum)?;
        written.push(save(
            body_energy_plot(&rows, &names, 1200, 800),
            "energies.png",
        )?);
    } else if let Some(rows) = &energy {
        written.push(save(
            total_energy_fallback_plot(rows, 1200, 800),
            "energies.png",
        )?);
    }
    if let Some(rows) = &energy {
        written.push(save(energy_plot(rows, 1000, 600), "energy.png")?);
    }
    Ok(written)
}

/// One panel of the sheet: the frame coloured by von Mises stress on its own scale,
/// with the moment(s) it stands for and when they happened.
fn panel_cell(f: &Frame, p: &Panel, camera: Camera) -> crate::render::Image {
    let caption = if (p.moment_time - f.time).abs() > 0.0 {
        format!("{} at {}", p.label(), format_time(p.moment_time))
    } else {
        p.label()
    };
    let opts = RenderOptions {
        width: CELL.0,
        height: CELL.1,
        colour: Colouring::ByVonMises { range: None },
        camera,
        caption: Some(&caption),
        ..RenderOptions::default()
    };
    render_frame(f, &opts)
}
