//! Scene files (TOML) → `SceneDescription`. Every key is checked: unknown keys, missing files,
//! non-finite numbers, impossible cameras and materials are errors with the file and line; degenerate
//! faces and a scene without emitters are warnings.

use super::obj::{self, ObjError};
use super::*;
use serde::Deserialize;
use toml::Spanned;

/// A scene that cannot be used, with where and why.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{path}: cannot read scene file: {source}")]
    Read { path: PathBuf, source: std::io::Error },
    #[error("{loc}: {message}")]
    Invalid { loc: SourceLoc, message: String },
    #[error(transparent)]
    Obj(#[from] ObjError),
}

type S<T> = Spanned<T>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    /// A named preset laid under the explicit settings of the file.
    quality: Option<Quality>,
    camera: Option<S<RawCamera>>,
    image: Option<RawImage>,
    radiosity: Option<RawRadiosity>,
    render: Option<RawRender>,
    #[serde(default)]
    material: Vec<S<RawMaterial>>,
    #[serde(default)]
    mesh: Vec<S<RawMesh>>,
    #[serde(default)]
    quad: Vec<S<RawQuad>>,
    #[serde(default)]
    triangle: Vec<S<RawTriangle>>,
    #[serde(default, rename = "box")]
    boxes: Vec<S<RawBox>>,
    #[serde(default)]
    sphere: Vec<S<RawSphere>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    eye: S<[f32; 3]>,
    look_at: S<[f32; 3]>,
    #[serde(default = "default_up")]
    up: S<[f32; 3]>,
    vfov_deg: S<f32>,
}

