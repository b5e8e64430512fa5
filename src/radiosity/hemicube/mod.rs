//! The hemicube (Cohen and Greenberg 1985): delta form factors and the item-buffer rasteriser that
//! turns "which polygon is seen through each hemicube pixel" into point-to-polygon form factors.
//!
//! Layout: a unit hemicube over the eye with its top face z = 1 covering [-1,1]² (N×N pixels) and four
//! side faces (±x, ±y) N pixels wide and N/2 high (height z ∈ [0,1]). All five faces live in one
//! buffer: the top face first, then the four side faces, row-major, row 0 of a side face at the base.
//!
//! One concept per file: `tables` (ΔF), `clip` (frame, culling, clipping), `item_buffer` (queueing and
//! drawing), `raster` (the scan converters), `accumulate` (summing ΔF per item, read-back), `point`.

mod accumulate;
mod clip;
mod item_buffer;
mod point;
mod raster;
mod tables;

pub use clip::HemicubeFrame;
pub use item_buffer::{BackItems, ItemBuffer};
pub use point::{newell_plane, point_form_factors};
pub use tables::Hemicube;
