//! Splitting chosen elements of a mesh into four: a quad at its edge midpoints and its centre, a
//! triangle at its edge midpoints. Midpoints are shared between the two elements of an edge (one
//! vertex per edge, `EdgeMidpoints`), so a split neighbour reuses them and the mesh stays shared-vertex
//! within a surface side; where the neighbour is not split the midpoint is a hanging vertex
//! (`hanging::conforming` gives it its edge's value).

use glam::Vec3;
use rustc_hash::FxHashMap;

use crate::mesh::{mean_element_albedo, mean_element_coverage, mean_element_emission, Mesh, NONE};

/// The vertex made at the midpoint of each split edge, keyed by the edge's end vertices (smaller
/// index first). Vertices are only ever appended, so keys stay valid from one level to the next.
#[derive(Clone, Debug, Default)]
pub struct EdgeMidpoints {
    map: FxHashMap<(u32, u32), u32>,
}

impl EdgeMidpoints {
    fn key(a: u32, b: u32) -> (u32, u32) {
        (a.min(b), a.max(b))
    }

    /// The midpoint vertex of edge (a, b), if that edge was split.
    pub fn get(&self, a: u32, b: u32) -> Option<u32> {
        self.map.get(&Self::key(a, b)).copied()
    }

    /// Number of split edges.
    pub fn len(&self) -> usize {
        self.map.len()
    }

    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// The split edges a refined mesh carries (`Mesh::split_edge_midpoints`, set by `split`).
    pub fn of(mesh: &Mesh) -> EdgeMidpoints {
        EdgeMidpoints { map: mesh.split_edge_midpoints.clone() }
    }

    /// The midpoint of edge (a, b), made (position and uv the mean of the ends: exact on a bilinear
    /// or affine edge) when the edge is split for the first time.
    fn vertex(&mut self, mesh: &mut Mesh, a: u32, b: u32) -> u32 {
        *self.map.entry(Self::key(a, b)).or_insert_with(|| {
            let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
            mesh.positions.push(0.5 * (pa + pb));
            let (ua, ub) = (mesh.uvs[a as usize], mesh.uvs[b as usize]);
            mesh.uvs.push(0.5 * (ua + ub));
            mesh.positions.len() as u32 - 1
        })
    }
}

/// The four children of a quad (a, b, c, d), counter-clockwise like their parent: corners, edge
/// midpoints m_ab, m_bc, m_cd, m_da and the centre m (the bilinear centre, the mean of the corners).
fn quad_children(c: [u32; 4], m: [u32; 4], centre: u32) -> [[u32; 4]; 4] {
    let [a, b, cc, d] = c;
    let [ab, bc, cd, da] = m;
    [[a, ab, centre, da], [ab, b, bc, centre], [centre, bc, cc, cd], [da, centre, cd, d]]
}

/// The four children of a triangle (a, b, c): three corner triangles and the middle one, all
/// counter-clockwise like their parent.
fn triangle_children(c: [u32; 3], m: [u32; 3]) -> [[u32; 4]; 4] {
    let [a, b, cc] = c;
    let [ab, bc, ca] = m;
    [[a, ab, ca, NONE], [ab, b, bc, NONE], [ca, bc, cc, NONE], [ab, bc, ca, NONE]]
}