fn default_up() -> S<[f32; 3]> {
    Spanned::new(0..0, [0.0, 1.0, 0.0])
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawImage {
    width: Option<S<i64>>,
    height: Option<S<i64>>,
    samples_per_pixel: Option<S<i64>>,
    filter: Option<FilterKind>,
    filter_radius: Option<S<f32>>,
    adaptive_threshold: Option<S<f32>>,
    adaptive_max_samples: Option<S<i64>>,
    seed: Option<u64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRadiosity {
    max_element_edge: Option<S<f32>>,
    hemicube_resolution: Option<S<i64>>,
    solver: Option<SolverKind>,
    relaxation: Option<S<f64>>,
    tolerance: Option<S<f64>>,
    max_iterations: Option<S<i64>>,
    store_form_factors: Option<S<bool>>,
    rotate_hemicubes: Option<bool>,
    seed: Option<u64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRender {
    direct: Option<DirectMode>,
    light_samples: Option<S<i64>>,
    max_depth: Option<S<i64>>,
    min_throughput: Option<S<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    name: String,
    #[serde(default)]
    kd: Option<S<[f32; 3]>>,
    #[serde(default)]
    ke: Option<S<[f32; 3]>>,
    #[serde(default)]
    ks: Option<S<[f32; 3]>>,
    ns: Option<S<f32>>,
    ni: Option<S<f32>>,
    d: Option<S<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    obj: S<String>,
    #[serde(default)]
    two_sided: bool,
    /// Uniform or per-axis scale, applied before `translate`.
    scale: Option<S<ScaleValue>>,
    translate: Option<S<[f32; 3]>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum ScaleValue {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawQuad {
    corners: S<[[f32; 3]; 4]>,
    material: S<String>,
    #[serde(default)]
    two_sided: bool,
    name: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTriangle {
    vertices: S<[[f32; 3]; 3]>,
    material: S<String>,
    #[serde(default)]
    two_sided: bool,
    name: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBox {
    min: S<[f32; 3]>,
    max: S<[f32; 3]>,
    material: S<String>,
    /// Faces look inwards (a room) instead of outwards (a block).
    #[serde(default)]
    inward: bool,
    name: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSphere {
    center: S<[f32; 3]>,
    radius: S<f32>,
    material: S<String>,
    /// Segments around the equator (rings are half as many).
    #[serde(default = "default_segments")]
    segments: S<i64>,
    name: Option<String>,
}

fn default_segments() -> S<i64> {
    Spanned::new(0..0, 32)
}

/// Turns byte offsets into source locations.
struct Locator<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Locator<'_> {
    fn at(&self, span: std::ops::Range<usize>) -> SourceLoc {
        let line = if span.start == 0 && span.end == 0 {
            0
        } else {
            self.text[..span.start.min(self.text.len())].bytes().filter(|&b| b == b'\n').count() + 1
        };
        SourceLoc { path: self.path.to_path_buf(), line }
    }

    fn error<T>(&self, span: std::ops::Range<usize>, message: impl Into<String>) -> Result<T, SceneError> {
        Err(SceneError::Invalid { loc: self.at(span), message: message.into() })
    }

    fn finite3(&self, v: &S<[f32; 3]>, what: &str) -> Result<Vec3, SceneError> {
        if v.get_ref().iter().all(|x| x.is_finite()) {
            Ok(Vec3::from(*v.get_ref()))
        } else {
            self.error(v.span(), format!("{what} must be finite numbers, got {:?}", v.get_ref()))
        }
    }

    fn positive_int(
        &self,
        v: &Option<S<i64>>,
        what: &str,
        min: i64,
        max: i64,
        default: u32,
    ) -> Result<u32, SceneError> {
        match v {
            None => Ok(default),
            Some(s) if (min..=max).contains(s.get_ref()) => Ok(*s.get_ref() as u32),
            Some(s) => self.error(s.span(), format!("{what} must be between {min} and {max}, got {}", s.get_ref())),
        }
    }

    fn ranged<T: Copy + PartialOrd + std::fmt::Display + Into<f64>>(
        &self,
        v: &Option<S<T>>,
        what: &str,
        ok: impl Fn(f64) -> bool,
        expect: &str,
    ) -> Result<Option<T>, SceneError> {
        match v {
            None => Ok(None),
            Some(s) => {
                let x: f64 = (*s.get_ref()).into();
                if x.is_finite() && ok(x) {
                    Ok(Some(*s.get_ref()))
                } else {
                    self.error(s.span(), format!("{what} must be {expect}, got {}", s.get_ref()))
                }
            }
        }
    }
}

/// Reads and parses a scene file.
pub fn load(path: &Path) -> Result<SceneDescription, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read { path: path.to_path_buf(), source })?;
    parse_str(&text, path)
}

/// Parses scene text; `path` locates relative files and names the file in messages.
pub fn parse_str(text: &str, path: &Path) -> Result<SceneDescription, SceneError> {
    let loc = Locator { path, text };
    let raw: RawScene = toml::from_str(text).map_err(|e| SceneError::Invalid {
        loc: loc.at(e.span().unwrap_or(0..0)),
        message: e.message().trim().to_string(),
    })?;
    let dir = path.parent().unwrap_or(Path::new("."));

    // The camera is checked first: it needs no geometry, and its errors are the cheapest to fix.
    let explicit_camera = raw.camera.as_ref().map(|c| camera(&loc, c)).transpose()?;
    let mut warnings = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut material_lines: Vec<std::ops::Range<usize>> = Vec::new();
    for m in &raw.material {
        let span = m.span();
        let m = m.get_ref();
        if materials.iter().any(|x| x.name == m.name) {
            return loc.error(span, format!("material `{}` is defined twice", m.name));
        }
        let v3 = |v: &Option<S<[f32; 3]>>, what| v.as_ref().map(|v| loc.finite3(v, what)).transpose();
        let scalar = |v: &Option<S<f32>>| v.as_ref().map(|s| (*s.get_ref(), s.span()));
        let mut material = Material::diffuse(&m.name, v3(&m.kd, "kd")?.unwrap_or(Vec3::ZERO));
        material.emitted_radiance = v3(&m.ke, "ke")?.unwrap_or(Vec3::ZERO);
        material.specular_reflectance = v3(&m.ks, "ks")?.unwrap_or(Vec3::ZERO);
        if let Some((ns, s)) = scalar(&m.ns) {
            if !(ns.is_finite() && ns > 0.0) {
                return loc.error(s, format!("ns (Phong exponent) must be a positive number, got {ns}"));
            }
            material.phong_exponent = Some(ns);
        }
        if let Some((ni, s)) = scalar(&m.ni) {
            if !(ni.is_finite() && ni > 0.0) {
                return loc.error(s, format!("ni (index of refraction) must be a positive number, got {ni}"));
            }
            material.ior = ni;
        }
        if let Some((d, s)) = scalar(&m.d) {
            if !(d.is_finite() && (0.0..=1.0).contains(&d)) {
                return loc.error(s, format!("d (dissolve) must be in [0, 1], got {d}"));
            }
            material.transmittance = 1.0 - d;
        }
        if let Some(clamped) = crate::material::clamp_albedo(&mut material) {
            warnings.push(format!("{}: {clamped}", loc.at(m.kd.as_ref().map_or(span.clone(), |s| s.span()))));
        }
        if let Err((field, message)) = check_material(&material) {
            let field_span = match field {
                MaterialField::Kd => m.kd.as_ref().map(|s| s.span()),
                MaterialField::Ks => m.ks.as_ref().map(|s| s.span()),
                MaterialField::Ke => m.ke.as_ref().map(|s| s.span()),
                MaterialField::Energy => None,
            };
            return loc.error(field_span.unwrap_or(span), message);
        }
        materials.push(material);
        material_lines.push(span);
    }
    let find = |name: &S<String>| -> Result<u32, SceneError> {
        match materials.iter().position(|m| &m.name == name.get_ref()) {
            Some(i) => Ok(i as u32),
            None => loc.error(name.span(), format!("no [[material]] named `{}`", name.get_ref())),
        }
    };

    let mut surfaces: Vec<Surface> = Vec::new();
    let inline = |span: std::ops::Range<usize>| loc.at(span);
    for q in &raw.quad {
        let qv = q.get_ref();
        let corners = finite_points(&loc, &qv.corners)?;
        let material = find(&qv.material)?;
        let name = qv.name.clone().unwrap_or_else(|| "quad".into());
        surfaces.push(surface(corners, material, qv.two_sided, &name, inline(q.span())));
    }
    for t in &raw.triangle {
        let tv = t.get_ref();
        let vertices = finite_points(&loc, &tv.vertices)?;
        let material = find(&tv.material)?;
        let name = tv.name.clone().unwrap_or_else(|| "triangle".into());
        surfaces.push(surface(vertices, material, tv.two_sided, &name, inline(t.span())));
    }
    for b in &raw.boxes {
        let bv = b.get_ref();
        let (lo, hi) = (loc.finite3(&bv.min, "min")?, loc.finite3(&bv.max, "max")?);
        if !(lo.cmplt(hi).all()) {
            return loc.error(b.span(), "a box needs min < max on every axis");
        }
        let material = find(&bv.material)?;
        let name = bv.name.clone().unwrap_or_else(|| "box".into());
        for face in box_faces(lo, hi, bv.inward) {
            surfaces.push(surface(face.to_vec(), material, false, &name, inline(b.span())));
        }
    }
    for s in &raw.sphere {
        let sv = s.get_ref();
        let centre = loc.finite3(&sv.center, "center")?;
        let radius = loc.ranged(&Some(sv.radius.clone()), "radius", |r| r > 0.0, "a positive number")?.unwrap_or(1.0);
        let segments = loc.positive_int(&Some(sv.segments.clone()), "segments", 3, 4096, 32)?;
        let material = find(&sv.material)?;
        let name = sv.name.clone().unwrap_or_else(|| "sphere".into());
        for tri in sphere_triangles(centre, radius, segments) {
            surfaces.push(surface(tri.to_vec(), material, false, &name, inline(s.span())));
        }
    }
    for m in &raw.mesh {
        let mv = m.get_ref();
        let obj_path = dir.join(mv.obj.get_ref());
        if !obj_path.is_file() {
            return loc.error(mv.obj.span(), format!("OBJ file `{}` not found", obj_path.display()));
        }
        let scale = match &mv.scale {
            None => Vec3::ONE,
            Some(s) => {
                let v = match s.get_ref() {
                    ScaleValue::Uniform(k) => Vec3::splat(*k),
                    ScaleValue::PerAxis(a) => Vec3::from(*a),
                };
                if !(v.is_finite() && v.cmpne(Vec3::ZERO).all()) {
                    return loc.error(s.span(), "scale must be finite and non-zero");
                }
                v
            }
        };
        let translate = mv.translate.as_ref().map(|t| loc.finite3(t, "translate")).transpose()?.unwrap_or(Vec3::ZERO);
        let contents = obj::load(&obj_path, mv.two_sided)?;
        let base = materials.len() as u32;
        for material in &contents.materials {
            check_material(material).map_err(|(_, message)| SceneError::Invalid {
                loc: SourceLoc { path: obj_path.with_extension("mtl"), line: 0 },
                message: format!("material `{}`: {message}", material.name),
            })?;
        }
        materials.extend(contents.materials);
        warnings.extend(contents.warnings);
        // A negative scale mirrors the mesh, which flips the winding: restore counter-clockwise.
        let mirrored = scale.x * scale.y * scale.z < 0.0;
        for mut s in contents.surfaces {
            s.material += base;
            for v in &mut s.vertices {
                *v = *v * scale + translate;
            }
            if let Some(normals) = &mut s.shading_normals {
                for n in normals.iter_mut() {
                    *n = (*n / scale).normalize_or_zero();
                }
            }
            if mirrored {
                s.vertices.reverse();
                if let Some(n) = &mut s.shading_normals {
                    n.reverse();
                }
            }
            surfaces.push(s);
        }
    }

    // Split what the mesher cannot take (polygons beyond quads, non-convex quads), drop zero-area faces.
    let (surfaces, degenerate) = normalise_surfaces(surfaces);
    if degenerate > 0 {
        warnings.push(format!("{}: skipped {degenerate} degenerate (zero-area) face(s)", path.display()));
    }
    if surfaces.is_empty() {
        return loc
            .error(0..0, "the scene has no surfaces: add a [[mesh]], [[quad]], [[triangle]], [[box]] or [[sphere]]");
    }

    let bounds = surfaces
        .iter()
        .flat_map(|s| s.vertices.iter())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let camera = match explicit_camera {
        Some(c) => c,
        None => {
            let centre = (bounds.0 + bounds.1) * 0.5;
            let extent = (bounds.1 - bounds.0).max_element().max(1e-3);
            warnings.push(format!("{}: no [camera]; looking at the scene's centre from -z", path.display()));
            Camera { eye: centre - Vec3::Z * (2.0 * extent), look_at: centre, up: Vec3::Y, vfov_deg: 40.0 }
        }
    };
    let mut scene = SceneDescription {
        path: path.to_path_buf(),
        camera,
        image: ImageSettings::default(),
        radiosity: RadiosityParams::default(),
        render: RenderParams::default(),
        materials,
        surfaces,
        warnings,
    };
    // Defaults (about 30 elements along the scene's diagonal), then the preset, then the file's keys.
    scene.radiosity.max_element_edge = scene.diagonal() / 30.0;
    if let Some(q) = raw.quality {
        scene.apply_quality(q);
    }
    scene.image = image_settings(&loc, raw.image.as_ref(), scene.image.clone())?;
    scene.radiosity = radiosity_params(&loc, raw.radiosity.as_ref(), scene.radiosity.clone())?;
    scene.render = render_params(&loc, raw.render.as_ref(), scene.render.clone())?;
    if !scene.has_emitter() {
        scene.warnings.push(format!(
            "{}: the scene has no emitter (no material with ke > 0): the solution is black",
            path.display()
        ));
    }
    Ok(scene)
}

fn surface(vertices: Vec<Vec3>, material: u32, two_sided: bool, name: &str, source: SourceLoc) -> Surface {
    Surface { vertices, material, two_sided, shading_normals: None, object: name.to_string(), source }
}

fn finite_points<const N: usize>(loc: &Locator, v: &S<[[f32; 3]; N]>) -> Result<Vec<Vec3>, SceneError> {
    if v.get_ref().iter().flatten().all(|x| x.is_finite()) {
        Ok(v.get_ref().iter().map(|&p| Vec3::from(p)).collect())
    } else {
        loc.error(v.span(), "coordinates must be finite numbers")
    }
}

/// Which part of a material `check_material` found wrong (to point at its line).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialField {
    Kd,
    Ks,
    Ke,
    /// The material as a whole (energy, dissolve, index of refraction).
    Energy,
}

/// Checks a material's physical sense. Reflectances lie in [0, 1); emission is non-negative; and energy
/// is conserved: Kd + Ks + (1 − d) ≤ 1 per channel for an opaque or partly reflective surface. For a
/// dielectric, Fresnel splits what is not diffusely reflected between reflection (scaled by Ks) and
/// transmission (scaled by 1 − d), so there the bound is Kd + max(Ks, 1 − d) ≤ 1 — which admits the
/// standard MTL glass (Ks 1, d 0).
pub fn check_material(m: &Material) -> Result<(), (MaterialField, String)> {
    let in_unit = |v: Vec3, upper_open: bool| {
        v.is_finite()
            && v.min_element() >= 0.0
            && if upper_open { v.max_element() < 1.0 } else { v.max_element() <= 1.0 }
    };
    if !in_unit(m.diffuse_reflectance, true) {
        return Err((
            MaterialField::Kd,
            format!("diffuse reflectance Kd must lie in [0, 1), got {:?}", m.diffuse_reflectance.to_array()),
        ));
    }
    if !in_unit(m.specular_reflectance, false) {
        return Err((
            MaterialField::Ks,
            format!("mirror reflectance Ks must lie in [0, 1], got {:?}", m.specular_reflectance.to_array()),
        ));
    }
    if !(m.emitted_radiance.is_finite() && m.emitted_radiance.min_element() >= 0.0) {
        return Err((
            MaterialField::Ke,
            format!("emitted radiance Ke must be finite and non-negative, got {:?}", m.emitted_radiance.to_array()),
        ));
    }
    if !(m.transmittance.is_finite() && (0.0..=1.0).contains(&m.transmittance)) {
        return Err((MaterialField::Energy, format!("dissolve d must lie in [0, 1], got {}", 1.0 - m.transmittance)));
    }
    if !(m.ior.is_finite() && m.ior > 0.0) {
        return Err((MaterialField::Energy, format!("index of refraction Ni must be positive, got {}", m.ior)));
    }
    let t = Vec3::splat(m.transmittance);
    let (total, rule) = if m.is_dielectric() {
        (m.diffuse_reflectance + m.specular_reflectance.max(t), "Kd + max(Ks, 1 - d)")
    } else {
        (m.diffuse_reflectance + m.specular_reflectance, "Kd + Ks")
    };
    if total.max_element() > 1.0 + 1e-6 {
        return Err((
            MaterialField::Energy,
            format!("{rule} = {:?} exceeds 1: the material would create energy", total.to_array()),
        ));
    }
    Ok(())
}

/// Checks that a camera can form an image: a field of view in (0°, 180°), `eye` away from `look_at`,
/// and `up` neither zero nor parallel to the view direction.
pub fn check_camera(c: &Camera) -> Result<(), (CameraField, String)> {
    if !(c.vfov_deg.is_finite() && c.vfov_deg > 0.0 && c.vfov_deg < 180.0) {
        return Err((CameraField::VfovDeg, format!("vfov_deg must lie in (0, 180) degrees, got {}", c.vfov_deg)));
    }
    if !(c.eye.is_finite() && c.look_at.is_finite() && c.up.is_finite()) {
        return Err((CameraField::Eye, "eye, look_at and up must be finite".to_string()));
    }
    let forward = c.look_at - c.eye;
    if !(forward.length() > 1e-6 * c.eye.length().max(1.0)) {
        return Err((CameraField::LookAt, "look_at must differ from eye".to_string()));
    }
    if !(c.up.length() > 0.0) || forward.normalize().cross(c.up.normalize()).length() < 1e-4 {
        return Err((CameraField::Up, "up must not be zero or parallel to the view direction".to_string()));
    }
    Ok(())
}

/// Which camera key `check_camera` found wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraField {
    Eye,
    LookAt,
    Up,
    VfovDeg,
}

fn camera(loc: &Locator, c: &S<RawCamera>) -> Result<Camera, SceneError> {
    let r = c.get_ref();
    let eye = loc.finite3(&r.eye, "eye")?;
    let look_at = loc.finite3(&r.look_at, "look_at")?;
    let explicit_up = r.up.span() != (0..0);
    let up = if explicit_up { loc.finite3(&r.up, "up")? } else { Vec3::Y };
    let camera = Camera { eye, look_at, up, vfov_deg: *r.vfov_deg.get_ref() };
    match check_camera(&camera) {
        Ok(()) => Ok(camera),
        Err((field, message)) => {
            let span = match field {
                CameraField::Eye => r.eye.span(),
                CameraField::LookAt => r.look_at.span(),
                CameraField::Up if explicit_up => r.up.span(),
                CameraField::Up => c.span(),
                CameraField::VfovDeg => r.vfov_deg.span(),
            };
            loc.error(span, message)
        }
    }
}

fn image_settings(loc: &Locator, raw: Option<&RawImage>, base: ImageSettings) -> Result<ImageSettings, SceneError> {
    let mut s = base;
    let Some(r) = raw else { return Ok(s) };
    s.width_px = loc.positive_int(&r.width, "width", 1, 16384, s.width_px)?;
    s.height_px = loc.positive_int(&r.height, "height", 1, 16384, s.height_px)?;
    s.samples_per_pixel = loc.positive_int(&r.samples_per_pixel, "samples_per_pixel", 1, 65536, s.samples_per_pixel)?;
    if let Some(f) = r.filter {
        s.filter = f;
        s.filter_radius_px = default_filter_radius(f);
    }
    if let Some(radius) = loc.ranged(&r.filter_radius, "filter_radius", |x| x > 0.0 && x <= 8.0, "in (0, 8] pixels")? {
        s.filter_radius_px = radius;
    }
    s.adaptive_threshold = loc.ranged(&r.adaptive_threshold, "adaptive_threshold", |x| x > 0.0, "a positive number")?;
    s.adaptive_max_samples = loc.positive_int(
        &r.adaptive_max_samples,
        "adaptive_max_samples",
        1,
        65536,
        s.adaptive_max_samples.max(s.samples_per_pixel),
    )?;
    if let Some(seed) = r.seed {
        s.seed = seed;
    }
    Ok(s)
}

/// The customary radius of each filter, in pixels.
pub fn default_filter_radius(f: FilterKind) -> f32 {
    match f {
        FilterKind::Box => 0.5,
        FilterKind::Tent => 1.0,
        FilterKind::Gaussian => 1.5,
        FilterKind::Mitchell => 2.0,
    }
}

fn radiosity_params(
    loc: &Locator,
    raw: Option<&RawRadiosity>,
    base: RadiosityParams,
) -> Result<RadiosityParams, SceneError> {
    let mut p = base;
    let Some(r) = raw else { return Ok(p) };
    if let Some(e) = loc.ranged(&r.max_element_edge, "max_element_edge", |x| x > 0.0, "a positive length")? {
        p.max_element_edge = e;
    }
    p.hemicube_resolution_px =
        loc.positive_int(&r.hemicube_resolution, "hemicube_resolution", 2, 4096, p.hemicube_resolution_px)?;
    if p.hemicube_resolution_px % 2 == 1 {
        return loc.error(
            r.hemicube_resolution.as_ref().map(|s| s.span()).unwrap_or(0..0),
            "hemicube_resolution must be even (side faces are half as high)",
        );
    }
    if let Some(s) = r.solver {
        p.solver = s;
    }
    if let Some(w) = loc.ranged(&r.relaxation, "relaxation", |x| x > 0.0 && x < 2.0, "in (0, 2)")? {
        p.relaxation = w;
    }
    if let Some(t) = loc.ranged(&r.tolerance, "tolerance", |x| x > 0.0 && x < 1.0, "in (0, 1)")? {
        p.tolerance = t;
    }
    p.max_iterations = loc.positive_int(&r.max_iterations, "max_iterations", 1, 1_000_000, p.max_iterations)?;
    if let Some(store) = &r.store_form_factors {
        p.store_form_factors = *store.get_ref();
        if !p.store_form_factors && p.solver != SolverKind::Progressive {
            return loc.error(
                store.span(),
                "store_form_factors = false needs solver = \"progressive\" (gathering solvers read the whole matrix \
                 every sweep)",
            );
        }
    }
    if let Some(b) = r.rotate_hemicubes {
        p.rotate_hemicubes = b;
    }
    if let Some(seed) = r.seed {
        p.seed = seed;
    }
    Ok(p)
}

fn render_params(loc: &Locator, raw: Option<&RawRender>, base: RenderParams) -> Result<RenderParams, SceneError> {
    let mut p = base;
    let Some(r) = raw else { return Ok(p) };
    if let Some(d) = r.direct {
        p.direct = d;
    }
    p.light_samples = loc.positive_int(&r.light_samples, "light_samples", 1, 4096, p.light_samples)?;
    p.max_depth = loc.positive_int(&r.max_depth, "max_depth", 1, 256, p.max_depth)?;
    if let Some(t) = loc.ranged(&r.min_throughput, "min_throughput", |x| (0.0..1.0).contains(&x), "in [0, 1)")? {
        p.min_throughput = t;
    }
    Ok(p)
}

/// The six faces of an axis-aligned box, counter-clockwise seen from outside (or inside if `inward`).
pub fn box_faces(lo: Vec3, hi: Vec3, inward: bool) -> Vec<[Vec3; 4]> {
    let p = |x: bool, y: bool, z: bool| {
        Vec3::new(if x { hi.x } else { lo.x }, if y { hi.y } else { lo.y }, if z { hi.z } else { lo.z })
    };
    let mut faces = vec![
        [p(false, false, false), p(false, false, true), p(false, true, true), p(false, true, false)], // x-
        [p(true, false, false), p(true, true, false), p(true, true, true), p(true, false, true)],     // x+
        [p(false, false, false), p(true, false, false), p(true, false, true), p(false, false, true)], // y-
        [p(false, true, false), p(false, true, true), p(true, true, true), p(true, true, false)],     // y+
        [p(false, false, false), p(false, true, false), p(true, true, false), p(true, false, false)], // z-
        [p(false, false, true), p(true, false, true), p(true, true, true), p(false, true, true)],     // z+
    ];
    if inward {
        for f in &mut faces {
            f.reverse();
        }
    }
    faces
}

/// A UV sphere as triangles, counter-clockwise seen from outside.
pub fn sphere_triangles(centre: Vec3, radius: f32, segments: u32) -> Vec<[Vec3; 3]> {
    let rings = (segments / 2).max(2);
    let point = |ring: u32, seg: u32| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = 2.0 * std::f32::consts::PI * seg as f32 / segments as f32;
        centre + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin())
    };
    let mut tris = Vec::new();
    for ring in 0..rings {
        for seg in 0..segments {
            let (a, b, c, d) = (point(ring, seg), point(ring + 1, seg), point(ring + 1, seg + 1), point(ring, seg + 1));
            if ring > 0 {
                tris.push([a, b, d]);
            }
            if ring + 1 < rings {
                tris.push([b, c, d]);
            }
        }
    }
    tris
}

/// Makes every surface something the mesher takes: triangles and convex quads stay; larger polygons
/// and non-convex quads become triangle fans; zero-area pieces are dropped and counted.
fn normalise_surfaces(surfaces: Vec<Surface>) -> (Vec<Surface>, usize) {
    let mut out = Vec::with_capacity(surfaces.len());
    let mut degenerate = 0;
    for s in surfaces {
        let n = polygon_normal(&s.vertices);
        let extent = s.vertices.iter().map(|v| (*v - s.vertices[0]).length()).fold(0.0f32, f32::max);
        if !(n.length() > 1e-6 * extent * extent) || !n.is_finite() {
            degenerate += 1;
            continue;
        }
        if s.vertices.len() == 3 || (s.vertices.len() == 4 && is_convex(&s.vertices, n)) {
            out.push(s);
            continue;
        }
        for k in 1..s.vertices.len() - 1 {
            let tri = vec![s.vertices[0], s.vertices[k], s.vertices[k + 1]];
            let tn = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            if !(tn.length() > 1e-6 * extent * extent) {
                degenerate += 1;
                continue;
            }
            let normals = s.shading_normals.as_ref().map(|n| vec![n[0], n[k], n[k + 1]]);
            out.push(Surface { vertices: tri, shading_normals: normals, ..s.clone() });
        }
    }
    (out, degenerate)
}

/// Newell's normal (twice the vector area) of a polygon.
fn polygon_normal(v: &[Vec3]) -> Vec3 {
    (0..v.len()).map(|i| v[i].cross(v[(i + 1) % v.len()])).sum()
}

fn is_convex(v: &[Vec3], n: Vec3) -> bool {
    (0..v.len()).all(|i| {
        let (a, b, c) = (v[i], v[(i + 1) % v.len()], v[(i + 2) % v.len()]);
        (b - a).cross(c - b).dot(n) > 0.0
    })
}
