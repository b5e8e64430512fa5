//! Photons: light traced from the emitters through mirrors and glass until it first reaches a diffuse
//! surface (Arvo 1986, backward ray tracing; Jensen 1996). Traced once per run and read by both passes:
//! pass one turns them into extended form factors to the emitters, pass two into its caustic map.

use glam::Vec3;
use std::collections::HashMap;
use std::f32::consts::PI;

use super::cut_outs::OpaqueRay;
use super::emitters::PhotonSources;
use super::hit::{leave_surface, ray_offset, scene_scale};
use super::scatter::{carries, scatter};
use crate::accel::Accel;
use crate::mesh::{Mesh, NONE};
use crate::rng::Pcg32;
use crate::scene::{Material, Surface};

/// Photons shot towards each group of specular elements (one group per scene object). The choice of
/// 2¹⁷ is measured in docs/performance.md ("Caustic photons per object").
pub const PHOTONS_PER_OBJECT: u32 = 1 << 17;
/// Photons are traced in batches of this many, each with its own generator stream, so that the
/// photons are the same whatever the thread count.
pub const PHOTON_BATCH: u32 = 4096;
/// Deepest specular chain a photon follows (as pass one's `radiosity::specular::MAX_DEPTH`).
pub const MAX_DEPTH: u32 = 8;
/// Seed of the photons' generators: fixed, so that a solution saved to a file still matches the
/// photons a later run traces for pass two.
pub const PHOTON_SEED: u64 = 0x5eed_ca05;

/// A photon where it landed: its power is L_e(source) · `throughput`, `throughput` the sampling weight
/// cos θ_e / (p_A p_ω N) times the specular tints along the path (scene units: area × steradian).
#[derive(Clone, Copy, Debug)]
pub struct Landing {
    pub position: Vec3,
    pub throughput: Vec3,
    /// The element (side) it landed on.
    pub element: u32,
    /// The emitting element (side) it left.
    pub source: u32,
}

/// All the photons that reached a diffuse surface through mirrors and glass, and the rays it took.
pub struct Photons {
    pub landings: Vec<Landing>,
    pub rays: u64,
}

/// Traces `PHOTONS_PER_OBJECT` photons from the emitting triangles (uniform by area) towards each
/// scene object made of specular elements, follows them through mirrors and dielectrics by the rules
/// of `transport::scatter` (a dielectric reflects with probability R and refracts otherwise:
/// `Scatter::choose` keeps one path), and stores them where they first reach a diffuse surface.
/// Directions are sampled uniformly in the cone from the emitter point that holds the object's
/// bounding sphere; a photon whose first hit is not that object is dropped, so each direction is
/// counted by one object only. Flux of a photon: Φ = L_e cos θ_e / (p_A p_ω N), with p_A = 1/A (A the
/// emitters' area) and p_ω = 1/(2π(1 − cos θ_max)). `surfaces` (the scene the mesh was built from)
/// name the objects and bend the rays by their shading normals.
/// `run_batches(count, trace)` maps `trace` over the batches 0..count in order (in parallel at the
/// call site). `None` when the scene has no specular element or no emitter.
pub fn trace_photons(
    mesh: &Mesh,
    accel: &Accel,
    materials: &[Material],
    surfaces: Option<&[Surface]>,
    run_batches: impl Fn(u32, &(dyn Fn(u32) -> (Vec<Landing>, u64) + Sync)) -> Vec<(Vec<Landing>, u64)>,
) -> Option<Photons> {
    let e = &mesh.elements;
    let specular: Vec<bool> =
        e.material.iter().map(|&m| materials.get(m as usize).is_some_and(Material::is_specular)).collect();
    // Groups: specular elements by scene object.
    let mut group_of_name: HashMap<&str, u32> = HashMap::new();
    let mut group = vec![NONE; e.len()];
    let mut bounds: Vec<(Vec3, Vec3)> = Vec::new();
    for i in (0..e.len()).filter(|&i| specular[i]) {
        let surface = mesh.surface_source.get(e.surface[i] as usize).copied().unwrap_or(NONE);
        let name = surfaces.and_then(|s| s.get(surface as usize)).map_or("", |s| s.object.as_str());
        let g = *group_of_name.entry(name).or_insert_with(|| {
            bounds.push((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)));
            (bounds.len() - 1) as u32
        });
        group[i] = g;
        for p in e.polygon(&mesh.positions, i) {
            bounds[g as usize].0 = bounds[g as usize].0.min(p);
            bounds[g as usize].1 = bounds[g as usize].1.max(p);
        }
    }
    if bounds.is_empty() {
        return None;
    }
    let sources = PhotonSources::new(mesh)?;
    // Bounding spheres about the boxes' centres, as tight as the elements' corners allow (a sphere
    // object gets its own radius, not the box's half-diagonal, √3 times more: fewer wasted photons).
    let mut spheres: Vec<(Vec3, f32)> = bounds.iter().map(|&(lo, hi)| ((lo + hi) * 0.5, 0.0)).collect();
    for i in (0..e.len()).filter(|&i| specular[i]) {
        let (centre, radius) = &mut spheres[group[i] as usize];
        for p in e.polygon(&mesh.positions, i) {
            *radius = radius.max(p.distance(*centre));
        }
    }
    let follower = Follower { mesh, accel, materials, surfaces, specular: &specular, group: &group };
    let offset = ray_offset(scene_scale(mesh));
    let batches_per_group = PHOTONS_PER_OBJECT.div_ceil(PHOTON_BATCH);
    let batch_count = batches_per_group * spheres.len() as u32;
    let photons_per_group = (batches_per_group * PHOTON_BATCH) as f32;
    let trace = |batch: u32| -> (Vec<Landing>, u64) {
        let g = batch / batches_per_group;
        let (centre, radius) = spheres[g as usize];
        let mut rng = Pcg32::new(PHOTON_SEED, batch as u64);
        let mut out = Vec::new();
        let mut rays = 0u64;
        for _ in 0..PHOTON_BATCH {
            // A point on the emitters, uniform by area.
            let xi = rng.next_f64();
            let s = rng.next_f32();
            let r = rng.next_f32();
            let emitted = sources.sample(mesh, xi, s, r);
            let (t, x) = (emitted.triangle as usize, emitted.point);
            // A direction uniform in the cone around the object's bounding sphere.
            let to_centre = centre - x;
            let distance = to_centre.length();
            let cos_max = if distance > radius { (1.0 - (radius / distance).powi(2)).max(0.0).sqrt() } else { -1.0 };
            let axis = if distance > 0.0 { to_centre / distance } else { Vec3::Y };
            let cos_theta = 1.0 - rng.next_f32() * (1.0 - cos_max);
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            let phi = 2.0 * PI * rng.next_f32();
            let (u, v) = axis.any_orthonormal_pair();
            let dir = (axis * cos_theta + (u * phi.cos() + v * phi.sin()) * sin_theta).normalize();
            let solid_angle = 2.0 * PI * (1.0 - cos_max);
            // Which side of the emitter faces the direction, and its radiance.
            let front_element = mesh.triangle_element[t] as usize;
            let cos_front = e.normal[front_element].dot(dir);
            let Some(element) = mesh.side_element(t, cos_front > 0.0) else {
                continue;
            };
            let cos_emit = cos_front.abs();
            let radiance = e.emission[element] / PI;
            if radiance.max_element() <= 0.0 {
                continue;
            }
            let weight = Vec3::splat(cos_emit * emitted.inverse_density * solid_angle / photons_per_group);
            let origin = leave_surface(
                x,
                if cos_front > 0.0 { e.normal[front_element] } else { -e.normal[front_element] },
                offset,
            );
            let photon = Photon { origin, dir, throughput: weight, source: element as u32 };
            rays += follower.follow(g, photon, offset, &mut rng, &mut out);
        }
        (out, rays)
    };
    let results = run_batches(batch_count, &trace);
    let mut landings = Vec::new();
    let mut rays = 0;
    for (l, r) in results {
        landings.extend(l);
        rays += r;
    }
    Some(Photons { landings, rays })
}

