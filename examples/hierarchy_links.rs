//! Where a surface's light comes from in a hierarchical solve: for each input triangle of the given
//! scene surface and the nodes below it down to a depth, the irradiance its own links bring, split by
//! the kind of source (element, far cluster, near cluster), with the node's area, open area and
//! exitance; then the same sums for the clusters above it. Last, per input triangle, what each link
//! of it and of its ancestors lands on it (a cluster's arrivals by the triangle's own cosine,
//! `gather::Arrival`), largest first, against the unoccluded exact transfer from the link's source
//! (Σ over the source's leaves of the element form factor × the leaf's exitance). A diagnostic for
//! accuracy work on a scene.
//!
//! usage: hierarchy_links SCENE.toml SURFACE [DEPTH] [MIN_ELEMENT_SIZE VISIBILITY_RAYS]

use std::process::ExitCode;

use glam::DVec3;
use radray::radiosity::hierarchy::form_factor::element_to_element;
use radray::radiosity::hierarchy::gather::{arrival_direction, ArrivalScales};
use radray::radiosity::hierarchy::links::is_near;
use radray::radiosity::hierarchy::{solve_reusing, HierarchyParams};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: hierarchy_links SCENE.toml SURFACE [DEPTH] [MIN_ELEMENT_SIZE VISIBILITY_RAYS]");
        return ExitCode::FAILURE;
    }
    let scene = match radray::scene::load(std::path::Path::new(&args[1])) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let surface: u32 = args[2].parse().unwrap_or(0);
    let depth: u8 = args.get(3).and_then(|d| d.parse().ok()).unwrap_or(2);
    let mut params = radray::radiosity::hierarchical::hierarchy_params(&scene);
    if let (Some(size), Some(rays)) = (args.get(4), args.get(5)) {
        params = HierarchyParams {
            min_element_divisor: scene.diagonal() / size.parse::<f32>().unwrap_or(1.0),
            visibility_rays: rays.parse().unwrap_or(8),
            ..params
        };
    }
    let (_, structure) = match solve_reusing(&scene, Default::default(), &params, None, &mut |_| {}) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let (nodes, links, inputs) = (structure.nodes(), structure.links(), structure.inputs());
    let describe = |n: usize, indent: usize| {
        let (mut element, mut far, mut near) = (0.0f64, 0.0f64, 0.0f64);
        let mut count = [0usize; 3];
        for k in links.range(n) {
            let s = links.source[k] as usize;
            let t = nodes.exitance[s].x * links.form_factor[k] as f64;
            if !nodes.is_cluster[s] && !nodes.is_cluster[n] {
                element += t;
                count[0] += 1;
            } else if is_near(nodes, n, s) {
                near += t;
                count[2] += 1;
            } else {
                far += t;
                count[1] += 1;
            }
        }
        println!(
            "{:indent$}node {n} level {} area {:.0} open {:.0} B.x {:.4} | own G.x: element {:.4} ({}) far cluster {:.4} ({}) near {:.4} ({})",
            "",
            nodes.level[n],
            nodes.area[n],
            nodes.open_area[n],
            nodes.exitance[n].x,
            element,
            count[0],
            far,
            count[1],
            near,
            count[2],
        );
    };
    for (i, &node) in inputs.node.iter().enumerate() {
        if inputs.surface[i] != surface || inputs.back[i] {
            continue;
        }
        println!("input triangle {i}: corners {:?}", nodes.corners[node as usize]);
        let mut up = nodes.parent[node as usize];
        while up != u32::MAX {
            describe(up as usize, 0);
            up = nodes.parent[up as usize];
        }
        let mut stack = vec![(node as usize, 0usize)];
        while let Some((n, d)) = stack.pop() {
            describe(n, 2 * d + 2);
            if (nodes.level[n]) < depth {
                stack.extend(nodes.children(n).rev().map(|c| (c, d + 1)));
            }
        }
    }
    let scales = ArrivalScales::new(nodes, links);
    for (i, &node) in inputs.node.iter().enumerate() {
        if inputs.surface[i] != surface || inputs.back[i] {
            continue;
        }
        let e = node as usize;
        let mut rows = Vec::new();
        let mut up = node;
        while up != u32::MAX {
            let a = up as usize;
            for k in links.range(a) {
                let s = links.source[k] as usize;
                let transfer = nodes.exitance[s] * links.form_factor[k] as f64;
                let share = scales.shares(k).find(|&(m, _)| m == e).map_or(0.0, |(_, c)| c as f64);
                let (landed, kind) = match arrival_direction(nodes, a, s) {
                    _ if nodes.is_cluster[a] && scales.has_shares(k) => (transfer * share, "member shares"),
                    Some(w) if nodes.is_cluster[a] && scales.scale[k] > 0.0 => (
                        transfer * scales.scale[k] as f64 * nodes.normal[e].dot(w).max(0.0) as f64,
                        if is_near(nodes, a, s) { "near arrival" } else { "far arrival" },
                    ),
                    _ => (transfer * nodes.open_gain(a), if nodes.is_cluster[a] { "uniform" } else { "element" }),
                };
                let mut exact = DVec3::ZERO;
                let mut stack = vec![s];
                while let Some(n) = stack.pop() {
                    if nodes.is_leaf(n) {
                        if n != e {
                            let (f, _) = element_to_element(&nodes.corners[e], nodes.normal[e], &nodes.corners[n]);
                            exact += nodes.exitance[n] * f;
                        }
                    } else {
                        stack.extend(nodes.children(n));
                    }
                }
                rows.push((a, s, kind, landed, exact));
            }
            up = nodes.parent[a];
        }
        rows.sort_by(|x, y| y.3.x.total_cmp(&x.3.x));
        let total: DVec3 = rows.iter().map(|r| r.3).sum();
        let exact: DVec3 = rows.iter().map(|r| r.4).sum();
        println!(
            "input triangle {i} (node {e}): landed G {total:.4} vs unoccluded exact over the same sources {exact:.4}"
        );
        for (a, s, kind, landed, exact) in rows.iter().take(16) {
            println!(
                "  at node {a} from node {s} ({kind}, source {}): G {:.4} {:.4} {:.4} | exact unoccluded {:.4} {:.4} {:.4}",
                if nodes.is_cluster[*s] { "cluster" } else { "element" },
                landed.x, landed.y, landed.z, exact.x, exact.y, exact.z
            );
        }
    }
    ExitCode::SUCCESS
}
