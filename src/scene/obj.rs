//! OBJ loading through tobj: the only user of tobj. Faces become `Surface`s (triangles and quads
//! as they are, larger or non-convex polygons as triangle fans). The MTL libraries an OBJ names are
//! read by `material::mtl` (tobj's MTL reader panics on `Kd 1`, drops line numbers and keeps one value
//! per unknown statement), and handed to tobj only as names, so that `usemtl` resolves as before.

use super::locate::locate;
use super::{Material, SourceLoc, Surface};
use crate::material::mtl::{self, MtlError};
use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// What went wrong reading an OBJ or MTL file.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    #[error("{path}: cannot read OBJ file: {source}")]
    Read { path: PathBuf, source: std::io::Error },
    #[error("{loc}: malformed OBJ: {message}")]
    Malformed { loc: SourceLoc, message: String },
    #[error("{path}: OBJ could not be loaded: {message}")]
    Load { path: PathBuf, message: String },
    #[error("{path}: material library could not be loaded: {message}")]
    Mtl { path: PathBuf, message: String },
    #[error("{path}: face uses material `{name}`, which its material library does not define")]
    UnknownMaterial { path: PathBuf, name: String },
    #[error(transparent)]
    MtlContent(MtlError),
}

/// The surfaces and materials of one OBJ file. Material indices in `surfaces` are local to
/// `materials`.
#[derive(Debug, Default)]
pub struct ObjContents {
    pub surfaces: Vec<Surface>,
    pub materials: Vec<Material>,
    /// Faces without a material (given the default grey) and other notes.
    pub warnings: Vec<String>,
}

/// Texture coordinates of every face in file order: `Some` for a face whose every corner names a `vt`.
type FaceUvs = Vec<Option<Vec<Vec2>>>;

/// Largest coordinate magnitude radray accepts. Areas and squared distances are products of two
/// coordinates, which must stay finite in f32 (max 3.4·10³⁸) with room to spare; exporters write
/// 10³⁰ or FLT_MAX for unset positions.
pub const MAX_COORDINATE: f64 = 1e18;

/// A material name no library can define (it holds a NUL): what a `usemtl` without a name becomes for
/// tobj, so its faces get the default material.
const NO_MATERIAL: &str = "\u{0}none";

/// An OBJ file's statements once read the way exporters write them, checked line by line.
#[derive(Debug, Default)]
struct Prepared {
    /// The statements for tobj, one per source line (continued lines joined on the first, the
    /// others left blank), words separated by single spaces, without `mtllib`.
    text: String,
    /// Each face's own texture coordinates (tobj loses them on objects whose faces only partly have
    /// `vt`).
    face_uvs: FaceUvs,
    /// `mtllib` file names in file order, with their lines.
    libraries: Vec<(String, usize)>,
    /// `usemtl` names in file order, with their lines.
    usemtl: Vec<(String, usize)>,
    warnings: Vec<String>,
}

