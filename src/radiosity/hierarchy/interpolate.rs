//! The leaf elements as a shared-vertex mesh with conforming per-vertex exitance: vertices are shared
//! within a smoothing group (`smoothing_groups`: edge-connected input triangles of one material and
//! side whose normals differ by less than about 25°). Vertex values come from the element meshes' one vertex step
//! (`boundary_vertices::vertex_values`): inside a group the mean of the leaves around a vertex
//! weighted by their open area (`Nodes::open_area`, the area-weighted mean when nothing rests on the
//! surface), on the group's boundary the clamped linear extrapolation from the leaves inside; then a
//! hanging node (a vertex inside a coarser neighbour's edge) takes that edge's interpolated value, so
//! Gouraud shading shows no T-vertex cracks. Input triangles of one plane that meet at T-junctions
//! instead of shared edges (a wall written as upright strips beside a stair: `t_junctions`) stay
//! groups of their own, but each leaf's linear fit reads the leaves across the junction, as the
//! uniform and adaptive meshes' fits do (`smooth_mesh`): without it a strip's corner inside its
//! neighbour's edge is extrapolated from the strip's own leaves alone (docs/accuracy.md, session 39).

use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap;

use super::clusters::InputTriangles;
use super::nodes::Nodes;
use crate::mesh::NONE;
use crate::radiosity::boundary_vertices::{self, ElementMesh};
use crate::radiosity::smooth_mesh::agree;
use crate::radiosity::smoothing_groups::{self, Facet};
use crate::radiosity::t_junctions::{t_junction_families, vertices_inside_edges};

/// Upper bound on the hanging-node sweeps of `leaf_mesh`: one per level of nested T-junctions (a leaf
/// is at most a few dozen subdivisions below its input triangle).
const MAX_HANGING_SWEEPS: usize = 64;

/// Leaf elements as an indexed mesh.
#[derive(Clone, Debug, Default)]
pub struct LeafMesh {
    pub positions: Vec<Vec3>,
    /// Per leaf: its corners (counter-clockwise from the front) as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// Per leaf: its node.
    pub leaf_node: Vec<u32>,
    /// Per leaf: its smoothing group, its unit normal, its area and the open part of it
    /// (`Nodes::open_area`; 0: buried inside an object resting on the surface), all m².
    pub leaf_group: Vec<u32>,
    pub leaf_normal: Vec<Vec3>,
    pub leaf_area: Vec<f32>,
    pub leaf_open_area: Vec<f32>,
    /// Per vertex: it lies on its smoothing group's boundary (`boundary_vertices::boundary_vertices`
    /// with the hanging nodes' edges cut at them).
    pub boundary: Vec<bool>,
    /// Hanging nodes as (m, a, b): vertex m at the midpoint of the leaf edge (a, b), in the order one
    /// conforming sweep visits them (`conform`).
    pub hanging: Vec<[u32; 3]>,
    /// Per vertex: conforming exitance (W/m²).
    pub vertex_exitance: Vec<Vec3>,
    /// T-junctions between groups (`t_junctions`): (vertex, leaf) where the vertex, of another group
    /// of the leaf's fit family, lies inside one of the leaf's edges.
    pub contacts: Vec<(u32, u32)>,
    /// Per leaf: its fit family (`t_junctions::t_junction_families` over the input triangles).
    pub leaf_family: Vec<u32>,
}

impl ElementMesh for LeafMesh {
    fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    fn element_count(&self) -> usize {
        self.triangles.len()
    }

    fn corners(&self, e: usize) -> [u32; 4] {
        let [a, b, c] = self.triangles[e];
        [a, b, c, NONE]
    }

    fn centre(&self, e: usize) -> Vec3 {
        self.triangles[e].iter().map(|&v| self.positions[v as usize]).sum::<Vec3>() / 3.0
    }

    fn normal(&self, e: usize) -> Vec3 {
        self.leaf_normal[e]
    }

    /// The open area: a leaf under an object resting on the surface is not averaged into its vertices.
    fn weight(&self, e: usize) -> f64 {
        self.leaf_open_area[e] as f64
    }

    fn surface(&self, e: usize) -> u32 {
        self.leaf_group[e]
    }

    fn contacts(&self) -> &[(u32, u32)] {
        &self.contacts
    }

    fn fit_surface(&self, e: usize) -> u32 {
        self.leaf_family.get(e).copied().unwrap_or(self.leaf_group[e])
    }

    /// Across a T-junction only where the two leaves' values agree (`smooth_mesh::agree`, without its
    /// floor): a sharp shadow edge lying on the junction keeps its step.
    fn fit_reads(&self, e: usize, n: usize, values: &[Vec3]) -> bool {
        self.leaf_group[e] == self.leaf_group[n] || agree(values[e], values[n], 0.0)
    }

