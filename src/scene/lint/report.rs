//! The geometry report as text, as `radray info` prints it.

use super::{GeometryReport, SurfaceRef};
use std::fmt;

impl fmt::Display for GeometryReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let point = |p: [f32; 3]| format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2]);
        let s = |r: &SurfaceRef| format!("#{} `{}`", r.index, r.object);
        writeln!(
            f,
            "Geometry check: {} surfaces ({} skipped as degenerate), {} nearby pairs examined, tolerance {:.3e} (scene diagonal {:.4})",
            self.surface_count, self.skipped_surfaces, self.candidate_pairs, self.tolerance, self.scene_diagonal
        )?;
        let more = |f: &mut fmt::Formatter<'_>, count: usize, shown: usize| {
            if count > shown {
                writeln!(f, "      ... and {} more", count - shown)
            } else {
                Ok(())
            }
        };
        writeln!(f, "  T-junctions (cracks in interpolated radiosity): {}", self.t_junctions.count)?;
        for t in &self.t_junctions.examples {
            writeln!(
                f,
                "    - corner of {} at {} lies inside an edge of {}",
                s(&t.vertex_surface),
                point(t.point),
                s(&t.edge_surface)
            )?;
        }
        more(f, self.t_junctions.count, self.t_junctions.examples.len())?;
        writeln!(f, "  coplanar overlapping faces: {}", self.coplanar_overlaps.count)?;
        for c in &self.coplanar_overlaps.examples {
            let how = if c.same_facing { "same way (z-fighting)" } else { "opposite ways (back to back)" };
            writeln!(
                f,
                "    - {} and {} overlap by {:.4} around {}, facing {how}",
                s(&c.a),
                s(&c.b),
                c.overlap_area,
                point(c.point)
            )?;
        }
        more(f, self.coplanar_overlaps.count, self.coplanar_overlaps.examples.len())?;
        writeln!(f, "  intersecting faces (light leaks): {}", self.intersections.count)?;
        for x in &self.intersections.examples {
            writeln!(f, "    - {} crosses {} along {:.4} around {}", s(&x.a), s(&x.b), x.length, point(x.point))?;
        }
        more(f, self.intersections.count, self.intersections.examples.len())?;
        writeln!(
            f,
            "  faces flipped against their neighbours: {} ({} shared edges traversed the same way)",
            self.flipped.count, self.flipped.inconsistent_edges
        )?;
        if !self.flipped.per_object.is_empty() {
            let objects: Vec<String> =
                self.flipped.per_object.iter().map(|o| format!("`{}`: {}", o.object, o.count)).collect();
            writeln!(f, "    per object: {}", objects.join(", "))?;
        }
        for x in &self.flipped.examples {
            writeln!(
                f,
                "    - {} disagrees with {} at the edge around {}",
                s(&x.surface),
                s(&x.neighbour),
                point(x.point)
            )?;
        }
        more(f, self.flipped.count, self.flipped.examples.len())?;
        writeln!(f, "  non-planar polygons: {}", self.non_planar.count)?;
        for x in &self.non_planar.examples {
            writeln!(
                f,
                "    - {}: a corner at {} is {:.4} off the polygon's plane",
                s(&x.surface),
                point(x.point),
                x.deviation
            )?;
        }
        more(f, self.non_planar.count, self.non_planar.examples.len())?;
        if self.is_clean() {
            write!(f, "  no suspicious geometry")?;
        } else {
            write!(f, "  see above: these are the usual causes of light leaks and cracks")?;
        }
        Ok(())
    }
}
