//! Image textures: decoded once to linear RGBA (8-bit colour maps through the exact sRGB curve),
//! a box-filtered mip-map pyramid, filtered lookups (bilinear, trilinear from a uv footprint), and
//! the exact area average over a uv triangle that pass one uses for an element's mean albedo.
//!
//! Conventions: `u` runs left to right and `v` bottom to top, as OBJ `vt` coordinates do, so image
//! row 0 (the top row of the file) is at `v = 1`. Texel (i, j) covers [i, i+1] × [j, j+1] in texel
//! coordinates x = u·width, y = (1 − v)·height; its value sits at its centre. Lookups wrap (repeat).

use glam::{Vec2, Vec4};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Largest width or height radray decodes, and the decoder's memory limit: a bad file is refused,
/// never allowed to exhaust memory.
pub const MAX_TEXTURE_SIDE_PX: u32 = 16384;
const MAX_DECODE_BYTES: u64 = 1 << 30;

/// Most texels of one pyramid level that the bounding box of a uv triangle may cover when
/// `mean_over_triangle` integrates over that level: the mean is taken at the finest level within this
/// budget (the level matched to the triangle's texel footprint), so one mean visits at most this many
/// texels, whatever the triangle's size. 32×32: a coarse level's texels are exact averages of level 0,
/// so only the texels cut by the triangle's edges (about a third of them here) differ from level 0.
pub const MEAN_TEXEL_BUDGET: f64 = 1024.0;

/// Why a texture file could not be used (the caller warns and falls back to the constant).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TextureError {
    #[error("{path}: texture file not found", path = .path.display())]
    Missing { path: PathBuf },
    #[error("{path}: texture file cannot be read: {message}", path = .path.display())]
    Unreadable { path: PathBuf, message: String },
    #[error("{path}: texture is {width_px}×{height_px} px; radray reads at most {MAX_TEXTURE_SIDE_PX} px a side, \
             and at least 1", path = .path.display())]
    BadSize { path: PathBuf, width_px: u32, height_px: u32 },
}

/// How a file's 8- or 16-bit colour channels encode values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorEncoding {
    /// Colour maps (`map_Kd`, `map_Ke`): RGB through the sRGB curve; alpha is linear.
    Srgb,
    /// Data maps (`map_d`): every channel is the stored value / its maximum.
    Linear,
}

/// sRGB electro-optical transfer function (IEC 61966-2-1), exact:
/// c ≤ 0.04045 → c / 12.92, else ((c + 0.055) / 1.055)^2.4, for an encoded value c ∈ [0, 1].
pub fn srgb_to_linear(encoded: f32) -> f32 {
    let c = encoded as f64;
    let linear = if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) };
    linear as f32
}

/// One level of the pyramid: linear RGBA texels, row-major, row 0 at the top (v = 1).
#[derive(Clone, Debug, PartialEq)]
pub struct MipLevel {
    pub width_px: u32,
    pub height_px: u32,
    pub texels: Vec<Vec4>,
}

impl MipLevel {
    /// The texel at integer coordinates, wrapped (repeat).
    fn texel(&self, i: i64, j: i64) -> Vec4 {
        let x = i.rem_euclid(self.width_px as i64) as usize;
        let y = j.rem_euclid(self.height_px as i64) as usize;
        self.texels[y * self.width_px as usize + x]
    }

    /// Bilinear interpolation between the four texel centres around uv (wrapping):
    /// T(x, y) = Σ (1 − |x − xᵢ − ½|)(1 − |y − yⱼ − ½|)·tᵢⱼ over the 2×2 neighbourhood.
    pub fn bilinear(&self, uv: Vec2) -> Vec4 {
        let x = uv.x as f64 * self.width_px as f64 - 0.5;
        let y = (1.0 - uv.y as f64) * self.height_px as f64 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return self.texel(0, 0);
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (i, j) = (x0 as i64, y0 as i64);
        let top = self.texel(i, j).lerp(self.texel(i + 1, j), fx);
        let bottom = self.texel(i, j + 1).lerp(self.texel(i + 1, j + 1), fx);
        top.lerp(bottom, fy)
    }
}

