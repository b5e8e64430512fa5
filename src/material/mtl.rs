//! MTL files as exporters write them → `scene::Material`s. Reads `Kd Ks Ke Tf Ns Ni d Tr illum` and
//! `map_Kd map_d map_Ke`; everything else is skipped with one warning per file (`Ka 0 0 0`, which asks
//! for nothing, silently). Numbers that cannot
//! be right (negative, non-finite, `d` outside [0, 1]) are errors with file:line.
//!
//! What the statements mean in radray (also the README's "MTL statements" table):
//! - `illum` 0, 1, 2, 10 or absent: radray's historic reading — `Ks` is mirror reflectance (with a
//!   Phong highlight when `Ns` > 0), `d` < 1 makes a smooth dielectric.
//! - `illum` 3, 5, 8 (reflection): a mirror of reflectance `Ks`; `Ks` defaults to 1 when absent. Radray
//!   has no conductor Fresnel, so 5 (Fresnel on) is the same mirror.
//! - `illum` 4, 6, 7, 9 (transparency): a smooth dielectric, Fresnel from `Ni` (default 1.5 here);
//!   `Ks` (default 1) tints the reflection.
//! - Transmittance: from `d` / `Tr` when they make the material transparent (1 − d, `Tr` = 1 − d, `d`
//!   wins if both disagree), with `Tf` as the spec's transmission *filter* colour. Without them, a
//!   transparent `illum` model is clear (1) unless `Tf` is given, which is then read as G3D reads it
//!   (transmission = 1 − Tf, `G3D-app ArticulatedModel_OBJ.cpp`): the McGuire archive's files were
//!   written for that reading (`illum 7`, `Tf 0.1`, `Ks 0.3` is clear glass and water, not a nearly
//!   black filter). The colour's largest channel becomes `transmittance`, the normalised colour
//!   `transmission_filter`.
//! - Reflectances of 1 or more are clamped (see `material::clamp_albedo`, `clamp_energy`), one warning
//!   per material naming the file, the material and the value.
//! - `map_*` options (`-bm 1`, `-s 2 2`, …) are skipped with a warning; the rest of the line is the
//!   file name (spaces allowed, `\` read as `/`), relative to the MTL's folder; a name that is not
//!   there as written (an absolute path from the exporter's machine, another letter case) is looked
//!   for by its file name next to the MTL (`scene::locate`), with a warning.
//! - `Tr 1` alone (no `d`, no transparent `illum`) is opaque: see `finish`.

use super::{clamp_albedo, clamp_energy};
use crate::scene::locate::locate;
use crate::scene::{Material, MaterialTextures, SourceLoc, TextureMap};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// An MTL file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum MtlError {
    #[error("{path}: cannot read material library: {source}", path = .path.display())]
    Read { path: PathBuf, source: std::io::Error },
    #[error("{loc}: {message}")]
    Invalid { loc: SourceLoc, message: String },
}

/// The materials of one MTL file, in file order, and what it said about them.
#[derive(Debug, Default)]
pub struct MtlLibrary {
    pub materials: Vec<Material>,
    /// Each prefixed with the file: clamped reflectances, skipped statements and options, …
    pub warnings: Vec<String>,
}

/// Index of refraction given to a transparent `illum` model without `Ni` (ordinary glass).
pub const DEFAULT_GLASS_IOR: f32 = 1.5;

/// Reads and parses an MTL file.
pub fn load(path: &Path) -> Result<MtlLibrary, MtlError> {
    let bytes = std::fs::read(path).map_err(|source| MtlError::Read { path: path.to_path_buf(), source })?;
    parse(path, &decode_text(&bytes))
}

/// The text of an OBJ or MTL file as exporters write it: a leading UTF-8 byte-order mark is dropped;
/// a file that is not UTF-8 is read as Latin-1 (Windows exporters write names and comments in the
/// machine's code page). Both files go through here, so a `usemtl` name matches its `newmtl`.
pub fn decode_text(bytes: &[u8]) -> String {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(text) => text.to_string(),
        Err(_) => bytes.iter().map(|&b| b as char).collect(),
    }
}

