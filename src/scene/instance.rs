//! OBJ instancing: a `[[mesh]]`'s surfaces placed in the scene by its `scale` and `translate`, with
//! their material indices moved past the materials already defined.

use super::Surface;
use glam::Vec3;

/// Where one `[[mesh]]` instance goes: x ↦ x·`scale` + `translate` (per-axis scale, applied first).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub scale: Vec3,
    pub translate: Vec3,
}

impl Placement {
    /// Places `surfaces`: corners are transformed, shading normals by the inverse transpose
    /// (n ↦ normalise(n / scale)), and material indices shifted by `material_base`. A scale with an odd
    /// number of negative factors mirrors the mesh, which flips the winding: the corner order is then
    /// reversed to keep fronts counter-clockwise.
    pub fn apply(&self, surfaces: Vec<Surface>, material_base: u32) -> impl Iterator<Item = Surface> + '_ {
        let mirrored = self.scale.x * self.scale.y * self.scale.z < 0.0;
        surfaces.into_iter().map(move |mut s| {
            s.material += material_base;
            for v in &mut s.vertices {
                *v = *v * self.scale + self.translate;
            }
            if let Some(normals) = &mut s.shading_normals {
                for n in normals.iter_mut() {
                    *n = (*n / self.scale).normalize_or_zero();
                }
            }
            if mirrored {
                s.vertices.reverse();
                if let Some(n) = &mut s.shading_normals {
                    n.reverse();
                }
            }
            s
        })
    }
}
