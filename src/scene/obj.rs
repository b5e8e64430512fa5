//! OBJ loading through tobj: the only user of tobj. Faces become `Surface`s (triangles and quads
//! as they are, larger or non-convex polygons as triangle fans). The MTL libraries an OBJ names are
//! read by `material::mtl` (tobj's MTL reader panics on `Kd 1`, drops line numbers and keeps one value
//! per unknown statement), and handed to tobj only as names, so that `usemtl` resolves as before.

use super::{Material, SourceLoc, Surface};
use crate::material::mtl::{self, MtlError};
use glam::{Vec2, Vec3};
use std::cell::RefCell;
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

/// Checks the OBJ text line by line for what tobj would reject without saying where: unparsable
/// numbers and face indices out of range. Returns the first problem with its line, or each face's
/// texture coordinates (tobj loses them on objects whose faces only partly have `vt`).
fn validate_text(path: &Path, text: &str) -> Result<FaceUvs, ObjError> {
    let (mut v, mut vt, mut vn) = (0i64, 0i64, 0i64);
    let mut texcoords: Vec<Vec2> = Vec::new();
    let mut faces: FaceUvs = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let fail =
            |message: String| ObjError::Malformed { loc: SourceLoc { path: path.to_path_buf(), line: k + 1 }, message };
        let line = line.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let args: Vec<&str> = words.collect();
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
        match keyword {
            "v" => {
                numbers(3)?;
                v += 1;
            }
            "vt" => {
                numbers(1)?;
                vt += 1;
                let coordinate = |k: usize| args.get(k).and_then(|a| a.parse::<f32>().ok()).unwrap_or(0.0);
                texcoords.push(Vec2::new(coordinate(0), coordinate(1)));
            }
            "vn" => {
                numbers(3)?;
                vn += 1;
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
                faces.push(uvs);
            }
            _ => {}
        }
    }
    Ok(faces)
}

/// Loads an OBJ file and its MTL library.
pub fn load(path: &Path, two_sided: bool) -> Result<ObjContents, ObjError> {
    let text = std::fs::read_to_string(path).map_err(|source| ObjError::Read { path: path.to_path_buf(), source })?;
    let face_uvs = validate_text(path, &text)?;
    let options = tobj::LoadOptions { single_index: true, triangulate: false, ignore_points: true, ignore_lines: true };
    let dir = path.parent().unwrap_or(Path::new("."));
    // Libraries in `mtllib` order; tobj numbers materials in the same order.
    let libraries: RefCell<Vec<mtl::MtlLibrary>> = RefCell::new(Vec::new());
    let failure: RefCell<Option<ObjError>> = RefCell::new(None);
    let loaded = tobj::load_obj_buf(&mut std::io::Cursor::new(text.as_bytes()), &options, |name| {
        let mtl_path = dir.join(name);
        match mtl::load(&mtl_path) {
            Ok(library) => {
                let names =
                    library.materials.iter().map(|m| tobj::Material { name: m.name.clone(), ..Default::default() });
                let names: Vec<tobj::Material> = names.collect();
                // The last definition of a repeated name wins (the library warned about it).
                let index = names.iter().enumerate().map(|(i, m)| (m.name.clone(), i)).collect();
                libraries.borrow_mut().push(library);
                Ok((names, index))
            }
            Err(e) => {
                let error = match e {
                    MtlError::Read { path: mtl_path, source } => ObjError::Mtl {
                        path: path.to_path_buf(),
                        message: format!("material library `{}` cannot be read: {source}", mtl_path.display()),
                    },
                    other => ObjError::MtlContent(other),
                };
                failure.borrow_mut().get_or_insert(error);
                Err(tobj::LoadError::MaterialParseError)
            }
        }
    });
    if let Some(error) = failure.into_inner() {
        return Err(error);
    }
    let (models, _) = loaded.map_err(|e| ObjError::Load { path: path.to_path_buf(), message: e.to_string() })?;

    let mut out = ObjContents::default();
    for library in libraries.into_inner() {
        out.materials.extend(library.materials);
        out.warnings.extend(library.warnings);
    }
    let mut default_material = None;
    // Faces of a textured material that lack `vt`: one warning per file.
    let mut untextured_faces = 0usize;
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
                out.warnings.push(format!(
                    "{}: object `{}` has no material; using grey Kd 0.5",
                    path.display(),
                    model.name
                ));
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
            let normals: Option<Vec<Vec3>> = idx.iter().map(|&i| normal(i)).collect();
            let uvs = if has_uv {
                Some(idx.iter().map(|&i| uv(i)).collect::<Vec<Vec2>>())
            } else {
                face_uvs.as_ref().and_then(|f| f[face].clone()).filter(|uvs| uvs.len() == idx.len())
            };
            face += 1;
            if textured && uvs.is_none() {
                untextured_faces += 1;
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
    if untextured_faces > 0 {
        out.warnings.push(format!(
            "{}: {untextured_faces} face(s) of textured materials have no texture coordinates (`vt`); they use \
             their Kd",
            path.display()
        ));
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
