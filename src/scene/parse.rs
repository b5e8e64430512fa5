//! Scene files (TOML) → `SceneDescription`, with every error located at its file and line
//! (`toml::Spanned`). Every key is checked (`validate`): unknown keys, missing files, non-finite
//! numbers, impossible cameras and materials are errors; degenerate faces and a scene without emitters
//! are warnings. Primitives become polygons in `shapes`, `[[mesh]]` instances are placed by `instance`.

use super::instance::Placement;
use super::obj::{self, ObjError};
use super::shapes::{box_faces, normalise_surfaces, sphere_triangles};
use super::validate::{check_material, CameraField, MaterialField};
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
    adaptive_error: Option<S<f32>>,
    adaptive_max_samples: Option<S<i64>>,
    adaptive_budget: Option<S<f32>>,
    seed: Option<u64>,
    exposure: Option<S<crate::output::Exposure>>,
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
    method: Option<MethodChoice>,
    memory: Option<S<MemorySize>>,
    error_threshold: Option<S<f64>>,
    min_element_size: Option<S<f32>>,
    visibility_rays: Option<S<i64>>,
    refinement_passes: Option<S<i64>>,
    dark_receiver_floor: Option<S<f64>>,
    correction_rays: Option<S<i64>>,
    correction: Option<CorrectionEstimator>,
    link_form_factors: Option<LinkFormFactors>,
    adaptive_levels: Option<S<i64>>,
    adaptive_threshold: Option<S<f64>>,
    auto_adaptive: Option<bool>,
}

