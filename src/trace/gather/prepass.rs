//! Filling the irradiance cache before the image, the same way at any thread count: the diffuse points
//! the camera sees at pixel centres on ever finer grids (32, 16, …, 1 pixels apart, the last one twice:
//! the cache's neighbour clamping at the end of a level can uncover pixel centres), level by level.
//! Within a level, the points no record serves yet are gathered in parallel (each from its own seeded
//! stream) and appended in grid order; only then does the next level look. Which records exist
//! therefore depends on the scene and the seed, never on the schedule.

use glam::Vec3;
use rayon::prelude::*;

use super::cache::IrradianceCache;
use super::hemisphere::Strata;
use super::refine::GatherRefinement;
use crate::film::Sampler;
use crate::trace::camera::PinholeCamera;
use crate::trace::whitted::{RayCounts, Tracer};
use crate::transport::ray_stack::RayStack;
use crate::transport::scatter::scatter;
use crate::transport::shading::SurfaceNormals;

/// Grid spacings of the levels, in pixels. The 1-pixel grid comes twice: `IrradianceCache::index`
/// clamps the radii to their neighbours' after every level, so the records a level adds at a contact
/// can shrink older records that served pixel centres when the level looked; the repeat gathers those
/// (without it, on the rotunda, the image's samples there gathered on their own: pass two took 35.4
/// CPU-s against 22.3).
const LEVEL_SPACINGS_PX: [u32; LEVELS] = [32, 16, 8, 4, 2, 1, 1];
/// How many levels the prepass fills (its progress steps).
pub const LEVELS: usize = 7;
/// Specular bounces followed from the camera to find the diffuse points behind mirrors and glass.
const CANDIDATE_SPECULAR_DEPTH: u32 = 4;
const CANDIDATE_STACK: usize = CANDIDATE_SPECULAR_DEPTH as usize + 2;
/// A record's reach a·R is clamped to [MIN_REACH_PX, MAX_REACH_PX] pixel footprints at its distance
/// along the camera path (as Tabellion and Lamorlette 2004 clamp in screen space): at least one pixel,
/// so that the finest level leaves no pixel centre and hardly any sample uncovered; at most a quarter
/// of a 128-pixel image, so a far wall still gets a few records.
const MIN_REACH_PX: f32 = 1.0;
const MAX_REACH_PX: f32 = 32.0;
/// The smallest reach is one pixel as the surface sees it: a pixel's footprint f = (path length) ×
/// (pixel angle) stretched along the view by 1/|cos θ_v| (θ_v between the camera path's last ray and
/// the geometric normal), so R_min = MIN_REACH_PX · f / (a·max(|cos θ_v|, MIN_VIEW_COSINE)). A floor or
/// ceiling seen at grazing angles otherwise leaves its pixels' samples away from the centre uncovered
/// where neighbour clamping brings records down to R_min, and they gather on their own (rotunda, pass
/// two: 30.7 CPU-s with the stretch off, 22.3 with it). The floor bounds the stretch at 10 pixels' worth
/// (a silhouette's grazing hit).
const MIN_VIEW_COSINE: f32 = 0.1;
/// Stream offset of the prepass's random numbers (the film's streams are pixel indices).
const PREPASS_STREAM: u64 = 0x9a7e_u64 << 48;

/// A diffuse point the camera sees, and how far along the camera path it lies.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    position: Vec3,
    /// Geometric and smooth shading normals; the record is keyed by the shading one.
    normals: SurfaceNormals,
    path_length: f32,
    /// |cos| between the arriving ray and the geometric normal: a pixel's footprint on the surface is
    /// longer by 1/|cos| along the view.
    view_cosine: f32,
}

/// What the prepass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PrepassStats {
    pub records: usize,
    /// Records gathered with `GatherRefinement::refined` strata.
    pub refined: usize,
    /// Diffuse points the camera's rays found, on all levels.
    pub candidates: usize,
    /// Camera and gather rays the prepass traced.
    pub rays: RayCounts,
}