/// Statements as written, before `illum` and the clamps give them their meaning.
#[derive(Default)]
struct Raw {
    name: String,
    kd: Option<Vec3>,
    ks: Option<Vec3>,
    ke: Option<Vec3>,
    tf: Option<Vec3>,
    ns: Option<f32>,
    ni: Option<(f32, usize)>,
    d: Option<f32>,
    tr: Option<f32>,
    illum: Option<u8>,
    map_kd: Option<(String, usize)>,
    map_d: Option<(String, usize)>,
    map_ke: Option<(String, usize)>,
}

/// Parses MTL text; `path` names the file in messages and locates texture files.
pub fn parse(path: &Path, text: &str) -> Result<MtlLibrary, MtlError> {
    let mut library = MtlLibrary::default();
    let mut ignored: Vec<String> = Vec::new();
    let mut ignored_options: Vec<String> = Vec::new();
    let mut current: Option<Raw> = None;
    // `newmtl` lines without a name; texture paths found by file name (line, as written, found).
    let mut nameless: Vec<usize> = Vec::new();
    let mut found_elsewhere: Vec<(usize, String, PathBuf)> = Vec::new();
    let note = |list: &mut Vec<String>, what: &str| {
        if !list.iter().any(|x| x == what) {
            list.push(what.to_string());
        }
    };
    for (k, raw_line) in text.lines().enumerate() {
        let line_no = k + 1;
        let loc = SourceLoc { path: path.to_path_buf(), line: line_no };
        let fail = |message: String| MtlError::Invalid { loc: loc.clone(), message };
        let line = strip_comment(raw_line).trim();
        let Some(keyword) = line.split_whitespace().next() else { continue };
        let rest = line[keyword.len()..].trim();
        let lower = keyword.to_ascii_lowercase();
        if lower == "newmtl" {
            if rest.is_empty() {
                nameless.push(line_no);
            }
            if let Some(done) = current.take() {
                finish(path, done, &mut library, &mut found_elsewhere)?;
            }
            current = Some(Raw { name: rest.to_string(), ..Raw::default() });
            continue;
        }
        let known = matches!(
            lower.as_str(),
            "kd" | "ks" | "ke" | "tf" | "ns" | "ni" | "d" | "tr" | "illum" | "map_kd" | "map_d" | "map_ke"
        );
        // An ambient colour of 0 asks for nothing radray lacks (the shipped MTLs write `Ka 0 0 0`).
        if lower == "ka" && matches!(colour(keyword, rest), Ok(Some(c)) if c == Vec3::ZERO) {
            continue;
        }
        let Some(m) = current.as_mut().filter(|_| known) else {
            let what = if known { format!("{keyword} (before any newmtl)") } else { keyword.to_string() };
            note(&mut ignored, &what);
            continue;
        };
        match lower.as_str() {
            "kd" | "ks" | "ke" | "tf" => {
                let Some(colour) = colour(keyword, rest).map_err(fail)? else {
                    note(&mut ignored, &format!("{keyword} {}", rest.split_whitespace().next().unwrap_or("")));
                    continue;
                };
                let slot = match lower.as_str() {
                    "kd" => &mut m.kd,
                    "ks" => &mut m.ks,
                    "ke" => &mut m.ke,
                    _ => &mut m.tf,
                };
                *slot = Some(colour);
            }
            "ns" => {
                let ns = number(keyword, rest).map_err(fail)?;
                if ns < 0.0 {
                    return Err(fail(format!("`Ns` (Phong exponent) must not be negative, got {ns}")));
                }
                m.ns = Some(ns);
            }
            "ni" => {
                let ni = number(keyword, rest).map_err(fail)?;
                if ni < 0.0 {
                    return Err(fail(format!("`Ni` (index of refraction) must not be negative, got {ni}")));
                }
                m.ni = Some((ni, line_no));
            }
            "d" | "tr" => {
                let mut args = rest;
                if let Some(value) = rest.strip_prefix("-halo") {
                    note(&mut ignored_options, "d -halo");
                    args = value.trim();
                }
                let v = number(keyword, args).map_err(fail)?;
                if !(0.0..=1.0).contains(&v) {
                    return Err(fail(format!("`{keyword}` must lie in [0, 1], got {v}")));
                }
                if lower == "d" {
                    m.d = Some(v);
                } else {
                    m.tr = Some(v);
                }
            }
            "illum" => {
                let model: i64 = rest
                    .split_whitespace()
                    .next()
                    .and_then(|w| w.parse().ok())
                    .ok_or_else(|| fail(format!("`illum` needs an integer model number, got `{rest}`")))?;
                match u8::try_from(model) {
                    Ok(n) if n <= 10 => m.illum = Some(n),
                    _ => note(&mut ignored, &format!("illum {model}")),
                }
            }
            _ => {
                let file = map_file(rest, &mut |o| note(&mut ignored_options, o));
                if file.is_empty() {
                    return Err(fail(format!("`{keyword}` needs a file name")));
                }
                let slot = match lower.as_str() {
                    "map_kd" => &mut m.map_kd,
                    "map_d" => &mut m.map_d,
                    _ => &mut m.map_ke,
                };
                *slot = Some((file, line_no));
            }
        }
    }
    if let Some(done) = current.take() {
        finish(path, done, &mut library, &mut found_elsewhere)?;
    }
    if let Some(first) = nameless.first() {
        library.warnings.push(format!(
            "{}:{first}: `newmtl` without a name ({} such line(s)): no `usemtl` can name what follows it",
            path.display(),
            nameless.len()
        ));
    }
    // Exporters write every map of a file with the same foreign folder: one warning per file.
    if let Some((line, written, found)) = found_elsewhere.first() {
        let more = match found_elsewhere.len() {
            1 => String::new(),
            n => format!(" ({} more texture path(s) found the same way)", n - 1),
        };
        library.warnings.push(format!(
            "{}:{line}: texture `{written}` not found as written; using {}{more}",
            path.display(),
            found.display()
        ));
    }
    let names: Vec<&str> = library.materials.iter().map(|m| m.name.as_str()).collect();
    for (i, name) in names.iter().enumerate() {
        if names[..i].contains(name) && !names[i + 1..].contains(name) {
            library.warnings.push(format!(
                "{}: material `{name}` is defined more than once; faces use the last definition",
                path.display()
            ));
        }
    }
    if !ignored.is_empty() {
        library.warnings.push(format!("{}: ignoring {} (not used by radray)", path.display(), ignored.join(", ")));
    }
    if !ignored_options.is_empty() {
        library.warnings.push(format!(
            "{}: ignoring texture options {} (radray reads each map as it is, repeated over uv)",
            path.display(),
            ignored_options.join(", ")
        ));
    }
    Ok(library)
}

