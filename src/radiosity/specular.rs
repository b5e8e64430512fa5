//! Extended form factors through specular surfaces (Wallace, Cohen and Greenberg 1987; Sillion and
//! Puech 1989): hemicube pixels that see a mirror or a dielectric are followed by rays with Whitted's
//! rules until they reach diffuse elements, so that B = E + ρ(F + Fˢ)B carries light along LS+D paths.

use glam::Vec3;

use super::hemicube::{BackItems, Hemicube, ItemBuffer};
use crate::accel::Accel;
use crate::mesh::Mesh;
use crate::rng::Pcg32;
use crate::scene::{Material, Surface};
use crate::transport::hit::{ray_offset, scene_scale};
use crate::transport::ray_stack::RayStack;
use crate::transport::scatter::scatter;
use crate::transport::{Photons, SurfaceHit};

/// Deepest specular chain followed from a hemicube pixel (bounces off or through specular surfaces).
pub const MAX_DEPTH: u32 = 8;
/// Branches are dropped when their throughput falls below this (`transport::scatter::carries`).
pub const MIN_THROUGHPUT: f32 = 1e-3;
/// Resolution at which the specular part of a hemicube is sampled: the hemicube's pixels are grouped
/// in blocks of s × s with s = max(1, N / SPECULAR_RESOLUTION_PX), and one path per block carries the
/// summed ΔF of the block's specular pixels (from one of them, chosen uniformly by a generator seeded
/// per element). Rays cost far more than rasterised pixels, and light through mirrors and glass is a
/// secondary term: this keeps its cost to about 3·64² paths per hemicube at most, with the hemicube's
/// O(1/N) error model at N = 64.
pub const SPECULAR_RESOLUTION_PX: u32 = 64;
/// Most rays on the explicit stack: one pop pushes at most two rays one level deeper.
const STACK_SIZE: usize = MAX_DEPTH as usize + 2;

/// True when some element of the mesh is specular (a material with Ks > 0 or a dielectric): only then
/// do extended form factors differ from the plain ones.
pub fn mesh_has_specular(mesh: &Mesh, materials: &[Material]) -> bool {
    mesh.elements.material.iter().any(|&m| materials.get(m as usize).is_some_and(Material::is_specular))
}

/// What following the specular pixels of the hemicubes cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpecularStats {
    /// Hemicube pixels that showed a specular element (one path each).
    pub pixels: u64,
    /// Rays traced (closest-hit queries), all branches included.
    pub rays: u64,
    /// Extended entries Fˢ_ij stored.
    pub entries: u64,
}

impl std::ops::AddAssign for SpecularStats {
    fn add_assign(&mut self, o: SpecularStats) {
        self.pixels += o.pixels;
        self.rays += o.rays;
        self.entries += o.entries;
    }
}

/// The scene as the specular path follower sees it: triangles in a BVH, materials per element, and
/// (optionally) the surfaces' shading normals. Shared between threads (`&self`).
pub struct SpecularPaths<'a> {
    mesh: &'a Mesh,
    accel: &'a Accel,
    materials: &'a [Material],
    surfaces: Option<&'a [Surface]>,
    /// Per element: its material reflects or refracts specularly (paths go on through it).
    specular: Vec<bool>,
    /// Per element: specular with Kd = 0 and E = 0, so B = 0: it ends no path and holds no light.
    pure_specular: Vec<bool>,
    /// Distance ray origins are moved off a surface (scene units).
    offset: f32,
    /// Per element: it emits (E > 0).
    emitter: Vec<bool>,
    /// With `with_light_paths`: per receiving element, its extended entries to the emitters
    /// (emitter element, Fˢ_ij) from light traced the other way, sorted by emitter.
    light_rows: Option<Vec<Vec<(u32, f32)>>>,
}

impl<'a> SpecularPaths<'a> {
    /// `accel` must be built from `mesh.triangles`; `materials` are indexed by `Elements::material`
    /// (an element with a missing material counts as diffuse).
    pub fn new(mesh: &'a Mesh, accel: &'a Accel, materials: &'a [Material]) -> Self {
        assert_eq!(accel.len(), mesh.triangles.len(), "the accelerator is built from the mesh's triangles");
        let e = &mesh.elements;
        let specular: Vec<bool> =
            e.material.iter().map(|&m| materials.get(m as usize).is_some_and(Material::is_specular)).collect();
        let pure_specular = (0..e.len())
            .map(|i| specular[i] && e.reflectance[i].max_element() <= 0.0 && e.emission[i].max_element() <= 0.0)
            .collect();
        SpecularPaths {
            mesh,
            accel,
            materials,
            surfaces: None,
            specular,
            pure_specular,
            offset: ray_offset(scene_scale(mesh)),
            emitter: e.emission.iter().map(|x| x.max_element() > 0.0).collect(),
            light_rows: None,
        }
    }

