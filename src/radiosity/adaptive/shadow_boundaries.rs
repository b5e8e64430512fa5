//! Shadow boundaries between an element's corners, found with shadow rays: a shadow that falls between
//! the centres the solution is sampled at (living_room's coffee table, its shadow cast by the table
//! lamp beside it and by the ceiling the uplighter lights) still splits the patches it crosses. The
//! solution cannot show it: each element's exitance is its centre's and a vertex value is a mean of
//! those, so a feature narrower than two elements is smoothed away before
//! `criterion::irradiance_variation` can measure it. The rays go to the emitters and to the reflecting
//! elements of the solved level (`reflectors`), so shadows of indirect light count as well. Used on the
//! patches (level 0), where elements are largest; the levels below see with their own centres what the
//! split patches bring into reach.

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

/// Per element, the spread over its corners of the light that shadow rays find blocked, in exitance
/// units:
///   δₑ = max_c ρ̄ₑ,c · (max_k Eᵇ_c(x_k) − min_k Eᵇ_c(x_k)),   Eᵇ = Eᵇ_emitters + Eᵇ_reflectors,
/// x_k its corners pulled `CORNER_INSET` towards its centre. Eᵇ_emitters is the irradiance the
/// emitters would add with nothing in the way (`direct_irradiance_at`'s `blocked`, `CORNER_SAMPLES`
/// rays, the same random numbers at every corner of an element); Eᵇ_reflectors the same for the light
/// the solution `element_exitance` reflects (`Reflectors::blocked_irradiance`, `REFLECTOR_SAMPLES`
/// points drawn by reflected power, the same points for every corner): a ceiling lit by an uplighter
/// casts a table's shadow on the floor as a lamp does. The blocked part, not the light itself: an
/// unshadowed falloff across a patch is smooth and the centres see it, while a change of visibility
/// between two corners is a shadow boundary between them; where no corner is shadowed δ = 0 exactly.
/// 0 for elements not `wanted`, emitters and black elements. Each element has its own random streams
/// (from `seed`), so the result does not depend on the thread count.
pub fn blocked_light_variation(
    mesh: &Mesh,
    materials: &[Material],
    element_exitance: &[Vec3],
    accel: &Accel,
    wanted: &[bool],
    seed: u64,
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
            let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            for &v in e.corners[i].iter().filter(|&&v| v != NONE) {
                let corner = mesh.positions[v as usize];
                let x = leave_surface(corner + (centre - corner) * CORNER_INSET, n, offset);
                let mut rng = Pcg32::new(seed ^ 0x636f_726e_6572, i as u64);
                let mut blocked =
                    direct_irradiance_at(mesh, &emitters, accel, x, n, CORNER_SAMPLES, &mut rng).blocked.as_vec3();
                if let Some(r) = &reflectors {
                    blocked += r.blocked_irradiance(mesh, accel, x, n, &points);
                }
                lo = lo.min(blocked);
                hi = hi.max(blocked);
            }
            (rho * (hi - lo).max(Vec3::ZERO)).max_element()
        })
        .collect()
}
