//! Plots of the run's histories: contact force per body pair (contacts.csv) with the key
//! moments marked, and energies per body (matsum.csv; scene totals from energy.csv when
//! it is absent, and the plot says so).

use super::colour::body_colour;
use super::image::{Image, Rgb, WHITE};
use super::lines::{line_plot, Axes, Labels, Line, Marker};
use super::moments::{key_moments, ForceSeries, Reason};
use super::sheet::sheet_from_cells;
use crate::history::{ContactRow, EnergyRow};
use crate::matsum_read::MatsumRow;

/// Body ids and names in id order (from a frame); an empty name (the .vtu files do not
/// store names) is written as "body N".
pub type Names<'a> = &'a [(u32, String)];

fn name_of(names: Names, id: u32) -> String {
    names
        .iter()
        .find(|(i, n)| *i == id && !n.is_empty())
        .map_or_else(|| format!("body {id}"), |(_, n)| n.clone())
}

/// Contact force [N] over time [ms]: one line per body pair, zero where the pair does
/// not touch (on the time base of `series`), the total when there are several pairs,
/// and markers at first contact, peak force and separation.
pub fn contact_force_plot(
    series: &ForceSeries,
    rows: &[ContactRow],
    names: Names,
    width: u32,
    height: u32,
) -> (Image, Axes) {
    let mut pairs: Vec<(u32, u32)> = rows.iter().map(|r| (r.a, r.b)).collect();
    pairs.sort_unstable();
    pairs.dedup();
    let mut lines: Vec<Line> = Vec::new();
    for (k, &(a, b)) in pairs.iter().enumerate() {
        let mut f = vec![0.0; series.time.len()];
        for r in rows.iter().filter(|r| (r.a, r.b) == (a, b)) {
            if let Ok(i) = series.time.binary_search_by(|t| t.total_cmp(&r.time)) {
                f[i] += r.force;
            }
        }
        lines.push(Line {
            name: format!("{} - {}", name_of(names, a), name_of(names, b)),
            colour: body_colour(k as u32 + 2),
            points: series.time.iter().map(|t| t * 1e3).zip(f).collect(),
        });
    }
    if pairs.len() > 1 {
        lines.push(Line {
            name: "total".into(),
            colour: [0, 0, 0],
            points: (series.time.iter().map(|t| t * 1e3))
                .zip(series.total.iter().copied())
                .collect(),
        });
    }
    let km = key_moments(&series.total);
    let markers: Vec<Marker> = [
        (km.first_contact, Reason::FirstContact),
        (km.peak, Reason::PeakForce),
        (km.separation, Reason::Separation),
    ]
    .iter()
    .filter_map(|(k, r)| {
        let t = *series.time.get((*k)?)?;
        Some(Marker {
            x: t * 1e3,
            label: r.text().to_string(),
        })
    })
    .collect();
    let note = if rows.is_empty() {
        Some("no contact recorded")
    } else {
        None
    };
    let labels = Labels {
        title: "Contact force per body pair",
        x: "time [ms]",
        y: "force [N]",
        note,
    };
    line_plot(&lines, &markers, &labels, width, height)
}

/// The four per-body terms: name and value.
type Term = (&'static str, fn(&MatsumRow) -> f64);
const TERMS: [Term; 4] = [
    ("kinetic", |r| r.kinetic),
    ("internal", |r| r.internal),
    ("hourglass", |r| r.hourglass),
    ("damping", |r| r.damping),
];

/// Energies per body [J] over time [ms]: four panels (kinetic, internal, hourglass,
/// damping), one line per body in its picture colour. A body name is matched to its id
/// with `names`; when `names` lacks it, the k-th body of matsum.csv (rows list bodies
/// in id order) takes the k-th id's colour.
pub fn body_energy_plot(rows: &[MatsumRow], names: Names, width: u32, height: u32) -> Image {
    let mut bodies: Vec<&str> = Vec::new();
    for r in rows {
        if !bodies.contains(&r.body.as_str()) {
            bodies.push(&r.body);
        }
    }
    let colour = |k: usize, name: &str| -> Rgb {
        names
            .iter()
            .find(|(_, n)| n == name)
            .or_else(|| names.get(k))
            .map_or(body_colour(k as u32), |(id, _)| body_colour(*id))
    };
    let cells: Vec<Image> = TERMS
        .iter()
        .map(|(term, value)| {
            let lines: Vec<Line> = bodies
                .iter()
                .enumerate()
                .map(|(k, b)| Line {
                    name: b.to_string(),
                    colour: colour(k, b),
                    points: rows
                        .iter()
                        .filter(|r| r.body == *b)
                        .map(|r| (r.time * 1e3, value(r)))
                        .collect(),
                })
                .collect();
            let title = format!("{term} energy per body");
            let labels = Labels {
                title: &title,
                x: "time [ms]",
                y: "[J]",
                note: None,
            };
            line_plot(&lines, &[], &labels, width / 2, height / 2).0
        })
        .collect();
    sheet_from_cells(&cells, 2)
}

/// Without matsum.csv: the same four panels with the scene totals of energy.csv, and a
/// note on each that these are not per body.
pub fn total_energy_fallback_plot(rows: &[EnergyRow], width: u32, height: u32) -> Image {
    type Total = (&'static str, fn(&EnergyRow) -> f64);
    let terms: [Total; 4] = [
        ("kinetic", |r| r.energy.kinetic),
        ("internal", |r| r.energy.internal),
        ("hourglass", |r| r.energy.hourglass),
        ("damping", |r| r.energy.damping),
    ];
    let cells: Vec<Image> = terms
        .iter()
        .map(|(term, value)| {
            let line = Line {
                name: "all bodies".into(),
                colour: [0, 0, 0],
                points: rows.iter().map(|r| (r.time * 1e3, value(r))).collect(),
            };
            let title = format!("{term} energy, all bodies");
            let labels = Labels {
                title: &title,
                x: "time [ms]",
                y: "[J]",
                note: Some("no matsum.csv: totals of energy.csv"),
            };
            line_plot(&[line], &[], &labels, width / 2, height / 2).0
        })
        .collect();
    if cells.is_empty() {
        return Image::new(width, height, WHITE);
    }
    sheet_from_cells(&cells, 2)
}