/// Reads OBJ text: joins `\` continuation lines, splits `mtllib` lists, turns a nameless `usemtl`
/// into "no material", drops vertex colours, and checks what tobj would reject without saying where
/// (unparsable numbers, coordinates beyond `MAX_COORDINATE`, face indices out of range). Returns the
/// first problem with its line.
fn prepare(path: &Path, text: &str) -> Result<Prepared, ObjError> {
    let (mut v, mut vt, mut vn) = (0i64, 0i64, 0i64);
    let mut texcoords: Vec<Vec2> = Vec::new();
    let mut out = Prepared::default();
    let mut extra_numbers = 0usize;
    let mut nameless_usemtl: Vec<usize> = Vec::new();
    let lines: Vec<&str> = text.lines().collect();
    let mut k = 0usize;
    while k < lines.len() {
        let line_no = k + 1;
        // A statement may continue over lines that end in `\`.
        let mut statement = String::new();
        let mut last = k;
        loop {
            let part = lines[last].trim_end();
            match part.strip_suffix('\\') {
                Some(head) if last + 1 < lines.len() => {
                    statement.push_str(head);
                    statement.push(' ');
                    last += 1;
                }
                _ => {
                    statement.push_str(part.strip_suffix('\\').unwrap_or(part));
                    break;
                }
            }
        }
        k = last + 1;
        let fail = |message: String| ObjError::Malformed {
            loc: SourceLoc { path: path.to_path_buf(), line: line_no },
            message,
        };
        let line = statement.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        let args: Vec<&str> = words.collect();
        let rest = line.trim_start().get(keyword.len()..).unwrap_or("").trim();
        let numbers = |want: usize| -> Result<(), ObjError> {
            if args.len() < want {
                return Err(fail(format!("`{keyword}` needs {want} numbers, found {}", args.len())));
            }
            for a in &args {
                match a.parse::<f64>() {
                    Ok(x) if x.is_finite() => {}
                    _ => return Err(fail(format!("`{a}` is not a finite number"))),
                }
            }
            Ok(())
        };
        let tobj_line = match keyword {
            "v" => {
                numbers(3)?;
                if let Some(a) = args[..3].iter().find(|a| a.parse::<f64>().is_ok_and(|x| x.abs() > MAX_COORDINATE)) {
                    return Err(fail(format!(
                        "coordinate {a} is beyond ±{MAX_COORDINATE:e} (an unset position? radray's areas would overflow)"
                    )));
                }
                v += 1;
                // x y z, or x y z w; colours (x y z r g b, MeshLab, ZBrush) are dropped.
                let keep = match args.len() {
                    3 | 4 => args.len(),
                    6 => 3,
                    _ => {
                        extra_numbers += 1;
                        3
                    }
                };
                format!("v {}", args[..keep].join(" "))
            }
            "vt" => {
                numbers(1)?;
                vt += 1;
                let coordinate = |k: usize| args.get(k).and_then(|a| a.parse::<f32>().ok()).unwrap_or(0.0);
                texcoords.push(Vec2::new(coordinate(0), coordinate(1)));
                // A `vt u` alone gets v = 0, as the spec says; tobj wants two numbers.
                format!("vt {} {}", coordinate(0), coordinate(1))
            }
            "vn" => {
                // A non-finite normal is dropped where it is used (the face keeps its flat normal).
                if args.len() < 3 || args[..3].iter().any(|a| a.parse::<f32>().is_err()) {
                    return Err(fail(format!("`vn` needs 3 numbers, found `{rest}`")));
                }
                vn += 1;
                format!("vn {}", args[..3].join(" "))
            }
            "f" => {
                if args.len() < 3 {
                    return Err(fail(format!("a face needs at least 3 vertices, found {}", args.len())));
                }
                let mut uvs = Some(Vec::with_capacity(args.len()));
                for a in &args {
                    let mut has_vt = false;
                    for (slot, (part, count)) in a.split('/').zip([v, vt, vn]).enumerate() {
                        if part.is_empty() && slot > 0 {
                            continue;
                        }
                        let index: i64 = part.parse().map_err(|_| fail(format!("bad face vertex `{a}`")))?;
                        let resolved = if index < 0 { count + index + 1 } else { index };
                        if index == 0 || resolved < 1 || resolved > count {
                            return Err(fail(format!("face vertex `{a}` refers to an element that does not exist")));
                        }
                        if slot == 1 {
                            has_vt = true;
                            if let Some(uvs) = uvs.as_mut() {
                                uvs.push(texcoords[resolved as usize - 1]);
                            }
                        }
                    }
                    if !has_vt {
                        uvs = None;
                    }
                }
                out.face_uvs.push(uvs);
                format!("f {}", args.join(" "))
            }
            "mtllib" => {
                if !rest.is_empty() {
                    out.libraries.push((rest.to_string(), line_no));
                }
                String::new()
            }
            "usemtl" if rest.is_empty() => {
                nameless_usemtl.push(line_no);
                format!("usemtl {NO_MATERIAL}")
            }
            "usemtl" => {
                out.usemtl.push((rest.to_string(), line_no));
                format!("usemtl {rest}")
            }
            "o" | "g" => format!("{keyword} {rest}"),
            // Lines, points, smoothing groups, free-form statements: nothing radray draws.
            _ => String::new(),
        };
        out.text.push_str(&tobj_line);
        out.text.push('\n');
        for _ in line_no..k {
            out.text.push('\n');
        }
    }
    if extra_numbers > 0 {
        out.warnings.push(format!(
            "{}: {extra_numbers} `v` line(s) have other than 3, 4 (x y z w) or 6 (x y z r g b) numbers; using x y z",
            path.display()
        ));
    }
    if let Some(first) = nameless_usemtl.first() {
        out.warnings.push(format!(
            "{}:{first}: `usemtl` without a name ({} such line(s)); the faces after it get grey Kd 0.5",
            path.display(),
            nameless_usemtl.len()
        ));
    }
    Ok(out)
}

/// Checks OBJ text as `prepare` does and returns each face's own texture coordinates.
#[cfg(test)]
fn validate_text(path: &Path, text: &str) -> Result<FaceUvs, ObjError> {
    prepare(path, text).map(|p| p.face_uvs)
}

