//! Whitted's ray tree without recursion: an explicit, fixed-size stack of rays with their path
//! throughput and depth, which both passes walk depth-first.

use glam::Vec3;

use super::hit::SurfaceHit;
use super::scatter::{carries, Scatter};

/// A ray waiting on the stack.
#[derive(Clone, Copy, Debug, Default)]
pub struct StackRay {
    pub origin: Vec3,
    pub dir: Vec3,
    /// Product of the specular weights along the path so far, the refractions' radiance factors
    /// (η_i/η_t)² included (`scatter`).
    pub throughput: Vec3,
    /// The product of those radiance factors alone: 1 in the medium the path started in, 1/n² inside
    /// a dielectric of index n entered from air.
    pub radiance_scale: f32,
    /// Bounces before this ray (0 for the root).
    pub depth: u32,
}

/// At most `N` rays. A depth-first walk pops one ray and pushes at most two one level deeper, so a
/// walk that stops at depth d never holds more than d + 2: choose `N` = deepest depth + 2.
pub struct RayStack<const N: usize> {
    rays: [StackRay; N],
    len: usize,
}

impl<const N: usize> RayStack<N> {
    /// A stack holding the root ray `origin + t·dir` (normalised) with throughput 1.
    pub fn new(origin: Vec3, dir: Vec3) -> RayStack<N> {
        let mut rays = [StackRay::default(); N];
        rays[0] = StackRay { origin, dir: dir.normalize(), throughput: Vec3::ONE, radiance_scale: 1.0, depth: 0 };
        RayStack { rays, len: 1 }
    }

    pub fn pop(&mut self) -> Option<StackRay> {
        self.len = self.len.checked_sub(1)?;
        Some(self.rays[self.len])
    }

    /// Pushes the branches of `scatter` (`Scatter::split` of `ray`'s throughput) one level deeper,
    /// leaving `hit` by `offset`, those that still carry light (`carries` with `min_throughput`, on
    /// the throughput without the radiance factors: a path inside glass is cut where it would be cut
    /// outside, since leaving undoes the factor of entering).
    pub fn push_branches(
        &mut self,
        ray: &StackRay,
        scatter: &Scatter,
        hit: &SurfaceHit,
        offset: f32,
        min_throughput: f32,
    ) {
        for branch in scatter.split(ray.throughput).into_iter().flatten() {
            let radiance_scale = ray.radiance_scale * branch.radiance_scale;
            if carries(branch.throughput / radiance_scale, min_throughput) {
                assert!(self.len < N, "ray stack overflow: the depth bound sizes the stack so this cannot happen");
                self.rays[self.len] = StackRay {
                    origin: branch.origin(hit, offset),
                    dir: branch.dir,
                    throughput: branch.throughput,
                    radiance_scale,
                    depth: ray.depth + 1,
                };
                self.len += 1;
            }
        }
    }
}
