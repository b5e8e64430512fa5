//! The solution file: a little-endian binary image of a `Solution` with a magic, a format version and
//! a checksum, written atomically and refused when foreign, truncated, corrupted or stale.

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::fingerprint::fnv1a64;
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
