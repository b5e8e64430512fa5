//! The film: the image (`image`), reconstruction filters sampled by filter importance sampling
//! (`filter`), the per-pixel sampler and its stratified patterns (`sampler`), and the tiled parallel
//! loop with adaptive supersampling (`tiles`).

mod filter;
mod image;
mod sampler;
mod tiles;

pub use filter::{
    box_filter, filter_1d, filter_2d, gaussian_filter, mitchell_filter, reconstruct_pixel, tent_filter, FilterSample,
    FilterSampler, FILTER_TABLE_BINS,
};
pub use image::{luminance, Image};
pub use sampler::{owen_scramble, owen_sobol_2d, sobol_2d_bits, Pattern2d, PixelSampler, Sampler};
pub use tiles::{
    luminance_contrast, one_sample_error, render, render_samples_with, render_with, within_budget, FilmProgress,
    FilmSample, FilmStats, Wanted, ADAPTIVE_CONTRAST_EPSILON, ADAPTIVE_ERROR_EPSILON_SQ, DEFAULT_ADAPTIVE_BUDGET,
    TILE_SIZE_PX,
};

use crate::scene::ImageSettings;

/// Invalid film settings (see [`check_settings`]).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FilmError {
    #[error("image size {width_px}×{height_px}: both sides must be at least one pixel")]
    EmptyImage { width_px: u32, height_px: u32 },
    #[error("samples per pixel must be at least 1")]
    NoSamples,
    #[error("filter radius {0} px must be finite and positive")]
    FilterRadius(f32),
    #[error("adaptive threshold {0} must be finite and non-negative")]
    AdaptiveThreshold(f32),
    #[error("adaptive error {0} must be finite and positive")]
    AdaptiveError(f32),
}

/// Rejects settings the film would otherwise have to repair: call it where settings enter the
/// program (parser, CLI). [`render`] itself never fails: it uses at least one sample per pixel and a
/// 0.5 px radius in place of a non-positive or non-finite one.
pub fn check_settings(settings: &ImageSettings) -> Result<(), FilmError> {
    if settings.width_px == 0 || settings.height_px == 0 {
        return Err(FilmError::EmptyImage { width_px: settings.width_px, height_px: settings.height_px });
    }
    if settings.samples_per_pixel == 0 {
        return Err(FilmError::NoSamples);
    }
    if !(settings.filter_radius_px.is_finite() && settings.filter_radius_px > 0.0) {
        return Err(FilmError::FilterRadius(settings.filter_radius_px));
    }
    if let Some(t) = settings.adaptive_threshold {
        if !(t.is_finite() && t >= 0.0) {
            return Err(FilmError::AdaptiveThreshold(t));
        }
    }
    if let Some(e) = settings.adaptive_error {
        if !(e.is_finite() && e > 0.0) {
            return Err(FilmError::AdaptiveError(e));
        }
    }
    Ok(())
}