/// The libraries of `mtllib` lines, in order. A line may name several files (the spec's form) or one
/// whose name has spaces: the whole rest of the line is tried first. A library that cannot be read
/// is a warning (its materials are missing; faces naming them get the default grey); one that reads
/// but is wrong is an error.
fn load_libraries(path: &Path, prepared: &Prepared) -> Result<(Vec<mtl::MtlLibrary>, Vec<String>), ObjError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut libraries = Vec::new();
    let mut warnings = Vec::new();
    let mut seen: Vec<PathBuf> = Vec::new();
    for (rest, line) in &prepared.libraries {
        let whole = locate(dir, rest);
        let names: Vec<&str> =
            if whole.path.is_file() { vec![rest.as_str()] } else { rest.split_whitespace().collect() };
        for name in names {
            let found = locate(dir, name);
            if seen.contains(&found.path) {
                continue;
            }
            seen.push(found.path.clone());
            if found.substituted {
                warnings.push(format!(
                    "{}:{line}: material library `{name}` not found as written; using {}",
                    path.display(),
                    found.path.display()
                ));
            }
            match mtl::load(&found.path) {
                Ok(library) => libraries.push(library),
                Err(MtlError::Read { path: mtl_path, source }) => warnings.push(format!(
                    "{}:{line}: material library `{}` cannot be read ({source}); faces using its materials get grey Kd 0.5",
                    path.display(),
                    mtl_path.display()
                )),
                Err(other) => return Err(ObjError::MtlContent(other)),
            }
        }
    }
    Ok((libraries, warnings))
}