/// `memory = 8000000000` or `memory = "8GB"`.
#[derive(Deserialize)]
#[serde(untagged)]
enum MemorySize {
    Bytes(i64),
    Text(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRender {
    direct: Option<DirectMode>,
    final_gather: Option<FinalGatherMode>,
    gather_rays: Option<S<i64>>,
    cache_accuracy: Option<S<f32>>,
    near_bounce: Option<S<f32>>,
    near_bounce_rays: Option<S<i64>>,
    gather_refine_error: Option<S<f32>>,
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
pub(super) struct Locator<'a> {
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

    pub(super) fn error<T>(&self, span: std::ops::Range<usize>, message: impl Into<String>) -> Result<T, SceneError> {
        Err(SceneError::Invalid { loc: self.at(span), message: message.into() })
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
        let mut material = Material::diffuse(&m.name, v3(&m.kd, "kd")?.unwrap_or(Vec3::ZERO));
        material.emitted_radiance = v3(&m.ke, "ke")?.unwrap_or(Vec3::ZERO);
        material.specular_reflectance = v3(&m.ks, "ks")?.unwrap_or(Vec3::ZERO);
        let positive = |x: f64| x > 0.0;
        if let Some(ns) = loc.ranged(&m.ns, "ns (Phong exponent)", positive, "a positive number")? {
            material.phong_exponent = Some(ns);
        }
        if let Some(ni) = loc.ranged(&m.ni, "ni (index of refraction)", positive, "a positive number")? {
            material.ior = ni;
        }
        if let Some(d) = loc.ranged(&m.d, "d (dissolve)", |x| (0.0..=1.0).contains(&x), "in [0, 1]")? {
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
    // A [[quad]] and a [[triangle]] are the same thing: a polygon given corner by corner.
    let quads = raw.quad.iter().map(|q| {
        let v = q.get_ref();
        Ok::<_, SceneError>((loc.finite_points(&v.corners)?, &v.material, v.two_sided, &v.name, "quad", q.span()))
    });
    let triangles = raw.triangle.iter().map(|t| {
        let v = t.get_ref();
        Ok((loc.finite_points(&v.vertices)?, &v.material, v.two_sided, &v.name, "triangle", t.span()))
    });
    for polygon in quads.chain(triangles) {
        let (corners, material, two_sided, name, kind, span) = polygon?;
        let name = name.as_deref().unwrap_or(kind);
        surfaces.push(surface(corners, find(material)?, two_sided, name, inline(span)));
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
        for (tri, normals) in sphere_triangles(centre, radius, segments) {
            let triangle = surface(tri.to_vec(), material, false, &name, inline(s.span()));
            surfaces.push(Surface { shading_normals: Some(normals.to_vec()), ..triangle });
        }
    }
    // OBJ files without a face, named if the scene ends up empty.
    let mut faceless: Vec<String> = Vec::new();
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
        if contents.surfaces.is_empty() {
            faceless.push(obj_path.display().to_string());
        }
        let base = materials.len() as u32;
        for material in &contents.materials {
            check_material(material).map_err(|(_, message)| SceneError::Invalid {
                loc: SourceLoc { path: obj_path.with_extension("mtl"), line: 0 },
                message: format!("material `{}`: {message}", material.name),
            })?;
        }
        materials.extend(contents.materials);
        warnings.extend(contents.warnings);
        surfaces.extend(Placement { scale, translate }.apply(contents.surfaces, base));
    }

    // Split what the mesher cannot take (polygons beyond quads, non-convex quads), drop zero-area faces.
    let (surfaces, degenerate) = normalise_surfaces(surfaces);
    for (source, count) in degenerate {
        warnings.push(format!("{}: skipped {count} degenerate (zero-area) face(s)", source.display()));
    }
    // The OBJ reader refuses such coordinates with their line; `scale` and `translate` can still make
    // them (the BVH builder panics on bounds near 1e25).
    let beyond = |s: &&Surface| s.vertices.iter().any(|v| v.abs().max_element() as f64 > obj::MAX_COORDINATE);
    if let Some(s) = surfaces.iter().find(beyond) {
        return Err(SceneError::Invalid {
            loc: s.source.clone(),
            message: format!(
                "a vertex of object `{}` lies beyond ±{:e} once scaled and moved ({:?})",
                s.object,
                obj::MAX_COORDINATE,
                s.vertices.iter().map(|v| v.to_array()).collect::<Vec<_>>()
            ),
        });
    }
    if surfaces.is_empty() {
        let why = if faceless.is_empty() { String::new() } else { format!(" ({} has no faces)", faceless.join(", ")) };
        return loc.error(
            0..0,
            format!("the scene has no surfaces{why}: add a [[mesh]], [[quad]], [[triangle]], [[box]] or [[sphere]]"),
        );
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
    Surface { vertices, material, two_sided, shading_normals: None, uvs: None, object: name.to_string(), source }
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
    if let Some(t) = loc.ranged(&r.adaptive_threshold, "adaptive_threshold", |x| x > 0.0, "a positive number")? {
        s.adaptive_threshold = Some(t);
    }
    if let Some(e) = loc.ranged(&r.adaptive_error, "adaptive_error", |x| x > 0.0, "a positive number")? {
        s.adaptive_error = Some(e);
    }
    s.adaptive_max_samples = loc.positive_int(
        &r.adaptive_max_samples,
        "adaptive_max_samples",
        1,
        65536,
        s.adaptive_max_samples.max(s.samples_per_pixel),
    )?;
    if let Some(b) = loc.ranged(&r.adaptive_budget, "adaptive_budget", |x| x >= 0.0, "a non-negative number")? {
        s.adaptive_budget = b;
    }
    if let Some(seed) = r.seed {
        s.seed = seed;
    }
    if let Some(e) = &r.exposure {
        s.exposure = *e.get_ref();
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
    hierarchy_settings(loc, r, &mut p)?;
    Ok(p)
}

/// The method and the hierarchy's keys of `[radiosity]`.
fn hierarchy_settings(loc: &Locator, r: &RawRadiosity, p: &mut RadiosityParams) -> Result<(), SceneError> {
    if let Some(m) = r.method {
        p.method = m;
    }
    let h = &mut p.hierarchy;
    if let Some(memory) = &r.memory {
        let bytes = match memory.get_ref() {
            MemorySize::Bytes(b) if *b > 0 => Some(*b as u64),
            MemorySize::Bytes(_) => None,
            MemorySize::Text(t) => parse_memory_size(t),
        };
        h.memory_bytes =
            match bytes {
                Some(b) => b,
                None => return loc.error(
                    memory.span(),
                    "memory must be a positive size: bytes, or a number with KB, MB, GB, TB (or KiB, MiB, GiB, TiB), \
                     such as \"8GB\"",
                ),
            };
    }
    if let Some(e) = loc.ranged(&r.error_threshold, "error_threshold", |x| x > 0.0 && x <= 100.0, "in (0, 100]")? {
        h.error_threshold = Some(e);
    }
    if let Some(s) = loc.ranged(&r.min_element_size, "min_element_size", |x| x > 0.0, "a positive length")? {
        h.min_element_size = Some(s);
    }
    if r.visibility_rays.is_some() {
        h.visibility_rays = Some(loc.positive_int(&r.visibility_rays, "visibility_rays", 1, 4096, 0)?);
    }
    if r.refinement_passes.is_some() {
        h.refinement_passes = Some(loc.positive_int(&r.refinement_passes, "refinement_passes", 1, 32, 0)?);
    }
    if let Some(d) = loc.ranged(&r.dark_receiver_floor, "dark_receiver_floor", |x| x > 0.0 && x <= 1.0, "in (0, 1]")? {
        h.dark_receiver_floor = Some(d);
    }
    if r.correction_rays.is_some() {
        h.correction_rays = Some(loc.positive_int(&r.correction_rays, "correction_rays", 0, 4096, 0)?);
    }
    if let Some(c) = r.correction {
        h.correction = Some(c);
    }
    if let Some(l) = r.link_form_factors {
        h.link_form_factors = Some(l);
    }
    let a = &mut p.adaptive;
    a.levels = loc.positive_int(&r.adaptive_levels, "adaptive_levels", 0, 6, a.levels)?;
    if let Some(t) = loc.ranged(&r.adaptive_threshold, "adaptive_threshold", |x| x > 0.0 && x <= 1.0, "in (0, 1]")? {
        a.threshold = t;
    }
    if let Some(b) = r.auto_adaptive {
        a.auto = Some(b);
    }
    Ok(())
}

fn render_params(loc: &Locator, raw: Option<&RawRender>, base: RenderParams) -> Result<RenderParams, SceneError> {
    let mut p = base;
    let Some(r) = raw else { return Ok(p) };
    if let Some(d) = r.direct {
        p.direct = d;
    }
    if let Some(g) = r.final_gather {
        p.final_gather = g;
    }
    p.gather_rays = loc.positive_int(&r.gather_rays, "gather_rays", 16, 16384, p.gather_rays)?;
    p.gather_rays_set |= r.gather_rays.is_some();
    if let Some(a) = loc.ranged(&r.cache_accuracy, "cache_accuracy", |x| (0.0..=1.0).contains(&x), "in [0, 1]")? {
        p.cache_accuracy = a;
    }
    if let Some(k) =
        loc.ranged(&r.near_bounce, "near_bounce", |x| x >= 0.0, "a non-negative number of element sizes")?
    {
        p.near_bounce = Some(k);
    }
    if r.near_bounce_rays.is_some() {
        let rays = loc.positive_int(&r.near_bounce_rays, "near_bounce_rays", 1, 256, DEFAULT_NEAR_BOUNCE_RAYS)?;
        p.near_bounce_rays = Some(rays);
    }
    if let Some(e) =
        loc.ranged(&r.gather_refine_error, "gather_refine_error", |x| x >= 0.0, "a non-negative relative error")?
    {
        p.gather_refine_error = e;
    }
    p.light_samples = loc.positive_int(&r.light_samples, "light_samples", 1, 4096, p.light_samples)?;
    p.max_depth = loc.positive_int(&r.max_depth, "max_depth", 1, 256, p.max_depth)?;
    if let Some(t) = loc.ranged(&r.min_throughput, "min_throughput", |x| (0.0..1.0).contains(&x), "in [0, 1)")? {
        p.min_throughput = t;
    }
    Ok(p)
}
