//! The two pictures of a contact zone: the kept body seen from below (through the
//! hidden body, which is left out) and the section cut through the zone's centre.

use super::camera::Fit;
use super::contact_zone::ContactZone;
use super::image::Image;
use super::scene::{render_frame, Camera, Colouring, RenderOptions};
use super::section::{render_section, Plane, Section};
use crate::frame::Frame;

/// The section through `zone`: the plane holds the contact normal and passes through
/// the zone's centre; the picture spans three zone radii each side (at least 20 shell
/// thicknesses, so a point contact still shows its surroundings), with the centre
/// below the middle (the kept body is above it).
pub fn zone_section(frame: &Frame, zone: &ContactZone) -> Section {
    let t = frame.bodies.iter().map(|b| b.thickness).fold(0.0, f64::max);
    let half_width = (3.0 * zone.radius).max(20.0 * t).max(1e-6);
    Section {
        plane: Plane {
            point: zone.centre,
            normal: zone.section_normal(),
        },
        up: zone.normal,
        centre: zone.centre + zone.normal * (0.35 * half_width),
        mark: zone.centre,
        half_width,
    }
}

fn hidden_name(frame: &Frame, zone: &ContactZone) -> String {
    frame
        .bodies
        .iter()
        .find(|b| b.id == zone.hidden && !b.name.is_empty())
        .map_or_else(|| format!("body {}", zone.hidden), |b| b.name.clone())
}

/// The kept body seen from the hidden body's side along the contact normal, the hidden
/// body left out, coloured by von Mises stress on the picture's own scale.
pub fn view_from_below(frame: &Frame, zone: &ContactZone, width: u32, height: u32) -> Image {
    let mut fit = Fit::new(-zone.normal, zone.section_normal());
    for b in frame.bodies.iter().filter(|b| b.id != zone.hidden) {
        b.x.iter().for_each(|p| fit.add(p));
    }
    let caption = format!("from below, {} left out", hidden_name(frame, zone));
    let opts = RenderOptions {
        width,
        height,
        colour: Colouring::ByVonMises { range: None },
        camera: fit.view().map_or(Camera::Auto, Camera::View),
        hidden: Some(zone.hidden),
        caption: Some(&caption),
        ..RenderOptions::default()
    };
    render_frame(frame, &opts)
}

/// The section picture of `zone`.
pub fn section_view(frame: &Frame, zone: &ContactZone, width: u32, height: u32) -> Image {
    let s = zone_section(frame, zone);
    render_section(
        frame,
        &s,
        width,
        height,
        Some("section through the contact zone"),
    )
    .0
}
