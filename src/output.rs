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

/// The exposure of a PNG: a fixed number of stops (radiance × 2^stops), or chosen from the image.
/// In TOML and job files: a number, or the string "auto".
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    Stops(f32),
    /// [`auto_exposure_stops`] of the image being written.
    Auto,
}

impl<'de> serde::Deserialize<'de> for Exposure {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Exposure, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Exposure;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number of stops or \"auto\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Exposure, E> {
                Exposure::Stops(v as f32).checked().map_err(E::custom)
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Exposure, E> {
                self.visit_f64(v as f64)
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Exposure, E> {
                self.visit_f64(v as f64)
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Exposure, E> {
                v.parse().map_err(E::custom)
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

impl Default for Exposure {
    fn default() -> Exposure {
        Exposure::Stops(0.0)
    }
}

/// Largest exposure magnitude accepted, in stops (2^±64 covers any f32 radiance worth showing).
pub const MAX_EXPOSURE_STOPS: f32 = 64.0;

impl std::str::FromStr for Exposure {
    type Err = String;

    /// `auto` or a finite number of stops within ±[`MAX_EXPOSURE_STOPS`].
    fn from_str(text: &str) -> Result<Exposure, String> {
        if text.trim().eq_ignore_ascii_case("auto") {
            return Ok(Exposure::Auto);
        }
        let stops: f32 =
            text.trim().parse().map_err(|_| format!("exposure {text:?} is neither a number of stops nor \"auto\""))?;
        Exposure::Stops(stops).checked()
    }
}

impl Exposure {
    /// The exposure itself when its stops are finite and within ±[`MAX_EXPOSURE_STOPS`].
    pub fn checked(self) -> Result<Exposure, String> {
        match self {
            Exposure::Stops(s) if !(s.is_finite() && s.abs() <= MAX_EXPOSURE_STOPS) => {
                Err(format!("exposure {s} stops must be finite and within ±{MAX_EXPOSURE_STOPS}"))
            }
            e => Ok(e),
        }
    }

    /// The stops to apply to `image`.
    pub fn stops_for(self, image: &Image) -> f32 {
        match self {
            Exposure::Stops(s) => s,
            Exposure::Auto => auto_exposure_stops(image),
        }
    }
}

/// The key of [`auto_exposure_stops`]: the exposed log-average luminance (Reinhard et al. 2002's
/// middle grey).
pub const AUTO_EXPOSURE_KEY: f32 = 0.18;

/// Automatic exposure from the log-average luminance (Reinhard, Stark, Shirley and Ferwerda 2002):
/// L̄ = exp((1/N) Σ ln Y_i) over the N pixels of finite, positive luminance Y (Rec. 709 weights),
/// and stops = log₂(key / L̄), key = [`AUTO_EXPOSURE_KEY`], so the exposed log-average is 0.18.
/// Black pixels (rays that left the scene) are left out rather than given Reinhard's small δ, which
/// would let an open background decide the exposure. 0 stops for an image with no such pixel; the
/// result is clamped to ±[`MAX_EXPOSURE_STOPS`].
pub fn auto_exposure_stops(image: &Image) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0u64);
    for p in &image.pixels {
        let y = crate::film::luminance(*p);
        if y.is_finite() && y > 0.0 {
            sum += (y as f64).ln();
            n += 1;
        }
    }
    if n == 0 {
        return 0.0;
    }
    let log_average = (sum / n as f64).exp();
    ((AUTO_EXPOSURE_KEY as f64 / log_average).log2() as f32).clamp(-MAX_EXPOSURE_STOPS, MAX_EXPOSURE_STOPS)
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

/// Encodes the image as a float32 RGB OpenEXR file in memory (lossless RLE in 64² tiles, written in
/// increasing order so that the same image always gives the same bytes: the tiles are compressed in
/// parallel, and in the encoder's default unspecified order they land as they finish).
pub fn encode_exr(image: &Image, path: &Path) -> Result<Vec<u8>, OutputError> {
    check_consistent(image, path)?;
    let width = image.width_px as usize;
    let channels = exr::image::SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
        let p = image.pixels[y * width + x];
        (p.x, p.y, p.z)
    });
    let encoding =
        exr::image::Encoding { line_order: exr::meta::attribute::LineOrder::Increasing, ..Default::default() };
    let exr_image = exr::image::Image::from_encoded_channels((width, image.height_px as usize), encoding, channels);
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
    fn the_same_image_encodes_to_the_same_exr_bytes_and_reads_back_exactly() {
        // 40 tiles of 64² compressed in parallel: in the encoder's default order they land in the
        // file as they finish, and two writes of one image differed (the tile offsets).
        let mut image = Image::new(320, 500);
        for (k, p) in image.pixels.iter_mut().enumerate() {
            *p = Vec3::new((k % 7) as f32 * 0.25, (k % 320) as f32 / 320.0, (k / 320) as f32 * 1e-3);
        }
        let path = Path::new("deterministic.exr");
        let first = encode_exr(&image, path).unwrap();
        for _ in 0..8 {
            assert!(encode_exr(&image, path).unwrap() == first, "the bytes changed between writes");
        }
        assert_eq!(decode_exr(&first, path).unwrap().pixels, image.pixels);
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

    #[test]
    fn auto_exposure_brings_the_log_average_to_middle_grey() {
        // Grey pixels of radiance 0.5 and 2 (log-average 1) and two black ones, which are left out:
        // stops = log2(0.18 / 1).
        let mut image = Image::new(2, 2);
        image.pixels = vec![Vec3::splat(0.5), Vec3::splat(2.0), Vec3::ZERO, Vec3::ZERO];
        let stops = auto_exposure_stops(&image);
        assert!((stops - 0.18f32.log2()).abs() < 1e-5, "{stops}");
        // Scaling the image by 2^k moves the exposure by −k stops: the exposed image is the same.
        image.pixels.iter_mut().for_each(|p| *p *= 8.0);
        assert!((auto_exposure_stops(&image) - (0.18f32.log2() - 3.0)).abs() < 1e-5);
        assert_eq!(auto_exposure_stops(&Image::new(3, 1)), 0.0);
    }

    #[test]
    fn exposure_reads_stops_or_auto_and_refuses_the_rest() {
        assert_eq!("auto".parse::<Exposure>(), Ok(Exposure::Auto));
        assert_eq!("-1.5".parse::<Exposure>(), Ok(Exposure::Stops(-1.5)));
        assert!("bright".parse::<Exposure>().is_err());
        assert!("inf".parse::<Exposure>().is_err());
        assert!("100".parse::<Exposure>().is_err());
    }
}
