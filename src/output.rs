//! Writing and reading images (the only user of `image` and `exr`), and atomic file writes: every
//! output goes to a temporary file beside its target and is renamed into place only when complete.

mod layers;

pub use layers::{read_exr_channels, write_layered_exr, Layers};

use crate::film::Image;
use glam::Vec3;
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically: a failed or interrupted write never leaves a partial file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temporary_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `dir/.name.tmp-PID` beside `path`.
pub fn temporary_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// Failures of image output and input; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}: unsupported image format (expected a .png or .exr extension)", path.display())]
    UnsupportedFormat { path: PathBuf },
    #[error("{}: image claims {width_px}×{height_px} pixels but holds {pixels}", path.display())]
    InconsistentImage { path: PathBuf, width_px: u32, height_px: u32, pixels: usize },
    #[error("{}: cannot write: {source}", path.display())]
    Write { path: PathBuf, source: std::io::Error },
    #[error("{}: cannot read: {source}", path.display())]
    Read { path: PathBuf, source: std::io::Error },
    #[error("{}: cannot encode EXR: {source}", path.display())]
    ExrEncode { path: PathBuf, source: exr::error::Error },
    #[error("{}: cannot decode EXR: {source}", path.display())]
    ExrDecode { path: PathBuf, source: exr::error::Error },
    #[error("{}: cannot encode PNG: {source}", path.display())]
    PngEncode { path: PathBuf, source: image::ImageError },
    #[error("{}: cannot decode PNG: {source}", path.display())]
    PngDecode { path: PathBuf, source: image::ImageError },
}

/// How radiance (after exposure) is compressed into [0, 1] before the sRGB encoding of a PNG.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum ToneCurve {
    /// t(x) = clamp(x, 0, 1).
    #[default]
    Clamp,
    /// Reinhard et al. 2002 global operator per channel: t(x) = x / (1 + x).
    Reinhard,
    /// Narkowicz 2015's fit of the ACES filmic curve: t(x) = x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14).
    Aces,
}

/// Image file formats radray writes and reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Exr,
}

impl ImageFormat {
    /// The format named by the path's extension (case-insensitive), if supported.
    pub fn from_path(path: &Path) -> Result<ImageFormat, OutputError> {
        match path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("exr") => Ok(ImageFormat::Exr),
            _ => Err(OutputError::UnsupportedFormat { path: path.to_path_buf() }),
        }
    }
}

/// The sRGB OETF (IEC 61966-2-1): V = 12.92·L for L ≤ 0.0031308, else 1.055·L^(1/2.4) − 0.055.
/// Input is clamped to [0, 1]; NaN maps to 0.
pub fn srgb_oetf(linear: f32) -> f32 {
    let l = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    if l <= 0.003_130_8 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    }
}

/// The sRGB EOTF, inverse of [`srgb_oetf`]: L = V/12.92 for V ≤ 0.04045, else ((V + 0.055)/1.055)^2.4.
pub fn srgb_eotf(encoded: f32) -> f32 {
    if encoded <= 0.040_45 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// The tone curve t(x) of `tone` (see [`ToneCurve`]); its result is in [0, 1], NaN and negatives → 0.
pub fn tone_curve(x: f32, tone: ToneCurve) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x.max(0.0) };
    let t = match tone {
        ToneCurve::Clamp => x,
        ToneCurve::Reinhard => {
            if x.is_infinite() {
                1.0
            } else {
                x / (1.0 + x)
            }
        }
        ToneCurve::Aces => {
            if x.is_infinite() {
                1.0
            } else {
                x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)
            }
        }
    };
    t.clamp(0.0, 1.0)
}

/// One 8-bit sRGB pixel: round(255 · sRGB(t(L · 2^exposure_stops))) per channel.
pub fn tone_map_to_srgb8(radiance: Vec3, exposure_stops: f32, tone: ToneCurve) -> [u8; 3] {
    let scale = exposure_stops.exp2();
    let encode = |c: f32| (srgb_oetf(tone_curve(c * scale, tone)) * 255.0).round() as u8;
    [encode(radiance.x), encode(radiance.y), encode(radiance.z)]
}