    fn buried(&self, e: usize) -> bool {
        !(self.leaf_open_area[e] > 0.0)
    }

    /// The weights are open areas (a leaf under an object resting on it weighs its open part).
    fn weights_are_areas(&self) -> bool {
        false
    }

    /// Open-area-weighted means: a vertex on the edge of an object resting on the surface takes the
    /// open leaves' value, not the dark hidden ones'; a vertex with only hidden leaves around it takes
    /// their area-weighted mean.
    fn vertex_mean(&self, element_values: &[DVec3]) -> Vec<DVec3> {
        let mut sum = vec![DVec3::ZERO; self.positions.len()];
        let mut weight = vec![0.0f64; self.positions.len()];
        let mut hidden_sum = vec![DVec3::ZERO; self.positions.len()];
        let mut hidden_weight = vec![0.0f64; self.positions.len()];
        for (l, t) in self.triangles.iter().enumerate() {
            let (open, a) = (self.leaf_open_area[l] as f64, self.leaf_area[l] as f64);
            for &v in t {
                sum[v as usize] += element_values[l] * open;
                weight[v as usize] += open;
                hidden_sum[v as usize] += element_values[l] * a;
                hidden_weight[v as usize] += a;
            }
        }
        (0..sum.len())
            .map(|v| {
                if weight[v] > 0.0 {
                    sum[v] / weight[v]
                } else if hidden_weight[v] > 0.0 {
                    hidden_sum[v] / hidden_weight[v]
                } else {
                    DVec3::ZERO
                }
            })
            .collect()
    }
}

impl LeafMesh {
    /// Conforming per-vertex values of per-leaf values (exitance, its direct part; W/m²): the vertex
    /// step of every element mesh (`boundary_vertices::vertex_values`: open-area means inside a
    /// smoothing group, clamped extrapolation at its boundary), then every hanging node set to its
    /// edge's interpolated value (`conform`).
    pub fn vertex_values(&self, leaf_values: &[DVec3]) -> Vec<Vec3> {
        let vertex = boundary_vertices::vertex_values(self, leaf_values, &self.boundary);
        let mut value: Vec<DVec3> = vertex.iter().map(|v| v.as_dvec3()).collect();
        self.conform(&mut value);
        value.iter().map(|v| v.as_vec3()).collect()
    }

    /// Sets every hanging node m on edge (a, b) to (V_a + V_b)/2. The sweep visits coarse edges first,
    /// but an edge's end can itself hang on an edge of the same or a shorter length visited later (a
    /// T-junction that points the other way), and then the midpoint read a stale end. The hanging
    /// nodes form a DAG (a midpoint depends only on its edge's ends), so repeating the sweep until
    /// nothing changes settles it, one dependency level per sweep.
    fn conform(&self, value: &mut [DVec3]) {
        for _sweep in 0..MAX_HANGING_SWEEPS {
            let mut changed = false;
            for &[m, a, b] in &self.hanging {
                let interpolated = (value[a as usize] + value[b as usize]) * 0.5;
                changed |= value[m as usize] != interpolated;
                value[m as usize] = interpolated;
            }
            if !changed {
                break;
            }
        }
    }
}

type PositionKey = [u32; 3];