    /// Bends specular rays with the surfaces' smooth-shading normals (the scene the mesh was built
    /// from), as pass two does.
    pub fn with_shading_normals(mut self, surfaces: &'a [Surface]) -> Self {
        self.surfaces = Some(surfaces);
        self
    }

    /// Extended form factors to the emitters from light traced from the emitters (Arvo 1986) instead
    /// of from the receivers' hemicubes: the run's `photons` (`transport::photons`, the same ones pass
    /// two's caustic map uses) give, for receiver i and emitter j,
    ///
    /// Fˢ_ij = Σ_{photons from j landing on i} w̄_k / (π A_i),
    ///
    /// w̄_k the photon's sampling weight and specular tints (mean over RGB): by reciprocity
    /// A_i Fˢ_ij B_j is the flux from j reaching i through mirrors and glass, Φ = Σ L_j w̄_k with
    /// B_j = π L_j. A small focused caustic is sampled densely from the light but only by a few
    /// hemicube blocks of each receiver; and pass one then holds exactly the element average of the
    /// caustic that pass two sharpens. `extend_row` stops following hemicube paths into emitters.
    /// Assumes emitters are not also lit through specular paths in a way that matters (their reflected
    /// light, Kd·irradiance, is then not carried along LS+D paths).
    pub fn with_light_paths(mut self, photons: &Photons) -> Self {
        let e = &self.mesh.elements;
        let mut flux: Vec<Vec<(u32, f64)>> = vec![Vec::new(); e.len()];
        for l in &photons.landings {
            flux[l.element as usize].push((l.source, (l.throughput.element_sum() / 3.0) as f64));
        }
        let rows = flux
            .into_iter()
            .enumerate()
            .map(|(i, mut entries)| {
                entries.sort_by_key(|&(j, _)| j); // stable: photon order within an emitter
                let scale = 1.0 / (std::f64::consts::PI * (e.area[i] as f64).max(f64::MIN_POSITIVE));
                let mut row: Vec<(u32, f32)> = Vec::new();
                for (j, w) in entries {
                    match row.last_mut() {
                        Some(last) if last.0 == j => last.1 = (last.1 as f64 + w * scale) as f32,
                        _ => row.push((j, (w * scale) as f32)),
                    }
                }
                row
            })
            .collect();
        self.light_rows = Some(rows);
        self
    }

    /// Element j reflects or refracts specularly.
    pub fn is_specular(&self, j: usize) -> bool {
        self.specular[j]
    }

    /// Element j is specular only (Kd = 0, E = 0): its exitance B_j is 0, so a plain entry F_ij is
    /// useless once the paths through it are followed.
    pub fn is_pure_specular(&self, j: usize) -> bool {
        self.pure_specular[j]
    }

    /// Follows the ray `origin + t·dir` whose first hit is a specular element through mirrors and
    /// dielectrics by Whitted's rules (Whitted 1980), on an explicit stack:
    ///
    /// mirror: T ← T·Ks;  dielectric: reflected T ← T·Ks·R, refracted T ← T·(1 − R)·(1 − d),
    ///
    /// R the unpolarised Fresnel reflectance (entering or leaving by the side hit; total internal
    /// reflection gives R = 1 and no refracted branch; `transport::scatter`). Whenever a later segment hits the front of an
    /// element that is not pure specular (or the back of a two-sided one), `reach(j, T̄)` is called with
    /// T̄ the branch's mean throughput over RGB; the branch ends there unless that element is also
    /// specular. The back of a one-sided opaque surface absorbs. Branches end after `MAX_DEPTH` bounces
    /// or below `MIN_THROUGHPUT` (`transport::scatter::carries`). With `first_hit_counts`, a first hit on a non-specular element (the
    /// ray and the rasteriser disagreeing about a pixel on an edge) reaches it with T = 1, so that a
    /// pixel whose plain entry was dropped keeps its ΔF. Returns the rays traced.
    pub fn follow(&self, origin: Vec3, dir: Vec3, first_hit_counts: bool, mut reach: impl FnMut(u32, f32)) -> u64 {
        let mesh = self.mesh;
        let mut stack = RayStack::<STACK_SIZE>::new(origin, dir);
        let mut rays = 0;
        while let Some(ray) = stack.pop() {
            rays += 1;
            let Some(hit) = self.accel.closest_hit(ray.origin, ray.dir, 0.0, f32::INFINITY) else {
                continue;
            };
            let hit = SurfaceHit::new(mesh, &hit, ray.dir);
            let front_element = hit.front_element as usize;
            let Some(material) = self.materials.get(hit.material as usize) else {
                continue;
            };
            match hit.element.map(|j| j as usize) {
                // The first hit is the specular element the hemicube pixel showed: its plain entry holds
                // whatever diffuse light it has.
                Some(j) if !self.pure_specular[j] && (ray.depth > 0 || (first_hit_counts && !self.specular[j])) => {
                    reach(j as u32, ray.throughput.element_sum() / 3.0);
                }
                Some(_) => {}
                None if !material.is_dielectric() => continue, // back of a one-sided surface: absorbed
                None => {}
            }
            if !self.specular[front_element] || ray.depth >= MAX_DEPTH {
                continue;
            }
            let hit = hit.with_shading_normal(mesh, self.surfaces, ray.dir);
            stack.push_branches(&ray, &scatter(material, ray.dir, &hit), &hit, self.offset, MIN_THROUGHPUT);
        }
        rays
    }