/// A decoded, mip-mapped texture in linear RGBA.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Level 0 is the file at full resolution; each next level halves each side (rounding up) down
    /// to 1×1.
    pub levels: Vec<MipLevel>,
    /// The file has an alpha channel (otherwise alpha is 1 everywhere).
    pub has_alpha: bool,
}

/// Box resampling of a piecewise-constant row to `dst_len` texels: with s = n / n′,
/// dst[i] = (1/s) ∫_{i·s}^{(i+1)·s} src(x) dx, src(x) = src[⌊x⌋]. Every output is an exact area
/// average, so the mean of the row is preserved for any n and n′ (odd sizes included).
pub fn box_resample(src: &[Vec4], dst_len: usize) -> Vec<Vec4> {
    let n = src.len();
    assert!(n > 0 && dst_len > 0, "box_resample needs non-empty rows");
    let s = n as f64 / dst_len as f64;
    (0..dst_len)
        .map(|i| {
            let (a, b) = (i as f64 * s, (i + 1) as f64 * s);
            let mut acc = Vec4::ZERO;
            for (k, &t) in src.iter().enumerate().take((b.ceil() as usize).min(n)).skip(a.floor() as usize) {
                let overlap = (b.min(k as f64 + 1.0) - a.max(k as f64)).max(0.0);
                acc += t * overlap as f32;
            }
            acc / s as f32
        })
        .collect()
}

/// The next pyramid level: separable `box_resample` to ⌈w/2⌉ × ⌈h/2⌉ (each output texel is the
/// exact linear-space average of the area it covers).
pub fn downsample(level: &MipLevel) -> MipLevel {
    let (w, h) = (level.width_px as usize, level.height_px as usize);
    let (w2, h2) = (w.div_ceil(2), h.div_ceil(2));
    let rows: Vec<Vec4> = level.texels.chunks(w).flat_map(|row| box_resample(row, w2)).collect();
    let mut texels = vec![Vec4::ZERO; w2 * h2];
    let mut column = vec![Vec4::ZERO; h];
    for x in 0..w2 {
        for (y, c) in column.iter_mut().enumerate() {
            *c = rows[y * w2 + x];
        }
        for (y, t) in box_resample(&column, h2).into_iter().enumerate() {
            texels[y * w2 + x] = t;
        }
    }
    MipLevel { width_px: w2 as u32, height_px: h2 as u32, texels }
}

impl Texture {
    /// A texture from linear RGBA texels (row-major, row 0 at the top), with its mip pyramid.
    pub fn from_linear(width_px: u32, height_px: u32, texels: Vec<Vec4>, has_alpha: bool) -> Texture {
        assert!(width_px > 0 && height_px > 0, "a texture has at least one texel");
        assert_eq!(texels.len(), width_px as usize * height_px as usize, "texel count must match the size");
        let mut levels = vec![MipLevel { width_px, height_px, texels }];
        while let Some(last) = levels.last().filter(|l| l.width_px > 1 || l.height_px > 1) {
            let next = downsample(last);
            levels.push(next);
        }
        Texture { levels, has_alpha }
    }

