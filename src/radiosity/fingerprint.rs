//! The hashes that identify pass one's inputs: FNV-1a 64 (stable across runs, builds and platforms),
//! the fingerprint a solution carries, and the keys under which a batch reuses form factors and
//! solutions.

use crate::mesh::Mesh;
use crate::scene::{Material, RadiosityParams};
use glam::Vec3;

/// FNV-1a 64-bit hash state (Fowler, Noll, Vo): stable across runs, builds and platforms.
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a64(u64);

impl Default for Fnv1a64 {
    fn default() -> Self {
        Fnv1a64(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a64 {
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    pub fn write_u64(&mut self, v: u64) {
        self.write(&v.to_le_bytes());
    }

    pub fn write_f32s(&mut self, values: impl IntoIterator<Item = f32>) {
        for v in values {
            self.write(&v.to_bits().to_le_bytes());
        }
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// FNV-1a 64 of `bytes`.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h = Fnv1a64::default();
    h.write(bytes);
    h.finish()
}

/// Identifies the scene a solution belongs to: FNV-1a 64 over the vertex and element counts, the
/// vertex positions, the element corners, reflectances and emissions, and every element's specular
/// material (`hash_specular_materials`), in little-endian bit patterns so the value is the same on
/// every platform; with textures also the texture digest (`SceneTextures::digest`) and the vertex uvs.
/// Any change of geometry, meshing or material (Kd, Ke, and Ks/Ni/d, which steer the
/// extended form factors through mirrors and glass) changes it.
pub fn fingerprint(mesh: &Mesh, materials: &[Material]) -> u64 {
    let e = &mesh.elements;
    let mut h = Fnv1a64::default();
    h.write_u64(mesh.positions.len() as u64);
    h.write_u64(e.len() as u64);
    h.write_f32s(mesh.positions.iter().flat_map(|p| p.to_array()));
    for c in &e.corners {
        for v in c {
            h.write(&v.to_le_bytes());
        }
    }
    h.write_f32s(e.reflectance.iter().flat_map(|r| r.to_array()));
    h.write_f32s(e.emission.iter().flat_map(|r| r.to_array()));
    hash_specular_materials(&mut h, mesh, materials);
    // Textures: which files, their decoded texels and the uv they are read at (pass one reads their
    // element means, pass two the texels). Untextured meshes hash nothing more, so their
    // fingerprints are those of radray before textures.
    if mesh.textures.is_textured() {
        h.write_u64(mesh.textures.digest());
        h.write_f32s(mesh.uvs.iter().flat_map(|uv| uv.to_array()));
    }
    h.finish()
}

/// Feeds `h` what decides where light goes at mirrors and glass: for each element with a specular
/// material, its index, Ks, Ni, transmittance (1 − d) and a tinted Tf, and for every element whether it is diffuse
/// and whether it emits (where specular paths end). Shared by the solution fingerprint and the batch
/// cache's geometry key, so both go stale together.
pub fn hash_specular_materials(h: &mut Fnv1a64, mesh: &Mesh, materials: &[Material]) {
    let e = &mesh.elements;
    for i in 0..e.len() {
        if let Some(m) = materials.get(e.material[i] as usize).filter(|m| m.is_specular()) {
            h.write_u64(i as u64);
            h.write_f32s(m.specular_reflectance.to_array());
            h.write_f32s([m.ior, m.transmittance]);
            // Only a tinted filter is hashed, so clear glass keeps the fingerprint it always had.
            if m.is_dielectric() && m.transmission_filter != Vec3::ONE {
                h.write_f32s(m.transmission_filter.to_array());
            }
        }
        h.write(&[(e.reflectance[i].max_element() > 0.0) as u8, (e.emission[i].max_element() > 0.0) as u8]);
    }
}

/// FNV-1a over the bytes that decide form factors: positions, corners, hemicube settings and, since
/// extended form factors follow light through mirrors and glass, each element's specular material
/// (Ks, Ni, 1 − d) and its diffuse/emissive flags (which decide where specular paths end). Two meshes
/// with the same key have the same form factors, so a materials-only change (Kd, Ke) re-solves from
/// them.
pub fn form_factor_key(mesh: &Mesh, materials: &[Material], params: &RadiosityParams) -> u64 {
    let mut h = Fnv1a64::default();
    h.write_f32s(mesh.positions.iter().flat_map(|p| p.to_array()));
    for c in &mesh.elements.corners {
        for v in c {
            h.write(&v.to_le_bytes());
        }
    }
    hash_specular_materials(&mut h, mesh, materials);
    h.write(&params.hemicube_resolution_px.to_le_bytes());
    h.write(&[params.rotate_hemicubes as u8]);
    h.write(&params.seed.to_le_bytes());
    h.finish()
}

/// What a solution depends on: the mesh fingerprint, the form-factor key and the solver settings
/// (relaxation, tolerance, iteration cap, solver, stored or matrix-free).
pub fn solution_key(mesh: &Mesh, materials: &[Material], params: &RadiosityParams) -> u64 {
    let r = params;
    let mut h = fingerprint(mesh, materials) ^ form_factor_key(mesh, materials, params).rotate_left(17);
    for x in [
        r.relaxation.to_bits(),
        r.tolerance.to_bits(),
        r.max_iterations as u64,
        r.solver as u64,
        r.store_form_factors as u64,
    ] {
        h = (h ^ x).wrapping_mul(0x100000001b3);
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a64_matches_the_published_test_vectors() {
        // From the FNV reference (Noll, "FNV hash" test suite): "" and "a".
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