fn check_consistent(image: &Image, path: &Path) -> Result<(), OutputError> {
    if image.is_consistent() {
        Ok(())
    } else {
        Err(OutputError::InconsistentImage {
            path: path.to_path_buf(),
            width_px: image.width_px,
            height_px: image.height_px,
            pixels: image.pixels.len(),
        })
    }
}

fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomically(path, bytes).map_err(|source| OutputError::Write { path: path.to_path_buf(), source })
}

/// Encodes the image as an uncompressed-float (f32) RGB OpenEXR file in memory.
pub fn encode_exr(image: &Image, path: &Path) -> Result<Vec<u8>, OutputError> {
    check_consistent(image, path)?;
    let width = image.width_px as usize;
    let channels = exr::image::SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
        let p = image.pixels[y * width + x];
        (p.x, p.y, p.z)
    });
    let exr_image = exr::image::Image::from_channels((width, image.height_px as usize), channels);
    let mut bytes = Cursor::new(Vec::new());
    exr::image::write::WritableImage::write(&exr_image)
        .to_buffered(&mut bytes)
        .map_err(|source| OutputError::ExrEncode { path: path.to_path_buf(), source })?;
    Ok(bytes.into_inner())
}

/// Encodes the image as an 8-bit sRGB PNG in memory (see [`tone_map_to_srgb8`]).
pub fn encode_png(image: &Image, path: &Path, exposure_stops: f32, tone: ToneCurve) -> Result<Vec<u8>, OutputError> {
    use image::ImageEncoder;
    check_consistent(image, path)?;
    let rgb: Vec<u8> = image.pixels.iter().flat_map(|p| tone_map_to_srgb8(*p, exposure_stops, tone)).collect();
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(&rgb, image.width_px, image.height_px, image::ExtendedColorType::Rgb8)
        .map_err(|source| OutputError::PngEncode { path: path.to_path_buf(), source })?;
    Ok(bytes)
}

/// Writes linear radiance as a float32 RGB OpenEXR file, atomically.
pub fn write_exr(image: &Image, path: &Path) -> Result<(), OutputError> {
    let bytes = encode_exr(image, path)?;
    write_bytes(path, &bytes)
}

/// Writes an 8-bit sRGB PNG (exposure in stops, then the tone curve, then the exact sRGB OETF),
/// atomically.
pub fn write_png(image: &Image, path: &Path, exposure_stops: f32, tone: ToneCurve) -> Result<(), OutputError> {
    let bytes = encode_png(image, path, exposure_stops, tone)?;
    write_bytes(path, &bytes)
}

/// Writes PNG or EXR by the path's extension; exposure and tone apply to PNG only (EXR keeps radiance).
pub fn write_image(image: &Image, path: &Path, exposure_stops: f32, tone: ToneCurve) -> Result<(), OutputError> {
    match ImageFormat::from_path(path)? {
        ImageFormat::Png => write_png(image, path, exposure_stops, tone),
        ImageFormat::Exr => write_exr(image, path),
    }
}

/// Reads an image as linear RGB: EXR (first layer with R, G, B; alpha ignored; f16/f32/u32 samples)
/// or PNG (8- or 16-bit, grey or colour, decoded with the exact sRGB EOTF).
pub fn read_image(path: &Path) -> Result<Image, OutputError> {
    let format = ImageFormat::from_path(path)?;
    let bytes = std::fs::read(path).map_err(|source| OutputError::Read { path: path.to_path_buf(), source })?;
    match format {
        ImageFormat::Exr => decode_exr(&bytes, path),
        ImageFormat::Png => decode_png(&bytes, path),
    }
}