/// A photon leaving an emitter.
#[derive(Clone, Copy, Debug)]
struct Photon {
    origin: Vec3,
    dir: Vec3,
    throughput: Vec3,
    source: u32,
}

/// The scene as a photon sees it.
struct Follower<'a> {
    mesh: &'a Mesh,
    accel: &'a Accel,
    materials: &'a [Material],
    surfaces: Option<&'a [Surface]>,
    /// Per element: its material is specular.
    specular: &'a [bool],
    /// Per element: its specular group (`NONE` for diffuse elements).
    group: &'a [u32],
}

impl Follower<'_> {
    /// Follows one photon whose first hit must be specular group `group_wanted`; appends where it
    /// lands and returns the rays traced.
    fn follow(&self, group_wanted: u32, photon: Photon, offset: f32, rng: &mut Pcg32, out: &mut Vec<Landing>) -> u64 {
        let (mesh, e) = (self.mesh, &self.mesh.elements);
        let Photon { mut origin, mut dir, throughput: mut power, source } = photon;
        let mut rays = 0;
        for depth in 0..=MAX_DEPTH {
            rays += 1;
            // Photons pass cut-outs as every other ray does (at their finest texels).
            let through_cut_outs = OpaqueRay { mesh, accel: self.accel, offset, spread_rad: 0.0 };
            let Some((hit, _)) = through_cut_outs.closest_hit(origin, dir, f32::INFINITY) else {
                break;
            };
            let front_element = mesh.triangle_element[hit.triangle as usize] as usize;
            if depth == 0 && self.group[front_element] != group_wanted {
                break;
            }
            let Some(material) = self.materials.get(hit.material as usize) else {
                break;
            };
            match hit.element {
                Some(j) if depth > 0 && e.reflectance[j as usize].max_element() > 0.0 => {
                    out.push(Landing { position: hit.position, throughput: power, element: j, source });
                }
                None if !material.is_dielectric() => break,
                _ => {}
            }
            if !self.specular[front_element] {
                break;
            }
            let hit = hit.with_shading_normal(mesh, self.surfaces, dir);
            let Some((next, transmitted, factor)) = scatter(material, dir, &hit).choose(|| rng.next_f32()) else {
                break;
            };
            origin = if transmitted { hit.below(offset) } else { hit.above(offset) };
            dir = next;
            power *= factor;
            if !carries(power, 0.0) {
                break;
            }
        }
        rays
    }
}

/// The photons of one run: traced by whichever pass needs them first, then read by both, pass one's
/// extended form factors (`radiosity::specular`) and pass two's caustic map. Make one per scene and
/// mesh; a run without mirrors or glass never traces any.
#[derive(Default)]
pub struct RunPhotons(std::sync::OnceLock<Option<Photons>>);

impl RunPhotons {
    /// The photons of the scene's `materials` and `surfaces` meshed as `mesh` (`accel` built from its
    /// triangles), traced in parallel batches on first use; `None` without specular surfaces or
    /// emitters.
    pub fn get(&self, mesh: &Mesh, accel: &Accel, materials: &[Material], surfaces: &[Surface]) -> Option<&Photons> {
        self.0
            .get_or_init(|| {
                trace_photons(mesh, accel, materials, Some(surfaces), |count, trace| {
                    use rayon::prelude::*;
                    (0..count).into_par_iter().map(trace).collect()
                })
            })
            .as_ref()
    }
}
