//! The immutable result of pass one: per-element and per-vertex radiosity (exitance), the direct part
//! of it, and how the solver got there. Pass two reads it; `radray solve` saves it to a file.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::form_factors::FormFactors;
use super::solver;
use crate::mesh::Mesh;
use crate::output;
use crate::scene::{Material, RadiosityParams, SolverKind};

/// How a solve went.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolveStats {
    pub solver: SolverKind,
    /// Sweeps (Gauss-Seidel, Jacobi) or shots (progressive refinement) performed.
    pub iterations: u32,
    /// The convergence measure after each sweep (largest relative change), or after each shot (unshot
    /// power / emitted power for progressive refinement).
    pub residual_history: Vec<f64>,
    pub converged: bool,
}

/// Radiosity of every element and vertex of a mesh. Exitance B (W/m²); radiance is B/π.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// Total exitance B_i of each element (emission plus all diffuse interreflection).
    pub element_exitance: Vec<Vec3>,
    /// The first-bounce part of B_i: light received straight from emitters and reflected,
    /// ρ_i Σ_j F_ij E_j (emission itself excluded).
    pub element_direct_exitance: Vec<Vec3>,
    /// Area-weighted vertex averages of `element_exitance` (Gouraud interpolation).
    pub vertex_exitance: Vec<Vec3>,
    /// Area-weighted vertex averages of `element_direct_exitance`.
    pub vertex_direct_exitance: Vec<Vec3>,
    /// Identifies the mesh and materials the solution belongs to: see `fingerprint`.
    pub mesh_fingerprint: u64,
    pub stats: SolveStats,
}

/// `RADRAYSO`: the first bytes of a solution file.
pub const FILE_MAGIC: [u8; 8] = *b"RADRAYSO";
/// Version of the solution file layout this build writes and reads. Version 2: the layout is that of
/// version 1, but the exitances of scenes with mirrors or glass include light that reached diffuse
/// surfaces through them (extended form factors), so version 1 files of such scenes are stale.
pub const FILE_VERSION: u32 = 2;

/// Why a solution file could not be written or read. Every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum SolutionFileError {
    #[error("cannot access radiosity solution file {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path} is not a radray solution file (it does not start with RADRAYSO)")]
    NotASolution { path: PathBuf },
    #[error(
        "{path}: solution file format version {found} is not supported (this radray reads version {supported}); \
         re-run `radray solve`"
    )]
    UnsupportedVersion { path: PathBuf, found: u32, supported: u32 },
    #[error(
        "{path} is truncated: {actual_bytes} bytes where its header announces {expected_bytes}; re-run `radray solve`"
    )]
    Truncated { path: PathBuf, expected_bytes: u64, actual_bytes: u64 },
    #[error("{path} is corrupted ({reason}); re-run `radray solve`")]
    Corrupted { path: PathBuf, reason: String },
    #[error(
        "{path}: solution was computed for a different scene or mesh; re-run `radray solve` \
         (file's fingerprint {found:016x}, current scene's {expected:016x})"
    )]
    Stale { path: PathBuf, expected: u64, found: u64 },
}

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
/// every platform. Any change of geometry, meshing or material (Kd, Ke, and Ks/Ni/d, which steer the
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
    h.finish()
}

/// Feeds `h` what decides where light goes at mirrors and glass: for each element with a specular
/// material, its index, Ks, Ni and transmittance (1 − d), and for every element whether it is diffuse
/// and whether it emits (where specular paths end). Shared by the solution fingerprint and the batch
/// cache's geometry key, so both go stale together.
pub fn hash_specular_materials(h: &mut Fnv1a64, mesh: &Mesh, materials: &[Material]) {
    let e = &mesh.elements;
    for i in 0..e.len() {
        if let Some(m) = materials.get(e.material[i] as usize).filter(|m| m.is_specular()) {
            h.write_u64(i as u64);
            h.write_f32s(m.specular_reflectance.to_array());
            h.write_f32s([m.ior, m.transmittance]);
        }
        h.write(&[(e.reflectance[i].max_element() > 0.0) as u8, (e.emission[i].max_element() > 0.0) as u8]);
    }
}

/// ρ_i Σ_j F_ij E_j for every element: the emission received in one bounce along straight lines and
/// reflected (the direct part of B, emission excluded). Only the plain entries count
/// (`FormFactors::row_plain`): light arriving through mirrors and glass belongs to the indirect
/// remainder, since pass two's shadow rays see only straight paths. Rows in parallel; each row is one
/// `solver::gather`.
pub fn direct_exitance(ff: &FormFactors, reflectance: &[Vec3], emission: &[Vec3]) -> Vec<DVec3> {
    let emission: Vec<DVec3> = emission.iter().map(|e| e.as_dvec3()).collect();
    (0..ff.len())
        .into_par_iter()
        .map(|i| {
            let (columns, factors) = ff.row_plain(i);
            reflectance[i].as_dvec3() * solver::gather(columns, factors, &emission)
        })
        .collect()
}

