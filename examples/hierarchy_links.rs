//! Where a surface's light comes from in a hierarchical solve: for each input triangle of the given
//! scene surface and the nodes below it down to a depth, the irradiance its own links bring, split by
//! the kind of source (element, far cluster, near cluster), with the node's area, open area and
//! exitance; then the same sums for the clusters above it. A diagnostic for accuracy work on a scene.
//!
//! usage: hierarchy_links SCENE.toml SURFACE [DEPTH] [MIN_ELEMENT_SIZE VISIBILITY_RAYS]

use std::process::ExitCode;

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
    ExitCode::SUCCESS
}
