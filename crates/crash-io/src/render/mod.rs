//! In-process pictures: a small software rasterizer, a 5x7 bitmap font, snapshots,
//! contact sheets and energy plots, saved as PNG.

pub mod camera;
pub mod colour;
pub mod font;
pub mod image;
pub mod loglog;
pub mod plot;
pub mod raster;
pub mod scene;
pub mod sheet;

pub use camera::View;
pub use image::{load_png, Image, Rgb};
pub use loglog::{loglog_plot, LogSeries};
pub use plot::energy_plot;
pub use scene::{render_frame, Camera, Colouring, RenderOptions};
pub use sheet::contact_sheet;
