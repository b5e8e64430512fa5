//! The geometry report as text, as `radray info` prints it: a heading per check with its count, then
//! one line per example and how many more were found.

use super::{Findings, GeometryReport, SurfaceRef};
use std::fmt;

fn point(p: [f32; 3]) -> String {
    format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2])
}

fn surface(r: &SurfaceRef) -> String {
    format!("#{} `{}`", r.index, r.object)
}

/// The example lines of one check (`    - …`) and, when some were left out, how many.
fn examples<T>(f: &mut fmt::Formatter<'_>, count: usize, shown: &[T], line: impl Fn(&T) -> String) -> fmt::Result {
    for x in shown {
        writeln!(f, "    - {}", line(x))?;
    }
    if count > shown.len() {
        writeln!(f, "      ... and {} more", count - shown.len())?;
    }
    Ok(())
}

/// One check's heading with its count (`  heading: N`), then its examples.
fn section<T>(
    f: &mut fmt::Formatter<'_>,
    heading: &str,
    found: &Findings<T>,
    line: impl Fn(&T) -> String,
) -> fmt::Result {
    writeln!(f, "  {heading}: {}", found.count)?;
    examples(f, found.count, &found.examples, line)
}

impl fmt::Display for GeometryReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "Geometry check: {} surfaces ({} skipped as degenerate), {} nearby pairs examined, tolerance {:.3e} (scene diagonal {:.4})",
            self.surface_count, self.skipped_surfaces, self.candidate_pairs, self.tolerance, self.scene_diagonal
        )?;

        section(f, "T-junctions (cracks in interpolated radiosity)", &self.t_junctions, |t| {
            let (corner, edge) = (surface(&t.vertex_surface), surface(&t.edge_surface));
            format!("corner of {corner} at {} lies inside an edge of {edge}", point(t.point))
        })?;

        section(f, "coplanar overlapping faces", &self.coplanar_overlaps, |c| {
            let how = if c.same_facing { "same way (z-fighting)" } else { "opposite ways (back to back)" };
            let (a, b) = (surface(&c.a), surface(&c.b));
            format!("{a} and {b} overlap by {:.4} around {}, facing {how}", c.overlap_area, point(c.point))
        })?;

        section(f, "intersecting faces (light leaks)", &self.intersections, |x| {
            format!("{} crosses {} along {:.4} around {}", surface(&x.a), surface(&x.b), x.length, point(x.point))
        })?;

        let flipped = &self.flipped;
        writeln!(
            f,
            "  faces flipped against their neighbours: {} ({} shared edges traversed the same way)",
            flipped.count, flipped.inconsistent_edges
        )?;
        if !flipped.per_object.is_empty() {
            let objects: Vec<String> =
                flipped.per_object.iter().map(|o| format!("`{}`: {}", o.object, o.count)).collect();
            writeln!(f, "    per object: {}", objects.join(", "))?;
        }
        examples(f, flipped.count, &flipped.examples, |x| {
            let (face, neighbour) = (surface(&x.surface), surface(&x.neighbour));
            format!("{face} disagrees with {neighbour} at the edge around {}", point(x.point))
        })?;

        section(f, "non-planar polygons", &self.non_planar, |x| {
            format!(
                "{}: a corner at {} is {:.4} off the polygon's plane",
                surface(&x.surface),
                point(x.point),
                x.deviation
            )
        })?;

        if self.is_clean() {
            write!(f, "  no suspicious geometry")
        } else {
            write!(f, "  see above: these are the usual causes of light leaks and cracks")
        }
    }
}