    /// Reads a PNG, JPEG or TGA file (the format is guessed from its content).
    pub fn load(path: &Path, encoding: ColorEncoding) -> Result<Texture, TextureError> {
        if !path.is_file() {
            return Err(TextureError::Missing { path: path.to_path_buf() });
        }
        let unreadable =
            |e: &dyn std::fmt::Display| TextureError::Unreadable { path: path.to_path_buf(), message: e.to_string() };
        let mut reader = image::ImageReader::open(path).map_err(|e| unreadable(&e))?;
        reader = reader.with_guessed_format().map_err(|e| unreadable(&e))?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_TEXTURE_SIDE_PX);
        limits.max_image_height = Some(MAX_TEXTURE_SIDE_PX);
        limits.max_alloc = Some(MAX_DECODE_BYTES);
        reader.limits(limits);
        let image = reader.decode().map_err(|e| unreadable(&e))?;
        Texture::from_image(path, &image, encoding)
    }

    /// Decodes an image already in memory (8-bit, 16-bit or float channels).
    pub fn from_image(
        path: &Path,
        image: &image::DynamicImage,
        encoding: ColorEncoding,
    ) -> Result<Texture, TextureError> {
        let (width_px, height_px) = (image.width(), image.height());
        if width_px == 0 || height_px == 0 || width_px > MAX_TEXTURE_SIDE_PX || height_px > MAX_TEXTURE_SIDE_PX {
            return Err(TextureError::BadSize { path: path.to_path_buf(), width_px, height_px });
        }
        let has_alpha = image.color().has_alpha();
        let colour = |c: f32| match encoding {
            ColorEncoding::Srgb => srgb_to_linear(c),
            ColorEncoding::Linear => c,
        };
        let texels: Vec<Vec4> = match image {
            image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_) => {
                // Float images are linear already.
                image.to_rgba32f().pixels().map(|p| Vec4::from_array(p.0)).collect()
            }
            image::DynamicImage::ImageLuma16(_)
            | image::DynamicImage::ImageLumaA16(_)
            | image::DynamicImage::ImageRgb16(_)
            | image::DynamicImage::ImageRgba16(_) => image
                .to_rgba16()
                .pixels()
                .map(|p| {
                    let f = |k: usize| p.0[k] as f32 / 65535.0;
                    Vec4::new(colour(f(0)), colour(f(1)), colour(f(2)), f(3))
                })
                .collect(),
            _ => {
                let table: Vec<f32> = (0..256).map(|k| colour(k as f32 / 255.0)).collect();
                image
                    .to_rgba8()
                    .pixels()
                    .map(|p| {
                        let [r, g, b, a] = p.0;
                        Vec4::new(table[r as usize], table[g as usize], table[b as usize], a as f32 / 255.0)
                    })
                    .collect()
            }
        };
        Ok(Texture::from_linear(width_px, height_px, texels, has_alpha))
    }

    pub fn width_px(&self) -> u32 {
        self.levels[0].width_px
    }

    pub fn height_px(&self) -> u32 {
        self.levels[0].height_px
    }

    /// Bilinear lookup at one pyramid level (clamped to the coarsest).
    pub fn bilinear(&self, uv: Vec2, level: usize) -> Vec4 {
        self.levels[level.min(self.levels.len() - 1)].bilinear(uv)
    }

    /// The pyramid level (fractional) whose texels are as wide as a footprint `footprint_uv` wide in
    /// uv units: λ = log₂(footprint_uv · max(width, height)), clamped to [0, levels − 1].
    pub fn level_of_footprint(&self, footprint_uv: f32) -> f32 {
        let texels = footprint_uv as f64 * self.width_px().max(self.height_px()) as f64;
        if !(texels.is_finite() && texels > 1.0) {
            return 0.0;
        }
        (texels.log2() as f32).min((self.levels.len() - 1) as f32)
    }

    /// Trilinear lookup: bilinear at the two levels around λ = `level_of_footprint(footprint_uv)`,
    /// blended linearly in λ (Williams 1983). A footprint of a texel or less reads level 0.
    pub fn trilinear(&self, uv: Vec2, footprint_uv: f32) -> Vec4 {
        let lambda = self.level_of_footprint(footprint_uv);
        let lower = lambda.floor() as usize;
        let t = lambda - lower as f32;
        if t <= 0.0 || lower + 1 >= self.levels.len() {
            return self.bilinear(uv, lower);
        }
        self.bilinear(uv, lower).lerp(self.bilinear(uv, lower + 1), t)
    }

    /// The area average of the texture over the uv triangle (u₀, u₁, u₂), in linear space, at the pyramid
    /// level L matched to its footprint (`mean_level`: the finest level whose texels the triangle's
    /// bounding box covers at most `MEAN_TEXEL_BUDGET` of):
    /// T̄ = (1/A) Σᵢⱼ tᴸᵢⱼ · area(△ ∩ texel ij of level L), with the texture read as constant over each
    /// texel (box reconstruction) and wrapping. Each texel's share is found by clipping the triangle to
    /// the texel's square (Sutherland–Hodgman), so T̄ is the exact average of level L's texels up to f64
    /// rounding (≈1e-12 relative). Level L's texels are exact box averages of level 0's
    /// (`downsample`), so T̄ is the exact level-0 average whenever L = 0 (a triangle within budget) or
    /// the triangle's edges follow level L's texel borders; otherwise only the level-L texels its edges
    /// cut contribute their whole average rather than that of the part inside. For an affine uv
    /// mapping (any triangle) the uv-area average is the surface-area average. A triangle with zero uv
    /// area returns the bilinear value at its centroid (the limit of the average).
    pub fn mean_over_triangle(&self, uv0: Vec2, uv1: Vec2, uv2: Vec2) -> Vec4 {
        self.mean_over_triangle_of(uv0, uv1, uv2, |t| t)
    }

    /// The pyramid level `mean_over_triangle` integrates the uv triangle at: the finest level l at which
    /// its bounding box, widened to whole texels, covers at most `MEAN_TEXEL_BUDGET` texels (the
    /// coarsest level if none does).
    pub fn mean_level(&self, uv0: Vec2, uv1: Vec2, uv2: Vec2) -> usize {
        let last = self.levels.len() - 1;
        (0..last).find(|&l| self.texels_in_bounds(l, [uv0, uv1, uv2]) <= MEAN_TEXEL_BUDGET).unwrap_or(last)
    }

    /// Texels of level `level` in the whole-texel bounding box of the uv points.
    fn texels_in_bounds(&self, level: usize, uv: [Vec2; 3]) -> f64 {
        let (lo, hi) = bounds(&self.texel_points(level, uv));
        (hi[0].ceil() - lo[0].floor()) * (hi[1].ceil() - lo[1].floor())
    }

    /// uv points in texel coordinates of level `level`: x = u·width, y = (1 − v)·height.
    fn texel_points(&self, level: usize, uv: [Vec2; 3]) -> [[f64; 2]; 3] {
        let l = &self.levels[level];
        let (w, h) = (l.width_px as f64, l.height_px as f64);
        uv.map(|p| [p.x as f64 * w, (1.0 - p.y as f64) * h])
    }

    /// `mean_over_triangle` of a per-texel function f: (1/A) Σᵢⱼ f(tᴸᵢⱼ) · area(△ ∩ texel ij). Used for
    /// the clamped product Kd·texel, whose average is not the product of averages.
    pub fn mean_over_triangle_of(&self, uv0: Vec2, uv1: Vec2, uv2: Vec2, f: impl Fn(Vec4) -> Vec4) -> Vec4 {
        let centroid = (uv0 + uv1 + uv2) / 3.0;
        if !centroid.is_finite() {
            return f(self.levels[0].texel(0, 0));
        }
        let level = self.mean_level(uv0, uv1, uv2);
        let l = &self.levels[level];
        let pts = self.texel_points(level, [uv0, uv1, uv2]);
        let (lo, hi) = bounds(&pts);
        let area = polygon_area(&pts).abs();
        if area <= 1e-12 {
            return f(l.bilinear(centroid));
        }
        // Scratch polygons, reused for every row and texel: no allocation per texel.
        let (mut half, mut strip, mut cell_half, mut cell) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut sum = [0.0f64; 4];
        let mut covered = 0.0f64;
        for j in lo[1].floor() as i64..hi[1].ceil() as i64 {
            clip_into(&pts, 1, j as f64, true, &mut half);
            clip_into(&half, 1, (j + 1) as f64, false, &mut strip);
            if strip.len() < 3 {
                continue;
            }
            let (slo, shi) = bounds(&strip);
            for i in slo[0].floor() as i64..shi[0].ceil() as i64 {
                clip_into(&strip, 0, i as f64, true, &mut cell_half);
                clip_into(&cell_half, 0, (i + 1) as f64, false, &mut cell);
                if cell.len() < 3 {
                    continue;
                }
                let a = polygon_area(&cell).abs();
                let v = f(l.texel(i, j));
                for (s, x) in sum.iter_mut().zip(v.to_array()) {
                    *s += a * x as f64;
                }
                covered += a;
            }
        }
        if covered <= 0.0 {
            return f(l.bilinear(centroid));
        }
        Vec4::from_array(sum.map(|s| (s / covered) as f32))
    }
}

