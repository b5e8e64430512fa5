//! The direct part of the exitance from a stored matrix: the emission received in one bounce along
//! straight lines and reflected.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::gather;
use crate::radiosity::matrix::FormFactors;

/// ρ_i Σ_j F_ij E_j for every element: the emission received in one bounce along straight lines and
/// reflected (the direct part of B, emission excluded). Only the plain entries count
/// (`FormFactors::row_plain`): light arriving through mirrors and glass belongs to the indirect
/// remainder, since pass two's shadow rays see only straight paths. Rows in parallel; each row is one
/// `gather`.
pub fn direct_exitance(ff: &FormFactors, reflectance: &[Vec3], emission: &[Vec3]) -> Vec<DVec3> {
    let emission: Vec<DVec3> = emission.iter().map(|e| e.as_dvec3()).collect();
    (0..ff.len())
        .into_par_iter()
        .map(|i| {
            let (columns, factors) = ff.row_plain(i);
            reflectance[i].as_dvec3() * gather(columns, factors, &emission)
        })
        .collect()
}