/// Text before a `#` that starts the line or follows white space (a trailing comment).
fn strip_comment(line: &str) -> &str {
    let bytes = line.as_bytes();
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'#' && (i == 0 || bytes[i - 1].is_ascii_whitespace()) {
            return &line[..i];
        }
    }
    line
}

/// A finite number, the first word of `args`.
fn number(keyword: &str, args: &str) -> Result<f32, String> {
    let word = args.split_whitespace().next().ok_or_else(|| format!("`{keyword}` needs a number"))?;
    match word.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("`{keyword}`: `{word}` is not a finite number")),
    }
}

/// `K? r [g b]`: one number (grey) or three, finite and non-negative. `spectral` and `xyz` forms give
/// `None` (skipped with a warning).
fn colour(keyword: &str, args: &str) -> Result<Option<Vec3>, String> {
    let words: Vec<&str> = args.split_whitespace().collect();
    if matches!(words.first().map(|w| w.to_ascii_lowercase()).as_deref(), Some("spectral" | "xyz")) {
        return Ok(None);
    }
    let mut values = Vec::with_capacity(3);
    for w in &words {
        match w.parse::<f32>() {
            Ok(x) if x.is_finite() && x >= 0.0 => values.push(x),
            Ok(x) if x.is_finite() => return Err(format!("`{keyword}` must not be negative, got {x}")),
            _ => return Err(format!("`{keyword}`: `{w}` is not a finite number")),
        }
    }
    match values[..] {
        [v] => Ok(Some(Vec3::splat(v))),
        [r, g, b] => Ok(Some(Vec3::new(r, g, b))),
        _ => Err(format!("`{keyword}` needs 1 or 3 numbers, found {}", values.len())),
    }
}

