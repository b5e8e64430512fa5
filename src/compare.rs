//! Image comparison: the error metrics of the project's reference script `compare.py` (relMSE, mean
//! absolute relative error, RMSE, best-fit scale), a false-colour difference image and a side-by-side.

use crate::film::Image;
use glam::Vec3;

/// ε in the relative metrics, as in `compare.py`.
pub const RELATIVE_EPSILON: f64 = 0.01;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CompareError {
    #[error("image size mismatch: test {test_width_px}×{test_height_px} vs reference {ref_width_px}×{ref_height_px}")]
    SizeMismatch { test_width_px: u32, test_height_px: u32, ref_width_px: u32, ref_height_px: u32 },
    #[error("mask has {mask} entries for {pixels} pixels")]
    MaskSize { mask: usize, pixels: usize },
    #[error("no pixels selected (empty image or empty mask)")]
    NothingSelected,
    #[error("image claims {width_px}×{height_px} pixels but holds {pixels}")]
    InconsistentImage { width_px: u32, height_px: u32, pixels: usize },
}

/// The three error metrics of `compare.py`'s `basic()`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ErrorMetrics {
    /// mean (x − ref)² / (ref² + 0.01)
    #[serde(rename = "relMSE")]
    pub rel_mse: f64,
    /// mean |x − ref| / (|ref| + 0.01)
    pub mean_abs_rel_err: f64,
    /// sqrt(mean (x − ref)²)
    pub rmse: f64,
}

/// Where the largest absolute difference is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PixelChannel {
    pub x: u32,
    pub y: u32,
    /// 0 = R, 1 = G, 2 = B.
    pub channel: u32,
}

/// Metrics of a test image against a reference, over the selected pixels and the 3 channels, linear
/// RGB; field names in JSON follow `compare.py` (FLIP is not computed).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Metrics {
    #[serde(flatten)]
    pub errors: ErrorMetrics,
    /// Best-fit s minimising Σ (s·x − ref)²: s = Σ x·ref / max(Σ x², 1e-30).
    pub scale: f64,
    /// The error metrics of s·x.
    pub scaled: ErrorMetrics,
    pub mean_test: f64,
    pub mean_ref: f64,
    /// Selected pixels.
    pub pixels: u64,
    /// Largest |x − ref| over selected pixels and channels, and where (first in row-major order).
    pub max_abs_diff: f64,
    pub max_abs_diff_at: PixelChannel,
    /// Test values that were NaN or infinite and counted as 0 (as `compare.py`'s `nan_to_num`).
    pub non_finite_test_values: u64,
}

fn check_consistent(image: &Image) -> Result<(), CompareError> {
    if image.is_consistent() {
        Ok(())
    } else {
        Err(CompareError::InconsistentImage {
            width_px: image.width_px,
            height_px: image.height_px,
            pixels: image.pixels.len(),
        })
    }
}

fn check_same_size(test: &Image, reference: &Image) -> Result<(), CompareError> {
    check_consistent(test)?;
    check_consistent(reference)?;
    if (test.width_px, test.height_px) != (reference.width_px, reference.height_px) {
        return Err(CompareError::SizeMismatch {
            test_width_px: test.width_px,
            test_height_px: test.height_px,
            ref_width_px: reference.width_px,
            ref_height_px: reference.height_px,
        });
    }
    Ok(())
}

/// relMSE, mean absolute relative error and RMSE of `test · scale` against `reference` over paired
/// values (already sanitised): the kernel of `compare.py`'s `basic()`.
pub fn error_metrics(test: &[f64], reference: &[f64], scale: f64) -> ErrorMetrics {
    assert_eq!(test.len(), reference.len());
    let (mut rel_sq, mut abs_rel, mut sq) = (0.0, 0.0, 0.0);
    for (&x, &r) in test.iter().zip(reference) {
        let d = scale * x - r;
        rel_sq += d * d / (r * r + RELATIVE_EPSILON);
        abs_rel += d.abs() / (r.abs() + RELATIVE_EPSILON);
        sq += d * d;
    }
    let n = test.len() as f64;
    ErrorMetrics { rel_mse: rel_sq / n, mean_abs_rel_err: abs_rel / n, rmse: (sq / n).sqrt() }
}