fn to_f32(values: &[DVec3]) -> Vec<Vec3> {
    values.iter().map(|v| v.as_vec3()).collect()
}

impl Solution {
    /// Pass one after the form factors: solves B = E + ρ·F·B with `params` (see `solver::solve_f64`),
    /// adds the direct part, the vertex averages and the fingerprint of `mesh` and `materials` (the
    /// scene's material table, which `mesh.elements.material` indexes). `on_iteration` sees every
    /// sweep or shot.
    pub fn compute(
        mesh: &Mesh,
        materials: &[Material],
        ff: &FormFactors,
        params: &RadiosityParams,
        on_iteration: &mut dyn FnMut(u32, f64),
    ) -> Solution {
        let e = &mesh.elements;
        assert_eq!(ff.len(), e.len(), "one form-factor row per element");
        let (exitance, stats) = solver::solve_f64(ff, &e.reflectance, &e.emission, &e.area, params, on_iteration);
        let direct = direct_exitance(ff, &e.reflectance, &e.emission);
        Solution::from_element_values(mesh, materials, &exitance, &direct, stats)
    }

    /// A solution from per-element exitance and its direct part (however they were solved): adds the
    /// vertex averages and the fingerprint of `mesh` and `materials`.
    pub fn from_element_values(
        mesh: &Mesh,
        materials: &[Material],
        exitance: &[DVec3],
        direct: &[DVec3],
        stats: SolveStats,
    ) -> Solution {
        assert!(exitance.len() == mesh.elements.len() && direct.len() == mesh.elements.len());
        Solution {
            element_exitance: to_f32(exitance),
            element_direct_exitance: to_f32(direct),
            vertex_exitance: to_f32(&mesh.vertex_average(exitance)),
            vertex_direct_exitance: to_f32(&mesh.vertex_average(direct)),
            mesh_fingerprint: fingerprint(mesh, materials),
            stats,
        }
    }

    /// The solution of a scene without emitters: everything black, converged without a sweep
    /// (`stats.solver` is Gauss-Seidel, nothing was run).
    pub fn black(mesh: &Mesh, materials: &[Material]) -> Solution {
        Solution {
            element_exitance: vec![Vec3::ZERO; mesh.elements.len()],
            element_direct_exitance: vec![Vec3::ZERO; mesh.elements.len()],
            vertex_exitance: vec![Vec3::ZERO; mesh.positions.len()],
            vertex_direct_exitance: vec![Vec3::ZERO; mesh.positions.len()],
            mesh_fingerprint: fingerprint(mesh, materials),
            stats: SolveStats {
                solver: SolverKind::GaussSeidel,
                iterations: 0,
                residual_history: Vec::new(),
                converged: true,
            },
        }
    }

    /// Radiance leaving element i (diffuse): L = B/π.
    pub fn element_radiance(&self, i: usize) -> Vec3 {
        self.element_exitance[i] * std::f32::consts::FRAC_1_PI
    }

    /// Radiance of the indirect part of element i, (B − E − direct)/π given its emission E: what pass
    /// two adds when it samples direct light per pixel.
    pub fn element_indirect_radiance(&self, i: usize, emission: Vec3) -> Vec3 {
        ((self.element_exitance[i] - emission - self.element_direct_exitance[i]) * std::f32::consts::FRAC_1_PI)
            .max(Vec3::ZERO)
    }

    /// Radiance at vertex v (Gouraud-interpolated by the caller): L = B/π.
    pub fn vertex_radiance(&self, v: usize) -> Vec3 {
        self.vertex_exitance[v] * std::f32::consts::FRAC_1_PI
    }