/// Loads an OBJ file and its MTL libraries.
pub fn load(path: &Path, two_sided: bool) -> Result<ObjContents, ObjError> {
    let bytes = std::fs::read(path).map_err(|source| ObjError::Read { path: path.to_path_buf(), source })?;
    let prepared = prepare(path, &mtl::decode_text(&bytes))?;
    let (libraries, library_warnings) = load_libraries(path, &prepared)?;
    let mut out = ObjContents::default();
    out.warnings.extend(prepared.warnings.iter().cloned());
    out.warnings.extend(library_warnings);
    for library in libraries {
        out.materials.extend(library.materials);
        out.warnings.extend(library.warnings);
    }
    // Names a `usemtl` gives that no library defines: one warning per name, at its first line.
    let mut undefined: Vec<(&str, usize, usize)> = Vec::new();
    for (name, line) in &prepared.usemtl {
        if out.materials.iter().any(|m| &m.name == name) {
            continue;
        }
        match undefined.iter_mut().find(|u| u.0 == name) {
            Some(u) => u.2 += 1,
            None => undefined.push((name, *line, 1)),
        }
    }
    for (name, line, count) in undefined {
        let more = if count > 1 { format!(" (and {} more `usemtl` line(s))", count - 1) } else { String::new() };
        out.warnings.push(format!(
            "{}:{line}: `usemtl {name}`: no material library defines it{more}; its faces get grey Kd 0.5",
            path.display()
        ));
    }

    let options = tobj::LoadOptions { single_index: true, triangulate: false, ignore_points: true, ignore_lines: true };
    // tobj numbers materials in the order its loader returns them: all libraries, loaded above, are
    // handed over at once by one `mtllib` line put first.
    let names: Vec<tobj::Material> =
        out.materials.iter().map(|m| tobj::Material { name: m.name.clone(), ..Default::default() }).collect();
    // The last definition of a repeated name wins (the library warned about it).
    let tobj_text = format!("mtllib radray\n{}", prepared.text);
    let loaded = tobj::load_obj_buf(&mut std::io::Cursor::new(tobj_text.as_bytes()), &options, |_| {
        Ok((names.clone(), names.iter().enumerate().map(|(i, m)| (m.name.clone(), i)).collect()))
    });
    let (models, _) = loaded.map_err(|e| ObjError::Load { path: path.to_path_buf(), message: e.to_string() })?;
    let face_uvs = prepared.face_uvs;

    let mut default_material = None;
    // Faces given the default grey; faces of a textured material that lack `vt`; faces whose `vn`
    // cannot be a normal: one warning each per file.
    let (mut grey_faces, mut untextured_faces, mut bad_normal_faces) = (0usize, 0usize, 0usize);
    let loc = SourceLoc { path: path.to_path_buf(), line: 0 };
    // tobj keeps the faces in file order, model after model; `face_uvs` can stand in for its texcoords
    // only when the counts agree.
    let face_count: usize = models
        .iter()
        .map(|m| if m.mesh.face_arities.is_empty() { m.mesh.indices.len() / 3 } else { m.mesh.face_arities.len() })
        .sum();
    let face_uvs = (face_count == face_uvs.len()).then_some(face_uvs);
    let mut face = 0usize;
    for model in &models {
        let mesh = &model.mesh;
        let material = match mesh.material_id {
            Some(id) if id < out.materials.len() => id as u32,
            Some(id) => return Err(ObjError::UnknownMaterial { path: path.to_path_buf(), name: format!("#{id}") }),
            None => *default_material.get_or_insert_with(|| {
                out.materials.push(Material::diffuse("default", Vec3::splat(0.5)));
                out.materials.len() as u32 - 1
            }),
        };
        let position = |i: u32| {
            Vec3::new(
                mesh.positions[3 * i as usize],
                mesh.positions[3 * i as usize + 1],
                mesh.positions[3 * i as usize + 2],
            )
        };
        let normal = |i: u32| {
            (mesh.normals.len() >= 3 * (i as usize + 1)).then(|| {
                Vec3::new(
                    mesh.normals[3 * i as usize],
                    mesh.normals[3 * i as usize + 1],
                    mesh.normals[3 * i as usize + 2],
                )
            })
        };
        // With `single_index`, tobj keeps one (v, vt, vn) tuple per mesh vertex but appends a texcoord
        // only where the face names one: the texcoords line up with the vertices only when every
        // face of the object has `vt`. Otherwise each face takes its own `vt` from the text, and the
        // faces without keep no uv (and their Kd).
        let vertex_count = mesh.positions.len() / 3;
        let has_uv = vertex_count > 0 && mesh.texcoords.len() == 2 * vertex_count;
        let uv = |i: u32| Vec2::new(mesh.texcoords[2 * i as usize], mesh.texcoords[2 * i as usize + 1]);
        let textured = out.materials.get(material as usize).is_some_and(|m| m.textures.diffuse.is_some());
        let arities: Vec<u32> =
            if mesh.face_arities.is_empty() { vec![3; mesh.indices.len() / 3] } else { mesh.face_arities.clone() };
        let mut start = 0usize;
        for arity in arities {
            let idx = &mesh.indices[start..start + arity as usize];
            start += arity as usize;
            let vertices: Vec<Vec3> = idx.iter().map(|&i| position(i)).collect();
            let mut normals: Option<Vec<Vec3>> = idx.iter().map(|&i| normal(i)).collect();
            // A zero-length or non-finite `vn` cannot bend anything: the face keeps its flat normal.
            if normals.as_ref().is_some_and(|n| n.iter().any(|n| !(n.is_finite() && n.length_squared() > 0.0))) {
                normals = None;
                bad_normal_faces += 1;
            }
            let uvs = if has_uv {
                Some(idx.iter().map(|&i| uv(i)).collect::<Vec<Vec2>>())
            } else {
                face_uvs.as_ref().and_then(|f| f[face].clone()).filter(|uvs| uvs.len() == idx.len())
            };
            face += 1;
            if textured && uvs.is_none() {
                untextured_faces += 1;
            }
            if mesh.material_id.is_none() {
                grey_faces += 1;
            }
            out.surfaces.push(Surface {
                vertices,
                material,
                two_sided,
                shading_normals: normals,
                uvs,
                object: model.name.clone(),
                source: loc.clone(),
            });
        }
    }
    if grey_faces > 0 {
        out.warnings.push(format!(
            "{}: {grey_faces} face(s) have no material (no `usemtl`, or one no library defines); using grey Kd 0.5",
            path.display()
        ));
    }
    if untextured_faces > 0 {
        out.warnings.push(format!(
            "{}: {untextured_faces} face(s) of textured materials have no texture coordinates (`vt`); they use \
             their Kd",
            path.display()
        ));
    }
    if bad_normal_faces > 0 {
        out.warnings.push(format!(
            "{}: {bad_normal_faces} face(s) name a zero-length or non-finite `vn`; they use their flat normal",
            path.display()
        ));
    }
    if out.surfaces.is_empty() {
        out.warnings.push(format!("{}: no faces (`f` statements); it adds nothing to the scene", path.display()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validator_reports_the_line_of_a_bad_face() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n";
        let err = validate_text(Path::new("x.obj"), text).unwrap_err();
        assert!(err.to_string().starts_with("x.obj:5:"), "{err}");
    }

    #[test]
    fn validator_rejects_non_finite_positions() {
        let err = validate_text(Path::new("x.obj"), "v 0 nan 0\n").unwrap_err();
        assert!(err.to_string().contains("x.obj:1:"), "{err}");
    }

    #[test]
    fn validator_accepts_negative_and_slashed_indices() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf -3//1 -2//1 -1//1\n";
        validate_text(Path::new("x.obj"), text).unwrap();
    }

    #[test]
    fn validator_reads_each_faces_own_texture_coordinates() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.5\nvt 1 0\nf 1/1 2/2 3/-1\nf 1 2 3\nf 1/1 2 3/2\n";
        let faces = validate_text(Path::new("x.obj"), text).unwrap();
        let (a, b) = (Vec2::new(0.25, 0.5), Vec2::new(1.0, 0.0));
        assert_eq!(faces, vec![Some(vec![a, b, b]), None, None]);
    }
}
