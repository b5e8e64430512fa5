//! Shadow boundaries between an element's corners, found with shadow rays: a shadow that falls between
//! the centres the solution is sampled at (living_room's coffee table, its shadow cast by the table
//! lamp beside it) still splits the patches it crosses. The solution cannot show it: each element's
//! exitance is its centre's and a vertex value is a mean of those, so a feature narrower than two
//! elements is smoothed away before `criterion::irradiance_variation` can measure it. Used on the
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

/// Shadow rays per corner.
pub const CORNER_SAMPLES: u32 = 16;

/// How far a corner is pulled towards its element's centre before it is sampled, as a fraction of the
/// way: off the edge, where a corner on a contact line would lie inside the object resting there.
const CORNER_INSET: f32 = 0.02;

/// Per element, the spread over its corners of the direct light that shadow rays find blocked, in
/// exitance units:
///   δₑ = max_c ρ̄ₑ,c · (max_k Eᵇ_c(x_k) − min_k Eᵇ_c(x_k)),
/// x_k its corners pulled `CORNER_INSET` towards its centre, Eᵇ the irradiance the emitters would add
/// with nothing in the way (`direct_irradiance_at`'s `blocked`, `CORNER_SAMPLES` rays, the same
/// random numbers at every corner of an element). The blocked part, not the direct light itself: an
/// unshadowed falloff across a patch is smooth and the centres see it, while a change of visibility
/// between two corners is a shadow boundary between them; where no corner is shadowed δ = 0 exactly.
/// 0 for elements not `wanted`, emitters, black elements and where the scene has no emitters. Each
/// element has its own random stream (from `seed`), so the result does not depend on the thread count.
pub fn blocked_light_variation(
    mesh: &Mesh,
    materials: &[Material],
    accel: &Accel,
    wanted: &[bool],
    seed: u64,
) -> Vec<f32> {
    let emitters = Emitters::new(mesh, materials);
    let e = &mesh.elements;
    if emitters.is_empty() {
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
            let (n, centre) = (e.normal[i], e.centre[i]);
            let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            for &v in e.corners[i].iter().filter(|&&v| v != NONE) {
                let corner = mesh.positions[v as usize];
                let x = leave_surface(corner + (centre - corner) * CORNER_INSET, n, offset);
                let mut rng = Pcg32::new(seed ^ 0x636f_726e_6572, i as u64);
                let blocked = direct_irradiance_at(mesh, &emitters, accel, x, n, CORNER_SAMPLES, &mut rng).blocked;
                lo = lo.min(blocked.as_vec3());
                hi = hi.max(blocked.as_vec3());
            }
            (rho * (hi - lo).max(Vec3::ZERO)).max_element()
        })
        .collect()
}