    /// The file image (format version `FILE_VERSION`), all little-endian:
    ///
    /// ```text
    /// offset  size     field
    /// 0       8        magic "RADRAYSO"
    /// 8       4        format version (u32)
    /// 12      8        element count n (u64)
    /// 20      8        vertex count m (u64)
    /// 28      8        mesh fingerprint (u64)
    /// 36      4        solver: 0 Gauss-Seidel, 1 Jacobi, 2 progressive (u32)
    /// 40      4        iterations (u32)
    /// 44      4        converged (u32, 0 or 1)
    /// 48      8        residual history length h (u64)
    /// 56      8h       residual history (f64)
    /// …       12n      element exitance (3 × f32 per element), then 12n element direct exitance,
    ///         12m      vertex exitance, then 12m vertex direct exitance
    /// end−8   8        FNV-1a 64 of every byte before it
    /// ```
    pub fn to_bytes(&self) -> Vec<u8> {
        let (n, m) = (self.element_exitance.len(), self.vertex_exitance.len());
        assert!(self.element_direct_exitance.len() == n && self.vertex_direct_exitance.len() == m);
        let h = self.stats.residual_history.len();
        let mut out = Vec::with_capacity(HEADER_BYTES + 8 * h + 24 * (n + m) + 8);
        out.extend_from_slice(&FILE_MAGIC);
        out.extend_from_slice(&FILE_VERSION.to_le_bytes());
        out.extend_from_slice(&(n as u64).to_le_bytes());
        out.extend_from_slice(&(m as u64).to_le_bytes());
        out.extend_from_slice(&self.mesh_fingerprint.to_le_bytes());
        out.extend_from_slice(&solver_code(self.stats.solver).to_le_bytes());
        out.extend_from_slice(&self.stats.iterations.to_le_bytes());
        out.extend_from_slice(&(self.stats.converged as u32).to_le_bytes());
        out.extend_from_slice(&(h as u64).to_le_bytes());
        for r in &self.stats.residual_history {
            out.extend_from_slice(&r.to_le_bytes());
        }
        for values in
            [&self.element_exitance, &self.element_direct_exitance, &self.vertex_exitance, &self.vertex_direct_exitance]
        {
            for v in values.iter() {
                for c in v.to_array() {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        let checksum = fnv1a64(&out);
        out.extend_from_slice(&checksum.to_le_bytes());
        out
    }

    /// Parses a file image written by `to_bytes`. `path` only names the source in errors. Checks, in
    /// order: magic, version, length against the header's counts, checksum, then that the solution
    /// belongs to the mesh with `expected_fingerprint`. Never panics, whatever the bytes.
    pub fn from_bytes(bytes: &[u8], path: &Path, expected_fingerprint: u64) -> Result<Solution, SolutionFileError> {
        let path = || path.to_path_buf();
        let corrupted = |reason: &str| SolutionFileError::Corrupted { path: path(), reason: reason.to_string() };
        if bytes.len() < FILE_MAGIC.len() || bytes[..FILE_MAGIC.len()] != FILE_MAGIC {
            return Err(SolutionFileError::NotASolution { path: path() });
        }
        let mut r = Reader { bytes, at: FILE_MAGIC.len() };
        let truncated_header = || SolutionFileError::Truncated {
            path: path(),
            expected_bytes: (HEADER_BYTES + 8) as u64,
            actual_bytes: bytes.len() as u64,
        };
        let version = r.u32().ok_or_else(truncated_header)?;
        if version != FILE_VERSION {
            return Err(SolutionFileError::UnsupportedVersion {
                path: path(),
                found: version,
                supported: FILE_VERSION,
            });
        }
        let n = r.u64().ok_or_else(truncated_header)?;
        let m = r.u64().ok_or_else(truncated_header)?;
        let found_fingerprint = r.u64().ok_or_else(truncated_header)?;
        let solver = r.u32().ok_or_else(truncated_header)?;
        let iterations = r.u32().ok_or_else(truncated_header)?;
        let converged = r.u32().ok_or_else(truncated_header)?;
        let h = r.u64().ok_or_else(truncated_header)?;
        // Total length from the header's counts, in u128 so that no count can overflow it.
        let expected = HEADER_BYTES as u128 + 8 * h as u128 + 24 * (n as u128 + m as u128) + 8;
        if (bytes.len() as u128) < expected {
            return Err(SolutionFileError::Truncated {
                path: path(),
                expected_bytes: expected.min(u64::MAX as u128) as u64,
                actual_bytes: bytes.len() as u64,
            });
        }
        if bytes.len() as u128 > expected {
            return Err(corrupted("bytes past the end of the data"));
        }
        let body = bytes.len() - 8;
        let stored = u64::from_le_bytes(bytes[body..].try_into().map_err(|_| corrupted("checksum"))?);
        if fnv1a64(&bytes[..body]) != stored {
            return Err(corrupted("checksum mismatch"));
        }
        let solver = match solver {
            0 => SolverKind::GaussSeidel,
            1 => SolverKind::Jacobi,
            2 => SolverKind::Progressive,
            _ => return Err(corrupted("unknown solver code")),
        };
        let converged = match converged {
            0 => false,
            1 => true,
            _ => return Err(corrupted("converged flag is neither 0 nor 1")),
        };
        if found_fingerprint != expected_fingerprint {
            return Err(SolutionFileError::Stale {
                path: path(),
                expected: expected_fingerprint,
                found: found_fingerprint,
            });
        }
        // The length check above guarantees every read below succeeds.
        let (n, m, h) = (n as usize, m as usize, h as usize);
        let residual_history = (0..h).map(|_| r.f64()).collect::<Option<Vec<f64>>>();
        let element_exitance = r.vec3s(n);
        let element_direct_exitance = r.vec3s(n);
        let vertex_exitance = r.vec3s(m);
        let vertex_direct_exitance = r.vec3s(m);
        match (residual_history, element_exitance, element_direct_exitance, vertex_exitance, vertex_direct_exitance) {
            (Some(residual_history), Some(ee), Some(ed), Some(ve), Some(vd)) => Ok(Solution {
                element_exitance: ee,
                element_direct_exitance: ed,
                vertex_exitance: ve,
                vertex_direct_exitance: vd,
                mesh_fingerprint: found_fingerprint,
                stats: SolveStats { solver, iterations, residual_history, converged },
            }),
            _ => Err(corrupted("data shorter than its header says")),
        }
    }

    /// Writes the solution atomically (see `to_bytes` for the layout).
    pub fn save(&self, path: &Path) -> Result<(), SolutionFileError> {
        output::write_atomically(path, &self.to_bytes())
            .map_err(|source| SolutionFileError::Io { path: path.to_path_buf(), source })
    }

    /// Reads a solution saved by `save`, refusing a file that is foreign, of another format version,
    /// truncated, corrupted, or computed for another mesh (`expected_fingerprint` = `fingerprint(mesh)`).
    pub fn load(path: &Path, expected_fingerprint: u64) -> Result<Solution, SolutionFileError> {
        let bytes = std::fs::read(path).map_err(|source| SolutionFileError::Io { path: path.to_path_buf(), source })?;
        Solution::from_bytes(&bytes, path, expected_fingerprint)
    }
}

/// Bytes before the residual history.
const HEADER_BYTES: usize = 56;

fn solver_code(solver: SolverKind) -> u32 {
    match solver {
        SolverKind::GaussSeidel => 0,
        SolverKind::Jacobi => 1,
        SolverKind::Progressive => 2,
    }
}

/// Little-endian reads that return `None` past the end instead of panicking.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let end = self.at.checked_add(N)?;
        let chunk = self.bytes.get(self.at..end)?;
        self.at = end;
        chunk.try_into().ok()
    }

    fn u32(&mut self) -> Option<u32> {
        self.take().map(u32::from_le_bytes)
    }

    fn u64(&mut self) -> Option<u64> {
        self.take().map(u64::from_le_bytes)
    }

    fn f64(&mut self) -> Option<f64> {
        self.take().map(f64::from_le_bytes)
    }

    fn f32(&mut self) -> Option<f32> {
        self.take().map(f32::from_le_bytes)
    }

    fn vec3s(&mut self, count: usize) -> Option<Vec<Vec3>> {
        (0..count).map(|_| Some(Vec3::new(self.f32()?, self.f32()?, self.f32()?))).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn fnv1a64_matches_the_published_test_vectors() {
        // From the FNV reference (Noll, "FNV hash" test suite): "" and "a".
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    fn sample() -> Solution {
        Solution {
            element_exitance: vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.5, f32::NAN, -0.0)],
            element_direct_exitance: vec![Vec3::new(0.1, 0.2, 0.3), Vec3::ZERO],
            vertex_exitance: vec![Vec3::ONE; 3],
            vertex_direct_exitance: vec![Vec3::splat(0.25); 3],
            mesh_fingerprint: 0x0123_4567_89ab_cdef,
            stats: SolveStats {
                solver: SolverKind::Jacobi,
                iterations: 3,
                residual_history: vec![0.5, 0.01, 1e-5],
                converged: true,
            },
        }
    }

    #[test]
    fn bytes_round_trip_bit_for_bit() {
        let s = sample();
        let bytes = s.to_bytes();
        let back = Solution::from_bytes(&bytes, Path::new("x"), s.mesh_fingerprint).unwrap();
        // NaN ≠ NaN, so compare the re-encoded bytes.
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!(back.stats, s.stats);
    }

    proptest! {
        #[test]
        fn parser_never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let _ = Solution::from_bytes(&bytes, Path::new("random"), 0);
            let mut with_magic = FILE_MAGIC.to_vec();
            with_magic.extend_from_slice(&FILE_VERSION.to_le_bytes());
            with_magic.extend_from_slice(&bytes);
            let _ = Solution::from_bytes(&with_magic, Path::new("random"), 0);
        }

        #[test]
        fn any_single_byte_change_or_truncation_is_refused(at in 0usize..1000, flip in 1u8..=255, cut in 0usize..1000) {
            let s = sample();
            let bytes = s.to_bytes();
            let mut mutated = bytes.clone();
            let at = at % bytes.len();
            mutated[at] ^= flip;
            prop_assert!(Solution::from_bytes(&mutated, Path::new("m"), s.mesh_fingerprint).is_err());
            let cut = cut % bytes.len();
            prop_assert!(Solution::from_bytes(&bytes[..cut], Path::new("t"), s.mesh_fingerprint).is_err());
        }
    }
}
