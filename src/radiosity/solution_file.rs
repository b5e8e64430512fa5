//! The solution file: a little-endian binary image of a `Solution` with a magic, a format version and
//! a checksum, written atomically and refused when foreign, truncated, corrupted or stale.

use std::path::{Path, PathBuf};

use glam::Vec3;

use std::sync::Arc;

use super::adaptive::refinement::{LevelSplits, Refinement, RefinementError};
use super::fingerprint::fnv1a64;
use super::leaf_mesh::LeafGeometry;
use super::solution::Solution;
use super::stats::SolveStats;
use crate::output;
use crate::scene::SolverKind;

/// `RADRAYSO`: the first bytes of a solution file.
pub const FILE_MAGIC: [u8; 8] = *b"RADRAYSO";
/// Version of the solution file layout this build writes and reads. Version 2: the layout is that of
/// version 1, but the exitances of scenes with mirrors or glass include light that reached diffuse
/// surfaces through them (extended form factors), so version 1 files of such scenes are stale.
pub const FILE_VERSION: u32 = 2;
/// Version of a file that also carries the leaf mesh of a hierarchical solution (`LeafGeometry`):
/// version 2's layout with the leaf counts after the header and the leaf section before the checksum.
pub const FILE_VERSION_LEAF_MESH: u32 = 3;
/// Version of a file that also carries the refinement of an adaptive solution (`Refinement`): version
/// 2's layout with the level and split counts after the header and the levels before the checksum.
pub const FILE_VERSION_REFINED_MESH: u32 = 4;
/// Version of a hierarchical solution whose exitance holds the light that reached diffuse surfaces
/// through mirrors and glass (`Solution::holds_caustic_light`): version 3's layout. A version 3 file
/// is still read, as a solution without that light (pass two then adds all of it).
pub const FILE_VERSION_LEAF_MESH_CAUSTICS: u32 = 5;

/// Which mesh a solution file's values live on, read from its format version.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolutionMesh {
    /// The scene's uniform mesh (version 2).
    Uniform,
    /// The leaf mesh of a hierarchical solution, which the file carries (version 3 or 5).
    Leaves,
    /// The scene's patch mesh refined as the file's adaptive refinement says (version 4).
    Refined,
}

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
    #[error("{path}: the adaptive mesh it carries does not fit the current scene ({source}); re-run `radray solve`")]
    StaleRefinement { path: PathBuf, source: RefinementError },
}

