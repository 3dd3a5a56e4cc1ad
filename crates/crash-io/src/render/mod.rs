//! In-process pictures: a small software rasterizer, a 5x7 bitmap font, snapshots,
//! contact sheets at the key moments, views of the contact zone (from below, section
//! cut), energy and contact-force plots, saved as PNG.

pub mod camera;
pub mod colour;
pub mod contact_zone;
pub mod font;
pub mod histories;
pub mod image;
pub mod lines;
pub mod loglog;
pub mod moments;
pub mod plot;
pub mod raster;
pub mod scale;
pub mod scene;
pub mod section;
pub mod sheet;
pub mod zone_views;

pub use camera::View;
pub use image::{load_png, Image, Rgb};
pub use loglog::{loglog_plot, LogSeries};
pub use plot::energy_plot;
pub use scene::{render_frame, Camera, Colouring, RenderOptions};
pub use sheet::contact_sheet;