/// How many arguments each `map_*` option takes (the MTL spec's list); `-o`, `-s`, `-t` take 1 to 3
/// numbers.
fn option_arity(option: &str) -> Option<(usize, usize)> {
    Some(match option {
        "-blendu" | "-blendv" | "-cc" | "-clamp" | "-bm" | "-boost" | "-texres" | "-imfchan" | "-type" => (1, 1),
        "-mm" => (2, 2),
        "-o" | "-s" | "-t" => (1, 3),
        _ => return None,
    })
}

/// The file name of a `map_*` statement: options are skipped (each reported once through `skipped`),
/// and the rest of the line, spaces included, is the name; `\` becomes `/`.
fn map_file(args: &str, skipped: &mut dyn FnMut(&str)) -> String {
    let mut rest = args.trim_start();
    while rest.starts_with('-') {
        let option = rest.split_whitespace().next().unwrap_or("");
        rest = rest[option.len()..].trim_start();
        skipped(option);
        let (min, max) = option_arity(option).unwrap_or((0, 0));
        for n in 0..max {
            let Some(word) = rest.split_whitespace().next() else { break };
            // Optional trailing numbers of -o/-s/-t stop at the first non-number.
            if n >= min && word.parse::<f32>().is_err() {
                break;
            }
            rest = rest[word.len()..].trim_start();
        }
    }
    rest.trim().replace('\\', "/")
}

