//! Contact sheet: several frames of a run in a grid, same camera, each with its time
//! (like Figure 1 of the seed paper).

use super::camera::View;
use super::image::{Image, WHITE};
use super::scene::{render_frame, Camera, RenderOptions};
use crate::frame::Frame;

const GRID: [u8; 3] = [200, 200, 200];

/// Assemble pre-rendered cells (all the same size) into a grid of `cols` columns.
pub fn sheet_from_cells(cells: &[Image], cols: usize) -> Image {
    let cols = cols.max(1).min(cells.len().max(1));
    let rows = cells.len().div_ceil(cols).max(1);
    let (cw, ch) = cells.first().map_or((1, 1), |c| (c.width, c.height));
    let mut img = Image::new(cw * cols as u32, ch * rows as u32, WHITE);
    for (k, c) in cells.iter().enumerate() {
        let (x, y) = ((k % cols) as i64 * cw as i64, (k / cols) as i64 * ch as i64);
        img.paste(c, x, y);
        img.stroke_rect(x, y, cw as i64, ch as i64, GRID);
    }
    img
}

/// Render `frames` into a grid of `cols` columns; each cell uses `cell` options. With
/// `Camera::Auto` one camera is fitted to all the frames.
pub fn contact_sheet(frames: &[Frame], cols: usize, cell: &RenderOptions) -> Image {
    let mut opts = *cell;
    if opts.camera == Camera::Auto {
        if let Some(v) = View::fit_frames(frames) {
            opts.camera = Camera::View(v);
        }
    }
    let cells: Vec<Image> = frames.iter().map(|f| render_frame(f, &opts)).collect();
    sheet_from_cells(&cells, cols)
}