fn decode_exr(bytes: &[u8], path: &Path) -> Result<Image, OutputError> {
    use exr::image::read::{image::ReadLayers, layers::ReadChannels};
    let decoded = exr::image::read::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution: exr::math::Vec2<usize>, _: &exr::image::RgbaChannels| {
                Image::new(resolution.width() as u32, resolution.height() as u32)
            },
            |image: &mut Image, position: exr::math::Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
                let i = position.y() * image.width_px as usize + position.x();
                image.pixels[i] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|source| OutputError::ExrDecode { path: path.to_path_buf(), source })?;
    Ok(decoded.layer_data.channel_data.pixels)
}

fn decode_png(bytes: &[u8], path: &Path) -> Result<Image, OutputError> {
    let decoded = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
        .map_err(|source| OutputError::PngDecode { path: path.to_path_buf(), source })?;
    let (width_px, height_px) = (decoded.width(), decoded.height());
    let sixteen_bit = matches!(
        decoded.color(),
        image::ColorType::L16 | image::ColorType::La16 | image::ColorType::Rgb16 | image::ColorType::Rgba16
    );
    let pixels: Vec<Vec3> = if sixteen_bit {
        let lut: Vec<f32> = (0..=u16::MAX).map(|v| srgb_eotf(v as f32 / 65535.0)).collect();
        decoded
            .to_rgb16()
            .pixels()
            .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
            .collect()
    } else {
        let lut: Vec<f32> = (0..=u8::MAX).map(|v| srgb_eotf(v as f32 / 255.0)).collect();
        decoded
            .to_rgb8()
            .pixels()
            .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
            .collect()
    };
    Ok(Image { width_px, height_px, pixels })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_oetf_and_eotf_are_inverse() {
        // Both are f32 evaluations of exact inverses; 1e-6 covers powf rounding in [0, 1].
        for i in 0..=1000 {
            let l = i as f32 / 1000.0;
            assert!((srgb_eotf(srgb_oetf(l)) - l).abs() < 1e-6, "{l}");
        }
    }

    #[test]
    fn rgba_half_float_exr_reads_as_rgb() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rgba.exr");
        // 0.25, 0.5, 2.0 are exact in f16, so the read values are exact.
        exr::prelude::write_rgba_file(&path, 2, 1, |x, _| {
            let v = exr::prelude::f16::from_f32(0.25 * (x + 1) as f32);
            (v, exr::prelude::f16::from_f32(0.5), exr::prelude::f16::from_f32(2.0), exr::prelude::f16::ONE)
        })
        .unwrap();
        let image = read_image(&path).unwrap();
        assert_eq!((image.width_px, image.height_px), (2, 1));
        assert_eq!(image.pixels, vec![Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.5, 0.5, 2.0)]);
    }

    #[test]
    fn sixteen_bit_grey_png_reads_through_the_srgb_eotf() {
        use image::ImageEncoder;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("grey16.png");
        let samples: [u16; 2] = [0, 65535];
        let bytes: Vec<u8> = samples.iter().flat_map(|v| v.to_ne_bytes()).collect();
        let mut png = Vec::new();
        image::codecs::png::PngEncoder::new(&mut png).write_image(&bytes, 2, 1, image::ExtendedColorType::L16).unwrap();
        std::fs::write(&path, png).unwrap();
        let image = read_image(&path).unwrap();
        assert_eq!(image.pixels, vec![Vec3::ZERO, Vec3::ONE]);
    }

    #[test]
    fn tone_curves_map_into_the_unit_interval() {
        for tone in [ToneCurve::Clamp, ToneCurve::Reinhard, ToneCurve::Aces] {
            for x in [-1.0, 0.0, 0.5, 1.0, 10.0, f32::INFINITY, f32::NAN] {
                let t = tone_curve(x, tone);
                assert!((0.0..=1.0).contains(&t), "{tone:?}({x}) = {t}");
            }
        }
        assert_eq!(tone_curve(1.0, ToneCurve::Reinhard), 0.5);
    }
}