fn bounds(pts: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    pts.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
        ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
    })
}

/// Signed area by the shoelace formula: A = ½ Σ (xₖ·yₖ₊₁ − xₖ₊₁·yₖ).
fn polygon_area(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    0.5 * (0..n).map(|k| pts[k][0] * pts[(k + 1) % n][1] - pts[(k + 1) % n][0] * pts[k][1]).sum::<f64>()
}

/// One Sutherland–Hodgman step into `out` (cleared first): keeps the part of a convex polygon with
/// coordinate `axis` ≥ `bound` (`keep_above`) or ≤ `bound`.
fn clip_into(pts: &[[f64; 2]], axis: usize, bound: f64, keep_above: bool, out: &mut Vec<[f64; 2]>) {
    out.clear();
    let inside = |p: &[f64; 2]| if keep_above { p[axis] >= bound } else { p[axis] <= bound };
    for k in 0..pts.len() {
        let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
        let (ia, ib) = (inside(&a), inside(&b));
        if ia {
            out.push(a);
        }
        if ia != ib {
            let t = (bound - a[axis]) / (b[axis] - a[axis]);
            let mut p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            p[axis] = bound;
            out.push(p);
        }
    }
}

/// Loads each (file, encoding) once. A file that cannot be used is remembered too, and every request
/// for it returns the same typed error, so the caller can warn once and fall back to the constant.
#[derive(Debug, Default)]
pub struct TextureCache {
    entries: HashMap<(PathBuf, ColorEncoding), Result<Arc<Texture>, TextureError>>,
}