/// `mesh` with every element `e` where `split[e]` replaced, in place, by its four children (see
/// module docs); the others keep their corners, and their traced triangles keep their back sides.
/// Children inherit their parent's surface and material; on textured materials their reflectance,
/// emission and opacity are their own means over their uv triangles (`mesh::mean_element_albedo`
/// and siblings), else the parent's. Elements of two-sided surfaces must not be split (their back
/// side mirrors the front's grid).
pub fn split(mesh: &Mesh, split: &[bool], midpoints: &mut EdgeMidpoints) -> Mesh {
    assert_eq!(split.len(), mesh.elements.len());
    let old = &mesh.elements;
    let mut out = Mesh {
        positions: mesh.positions.clone(),
        uvs: mesh.uvs.clone(),
        surface_source: mesh.surface_source.clone(),
        surface_has_uv: mesh.surface_has_uv.clone(),
        surface_partner: mesh.surface_partner.clone(),
        surface_back_refracts: mesh.surface_back_refracts.clone(),
        textures: mesh.textures.clone(),
        ..Default::default()
    };
    // The traced triangles of each element (front sides only; in element order).
    let mut triangles_of: Vec<Vec<usize>> = vec![Vec::new(); old.len()];
    for (t, &e) in mesh.triangle_element.iter().enumerate() {
        triangles_of[e as usize].push(t);
    }
    let mut new_index = vec![NONE; old.len()];
    let mut parent = Vec::with_capacity(old.len());
    for e in 0..old.len() {
        if !split[e] {
            new_index[e] = push(&mut out, mesh, e, old.corners[e]);
            parent.push(e);
            continue;
        }
        let c = old.corners[e];
        let children = if c[3] == NONE {
            let m = [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])].map(|(a, b)| midpoints.vertex(&mut out, a, b));
            triangle_children([c[0], c[1], c[2]], m)
        } else {
            let m =
                [(c[0], c[1]), (c[1], c[2]), (c[2], c[3]), (c[3], c[0])].map(|(a, b)| midpoints.vertex(&mut out, a, b));
            out.positions.push(c.iter().map(|&v| mesh.positions[v as usize]).sum::<Vec3>() * 0.25);
            out.uvs.push(c.iter().map(|&v| mesh.uvs[v as usize]).sum::<glam::Vec2>() * 0.25);
            quad_children(c, m, out.positions.len() as u32 - 1)
        };
        for child in children {
            push(&mut out, mesh, e, child);
            parent.push(e);
        }
    }
    // Traced triangles: an unsplit element keeps its own (and their back sides, renumbered); a child
    // gets its fan (0, 1, 2), (0, 2, 3) like `Mesh::build`.
    for (new_e, &e) in parent.iter().enumerate() {
        if triangles_of[e].is_empty() {
            continue; // a back side: read through its front's triangles
        }
        if !split[e] {
            for &t in &triangles_of[e] {
                out.triangles.push(mesh.triangles[t]);
                out.triangle_element.push(new_e as u32);
                let back = mesh.triangle_back_element[t];
                out.triangle_back_element.push(if back == NONE { NONE } else { new_index[back as usize] });
                out.triangle_back_vertices.push(mesh.triangle_back_vertices[t]);
            }
            continue;
        }
        let c = out.elements.corners[new_e];
        let fans: &[[usize; 3]] = if c[3] == NONE { &[[0, 1, 2]] } else { &[[0, 1, 2], [0, 2, 3]] };
        for f in fans {
            out.triangles.push(f.map(|k| c[k]));
            out.triangle_element.push(new_e as u32);
            out.triangle_back_element.push(NONE);
            out.triangle_back_vertices.push([NONE; 3]);
        }
    }
    if mesh.textures.is_textured() {
        let means: Vec<(usize, Option<Vec3>, Option<Vec3>)> = (0..parent.len())
            .filter(|&new_e| split[parent[new_e]])
            .map(|new_e| {
                let textures = &mesh.textures;
                (new_e, mean_element_albedo(&out, textures, new_e), mean_element_emission(&out, textures, new_e))
            })
            .collect();
        for (new_e, albedo, emission) in means {
            if let Some(a) = albedo {
                out.elements.reflectance[new_e] = a;
            }
            if let Some(x) = emission {
                out.elements.emission[new_e] = x;
            }
        }
    }
    if !mesh.element_coverage.is_empty() {
        out.element_coverage = parent
            .iter()
            .enumerate()
            .map(|(new_e, &e)| match split[e] {
                true => mean_element_coverage(&out, &mesh.textures, new_e).unwrap_or(mesh.element_coverage[e]),
                false => mesh.element_coverage[e],
            })
            .collect();
    }
    out.split_edge_midpoints = midpoints.map.clone();
    out
}

/// Appends element `from` of `mesh` to `out` with `corners`: the same corners keep its centre, normal
/// and area bit for bit; new corners get them as `Mesh::build` computes them (a quad's area is half
/// its diagonals' cross product, its centre the corners' mean). Returns the new index.
fn push(out: &mut Mesh, mesh: &Mesh, from: usize, corners: [u32; 4]) -> u32 {
    let old = &mesh.elements;
    let (centre, normal, area) = if corners == old.corners[from] {
        (old.centre[from], old.normal[from], old.area[from])
    } else {
        let p = |k: usize| out.positions[corners[k] as usize];
        let (cross, centre) = if corners[3] == NONE {
            ((p(1) - p(0)).cross(p(2) - p(0)), (p(0) + p(1) + p(2)) / 3.0)
        } else {
            ((p(2) - p(0)).cross(p(3) - p(1)), (p(0) + p(1) + p(2) + p(3)) / 4.0)
        };
        let area = 0.5 * cross.length();
        (centre, cross / (2.0 * area), area)
    };
    let e = &mut out.elements;
    e.corners.push(corners);
    e.centre.push(centre);
    e.normal.push(normal);
    e.area.push(area);
    e.surface.push(old.surface[from]);
    e.material.push(old.material[from]);
    e.reflectance.push(old.reflectance[from]);
    e.emission.push(old.emission[from]);
    e.len() as u32 - 1
}