fn key(p: Vec3) -> PositionKey {
    [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
}

/// Input triangle i as a facet for `smoothing_groups` (its corners compared bit for bit).
fn input_facet(nodes: &Nodes, inputs: &InputTriangles, i: usize) -> Facet<PositionKey> {
    let n = inputs.node[i] as usize;
    let c = nodes.corners[n];
    Facet {
        corners: [key(c[0]), key(c[1]), key(c[2]), [0; 3]],
        corner_count: 3,
        normal: nodes.normal[n],
        material: inputs.material[i],
        back: inputs.back[i],
    }
}

/// Smoothing group of each input triangle (`smoothing_groups::smoothing_groups` over the input
/// triangles, their corners compared bit for bit).
pub fn smoothing_groups(nodes: &Nodes, inputs: &InputTriangles) -> Vec<u32> {
    smoothing_groups::smoothing_groups(inputs.node.len(), |i| input_facet(nodes, inputs, i))
}

/// Leaf elements below `root` (depth-first order) with shared vertices and conforming vertex
/// exitance (`LeafMesh::vertex_values`).
pub fn leaf_mesh(nodes: &Nodes, inputs: &InputTriangles, root: usize) -> LeafMesh {
    let groups = smoothing_groups(nodes, inputs);
    let mut mesh = LeafMesh::default();
    let mut vertex_of: FxHashMap<(u32, PositionKey), u32> = FxHashMap::default();
    // Per vertex: the input triangle of the first leaf that made it (its group's facet, for the
    // T-junction families).
    let mut vertex_input: Vec<u32> = Vec::new();
    let mut stack = vec![root];
    while let Some(n) = stack.pop() {
        if !nodes.is_leaf(n) {
            stack.extend(nodes.children(n).rev());
            continue;
        }
        let group = groups[nodes.input[n] as usize];
        let tri = nodes.corners[n].map(|p| {
            *vertex_of.entry((group, key(p))).or_insert_with(|| {
                mesh.positions.push(p);
                vertex_input.push(nodes.input[n]);
                mesh.positions.len() as u32 - 1
            })
        });
        mesh.triangles.push(tri);
        mesh.leaf_node.push(n as u32);
        mesh.leaf_group.push(group);
        mesh.leaf_normal.push(nodes.normal[n]);
        mesh.leaf_area.push(nodes.area[n]);
        mesh.leaf_open_area.push(nodes.open_area[n]);
    }
    // Hanging nodes, coarsest edges first so that an edge's ends are usually final before its midpoint
    // (`LeafMesh::conform` repeats the sweep for the rest).
    let mut edges: Vec<(f32, u32, u32, u32)> = Vec::new();
    for (t, &group) in mesh.triangles.iter().zip(&mesh.leaf_group) {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            let len = mesh.positions[a as usize].distance_squared(mesh.positions[b as usize]);
            edges.push((len, group, a.min(b), a.max(b)));
        }
    }
    edges.sort_by(|x, y| y.0.total_cmp(&x.0).then((x.1, x.2, x.3).cmp(&(y.1, y.2, y.3))));
    edges.dedup_by(|x, y| (x.1, x.2, x.3) == (y.1, y.2, y.3));
    let mut midpoint_of: FxHashMap<(u32, u32), u32> = FxHashMap::default();
    let mut work = Vec::new();
    for &(_, group, a, b) in &edges {
        work.push((a, b));
        while let Some((a, b)) = work.pop() {
            let mid = (mesh.positions[a as usize] + mesh.positions[b as usize]) * 0.5;
            if let Some(&m) = vertex_of.get(&(group, key(mid))) {
                if m != a && m != b {
                    mesh.hanging.push([m, a, b]);
                    midpoint_of.insert((a.min(b), a.max(b)), m);
                    work.push((a, m));
                    work.push((m, b));
                }
            }
        }
    }
    mesh.boundary =
        boundary_vertices::boundary_vertices(&mesh, &|a, b| midpoint_of.get(&(a.min(b), a.max(b))).copied());
    t_junction_contacts(&mut mesh, nodes, inputs, &groups, &vertex_input);
    let exitance: Vec<DVec3> = mesh.leaf_node.iter().map(|&n| nodes.exitance[n as usize]).collect();
    mesh.vertex_exitance = mesh.vertex_values(&exitance);
    mesh
}

/// Finds the T-junctions between groups (vertices of one group strictly inside a leaf edge of
/// another, `t_junctions::vertices_inside_edges`), joins the groups into fit families where their
/// input triangles may be one smooth surface (`t_junction_families`), and records the contacts within
/// a family (`LeafMesh::contacts`, `leaf_family`).
fn t_junction_contacts(
    mesh: &mut LeafMesh,
    nodes: &Nodes,
    inputs: &InputTriangles,
    groups: &[u32],
    vertex_input: &[u32],
) {
    let vertex_group: Vec<u32> = vertex_input.iter().map(|&i| groups[i as usize]).collect();
    let corners: Vec<[u32; 4]> = mesh.triangles.iter().map(|&[a, b, c]| [a, b, c, NONE]).collect();
    let leaf_input: Vec<u32> = mesh.leaf_node.iter().map(|&n| nodes.input[n as usize]).collect();
    let class = |i: u32| inputs.material[i as usize].wrapping_mul(2) | inputs.back[i as usize] as u32;
    let junctions = vertices_inside_edges(
        &mesh.positions,
        &corners,
        |v| class(vertex_input[v as usize]),
        |l| class(leaf_input[l]),
        |v, l| vertex_group[v as usize] != mesh.leaf_group[l],
    );
    let facets: Vec<Facet<PositionKey>> = (0..inputs.node.len()).map(|i| input_facet(nodes, inputs, i)).collect();
    let family = t_junction_families(groups, &facets, &junctions, vertex_input, &leaf_input);
    mesh.leaf_family = leaf_input.iter().map(|&i| family[i as usize]).collect();
    mesh.contacts = junctions
        .iter()
        .flat_map(|edge| edge.inside.iter().map(move |&v| (v, edge.element)))
        .filter(|&(v, l)| family[vertex_input[v as usize] as usize] == mesh.leaf_family[l as usize])
        .collect();
    mesh.contacts.sort_unstable();
    mesh.contacts.dedup();
}