/// The cache for one image of `width_px` × `height_px` through `camera` (a pixel subtends
/// `pixel_angle_rad`), gathering `strata` (or `refinement`'s where its pilot asks) at accuracy
/// a = `accuracy`, random numbers from `seed`.
/// `on_level_done(records)` is called after each of the [`LEVELS`] levels with the records so far.
#[allow(clippy::too_many_arguments)]
pub fn fill(
    tracer: &Tracer,
    camera: &PinholeCamera,
    width_px: u32,
    height_px: u32,
    pixel_angle_rad: f32,
    strata: Strata,
    refinement: Option<&GatherRefinement>,
    accuracy: f32,
    seed: u64,
    on_level_done: &(dyn Fn(usize) + Sync),
) -> (IrradianceCache, PrepassStats) {
    let mut cache = IrradianceCache::new(accuracy);
    let mut stats = PrepassStats::default();
    for (level, &spacing) in LEVEL_SPACINGS_PX.iter().enumerate() {
        let (columns, rows) = (width_px.div_ceil(spacing), height_px.div_ceil(spacing));
        let found: Vec<(Vec<Candidate>, RayCounts)> = (0..columns * rows)
            .into_par_iter()
            .map(|i| {
                let x = ((i % columns) * spacing + spacing / 2).min(width_px - 1) as f32 + 0.5;
                let y = ((i / columns) * spacing + spacing / 2).min(height_px - 1) as f32 + 0.5;
                let ray = camera.ray(x, y);
                let mut c = RayCounts::default();
                let points = candidates(tracer, ray.origin, ray.dir, &mut c);
                (points.into_iter().filter(|p| !cache.covers(p.position, p.normals.shading)).collect(), c)
            })
            .collect();
        let uncovered: Vec<Candidate> = found.iter().flat_map(|(p, _)| p.iter().copied()).collect();
        stats.rays += found.iter().map(|(_, c)| *c).sum();
        let gathered: Vec<_> = uncovered
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let mut sampler = Sampler::independent(seed, PREPASS_STREAM + ((level as u64) << 32) + i as u64);
                let mut c = RayCounts::default();
                let (estimate, refined) =
                    tracer.record_gather(p.position, p.normals, strata, refinement, &mut sampler, &mut c);
                (estimate, refined, c)
            })
            .collect();
        for (p, (estimate, refined, c)) in uncovered.iter().zip(gathered) {
            stats.refined += refined as usize;
            let footprint = p.path_length * pixel_angle_rad;
            let oblique = footprint / p.view_cosine.max(MIN_VIEW_COSINE);
            cache.insert(
                p.position,
                p.normals.shading,
                estimate,
                MIN_REACH_PX * oblique / accuracy,
                MAX_REACH_PX * footprint / accuracy,
            );
            stats.rays += c;
        }
        stats.candidates += found.iter().map(|(p, _)| p.len()).sum::<usize>();
        cache.index();
        on_level_done(cache.len());
    }
    stats.records = cache.len();
    (cache, stats)
}

/// The diffuse points along the camera ray `origin + t·dir` and its specular branches (up to
/// `CANDIDATE_SPECULAR_DEPTH` bounces), in the tracer's depth-first order.
fn candidates(tracer: &Tracer, origin: Vec3, dir: Vec3, counts: &mut RayCounts) -> Vec<Candidate> {
    let mut stack = RayStack::<CANDIDATE_STACK>::new(origin, dir);
    let mut travelled = [0.0f32; CANDIDATE_STACK + 1];
    let mut out = Vec::new();
    while let Some(ray) = stack.pop() {
        counts.primary += 1;
        let Some((hit, distance)) = tracer.closest_opaque_hit(ray.origin, ray.dir) else {
            continue;
        };
        let path_length = travelled[ray.depth as usize] + distance;
        let material = &tracer.materials()[hit.material as usize];
        // The normals as the image's hits get them (`Tracer::radiance`).
        let hit = hit.with_shading_normal(tracer.mesh(), tracer.surfaces(), ray.dir);
        if let Some(element) = hit.element {
            if tracer.mesh().elements.reflectance[element as usize].max_element() > 0.0 {
                let view_cosine = ray.dir.normalize().dot(hit.normals().geometric).abs();
                out.push(Candidate { position: hit.position, normals: hit.normals(), path_length, view_cosine });
            }
        } else if !material.is_dielectric() {
            continue;
        }
        if ray.depth >= CANDIDATE_SPECULAR_DEPTH || !material.is_specular() {
            continue;
        }
        travelled[ray.depth as usize + 1] = path_length;
        stack.push_branches(
            &ray,
            &scatter(material, ray.dir, &hit),
            &hit,
            tracer.ray_offset(),
            tracer.min_throughput(),
        );
    }
    out
}