impl Solution {
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
    ///
    /// A hierarchical solution (with `leaf_geometry`) is written as version
    /// `FILE_VERSION_LEAF_MESH_CAUSTICS` (`FILE_VERSION_LEAF_MESH` if it does not hold caustic light):
    /// after the header (at 56) the leaf mesh's position count p and leaf count t (u64 each), and
    /// before the checksum 12p leaf positions (3 × f32), 12t leaf corners (3 × u32), 4t scene surfaces
    /// (u32) and t back-side flags (u8, 0 or 1); t equals n.
    ///
    /// An adaptive solution (with `refinement`) is written as version `FILE_VERSION_REFINED_MESH`:
    /// after the header (at 56) the level count L and the total split count S (u64 each), and before
    /// the checksum, per level, the element count of the mesh it split and its split count (u64 each),
    /// then the S split element indices (u32, ascending within a level, levels in order).
    pub fn to_bytes(&self) -> Vec<u8> {
        let (n, m) = (self.element_exitance.len(), self.vertex_exitance.len());
        assert!(self.element_direct_exitance.len() == n && self.vertex_direct_exitance.len() == m);
        let h = self.stats.residual_history.len();
        let mut out = Vec::with_capacity(HEADER_BYTES + 8 * h + 24 * (n + m) + 8);
        out.extend_from_slice(&FILE_MAGIC);
        assert!(self.leaf_geometry.is_none() || self.refinement.is_none(), "a solution has one own mesh");
        let version = match (&self.leaf_geometry, &self.refinement) {
            (Some(_), _) if self.holds_caustic_light => FILE_VERSION_LEAF_MESH_CAUSTICS,
            (Some(_), _) => FILE_VERSION_LEAF_MESH,
            (None, Some(_)) => FILE_VERSION_REFINED_MESH,
            (None, None) => FILE_VERSION,
        };
        out.extend_from_slice(&version.to_le_bytes());
        out.extend_from_slice(&(n as u64).to_le_bytes());
        out.extend_from_slice(&(m as u64).to_le_bytes());
        out.extend_from_slice(&self.mesh_fingerprint.to_le_bytes());
        out.extend_from_slice(&solver_code(self.stats.solver).to_le_bytes());
        out.extend_from_slice(&self.stats.iterations.to_le_bytes());
        out.extend_from_slice(&(self.stats.converged as u32).to_le_bytes());
        out.extend_from_slice(&(h as u64).to_le_bytes());
        if let Some(g) = &self.leaf_geometry {
            out.extend_from_slice(&(g.positions.len() as u64).to_le_bytes());
            out.extend_from_slice(&(g.triangles.len() as u64).to_le_bytes());
        }
        if let Some(r) = &self.refinement {
            out.extend_from_slice(&(r.levels.len() as u64).to_le_bytes());
            out.extend_from_slice(&(r.split_count() as u64).to_le_bytes());
        }
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
        if let Some(g) = &self.leaf_geometry {
            for c in g.positions.iter().flat_map(|p| p.to_array()) {
                out.extend_from_slice(&c.to_le_bytes());
            }
            for v in g.triangles.iter().flatten() {
                out.extend_from_slice(&v.to_le_bytes());
            }
            for s in &g.surface {
                out.extend_from_slice(&s.to_le_bytes());
            }
            out.extend(g.back.iter().map(|&b| b as u8));
        }
        if let Some(r) = &self.refinement {
            for level in &r.levels {
                out.extend_from_slice(&level.elements.to_le_bytes());
                out.extend_from_slice(&(level.split.len() as u64).to_le_bytes());
            }
            for e in r.levels.iter().flat_map(|l| &l.split) {
                out.extend_from_slice(&e.to_le_bytes());
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
        Solution::from_bytes_with(bytes, path, |_| Ok(expected_fingerprint))
    }

    /// `from_bytes` for a solution whose expected fingerprint depends on what the file carries (the
    /// mesh an adaptive refinement rebuilds): `expected` is asked with the parsed solution, after
    /// every check of the file itself, and may refuse it.
    pub fn from_bytes_with(
        bytes: &[u8],
        path: &Path,
        expected: impl FnOnce(&Solution) -> Result<u64, SolutionFileError>,
    ) -> Result<Solution, SolutionFileError> {
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
        if ![FILE_VERSION, FILE_VERSION_LEAF_MESH, FILE_VERSION_REFINED_MESH, FILE_VERSION_LEAF_MESH_CAUSTICS]
            .contains(&version)
        {
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
        let leaf_mesh = [FILE_VERSION_LEAF_MESH, FILE_VERSION_LEAF_MESH_CAUSTICS].contains(&version);
        let refined = version == FILE_VERSION_REFINED_MESH;
        let (p, t) = if leaf_mesh {
            (r.u64().ok_or_else(truncated_header)?, r.u64().ok_or_else(truncated_header)?)
        } else {
            (0, 0)
        };
        let (levels, splits) = if refined {
            (r.u64().ok_or_else(truncated_header)?, r.u64().ok_or_else(truncated_header)?)
        } else {
            (0, 0)
        };
        // Total length from the header's counts, in u128 so that no count can overflow it.
        let expected_bytes = HEADER_BYTES as u128
            + if leaf_mesh || refined { 16 } else { 0 }
            + 8 * h as u128
            + 24 * (n as u128 + m as u128)
            + 12 * p as u128
            + 17 * t as u128
            + 16 * levels as u128
            + 4 * splits as u128
            + 8;
        if (bytes.len() as u128) < expected_bytes {
            return Err(SolutionFileError::Truncated {
                path: path(),
                expected_bytes: expected_bytes.min(u64::MAX as u128) as u64,
                actual_bytes: bytes.len() as u64,
            });
        }
        if bytes.len() as u128 > expected_bytes {
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
        if leaf_mesh && t != n {
            return Err(corrupted("leaf count differs from element count"));
        }
        // The length check above guarantees every read below succeeds.
        let (n, m, h) = (n as usize, m as usize, h as usize);
        let residual_history = (0..h).map(|_| r.f64()).collect::<Option<Vec<f64>>>();
        let element_exitance = r.vec3s(n);
        let element_direct_exitance = r.vec3s(n);
        let vertex_exitance = r.vec3s(m);
        let vertex_direct_exitance = r.vec3s(m);
        let leaf_geometry = if leaf_mesh {
            Some(read_leaf_geometry(&mut r, p as usize, t as usize).ok_or_else(|| corrupted("leaf mesh"))?)
        } else {
            None
        };
        if let Some(g) = &leaf_geometry {
            if g.triangles.iter().flatten().any(|&v| v as u64 >= p) {
                return Err(corrupted("leaf corner past the leaf positions"));
            }
        }
        let refinement = if refined {
            let refinement = read_refinement(&mut r, levels as usize, splits as usize)
                .ok_or_else(|| corrupted("level split counts differ from the total"))?;
            if !refinement.is_consistent() {
                return Err(corrupted("refinement levels are inconsistent"));
            }
            Some(refinement)
        } else {
            None
        };
        let solution = match (
            residual_history,
            element_exitance,
            element_direct_exitance,
            vertex_exitance,
            vertex_direct_exitance,
        ) {
            (Some(residual_history), Some(ee), Some(ed), Some(ve), Some(vd)) => Solution {
                element_exitance: ee,
                element_direct_exitance: ed,
                vertex_exitance: ve,
                vertex_direct_exitance: vd,
                mesh_fingerprint: found_fingerprint,
                stats: SolveStats { solver, iterations, residual_history, converged },
                leaf_geometry: leaf_geometry.map(Arc::new),
                refinement: refinement.map(Arc::new),
                holds_caustic_light: version != FILE_VERSION_LEAF_MESH,
            },
            _ => return Err(corrupted("data shorter than its header says")),
        };
        let expected_fingerprint = expected(&solution)?;
        if found_fingerprint != expected_fingerprint {
            return Err(SolutionFileError::Stale {
                path: path(),
                expected: expected_fingerprint,
                found: found_fingerprint,
            });
        }
        Ok(solution)
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

    /// `load` with the expected fingerprint asked of the parsed solution (see `from_bytes_with`).
    pub fn load_with(
        path: &Path,
        expected: impl FnOnce(&Solution) -> Result<u64, SolutionFileError>,
    ) -> Result<Solution, SolutionFileError> {
        let bytes = std::fs::read(path).map_err(|source| SolutionFileError::Io { path: path.to_path_buf(), source })?;
        Solution::from_bytes_with(&bytes, path, expected)
    }
}

/// The refinement section of a version-4 file: `levels` (elements, split count) pairs, then the
/// `splits` indices; `None` when the levels' counts do not add up to `splits`.
fn read_refinement(r: &mut Reader, levels: usize, splits: usize) -> Option<Refinement> {
    let counts = (0..levels).map(|_| Some((r.u64()?, r.u64()?))).collect::<Option<Vec<_>>>()?;
    let total = counts.iter().try_fold(0u64, |sum, &(_, k)| sum.checked_add(k))?;
    if total != splits as u64 {
        return None;
    }
    let levels = counts
        .into_iter()
        .map(|(elements, k)| Some(LevelSplits { elements, split: (0..k).map(|_| r.u32()).collect::<Option<_>>()? }))
        .collect::<Option<Vec<_>>>()?;
    Some(Refinement { levels })
}

/// The leaf section of a version-3 file: p positions, t corners, surfaces and back flags.
fn read_leaf_geometry(r: &mut Reader, p: usize, t: usize) -> Option<LeafGeometry> {
    let positions = r.vec3s(p)?;
    let triangles = (0..t).map(|_| Some([r.u32()?, r.u32()?, r.u32()?])).collect::<Option<Vec<_>>>()?;
    let surface = (0..t).map(|_| r.u32()).collect::<Option<Vec<_>>>()?;
    let back = (0..t)
        .map(|_| match r.take::<1>()?[0] {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        })
        .collect::<Option<Vec<_>>>()?;
    Some(LeafGeometry { positions, triangles, surface, back })
}

/// Which mesh the solution file at `path` lives on, read from its version field; a file too short or
/// foreign says `Uniform` here and is refused by `Solution::load`.
pub fn solution_mesh(path: &Path) -> Result<SolutionMesh, SolutionFileError> {
    use std::io::Read;
    let mut head = [0u8; 12];
    let mut file =
        std::fs::File::open(path).map_err(|source| SolutionFileError::Io { path: path.to_path_buf(), source })?;
    let read = file.read(&mut head).map_err(|source| SolutionFileError::Io { path: path.to_path_buf(), source })?;
    if read < 12 || head[..8] != FILE_MAGIC {
        return Ok(SolutionMesh::Uniform);
    }
    Ok(match u32::from_le_bytes([head[8], head[9], head[10], head[11]]) {
        FILE_VERSION_LEAF_MESH | FILE_VERSION_LEAF_MESH_CAUSTICS => SolutionMesh::Leaves,
        FILE_VERSION_REFINED_MESH => SolutionMesh::Refined,
        _ => SolutionMesh::Uniform,
    })
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
    use crate::radiosity::SolveStats;
    use glam::Vec3;
    use proptest::prelude::*;

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
            leaf_geometry: None,
            refinement: None,
            holds_caustic_light: true,
        }
    }

    fn sample_with_leaves() -> Solution {
        let geometry = LeafGeometry {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2], [0, 2, 1]],
            surface: vec![3, 3],
            back: vec![false, true],
        };
        Solution { leaf_geometry: Some(Arc::new(geometry)), ..sample() }
    }

    /// Two levels: elements 0 and 1 of 2 patches split (2 + 3·2 = 8 elements), then element 7.
    fn sample_with_refinement() -> Solution {
        let levels = vec![LevelSplits { elements: 2, split: vec![0, 1] }, LevelSplits { elements: 8, split: vec![7] }];
        Solution { refinement: Some(Arc::new(Refinement { levels })), ..sample() }
    }

    /// Only a leaf mesh moves the version: a hierarchical solution is written as version 5 when its
    /// exitance holds the caustic light and as version 3 when not (as older files are); each reads
    /// back with its leaves, its flag and the same bytes.
    #[test]
    fn a_leaf_mesh_round_trips_and_its_version_says_whether_it_holds_caustic_light() {
        assert_eq!(sample().to_bytes()[8..12], FILE_VERSION.to_le_bytes());
        for (holds, version) in [(true, FILE_VERSION_LEAF_MESH_CAUSTICS), (false, FILE_VERSION_LEAF_MESH)] {
            let s = Solution { holds_caustic_light: holds, ..sample_with_leaves() };
            let bytes = s.to_bytes();
            assert_eq!(bytes[8..12], version.to_le_bytes());
            let back = Solution::from_bytes(&bytes, Path::new("x"), s.mesh_fingerprint).unwrap();
            assert_eq!(back.holds_caustic_light, holds);
            assert_eq!(back.leaf_geometry, s.leaf_geometry);
            assert_eq!(back.to_bytes(), bytes);
        }
    }

    #[test]
    fn a_refinement_round_trips_as_version_4() {
        let s = sample_with_refinement();
        let bytes = s.to_bytes();
        assert_eq!(bytes[8..12], FILE_VERSION_REFINED_MESH.to_le_bytes());
        let back = Solution::from_bytes(&bytes, Path::new("x"), s.mesh_fingerprint).unwrap();
        assert_eq!(back.refinement, s.refinement);
        assert_eq!(back.to_bytes(), bytes);
    }

    #[test]
    fn the_expected_fingerprint_may_come_from_the_refinement_and_refuse_it() {
        let s = sample_with_refinement();
        let bytes = s.to_bytes();
        let seen = Solution::from_bytes_with(&bytes, Path::new("x"), |loaded| {
            assert_eq!(loaded.refinement, s.refinement);
            Ok(s.mesh_fingerprint)
        });
        assert!(seen.is_ok());
        let refused = Solution::from_bytes_with(&bytes, Path::new("x"), |_| {
            Err(SolutionFileError::StaleRefinement {
                path: "x".into(),
                source: RefinementError::ElementCount { level: 0, recorded: 2, found: 3 },
            })
        });
        assert!(matches!(refused, Err(SolutionFileError::StaleRefinement { .. })), "{refused:?}");
        let stale = Solution::from_bytes_with(&bytes, Path::new("x"), |_| Ok(s.mesh_fingerprint ^ 1));
        assert!(matches!(stale, Err(SolutionFileError::Stale { .. })), "{stale:?}");
    }

    #[test]
    fn inconsistent_levels_are_corrupted_even_with_a_valid_checksum() {
        // Level 1 claims 9 elements where level 0's two splits make 8: rewrite it and re-sum.
        let mut bytes = sample_with_refinement().to_bytes();
        bytes.truncate(bytes.len() - 8);
        let levels_at = bytes.len() - 4 * 3 - 16 * 2;
        bytes[levels_at + 16..levels_at + 24].copy_from_slice(&9u64.to_le_bytes());
        let checksum = fnv1a64(&bytes);
        bytes.extend_from_slice(&checksum.to_le_bytes());
        let e = Solution::from_bytes(&bytes, Path::new("x"), sample().mesh_fingerprint).unwrap_err();
        assert!(matches!(e, SolutionFileError::Corrupted { .. }), "{e:?}");
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
            for version in [FILE_VERSION, FILE_VERSION_LEAF_MESH, FILE_VERSION_REFINED_MESH] {
                let mut with_magic = FILE_MAGIC.to_vec();
                with_magic.extend_from_slice(&version.to_le_bytes());
                with_magic.extend_from_slice(&bytes);
                let _ = Solution::from_bytes(&with_magic, Path::new("random"), 0);
            }
        }

        #[test]
        fn any_single_byte_change_or_truncation_is_refused(at in 0usize..1000, flip in 1u8..=255, cut in 0usize..1000, own_mesh in 0u8..3) {
            let s = match own_mesh { 0 => sample(), 1 => sample_with_leaves(), _ => sample_with_refinement() };
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
