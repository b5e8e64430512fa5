//! Shadow boundaries between an element's corners, found with shadow rays: a shadow that falls between
//! the centres the solution is sampled at (living_room's coffee table, its shadow cast by the table
//! lamp beside it and by the ceiling the uplighter lights) still splits the patches it crosses. The
//! solution cannot show it: each element's exitance is its centre's and a vertex value is a mean of
//! those, so a feature narrower than two elements is smoothed away before
//! `criterion::irradiance_variation` can measure it. The rays go to the emitters and to the reflecting
//! elements of the solved level (`reflectors`), so shadows of indirect light count as well. On the
//! patches (level 0) the test is the spread over the corners: any shadow boundary between them. On the
//! next deciding level it is the interpolation error (`BlockedLightTest::Interpolation`): the children
//! of split patches lie in shadows and penumbrae already, and what still needs splitting is where the
//! blocked light is not linear across them, a sharp edge or a narrow streak (a stair's nosing, a
//! table's legs), not a soft penumbra the corners interpolate.

use glam::Vec3;
use rayon::prelude::*;

use crate::accel::Accel;
use crate::mesh::{Mesh, NONE};
use crate::radiosity::sampled_direct::{direct_irradiance_at, surface_offset};
use crate::rng::Pcg32;
use crate::scene::Material;
use crate::transport::emitters::Emitters;
use crate::transport::hit::leave_surface;

use super::reflectors::Reflectors;

/// Shadow rays per corner to the emitters.
pub const CORNER_SAMPLES: u32 = 16;

/// Shadow rays per corner to points on the reflecting elements (`Reflectors`).
pub const REFLECTOR_SAMPLES: u32 = 64;

/// How far a corner is pulled towards its element's centre before it is sampled, as a fraction of the
/// way: off the edge, where a corner on a contact line would lie inside the object resting there.
const CORNER_INSET: f32 = 0.02;

/// What `blocked_light_variation` measures across an element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockedLightTest {
    /// The spread over its corners: δₑ = max_c ρ̄ₑ,c · (max_k Eᵇ_c(x_k) − min_k Eᵇ_c(x_k)), x_k the
    /// corners.
    CornerSpread,
    /// The error of interpolating the corners: δₑ = max_c ρ̄ₑ,c · max_m |Eᵇ_c(y_m) − Ẽᵇ_c(y_m)| over
    /// the edges' midpoints and the centre y_m, Ẽᵇ the corners' linear (triangle) or bilinear (quad)
    /// interpolation there: the mean of an edge's two ends at its midpoint, of all corners at the
    /// centre. 0 for a blocked light linear across the element, however steep.
    Interpolation,
}

/// Per element, how the light that shadow rays find blocked varies across it (`test`), in exitance
/// units, with Eᵇ = Eᵇ_emitters + Eᵇ_reflectors at points pulled `CORNER_INSET` towards its centre.
/// Eᵇ_emitters is the irradiance the emitters would add with nothing in the way
/// (`direct_irradiance_at`'s `blocked`, `CORNER_SAMPLES` rays, the same random numbers at every point
/// of an element); Eᵇ_reflectors the same for the light the solution `element_exitance` reflects
/// (`Reflectors::blocked_irradiance`, `REFLECTOR_SAMPLES` points drawn by reflected power, the same
/// points for every point of the element): a ceiling lit by an uplighter
/// casts a table's shadow on the floor as a lamp does. The blocked part, not the light itself: an
/// unshadowed falloff across a patch is smooth and the centres see it, while a change of visibility
/// between two corners is a shadow boundary between them; where no corner is shadowed δ = 0 exactly.
/// 0 for elements not `wanted`, emitters and black elements. Each element has its own random streams
/// (from `seed`; the same at every point of it), so the result does not depend on the thread count.
pub fn blocked_light_variation(
    mesh: &Mesh,
    materials: &[Material],
    element_exitance: &[Vec3],
    accel: &Accel,
    wanted: &[bool],
    seed: u64,
    test: BlockedLightTest,
) -> Vec<f32> {
    let emitters = Emitters::new(mesh, materials);
    let reflectors = Reflectors::new(mesh, element_exitance);
    let e = &mesh.elements;
    if emitters.is_empty() && reflectors.is_none() {
        return vec![0.0; e.len()];
    }
    let offset = surface_offset(mesh);
    (0..e.len())
        .into_par_iter()
        .map(|i| {
            let rho = e.reflectance[i];
            if !wanted[i] || rho.max_element() <= 0.0 || e.emission[i].max_element() > 0.0 {
                return 0.0;
            }
            let points = match &reflectors {
                Some(r) => r.draw(mesh, REFLECTOR_SAMPLES, &mut Pcg32::new(seed ^ 0x7265_666c_6563, i as u64)),
                None => Vec::new(),
            };
            let (n, centre) = (e.normal[i], e.centre[i]);
            let blocked_at = |p: Vec3| {
                let x = leave_surface(p + (centre - p) * CORNER_INSET, n, offset);
                let mut rng = Pcg32::new(seed ^ 0x636f_726e_6572, i as u64);
                let mut blocked =
                    direct_irradiance_at(mesh, &emitters, accel, x, n, CORNER_SAMPLES, &mut rng).blocked.as_vec3();
                if let Some(r) = &reflectors {
                    blocked += r.blocked_irradiance(mesh, accel, x, n, &points);
                }
                blocked
            };
            let corners: Vec<Vec3> =
                e.corners[i].iter().filter(|&&v| v != NONE).map(|&v| mesh.positions[v as usize]).collect();
            let at_corners: Vec<Vec3> = corners.iter().map(|&p| blocked_at(p)).collect();
            let variation = match test {
                BlockedLightTest::CornerSpread => {
                    let lo = at_corners.iter().copied().fold(Vec3::splat(f32::MAX), Vec3::min);
                    let hi = at_corners.iter().copied().fold(Vec3::splat(f32::MIN), Vec3::max);
                    (hi - lo).max(Vec3::ZERO)
                }
                BlockedLightTest::Interpolation => {
                    let k = corners.len();
                    let mean = |points: &[Vec3]| points.iter().copied().sum::<Vec3>() / points.len() as f32;
                    let at_centre = (blocked_at(mean(&corners)) - mean(&at_corners)).abs();
                    (0..k).fold(at_centre, |worst, a| {
                        let b = (a + 1) % k;
                        let at_mid =
                            blocked_at(0.5 * (corners[a] + corners[b])) - 0.5 * (at_corners[a] + at_corners[b]);
                        worst.max(at_mid.abs())
                    })
                }
            };
            (rho * variation).max_element()
        })
        .collect()
}