/// Gives a material's statements their meaning (see the module header) and applies the clamps.
fn finish(
    path: &Path,
    raw: Raw,
    library: &mut MtlLibrary,
    found_elsewhere: &mut Vec<(usize, String, PathBuf)>,
) -> Result<(), MtlError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mirror_model = matches!(raw.illum, Some(3 | 5 | 8));
    let transparent_model = matches!(raw.illum, Some(4 | 6 | 7 | 9));
    let warn = |library: &mut MtlLibrary, message: String| {
        library.warnings.push(format!("{}: material `{}`: {message}", path.display(), raw.name));
    };

    let dissolve = match (raw.d, raw.tr) {
        (Some(d), Some(tr)) => {
            if (d - (1.0 - tr)).abs() > 1e-4 {
                warn(library, format!("`d {d}` and `Tr {tr}` disagree (Tr = 1 - d); using d"));
            }
            Some(d)
        }
        (Some(d), None) => Some(d),
        // 3ds Max, MeshLab and vcglib write `Tr` as opacity (= d): their opaque materials say `Tr 1`,
        // which the usual reading (Tr = 1 − d) makes invisible. Alone, `Tr 1` is read their way.
        (None, Some(tr)) if tr >= 1.0 && !transparent_model => {
            warn(
                library,
                "`Tr 1` without `d` read as opaque (3ds Max and MeshLab write Tr as opacity); write `d 0` for a \
                 fully transparent material"
                    .into(),
            );
            None
        }
        (None, Some(tr)) => Some(1.0 - tr),
        (None, None) => None,
    };
    let filter_of = |c: Vec3| {
        let amount = c.max_element();
        if amount > 0.0 {
            (amount.min(1.0), c / amount)
        } else {
            (0.0, Vec3::ONE)
        }
    };
    let (transmittance, transmission_filter, from_illum) = match dissolve {
        Some(d) if d < 1.0 => {
            let (amount, filter) = filter_of(raw.tf.unwrap_or(Vec3::ONE));
            ((1.0 - d) * amount, filter, false)
        }
        _ if transparent_model => match raw.tf {
            Some(tf) => {
                let (amount, filter) = filter_of((Vec3::ONE - tf).max(Vec3::ZERO));
                (amount, filter, true)
            }
            None => (1.0, Vec3::ONE, true),
        },
        _ => (0.0, Vec3::ONE, false),
    };
    let dielectric = transmittance > 0.0;
    let ior = match raw.ni {
        Some((ni, line)) if dielectric && ni <= 0.0 => {
            return Err(MtlError::Invalid {
                loc: SourceLoc { path: path.to_path_buf(), line },
                message: format!("material `{}`: a transparent material needs `Ni` > 0, got {ni}", raw.name),
            })
        }
        Some((ni, _)) if ni > 0.0 => ni,
        _ if from_illum => DEFAULT_GLASS_IOR,
        _ => 1.0,
    };
    let specular = match raw.ks {
        Some(ks) => ks,
        None if mirror_model || transparent_model => Vec3::ONE,
        None => Vec3::ZERO,
    };
    if mirror_model && specular.max_element() <= 0.0 {
        warn(library, format!("illum {} asks for a mirror but Ks is 0: it will not reflect", raw.illum.unwrap_or(0)));
    }
    let mut texture = |map: &Option<(String, usize)>, factor: Vec3| {
        map.as_ref().map(|(file, line)| {
            let found = locate(dir, file);
            if found.substituted {
                found_elsewhere.push((*line, file.clone(), found.path.clone()));
            }
            TextureMap { path: found.path, factor, source: SourceLoc { path: path.to_path_buf(), line: *line } }
        })
    };
    let ke = raw.ke.unwrap_or(Vec3::ZERO);
    let textures = MaterialTextures {
        diffuse: texture(&raw.map_kd, raw.kd.unwrap_or(Vec3::ONE)),
        opacity: texture(&raw.map_d, Vec3::ONE),
        emission: texture(&raw.map_ke, if ke.max_element() > 0.0 { ke } else { Vec3::ONE }),
    };
    // A textured material without Kd multiplies its texture by 1; should the texture be unreadable it
    // falls back to the grey that faces without a material get.
    let kd = raw.kd.unwrap_or(if textures.diffuse.is_some() { Vec3::splat(0.5) } else { Vec3::ZERO });
    let mut m = Material {
        name: raw.name.clone(),
        diffuse_reflectance: kd,
        emitted_radiance: ke,
        specular_reflectance: specular,
        // Only an explicit, positive `Ns` asks for a highlight.
        phong_exponent: raw.ns.filter(|&n| n > 0.0),
        ior,
        transmittance,
        transmission_filter,
        illum: raw.illum,
        textures,
    };
    // One warning per material, however many of its quantities were clamped.
    let prefix = format!("material `{}`: ", raw.name);
    let notes: Vec<String> = [clamp_albedo(&mut m), clamp_energy(&mut m)]
        .into_iter()
        .flatten()
        .map(|n| n.to_string().strip_prefix(&prefix).map(str::to_string).unwrap_or_default())
        .collect();
    if !notes.is_empty() {
        warn(library, notes.join("; "));
    }
    library.materials.push(m);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn skipped(args: &str) -> (String, Vec<String>) {
        let mut options = Vec::new();
        let file = map_file(args, &mut |o| options.push(o.to_string()));
        (file, options)
    }

    #[test]
    fn map_options_are_skipped_and_the_rest_is_the_file() {
        assert_eq!(skipped("wood.jpg"), ("wood.jpg".into(), vec![]));
        assert_eq!(skipped("-bm 1 bricks.tga"), ("bricks.tga".into(), vec!["-bm".into()]));
        assert_eq!(skipped("-s 2 2 1 -o 0.5 my tex.png"), ("my tex.png".into(), vec!["-s".into(), "-o".into()]));
        assert_eq!(skipped("-s 2 tex.png"), ("tex.png".into(), vec!["-s".into()]));
        assert_eq!(skipped("-clamp on textures\\a b.png"), ("textures/a b.png".into(), vec!["-clamp".into()]));
        assert_eq!(skipped("-bm 1").0, "");
    }

    #[test]
    fn trailing_comments_are_stripped_but_not_hashes_inside_words() {
        assert_eq!(strip_comment("Ka 0.9 0.3 0.2 # Orange"), "Ka 0.9 0.3 0.2 ");
        assert_eq!(strip_comment("# all comment"), "");
        assert_eq!(strip_comment("map_Kd tex#1.png"), "map_Kd tex#1.png");
    }

    #[test]
    fn colours_take_one_or_three_numbers() {
        assert_eq!(colour("Kd", "0.5"), Ok(Some(Vec3::splat(0.5))));
        assert_eq!(colour("Kd", "0.1 0.2 0.3"), Ok(Some(Vec3::new(0.1, 0.2, 0.3))));
        assert_eq!(colour("Kd", "spectral ident.rfl"), Ok(None));
        assert!(colour("Kd", "0.1 0.2").is_err());
        assert!(colour("Kd", "-0.1 0.2 0.3").unwrap_err().contains("negative"));
        assert!(colour("Kd", "nan 0.2 0.3").unwrap_err().contains("finite"));
    }
}
