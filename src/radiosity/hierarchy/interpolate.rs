//! The leaf elements as a shared-vertex mesh with conforming per-vertex exitance: vertices are shared
//! within a smoothing group (edge-connected input triangles of one material and side whose normals
//! differ by less than about 25°); a vertex takes the mean of the leaves around it weighted by their
//! open area (`Nodes::open_area`, the area-weighted mean when nothing rests on the surface),
//! except a hanging node (a vertex inside a coarser neighbour's edge), which takes that edge's
//! interpolated value, so Gouraud shading shows no T-vertex cracks.

use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap;

use super::clusters::InputTriangles;
use super::nodes::Nodes;

/// Normals of triangles in one smoothing group differ by less than acos(0.9) ≈ 25.8°.
const SMOOTHING_COS: f32 = 0.9;

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
    /// Per vertex: conforming exitance (W/m²).
    pub vertex_exitance: Vec<Vec3>,
}

type PositionKey = [u32; 3];

fn key(p: Vec3) -> PositionKey {
    [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
}

/// Union-find root with path halving.
fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let up = parent[parent[i as usize] as usize];
        parent[i as usize] = up;
        i = up;
    }
    i
}

/// Smoothing group of each input triangle (see module docs).
pub fn smoothing_groups(nodes: &Nodes, inputs: &InputTriangles) -> Vec<u32> {
    let count = inputs.node.len();
    let mut parent: Vec<u32> = (0..count as u32).collect();
    let mut first_on_edge: FxHashMap<(PositionKey, PositionKey), u32> = FxHashMap::default();
    for i in 0..count {
        let n = inputs.node[i] as usize;
        let c = nodes.corners[n];
        for e in 0..3 {
            let (a, b) = (key(c[e]), key(c[(e + 1) % 3]));
            let edge = if a <= b { (a, b) } else { (b, a) };
            match first_on_edge.get(&edge) {
                None => {
                    first_on_edge.insert(edge, i as u32);
                }
                Some(&j) => {
                    let m = inputs.node[j as usize] as usize;
                    let compatible = inputs.material[i] == inputs.material[j as usize]
                        && inputs.back[i] == inputs.back[j as usize]
                        && nodes.normal[n].dot(nodes.normal[m]) > SMOOTHING_COS;
                    if compatible {
                        let (ri, rj) = (find(&mut parent, i as u32), find(&mut parent, j));
                        if ri != rj {
                            parent[ri.max(rj) as usize] = ri.min(rj);
                        }
                    }
                }
            }
        }
    }
    (0..count as u32).map(|i| find(&mut parent, i)).collect()
}

/// Leaf elements below `root` (depth-first order) with shared vertices and conforming vertex
/// exitance.
pub fn leaf_mesh(nodes: &Nodes, inputs: &InputTriangles, root: usize) -> LeafMesh {
    let groups = smoothing_groups(nodes, inputs);
    let mut mesh = LeafMesh::default();
    let mut vertex_of: FxHashMap<(u32, PositionKey), u32> = FxHashMap::default();
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
                mesh.positions.len() as u32 - 1
            })
        });
        mesh.triangles.push(tri);
        mesh.leaf_node.push(n as u32);
    }
    // Open-area-weighted means (`Nodes::open_area`): a vertex on the edge of an object resting on the
    // surface takes the open leaves' value, not the dark hidden ones'; a vertex with only hidden
    // leaves around it takes their area-weighted mean.
    let mut sum = vec![DVec3::ZERO; mesh.positions.len()];
    let mut weight = vec![0.0f64; mesh.positions.len()];
    let mut hidden_sum = vec![DVec3::ZERO; mesh.positions.len()];
    let mut hidden_weight = vec![0.0f64; mesh.positions.len()];
    for (t, &n) in mesh.triangles.iter().zip(&mesh.leaf_node) {
        let (open, a) = (nodes.open_area[n as usize] as f64, nodes.area[n as usize] as f64);
        for &v in t {
            sum[v as usize] += nodes.exitance[n as usize] * open;
            weight[v as usize] += open;
            hidden_sum[v as usize] += nodes.exitance[n as usize] * a;
            hidden_weight[v as usize] += a;
        }
    }
    let mut value: Vec<DVec3> = (0..sum.len())
        .map(|v| {
            if weight[v] > 0.0 {
                sum[v] / weight[v]
            } else if hidden_weight[v] > 0.0 {
                hidden_sum[v] / hidden_weight[v]
            } else {
                DVec3::ZERO
            }
        })
        .collect();
    // Hanging nodes, coarsest edges first so that an edge's ends are final before its midpoint.
    let mut edges: Vec<(f32, u32, u32, u32)> = Vec::new();
    for (t, &n) in mesh.triangles.iter().zip(&mesh.leaf_node) {
        let group = groups[nodes.input[n as usize] as usize];
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            let len = mesh.positions[a as usize].distance_squared(mesh.positions[b as usize]);
            edges.push((len, group, a.min(b), a.max(b)));
        }
    }
    edges.sort_by(|x, y| y.0.total_cmp(&x.0).then((x.1, x.2, x.3).cmp(&(y.1, y.2, y.3))));
    edges.dedup_by(|x, y| (x.1, x.2, x.3) == (y.1, y.2, y.3));
    // Longest first is not always enough: an edge's end can itself hang on an edge of the same or a
    // shorter length processed later (a T-junction that points the other way), and then the midpoint
    // read a stale end. The hanging nodes form a DAG (a midpoint depends only on its edge's ends), so
    // repeating the sweep until nothing changes settles it, one dependency level per sweep.
    let mut work = Vec::new();
    for _sweep in 0..MAX_HANGING_SWEEPS {
        let mut changed = false;
        for &(_, group, a, b) in &edges {
            work.push((a, b));
            while let Some((a, b)) = work.pop() {
                let mid = (mesh.positions[a as usize] + mesh.positions[b as usize]) * 0.5;
                if let Some(&m) = vertex_of.get(&(group, key(mid))) {
                    if m != a && m != b {
                        let interpolated = (value[a as usize] + value[b as usize]) * 0.5;
                        changed |= value[m as usize] != interpolated;
                        value[m as usize] = interpolated;
                        work.push((a, m));
                        work.push((m, b));
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    mesh.vertex_exitance = value.iter().map(|v| v.as_vec3()).collect();
    mesh
}