    /// The extended row of element `element`'s hemicube just rasterised in `buffers` (its pixels are
    /// still in place after `ItemBuffer::finish`): the pixels that show a specular element are grouped
    /// in blocks (see `SPECULAR_RESOLUTION_PX`); per block b, the path from the hemicube's eye through
    /// the centre of one of its specular pixels (chosen with `Pcg32::new(seed, element)`) is followed
    /// (`follow`) and
    ///
    /// Fˢ_ij = Σ_b (Σ_{p∈b specular} ΔF_p) · T_b→j
    ///
    /// summed over the blocks and branches reaching element j with throughput T (Wallace, Cohen and
    /// Greenberg 1987, eq. 6: the form factor through a specular surface is its reflectance times the
    /// form factor to the mirror image). Appends (j, Fˢ_ij) with increasing j to `row`; sums in f64 in
    /// block order, so the result does not depend on threads.
    pub fn extend_row(
        &self,
        hc: &Hemicube,
        buffers: &ItemBuffer,
        seed: u64,
        element: usize,
        row: &mut Vec<(u32, f32)>,
    ) -> SpecularStats {
        let eye = buffers.frame().eye;
        let n = hc.resolution_px() as usize;
        let stride = (n / SPECULAR_RESOLUTION_PX as usize).max(1);
        let blocks_across = n.div_ceil(stride);
        // Block of a buffer pixel: the top face is N × N, each side face N/2 rows of N.
        let block_of = |pixel: usize| {
            let (face, local) = if pixel < n * n {
                (0, pixel)
            } else {
                (1 + (pixel - n * n) / (n * n / 2), (pixel - n * n) % (n * n / 2))
            };
            let (i, j) = (local % n, local / n);
            let rows_before = if face == 0 { 0 } else { n.div_ceil(stride) + (face - 1) * (n / 2).div_ceil(stride) };
            (rows_before + j / stride) * blocks_across + i / stride
        };
        let block_count = block_of(hc.pixel_count() - 1) + 1;
        // Per block: Σ ΔF of its specular pixels, how many, and the one chosen (reservoir sampling).
        let mut weight = vec![0.0f64; block_count];
        let mut count = vec![0u32; block_count];
        let mut chosen = vec![0usize; block_count];
        let mut rng = Pcg32::new(seed, element as u64);
        let mut stats = SpecularStats::default();
        let backs = BackItems::past(self.mesh.elements.len());
        buffers.for_each_covered_pixel(hc, |pixel, item, delta| {
            // Past the elements: the backs of one-sided surfaces; only a dielectric's lets light through.
            let specular = self.specular.get(item as usize).copied().unwrap_or(item == backs.refracting);
            if !specular {
                return;
            }
            stats.pixels += 1;
            let b = block_of(pixel);
            weight[b] += delta as f64;
            count[b] += 1;
            if count[b] == 1 || rng.next_f32() * (count[b] as f32) < 1.0 {
                chosen[b] = pixel;
            }
        });
        let mut reached: Vec<(u32, f64)> = Vec::new();
        let light_paths = self.light_rows.is_some();
        for b in 0..block_count {
            if count[b] == 0 {
                continue;
            }
            let pixel = chosen[b];
            let dir = buffers.pixel_direction(hc, pixel);
            let first_hit_counts =
                buffers.item_at(pixel).is_some_and(|item| self.pure_specular.get(item as usize) == Some(&true));
            let w = weight[b];
            stats.rays += self.follow(eye, dir, first_hit_counts, |j, throughput| {
                // With light paths, LS+D light comes from the photons (`with_light_paths`).
                if !(light_paths && self.emitter[j as usize]) {
                    reached.push((j, throughput as f64 * w));
                }
            });
        }
        if let Some(rows) = &self.light_rows {
            reached.extend(rows[element].iter().map(|&(j, f)| (j, f as f64)));
        }
        reached.sort_by_key(|&(j, _)| j); // stable: equal j keep block order
        let mut k = 0;
        while k < reached.len() {
            let j = reached[k].0;
            let mut sum = 0.0;
            while k < reached.len() && reached[k].0 == j {
                sum += reached[k].1;
                k += 1;
            }
            if sum > 0.0 {
                row.push((j, sum as f32));
                stats.entries += 1;
            }
        }
        stats
    }
}