/// Compares `test` against `reference` like `compare.py` (over pixels where `mask` is true, all when
/// `None`); non-finite test values count as 0.
pub fn metrics(test: &Image, reference: &Image, mask: Option<&[bool]>) -> Result<Metrics, CompareError> {
    check_same_size(test, reference)?;
    let pixels = reference.pixels.len();
    if let Some(m) = mask {
        if m.len() != pixels {
            return Err(CompareError::MaskSize { mask: m.len(), pixels });
        }
    }
    let selected = |i: usize| mask.is_none_or(|m| m[i]);
    let mut xs = Vec::with_capacity(3 * pixels);
    let mut rs = Vec::with_capacity(3 * pixels);
    let mut non_finite_test_values = 0;
    let mut max_abs_diff = -1.0f64;
    let mut max_abs_diff_at = PixelChannel { x: 0, y: 0, channel: 0 };
    for i in (0..pixels).filter(|&i| selected(i)) {
        for c in 0..3 {
            let raw = test.pixels[i][c];
            let x = if raw.is_finite() {
                raw as f64
            } else {
                non_finite_test_values += 1;
                0.0
            };
            let r = reference.pixels[i][c] as f64;
            let d = (x - r).abs();
            if d > max_abs_diff {
                max_abs_diff = d;
                let w = reference.width_px as usize;
                max_abs_diff_at = PixelChannel { x: (i % w) as u32, y: (i / w) as u32, channel: c as u32 };
            }
            xs.push(x);
            rs.push(r);
        }
    }
    if xs.is_empty() {
        return Err(CompareError::NothingSelected);
    }
    let errors = error_metrics(&xs, &rs, 1.0);
    let xr: f64 = xs.iter().zip(&rs).map(|(x, r)| x * r).sum();
    let xx: f64 = xs.iter().map(|x| x * x).sum();
    let scale = xr / xx.max(1e-30);
    let n = xs.len() as f64;
    Ok(Metrics {
        errors,
        scale,
        scaled: error_metrics(&xs, &rs, scale),
        mean_test: xs.iter().sum::<f64>() / n,
        mean_ref: rs.iter().sum::<f64>() / n,
        pixels: (xs.len() / 3) as u64,
        max_abs_diff: max_abs_diff.max(0.0),
        max_abs_diff_at,
        non_finite_test_values,
    })
}

/// Control points of a magma-like ramp (matplotlib's magma at t = 0, ¼, ½, ¾, 1), sRGB-encoded.
const MAGMA_SRGB: [[f32; 3]; 5] =
    [[0.001, 0.000, 0.014], [0.316, 0.071, 0.485], [0.716, 0.215, 0.475], [0.987, 0.535, 0.382], [0.987, 0.991, 0.750]];

/// The magma-like colour of t ∈ [0, 1] as LINEAR radiance (so that writing it as an sRGB PNG shows the
/// ramp): piecewise-linear interpolation of [`MAGMA_SRGB`], then the sRGB EOTF.
pub fn magma(t: f32) -> Vec3 {
    let t = if t.is_nan() { 1.0 } else { t.clamp(0.0, 1.0) };
    let s = t * (MAGMA_SRGB.len() - 1) as f32;
    let k = (s.floor() as usize).min(MAGMA_SRGB.len() - 2);
    let f = s - k as f32;
    let (a, b) = (MAGMA_SRGB[k], MAGMA_SRGB[k + 1]);
    let c = |i: usize| crate::output::srgb_eotf(a[i] + (b[i] - a[i]) * f);
    Vec3::new(c(0), c(1), c(2))
}

/// A false-colour map of the relative difference of `test` from `reference`: per pixel
/// e = max over channels |x − ref| / (|ref| + 0.01), shown as magma(e) (0 black-violet, ≥ 1 pale
/// yellow, non-finite as 1).
pub fn difference_image(test: &Image, reference: &Image) -> Result<Image, CompareError> {
    check_same_size(test, reference)?;
    let pixels = test
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(x, r)| {
            let e = ((*x - *r).abs() / (r.abs() + Vec3::splat(RELATIVE_EPSILON as f32))).max_element();
            magma(e)
        })
        .collect();
    Ok(Image { width_px: test.width_px, height_px: test.height_px, pixels })
}

/// The images left to right, top-aligned; shorter ones padded with black below.
pub fn side_by_side(images: &[&Image]) -> Image {
    let width_px = images.iter().map(|i| i.width_px).sum();
    let height_px = images.iter().map(|i| i.height_px).max().unwrap_or(0);
    let mut out = Image::new(width_px, height_px);
    let mut x0 = 0;
    for image in images {
        for y in 0..image.height_px {
            for x in 0..image.width_px {
                let i = (y * image.width_px + x) as usize;
                if let Some(p) = image.pixels.get(i) {
                    out.set(x0 + x, y, *p);
                }
            }
        }
        x0 += image.width_px;
    }
    out
}