impl TextureCache {
    pub fn new() -> Self {
        TextureCache::default()
    }

    /// The texture, read from disk on the first request only. The first value in the pair is true on
    /// that first request (so a failure is reported once).
    pub fn get(&mut self, path: &Path, encoding: ColorEncoding) -> (Result<Arc<Texture>, TextureError>, bool) {
        let key = (path.to_path_buf(), encoding);
        let first = !self.entries.contains_key(&key);
        let entry = self.entries.entry(key).or_insert_with(|| Texture::load(path, encoding).map(Arc::new));
        (entry.clone(), first)
    }

    /// Files read or attempted so far.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn grey(v: f32) -> Vec4 {
        Vec4::new(v, v, v, 1.0)
    }

    /// n×n texels, 1 where i + j is even, 0 elsewhere.
    fn checker(n: u32) -> Texture {
        let texels = (0..n * n).map(|k| grey((k % n + k / n).is_multiple_of(2) as u32 as f32)).collect();
        Texture::from_linear(n, n, texels, false)
    }

    #[test]
    fn srgb_decode_matches_the_iec_formula_at_every_8_bit_value() {
        for k in 0..=255u32 {
            let c = k as f64 / 255.0;
            let exact = if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) };
            // f32 rounding of a value in [0, 1]: half an ulp at 1 is 6e-8.
            assert!((srgb_to_linear(c as f32) as f64 - exact).abs() < 1e-7, "{k}");
        }
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert_relative_eq!(srgb_to_linear(1.0), 1.0, max_relative = 1e-7);
        // The linear toe and the curve meet at 0.04045 (continuity to 1e-7).
        assert_relative_eq!(srgb_to_linear(0.04045), 0.04045 / 12.92, max_relative = 1e-6);
    }

    #[test]
    fn box_resample_preserves_the_mean_for_odd_lengths() {
        let src: Vec<Vec4> = (0..7).map(|k| grey(k as f32 * 0.1)).collect();
        let dst = box_resample(&src, 4);
        let mean = |v: &[Vec4]| v.iter().map(|t| t.x).sum::<f32>() / v.len() as f32;
        assert_relative_eq!(mean(&dst), mean(&src), max_relative = 1e-6);
        // dst[0] covers [0, 1.75): (0·1 + 0.1·0.75) / 1.75.
        assert_relative_eq!(dst[0].x, 0.075 / 1.75, max_relative = 1e-6);
    }

    #[test]
    fn every_mip_level_of_a_checker_averages_to_its_mean() {
        for n in [4u32, 5, 8] {
            let t = checker(n);
            let level0 = t.levels[0].texels.iter().map(|v| v.x as f64).sum::<f64>() / (n * n) as f64;
            for l in &t.levels {
                let mean = l.texels.iter().map(|v| v.x as f64).sum::<f64>() / l.texels.len() as f64;
                assert!((mean - level0).abs() < 1e-6, "n {n} level {}×{}: {mean} vs {level0}", l.width_px, l.height_px);
            }
            assert_eq!(t.levels.last().map(|l| (l.width_px, l.height_px)), Some((1, 1)));
        }
        // A power-of-two checker: level 1 is uniformly one half.
        for v in &checker(4).levels[1].texels {
            assert_relative_eq!(v.x, 0.5, max_relative = 1e-6);
        }
    }

    #[test]
    fn bilinear_reads_texel_centres_and_wraps() {
        let t = checker(2);
        // Texel (0, 0) is the top-left one: u = 0.25, v = 0.75.
        assert_relative_eq!(t.bilinear(Vec2::new(0.25, 0.75), 0).x, 1.0);
        assert_relative_eq!(t.bilinear(Vec2::new(0.75, 0.75), 0).x, 0.0);
        // Half-way between centres: the average; u + 1 is the same point.
        assert_relative_eq!(t.bilinear(Vec2::new(0.5, 0.75), 0).x, 0.5);
        assert_relative_eq!(t.bilinear(Vec2::new(1.25, -0.25), 0).x, 1.0);
    }

    #[test]
    fn trilinear_chooses_the_level_of_the_footprint() {
        let t = checker(8);
        // Footprint of one texel → level 0; of the whole texture → the 1×1 mean.
        assert_relative_eq!(t.trilinear(Vec2::new(1.0 / 16.0, 1.0 - 1.0 / 16.0), 1.0 / 8.0).x, 1.0);
        assert_relative_eq!(t.trilinear(Vec2::new(0.3, 0.6), 1.0).x, 0.5, max_relative = 1e-6);
        assert_relative_eq!(t.level_of_footprint(0.25), 1.0);
    }

    #[test]
    fn mean_over_half_square_triangles_of_a_checker_is_one_half() {
        // 2×2 checker: 1 at top-left and bottom-right. Either diagonal splits the square into two
        // triangles that each hold one whole texel and two half texels: one diagonal halves both
        // 1-texels (½ + ½ + 0 over area 2), the other keeps one 1-texel whole (1 + ½·0 + ½·0 over 2).
        let t = checker(2);
        let (a, b, c, d) = (Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0));
        for (p, q, r) in [(a, b, c), (a, c, d), (a, b, d), (b, c, d)] {
            assert_relative_eq!(t.mean_over_triangle(p, q, r).x, 0.5, max_relative = 1e-9);
        }
    }

    #[test]
    fn mean_over_a_sub_triangle_weights_texels_by_covered_area() {
        // 2×2 texture with values 1, 2 (top row), 3, 4 (bottom row). Triangle in texel space
        // (0,0), (2,0), (0,2) = uv (0,1), (1,1), (0,0): covers top-left whole (area 1), top-right and
        // bottom-left by half (½ each). Mean = (1·1 + 2·½ + 3·½) / 2 = 1.75.
        let t = Texture::from_linear(2, 2, vec![grey(1.0), grey(2.0), grey(3.0), grey(4.0)], false);
        let m = t.mean_over_triangle(Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 0.0));
        assert_relative_eq!(m.x, 1.75, max_relative = 1e-9);
        assert_relative_eq!(m.w, 1.0, max_relative = 1e-9);
    }

    #[test]
    fn mean_over_a_degenerate_triangle_is_the_value_there() {
        let t = checker(2);
        let p = Vec2::new(0.25, 0.75);
        assert_relative_eq!(t.mean_over_triangle(p, p, p).x, 1.0);
    }

    #[test]
    fn cache_loads_once_and_reports_a_missing_file_with_its_name() {
        let mut cache = TextureCache::new();
        let path = Path::new("/nonexistent/radray/wood.png");
        let (first, is_first) = cache.get(path, ColorEncoding::Srgb);
        let (second, again) = cache.get(path, ColorEncoding::Srgb);
        assert!(is_first && !again);
        assert_eq!(first, second);
        let message = first.unwrap_err().to_string();
        assert!(message.contains("wood.png") && message.contains("not found"), "{message}");
        assert_eq!(cache.len(), 1);
    }
}
