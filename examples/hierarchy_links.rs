//! Where a surface's light comes from in a hierarchical solve: for each input triangle of the given
//! scene surface and the nodes below it down to a depth, the irradiance its own links bring, split by
//! the kind of source (element, far cluster, near cluster), with the node's area, open area and
//! exitance; then the same sums for the clusters above it. Last, per input triangle, what each link
//! of it and of its ancestors lands on it (a cluster's arrivals by the triangle's own cosine,
//! `gather::Arrival`), largest first, against the unoccluded exact transfer from the link's source
//! (Σ over the source's leaves of the element form factor × the leaf's exitance). A diagnostic for
//! accuracy work on a scene.
//!
//! Reports per object (the scene's OBJ object names) instead of a surface:
//! - `--object NAME...`: the form-factor sum of its leaves' links (1 in a closed room); the power
//!   Σ A_open·G its leaves receive, split by how it lands (element link, cluster member shares, far
//!   arrival, near arrival, uniform) and into its direct part (the sources' emission E instead of B)
//!   and the rest, against ray-traced direct light (each leaf's exact element form factor to every
//!   emitting leaf times its E, visibility by rays from the leaf's three quadrature points).
//! - `--link-bias [EVERY] [RECEIVER_OBJECT SOURCE_OBJECT]`: every EVERY-th link's A_R·B_S·F against a
//!   1024-sample `visibility::sampled_form_factor` (unbiased, visibility included), by link type;
//!   an object named `-` is any object; with `LINK_BIAS_LEAVES` set the reference weights each source leaf by its own exitance.
//! - `--sent NAME`: where the power NAME sends lands, by receiving object: the links' A_R·F_RS (a
//!   cluster source's share by open area, the receiver's split by open area) against cosine rays.
//! - `--gathered NAME...`: per leaf, the indirect irradiance the links push against cosine rays that
//!   read the exitance of the leaf they hit (256 per leaf, emission left out of both): the same
//!   exitance, so only the transfer and its spread over the members differ; by the leaves' normal
//!   (facing down, sideways, up); `GATHERED_DETAIL` prints every leaf; `GATHERED_LINKS` lists the
//!   near cluster links by the ray power through them (the 40 largest with their form factor, the
//!   same estimate again, its facing samples and deviation, a 384-sample estimate with and without
//!   occluders, the object's share of the receiver, and what lands against what rays bring).
//! - `--coverage NAME`: for every leaf of NAME (receiver) and every 16th leaf of the scene (source),
//!   how many links join an ancestor-or-self of the one to an ancestor-or-self of the other (one, or
//!   none where they cannot exchange light, is right): the unoccluded pair transfer of the pairs with
//!   none (and their visible part by source object) and with two or more.
//!
//! - `--row-sums [RAYS]`: per object and sheet (front, back of a two-sided surface), the leaves'
//!   row sums R (`row_sums`: what their own and their ancestors' links bring with every node at
//!   exitance 1, the share of the hemisphere the links see) against the share cosine rays see
//!   (RAYS per leaf, default 16: the fraction that meets a surface facing them), area-weighted;
//!   largest |R − rays| × area first. Inside a closed room both are 1. R is also split by link
//!   kind (element pairs, far cluster links, near self-links, other near links), and per kind the
//!   links' Σ A_R·F (what they claim at unit exitance) against Σ A_open·R over the leaves (what the
//!   push delivers). With `ROW_SUMS_REESTIMATE=SEED` every link is estimated again with rays of
//!   another seed (no cap, no threshold) and the same sums are printed: an estimate independent of
//!   the one refinement kept or split the link by.
//!
//! - `--unlinked NAME`: cosine rays from every leaf of NAME (both sheets) to the leaf they hit, and
//!   whether any link joins an ancestor-or-self of the one to an ancestor-or-self of the other: the
//!   exitance those rays read, linked and not, by the hit leaf's object; `UNLINKED_DETAIL=K` prints
//!   K unlinked pairs with their ancestor chains.
//!
//! usage: hierarchy_links SCENE.toml SURFACE [DEPTH] [MIN_ELEMENT_SIZE VISIBILITY_RAYS]
//!        hierarchy_links SCENE.toml --object|--gathered NAME [NAME...]
//!        hierarchy_links SCENE.toml --link-bias [EVERY] [RECEIVER_OBJECT SOURCE_OBJECT]
//!        hierarchy_links SCENE.toml --sent|--coverage|--unlinked NAME
//!        hierarchy_links SCENE.toml --row-sums [RAYS]

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::process::ExitCode;

use glam::DVec3;
use radray::radiosity::hierarchy::form_factor::element_to_element;
use radray::radiosity::hierarchy::gather::ArrivalScales;
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
    if args[2] == "--link-bias" {
        return link_bias(&scene, args.get(3).and_then(|a| a.parse().ok()).unwrap_or(100), args.get(4), args.get(5));
    }
    if args[2] == "--gathered" {
        return gathered_by_normal(&scene, &args[3..]);
    }
    if args[2] == "--unlinked" {
        return unlinked(&scene, &args[3]);
    }
    if args[2] == "--row-sums" {
        return row_sums_by_object(&scene, args.get(3).and_then(|a| a.parse().ok()).unwrap_or(16));
    }
    if args[2] == "--coverage" {
        return coverage(&scene, &args[3]);
    }
    if args[2] == "--sent" {
        return sent_by_object(&scene, &args[3]);
    }
    if args[2] == "--object" {
        return object_breakdown(&scene, &args[3..]);
    }
    let surface: u32 = args[2].parse().unwrap_or(0);
    // SURFACE_LAST: report surfaces SURFACE..=SURFACE_LAST (one solve).
    let last: u32 = std::env::var("SURFACE_LAST").ok().and_then(|v| v.parse().ok()).unwrap_or(surface);
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
        if !(surface..=last).contains(&inputs.surface[i]) || inputs.back[i] {
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
    if let Ok(pair) = std::env::var("LINK_DEBUG") {
        let ids: Vec<usize> = pair.split(',').filter_map(|v| v.parse().ok()).collect();
        let (r, s) = (ids[0], ids[1]);
        for n in [r, s] {
            let mut m = Vec::new();
            nodes.members(n, &mut m);
            println!(
                "node {n}: cluster {} area {:.3} centre {:.3} radius {:.3} members {}",
                nodes.is_cluster[n],
                nodes.area[n],
                nodes.centre[n],
                nodes.radius[n],
                m.len()
            );
            for &x in &m {
                println!(
                    "   member {x} input {} area {:.3} centre {:.3} normal {:.2} leaves {}",
                    nodes.input[x],
                    nodes.area[x],
                    nodes.centre[x],
                    nodes.normal[x],
                    nodes.is_leaf(x)
                );
            }
        }
        for k in links.range(r) {
            if links.source[k] as usize == s {
                let (mut rs, mut ss) = (Vec::new(), Vec::new());
                radiosity_leaves(nodes, r, &mut rs);
                radiosity_leaves(nodes, s, &mut ss);
                let mut sum = 0.0;
                for &a in &rs {
                    for &b in &ss {
                        sum += nodes.area[a] as f64
                            * element_to_element(&nodes.corners[a], nodes.normal[a], &nodes.corners[b]).0;
                    }
                }
                println!(
                    "link F {} spread {} near {} leaves {}x{} unoccluded pair F {}",
                    links.form_factor[k],
                    links.spread[k],
                    is_near(nodes, r, s),
                    rs.len(),
                    ss.len(),
                    sum / nodes.area[r] as f64
                );
            }
        }
    }
    for (i, &node) in inputs.node.iter().enumerate() {
        if !(surface..=last).contains(&inputs.surface[i]) || inputs.back[i] {
            continue;
        }
        let e = node as usize;
        let mut rows = Vec::new();
        let mut up = node;
        while up != u32::MAX {
            let a = up as usize;
            let reach = scales.receiver(a);
            for (i, k) in links.range(a).enumerate() {
                let s = links.source[k] as usize;
                let transfer = scales.sent(nodes, links, a, k, &nodes.exitance) * links.form_factor[k] as f64;
                let share = reach.shares(i).find(|&(m, _)| m == e).map_or(0.0, |(_, c)| c as f64);
                let (landed, kind) = match scales.unit_arrival(nodes, a, i, s) {
                    _ if nodes.is_cluster[a] && reach.has_shares(i) => (transfer * share, "member shares"),
                    Some(unit) => (
                        transfer * unit.on_element(nodes.normal[e], nodes.centre[e]).x,
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
        for k in KINDS {
            let (g, x): (f64, f64) =
                rows.iter().filter(|r| r.2 == k).fold((0.0, 0.0), |(g, x), r| (g + r.3.x, x + r.4.x));
            print!(" {k}: {g:.4}/{x:.4};");
        }
        println!();
        rows.sort_by(|x, y| (x.3.x - x.4.x).total_cmp(&(y.3.x - y.4.x)));
        for (a, s, kind, landed, exact) in rows.iter().take(10) {
            println!(
                "  at node {a} from node {s} ({kind}, source {}): G {:.4} {:.4} {:.4} | exact unoccluded {:.4} {:.4} {:.4}",
                if nodes.is_cluster[*s] { "cluster" } else { "element" },
                landed.x, landed.y, landed.z, exact.x, exact.y, exact.z
            );
        }
    }
    ExitCode::SUCCESS
}

/// How a link's light lands on a leaf (see the module header).
const KINDS: [&str; 5] = ["element", "member shares", "far arrival", "near arrival", "uniform"];

/// The `--object` report.
fn object_breakdown(scene: &radray::scene::SceneDescription, objects: &[String]) -> ExitCode {
    use radray::radiosity::hierarchy::form_factor::quadrature_points;
    use radray::transport::hit::leave_surface;
    let Some(structure) = solved(scene) else { return ExitCode::FAILURE };
    let (nodes, links, inputs) = (structure.nodes(), structure.links(), structure.inputs());
    let scales = ArrivalScales::new(nodes, links);
    // The scene's triangles for visibility rays.
    let accel = scene_accel(scene);
    let offset = scene.diagonal() * 1e-5;
    let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n]).collect();
    let emitters: Vec<usize> = leaves.iter().copied().filter(|&n| nodes.emission[n].max_element() > 0.0).collect();
    let mean = |v: DVec3| (v.x + v.y + v.z) / 3.0;
    // Σ_R A_R·F_RS / A_open,S over the links from each node S: the share of its power its links
    // deliver; a leaf's form-factor sum is that over itself and its ancestors (1 in a closed room).
    let mut sent = vec![0.0f64; nodes.len()];
    for r in 0..links.offsets.len().saturating_sub(1) {
        for k in links.range(r) {
            let s = links.source[k] as usize;
            if nodes.open_area[s] > 0.0 {
                sent[s] += nodes.area[r] as f64 * links.form_factor[k] as f64 / nodes.open_area[s] as f64;
            }
        }
    }
    let form_factor_sum = |e: usize| {
        let (mut sum, mut up) = (0.0, e as u32);
        while up != u32::MAX {
            sum += sent[up as usize];
            up = nodes.parent[up as usize];
        }
        sum
    };
    for name in objects {
        // Area-weighted form-factor sum, and the share of the area below 0.97 and above 1.03.
        let (mut sum, mut low, mut high, mut a_all) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for &e in &leaves {
            let input = nodes.input[e] as usize;
            if inputs.back[input] || scene.surfaces[inputs.surface[input] as usize].object != *name {
                continue;
            }
            let (a, f) = (nodes.open_area[e] as f64, form_factor_sum(e));
            sum += a * f;
            a_all += a;
            if f < 0.97 {
                low += a;
            }
            if f > 1.03 {
                high += a;
            }
        }
        println!(
            "object {name}: form-factor sum over its leaves' links {:.4} (area below 0.97: {:.1}%, above 1.03: {:.1}%)",
            sum / a_all.max(1e-30),
            100.0 * low / a_all.max(1e-30),
            100.0 * high / a_all.max(1e-30)
        );
    }
    for name in objects {
        // (direct, other) per kind; reference direct; area; Σ A·B.
        let mut landed = [[0.0f64; 2]; 5];
        let (mut reference, mut area, mut power_b) = (0.0f64, 0.0f64, 0.0f64);
        for &e in &leaves {
            let input = nodes.input[e] as usize;
            let surface = inputs.surface[input] as usize;
            if inputs.back[input] || scene.surfaces[surface].object != *name {
                continue;
            }
            let open = nodes.open_area[e] as f64;
            if !(open > 0.0) {
                continue;
            }
            area += open;
            power_b += open * mean(nodes.exitance[e]);
            let member = inputs.node[input] as usize;
            let mut up = e as u32;
            while up != u32::MAX {
                let a = up as usize;
                let reach = scales.receiver(a);
                for (i, k) in links.range(a).enumerate() {
                    let s = links.source[k] as usize;
                    let f = links.form_factor[k] as f64;
                    let (gain, kind) = if !nodes.is_cluster[a] {
                        (nodes.open_gain(a), 0)
                    } else if reach.has_shares(i) {
                        (reach.shares(i).find(|&(m, _)| m == member).map_or(0.0, |(_, c)| c as f64), 1)
                    } else {
                        match scales.unit_arrival(nodes, a, i, s) {
                            Some(unit) => (
                                unit.on_element(nodes.normal[member], nodes.centre[member]).x,
                                if is_near(nodes, a, s) { 3 } else { 2 },
                            ),
                            _ => (nodes.open_gain(a), 4),
                        }
                    };
                    let direct = mean(nodes.emission[s].as_dvec3()) * f * gain;
                    let all = mean(scales.sent(nodes, links, a, k, &nodes.exitance)) * f * gain;
                    landed[kind][0] += open * direct;
                    landed[kind][1] += open * (all - direct);
                }
                up = nodes.parent[a];
            }
            // Reference direct irradiance: exact element form factor × visibility from the
            // quadrature points to the emitting leaf's centroid.
            let points = quadrature_points(&nodes.corners[e]);
            let mut g = 0.0;
            for &l in &emitters {
                let (f, _) = element_to_element(&nodes.corners[e], nodes.normal[e], &nodes.corners[l]);
                if !(f > 0.0) {
                    continue;
                }
                let y = leave_surface(nodes.centre[l], nodes.normal[l], offset);
                let seen = points
                    .iter()
                    .filter(|&&x| {
                        let xo = leave_surface(x, nodes.normal[e], offset);
                        !accel.occluded(xo, y - xo, 1.0)
                    })
                    .count();
                g += f * seen as f64 / 3.0 * mean(nodes.emission[l].as_dvec3());
            }
            reference += open * g;
        }
        let direct: f64 = landed.iter().map(|k| k[0]).sum();
        let other: f64 = landed.iter().map(|k| k[1]).sum();
        println!(
            "object {name}: open area {area:.4} m², mean B {:.4}; direct power {direct:.4} W vs ray-traced {reference:.4} ({:+.1}%), indirect {other:.4} W",
            power_b / area.max(1e-30),
            100.0 * (direct / reference - 1.0)
        );
        for (kind, [d, o]) in KINDS.iter().zip(landed) {
            println!("  {kind:>14}: direct {d:.4} W, indirect {o:.4} W");
        }
    }
    ExitCode::SUCCESS
}

/// Link types of the `--link-bias` report.
const LINK_TYPES: [&str; 7] = [
    "element pair (3-point)",
    "element pair (48-point)",
    "far cluster, member pairs",
    "far cluster, Sillion",
    "near, leaf pairs",
    "near, sampled",
    "self-link",
];

/// The `--link-bias` report.
fn link_bias(
    scene: &radray::scene::SceneDescription,
    every: usize,
    receiver_object: Option<&String>,
    source_object: Option<&String>,
) -> ExitCode {
    use radray::radiosity::hierarchy::links::{leaves_below, member_pair_form_factor, EXACT_NEAR_PAIRS};
    use radray::radiosity::hierarchy::visibility::{sampled_form_factor, VisibilityContext};
    use rayon::prelude::*;
    let params = radray::radiosity::hierarchical::hierarchy_params(scene);
    let Some(structure) = solved(scene) else { return ExitCode::FAILURE };
    let (nodes, links) = (structure.nodes(), structure.links());
    let accel = scene_accel(scene);
    let ctx = VisibilityContext { accel: &accel, rays: 1024, offset: scene.diagonal() * 1e-5, seed: 0xb1a5 };
    let inputs = structure.inputs();
    // Whether node n has a leaf on object `name` (any, when no name is given), for every node at once.
    let on_object = |name: Option<&String>| -> Vec<bool> {
        let Some(name) = name.filter(|n| n.as_str() != "-") else { return vec![true; nodes.len()] };
        let mut has = vec![false; nodes.len()];
        for m in 0..nodes.len() {
            if nodes.is_leaf(m)
                && !nodes.is_cluster[m]
                && scene.surfaces[inputs.surface[nodes.input[m] as usize] as usize].object == *name
            {
                let mut up = m as u32;
                while up != u32::MAX && !has[up as usize] {
                    has[up as usize] = true;
                    up = nodes.parent[up as usize];
                }
            }
        }
        has
    };
    let (receiving, sending) = (on_object(receiver_object), on_object(source_object));
    let records: Vec<_> = links
        .to_records()
        .into_iter()
        .filter(|l| receiving[l.receiver as usize] && sending[l.source as usize])
        .collect();
    let picked: Vec<_> = records.iter().step_by(every.max(1)).collect();
    let rows: Vec<(usize, f64, f64)> = picked
        .par_iter()
        .map(|l| {
            let (r, s) = (l.receiver as usize, l.source as usize);
            let kind = if r == s {
                6
            } else if !nodes.is_cluster[r] && !nodes.is_cluster[s] {
                let c = |t: &[glam::Vec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
                let rad = |t: &[glam::Vec3; 3]| t.iter().map(|p| p.distance(c(t))).fold(0.0f32, f32::max);
                let (a, b) = (&nodes.corners[r], &nodes.corners[s]);
                if c(a).distance(c(b)) < 1.5 * (rad(a) + rad(b)) {
                    1
                } else {
                    0
                }
            } else if !is_near(nodes, r, s) {
                if member_pair_form_factor(nodes, r, s).is_some() {
                    2
                } else {
                    3
                }
            } else {
                let (mut rs, mut ss) = (Vec::new(), Vec::new());
                let small = leaves_below(nodes, r, EXACT_NEAR_PAIRS, &mut rs)
                    && leaves_below(nodes, s, EXACT_NEAR_PAIRS, &mut ss)
                    && rs.len() * ss.len() <= EXACT_NEAR_PAIRS;
                if small {
                    4
                } else {
                    5
                }
            };
            let mut reference = sampled_form_factor(&ctx, nodes, r, s).form_factor;
            let w = nodes.area[r] as f64 * nodes.exitance_mean[s];
            if std::env::var("LINK_BIAS_LEAVES").is_ok() && nodes.exitance_mean[s] > 0.0 {
                // The transfer with each source leaf's own exitance: Σ_c F_Rc B_c / B_S.
                reference = leaf_weighted_form_factor(&ctx, nodes, r, s) / nodes.exitance_mean[s];
            }
            if kind == 5 && std::env::var("LINK_BIAS_DETAIL").is_ok() {
                let again = VisibilityContext { rays: params.visibility_rays, seed: params.seed, ..ctx };
                let redo = radray::radiosity::hierarchy::links::near_form_factor(nodes, &again, r, s);
                println!(
                    "near {r}{} <- {s}{}: areas {:.4} {:.4} radii {:.3} {:.3} d {:.3} F {:.5} again {:?} ref {:.5} power {:.5} -> {:.5}",
                    if nodes.is_cluster[r] { "c" } else { "e" },
                    if nodes.is_cluster[s] { "c" } else { "e" },
                    nodes.area[r], nodes.area[s], nodes.radius[r], nodes.radius[s],
                    nodes.centre[r].distance(nodes.centre[s]),
                    l.form_factor, redo, reference, w * l.form_factor as f64, w * reference
                );
            }
            (kind, w * l.form_factor as f64, w * reference)
        })
        .collect();
    let mut sums = [[0.0f64; 3]; 7];
    for (kind, f, reference) in rows {
        sums[kind][0] += f;
        sums[kind][1] += reference;
        sums[kind][2] += 1.0;
    }
    println!(
        "{} links, every {every}th: power A_R·B_S·F (W, × {every}) against a 1024-sample reference",
        records.len()
    );
    for (name, [f, reference, n]) in LINK_TYPES.iter().zip(sums) {
        println!(
            "  {name:>26}: {n:>7} links, solve {:.4} W, reference {:.4} W ({:+.2}%)",
            f * every as f64,
            reference * every as f64,
            100.0 * (f / reference - 1.0)
        );
    }
    ExitCode::SUCCESS
}

/// The `--sent` report.
fn sent_by_object(scene: &radray::scene::SceneDescription, name: &str) -> ExitCode {
    use radray::radiosity::hierarchy::visibility::triangle_point;
    use radray::transport::hit::leave_surface;
    let Some(structure) = solved(scene) else { return ExitCode::FAILURE };
    let (nodes, links, inputs) = (structure.nodes(), structure.links(), structure.inputs());
    let mut objects: Vec<String> = scene.surfaces.iter().map(|s| s.object.clone()).collect();
    objects.sort();
    objects.dedup();
    let object_of = |surface: usize| objects.iter().position(|o| *o == scene.surfaces[surface].object).unwrap();
    let k = objects.len();
    // Open area per node and object, children after parents.
    let mut area = vec![0.0f64; nodes.len() * k];
    for n in (0..nodes.len()).rev() {
        if nodes.is_leaf(n) && !nodes.is_cluster[n] {
            let input = nodes.input[n] as usize;
            if !inputs.back[input] {
                area[n * k + object_of(inputs.surface[input] as usize)] = nodes.open_area[n] as f64;
            }
        } else {
            for c in nodes.children(n) {
                for o in 0..k {
                    area[n * k + o] += area[c * k + o];
                }
            }
        }
    }
    let me = objects.iter().position(|o| o == name).unwrap();
    let mut by_links = vec![0.0f64; k];
    for r in 0..links.offsets.len().saturating_sub(1) {
        let receiver_open: f64 = (0..k).map(|o| area[r * k + o]).sum();
        if !(receiver_open > 0.0) {
            continue;
        }
        for l in links.range(r) {
            let s = links.source[l] as usize;
            let source_open: f64 = (0..k).map(|o| area[s * k + o]).sum();
            if !(source_open > 0.0) || area[s * k + me] == 0.0 {
                continue;
            }
            let power = nodes.area[r] as f64 * links.form_factor[l] as f64 * area[s * k + me] / source_open;
            for o in 0..k {
                by_links[o] += power * area[r * k + o] / receiver_open;
            }
        }
    }
    let (mut positions, mut triangles, mut tri_object) = (Vec::new(), Vec::new(), Vec::new());
    for (i, s) in scene.surfaces.iter().enumerate() {
        let base = positions.len() as u32;
        positions.extend_from_slice(&s.vertices);
        for j in 1..s.vertices.len().saturating_sub(1) as u32 {
            triangles.push([base, base + j, base + j + 1]);
            tri_object.push(object_of(i));
        }
    }
    let accel = radray::accel::Accel::build(&positions, &triangles);
    let offset = scene.diagonal() * 1e-5;
    let mut by_rays = vec![0.0f64; k];
    let mut rng = 0x12345678u64;
    let mut uniform = || {
        rng = radray::rng::splitmix64(rng);
        (rng >> 11) as f32 / (1u64 << 53) as f32
    };
    let mut total = 0.0;
    for n in 0..nodes.len() {
        if !nodes.is_leaf(n) || nodes.is_cluster[n] || area[n * k + me] == 0.0 {
            continue;
        }
        let a = area[n * k + me];
        total += a;
        const RAYS: usize = 64;
        for _ in 0..RAYS {
            let p = triangle_point(&nodes.corners[n], uniform(), uniform());
            let (u1, u2) = (uniform(), uniform());
            let (t, b) = nodes.normal[n].any_orthonormal_pair();
            let r = u1.sqrt();
            let phi = std::f32::consts::TAU * u2;
            let d = t * (r * phi.cos()) + b * (r * phi.sin()) + nodes.normal[n] * (1.0 - u1).max(0.0).sqrt();
            let o = leave_surface(p, nodes.normal[n], offset);
            if let Some(hit) = accel.closest_hit(o, d, 0.0, f32::INFINITY) {
                by_rays[tri_object[hit.triangle as usize]] += a / RAYS as f64;
            }
        }
    }
    println!("object {name}: open area {total:.4}; the share of its power landing on each object, links / rays");
    for o in 0..k {
        println!("  {:>12}: links {:.4}  rays {:.4}", objects[o], by_links[o] / total, by_rays[o] / total);
    }
    println!(
        "  {:>12}: links {:.4}  rays {:.4}",
        "all",
        by_links.iter().sum::<f64>() / total,
        by_rays.iter().sum::<f64>() / total
    );
    ExitCode::SUCCESS
}

/// One leaf of the `--gathered` report: its normal's bin, open area, what its links bring by kind,
/// what rays bring, the share of rays escaping, the links with directional cluster sources, and the
/// links with near cluster sources read through their samples (occluded, unoccluded).
type GatheredRow = (usize, f64, [f64; 5], f64, f64, f64, (f64, f64));

/// The `--gathered` report.
fn gathered_by_normal(scene: &radray::scene::SceneDescription, objects: &[String]) -> ExitCode {
    use rayon::prelude::*;
    let Some(structure) = solved(scene) else { return ExitCode::FAILURE };
    let (nodes, links, inputs) = (structure.nodes(), structure.links(), structure.inputs());
    let scales = ArrivalScales::new(nodes, links);
    // What the sweeps send over far links from clusters (`lobes`).
    let lobes = radray::radiosity::hierarchy::lobes::Lobes::new(nodes, links, structure.root());
    let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n]).collect();
    let front: Vec<usize> = leaves.iter().copied().filter(|&n| !inputs.back[nodes.input[n] as usize]).collect();
    let tracer = LeafTracer::new(nodes, inputs, &leaves);
    let params = radray::radiosity::hierarchical::hierarchy_params(scene);
    let accel = scene_accel(scene);
    let ctx = radray::radiosity::hierarchy::visibility::VisibilityContext {
        accel: &accel,
        rays: params.visibility_rays,
        offset: scene.diagonal() * 1e-5,
        seed: params.seed,
    };
    // Nothing to block a ray: what the same samples read unoccluded.
    let far = glam::Vec3::splat(1e7);
    let nothing = radray::accel::Accel::build(&[far, far + glam::Vec3::X, far + glam::Vec3::Y], &[[0, 1, 2]]);
    let open_ctx = radray::radiosity::hierarchy::visibility::VisibilityContext { accel: &nothing, ..ctx };
    let offset = scene.diagonal() * 1e-5;
    let mean = |v: DVec3| (v.x + v.y + v.z) / 3.0;
    let mut objects_all: Vec<String> = scene.surfaces.iter().map(|s| s.object.clone()).collect();
    objects_all.sort();
    objects_all.dedup();
    let object_of = |n: usize| {
        let name = &scene.surfaces[inputs.surface[nodes.input[n] as usize] as usize].object;
        objects_all.binary_search(name).unwrap()
    };
    for name in objects {
        let by_object = std::sync::Mutex::new(vec![0.0f64; 2 * objects_all.len()]);
        let mine: Vec<usize> = front
            .iter()
            .copied()
            .filter(|&e| {
                scene.surfaces[inputs.surface[nodes.input[e] as usize] as usize].object == *name
                    && nodes.open_area[e] > 0.0
            })
            .collect();
        // What each near link with a cluster source reads through its samples, once per link of
        // the leaves' ancestors.
        let mut receivers: Vec<usize> = Vec::new();
        for &e in &mine {
            let mut up = e as u32;
            while up != u32::MAX {
                receivers.push(up as usize);
                up = nodes.parent[up as usize];
            }
        }
        receivers.sort_unstable();
        receivers.dedup();
        let sampled: std::collections::HashMap<usize, (f64, f64, f64, f64)> = receivers
            .par_iter()
            .flat_map_iter(|&a| {
                links.range(a).filter_map(move |k| {
                    let s = links.source[k] as usize;
                    (nodes.is_cluster[s] && is_near(nodes, a, s)).then_some((k, a, s))
                })
            })
            .collect::<Vec<_>>()
            .into_par_iter()
            .filter_map(|(k, a, s)| {
                let b = sample_read(nodes, &ctx, a, s, 0)?;
                let open = sample_read(nodes, &open_ctx, a, s, 0).unwrap_or(b);
                let cut4 = sample_read(nodes, &ctx, a, s, 2).unwrap_or(b);
                let cut16 = sample_read(nodes, &ctx, a, s, 4).unwrap_or(b);
                Some((k, (b, open, cut4, cut16)))
            })
            .collect();
        // By the kind of the link a transfer goes through (links) or would (rays: the link joining an
        // ancestor-or-self of the leaf to one of the leaf hit): [links, links with sampled reads, rays]
        // for element source (leaf), element source (subdivided), far cluster, near cluster, self, none.
        let set = linked_pairs(links);
        let link_kind = |a: usize, s: usize| {
            if a == s {
                4
            } else if nodes.is_cluster[s] {
                if is_near(nodes, a, s) {
                    3
                } else {
                    2
                }
            } else if nodes.is_leaf(s) {
                0
            } else {
                1
            }
        };
        let by_source_kind = std::sync::Mutex::new([[0.0f64; 5]; 6]);
        // Per near-cluster link: (landed, rays) on this object's leaves, weighted by open area.
        let per_link = std::sync::Mutex::new(std::collections::HashMap::<usize, (f64, f64)>::new());
        let rows: Vec<GatheredRow> = mine
            .par_iter()
            .map(|&e| {
                let member = inputs.node[nodes.input[e] as usize] as usize;
                let mut by_kind = [0.0f64; 5];
                let mut per_source_kind = [[0.0f64; 5]; 6];
                let up_e = ancestors_of(nodes, e);
                let mut direct_by_kind = [0.0f64; 5];
                let mut directional = 0.0f64;
                let mut read = 0.0f64;
                let mut read_open = 0.0f64;
                let mut per_object = vec![0.0f64; 2 * objects_all.len()];
                let mut link_rows: Vec<(usize, f64, f64)> = Vec::new();
                let mut up = e as u32;
                while up != u32::MAX {
                    let a = up as usize;
                    let reach = scales.receiver(a);
                    for (i, k) in links.range(a).enumerate() {
                        let s = links.source[k] as usize;
                        let sent = lobes
                            .sent_over(nodes, k, a, s)
                            .unwrap_or_else(|| scales.sent(nodes, links, a, k, &nodes.exitance));
                        let t = mean(sent - nodes.emission[s].as_dvec3()) * links.form_factor[k] as f64;
                        let t_direct = mean(nodes.emission[s].as_dvec3()) * links.form_factor[k] as f64;
                        let (gain, kind) = if !nodes.is_cluster[a] {
                            (nodes.open_gain(a), 0)
                        } else if reach.has_shares(i) {
                            (reach.shares(i).find(|&(m, _)| m == member).map_or(0.0, |(_, c)| c as f64), 1)
                        } else {
                            match scales.unit_arrival(nodes, a, i, s) {
                                Some(unit) => (
                                    unit.on_element(nodes.normal[member], nodes.centre[member]).x,
                                    if is_near(nodes, a, s) { 3 } else { 2 },
                                ),
                                _ => (nodes.open_gain(a), 4),
                            }
                        };
                        by_kind[kind] += t * gain;
                        direct_by_kind[kind] += t_direct * gain;
                        // The same link with a cluster source sending its members' exitance weighted by
                        // their open projected area towards the receiver (Sillion's directional cluster).
                        let t_dir = if nodes.is_cluster[s] {
                            let w = (nodes.centre[a] - nodes.centre[s]).normalize_or_zero();
                            let p = nodes.member_sum(s, |m| nodes.open_area[m] as f64 * nodes.normal[m].dot(w).max(0.0) as f64);
                            let pb = nodes.member_sum(s, |m| {
                                nodes.open_area[m] as f64
                                    * nodes.normal[m].dot(w).max(0.0) as f64
                                    * mean(nodes.exitance[m] - nodes.emission[m].as_dvec3())
                            });
                            if p > 0.0 { pb / p * links.form_factor[k] as f64 } else { t }
                        } else {
                            t
                        };
                        directional += t_dir * gain;
                        // The same link sending the exitance its own samples see of a cluster source
                        // (Σ_k w_k B(t_k) / Σ_k w_k, `visibility::sampled_form_factor_reads`).
                        read += gain
                            * sampled.get(&k).map_or(t, |b| b.0 * links.form_factor[k] as f64);
                        read_open += gain * sampled.get(&k).map_or(t, |b| b.1 * links.form_factor[k] as f64);
                        let kind = link_kind(a, s);
                        if kind == 3 {
                            link_rows.push((k, gain * t, 0.0));
                        }
                        per_source_kind[kind][0] += gain * t;
                        per_source_kind[kind][1] += gain * sampled.get(&k).map_or(t, |b| b.0 * links.form_factor[k] as f64);
                        per_source_kind[kind][3] += gain * sampled.get(&k).map_or(t, |b| b.2 * links.form_factor[k] as f64);
                        per_source_kind[kind][4] += gain * sampled.get(&k).map_or(t, |b| b.3 * links.form_factor[k] as f64);
                        // By source object: an element's own; a cluster's members by their share of
                        // the directional transfer.
                        if nodes.is_cluster[s] {
                            let w = (nodes.centre[a] - nodes.centre[s]).normalize_or_zero();
                            let mut members = Vec::new();
                            nodes.members(s, &mut members);
                            let weight = |m: usize| {
                                nodes.open_area[m] as f64
                                    * nodes.normal[m].dot(w).max(0.0) as f64
                                    * mean(nodes.exitance[m] - nodes.emission[m].as_dvec3())
                            };
                            let total: f64 = members.iter().map(|&m| weight(m)).sum();
                            if total > 0.0 {
                                for &m in &members {
                                    per_object[object_of(m)] += t_dir * gain * weight(m) / total;
                                }
                            }
                        } else {
                            per_object[object_of(s)] += t * gain;
                        }
                    }
                    up = nodes.parent[a];
                }
                let mut state = radray::rng::splitmix64(e as u64 ^ 0xfeed);
                let mut uniform = || {
                    state = radray::rng::splitmix64(state);
                    (state >> 40) as f32 / (1u64 << 24) as f32
                };
                const RAYS: usize = 256;
                let n = nodes.normal[e];
                let (mut g, mut escaped) = (0.0, 0u32);
                for _ in 0..RAYS {
                    match tracer.cosine_ray(nodes, e, offset, &mut uniform) {
                        // Only the front of a hit leaf sends.
                        RayEnd::Facing(l) => {
                            let b = mean(nodes.exitance[l] - nodes.emission[l].as_dvec3());
                            g += b;
                            let up_l = ancestors_of(nodes, l);
                            // The link joining an ancestor-or-self of e to one of l, if any.
                            let pair = up_e.iter().find_map(|&a| {
                                up_l.iter().find(|&&c| set.contains(&(a, c))).map(|&c| (a as usize, c as usize))
                            });
                            let kind = pair.map_or(5, |(a, c)| link_kind(a, c));
                            per_source_kind[kind][2] += b / RAYS as f64;
                            if let (3, Some((a, c))) = (kind, pair) {
                                if let Some(k) = links.range(a).find(|&k| links.source[k] as usize == c) {
                                    link_rows.push((k, 0.0, b / RAYS as f64));
                                }
                            }
                            per_object[objects_all.len() + object_of(l)] += b / RAYS as f64;
                        }
                        RayEnd::Behind => {}
                        RayEnd::Escaped => escaped += 1,
                    }
                }
                if std::env::var("GATHERED_DETAIL").is_ok() {
                    println!(
                        "leaf {e} at {:.3} {:.3} {:.3} level {} B {:.4} direct {:.4} {:.4} {:.4} {:.4} {:.4} n {:.2} {:.2} {:.2} links {:.4} {:.4} {:.4} {:.4} {:.4} rays {:.4}",
                        nodes.centre[e].x,
                        nodes.centre[e].y,
                        nodes.centre[e].z,
                        nodes.level[e],
                        mean(nodes.exitance[e]),
                        direct_by_kind[0],
                        direct_by_kind[1],
                        direct_by_kind[2],
                        direct_by_kind[3],
                        direct_by_kind[4],
                        n.x,
                        n.y,
                        n.z,
                        by_kind[0],
                        by_kind[1],
                        by_kind[2],
                        by_kind[3],
                        by_kind[4],
                        g / RAYS as f64
                    );
                }
                let y = n.y;
                let bin = if y < -0.3 {
                    0
                } else if y > 0.3 {
                    2
                } else {
                    1
                };
                let open = nodes.open_area[e] as f64;
                {
                    let mut m = per_link.lock().unwrap();
                    for (k, landed, rays) in link_rows {
                        let entry = m.entry(k).or_insert((0.0, 0.0));
                        entry.0 += open * landed;
                        entry.1 += open * rays;
                    }
                }
                {
                    let mut sums = by_source_kind.lock().unwrap();
                    for (kind, v) in per_source_kind.iter().enumerate() {
                        for j in 0..5 {
                            sums[kind][j] += open * v[j];
                        }
                    }
                }
                {
                    let mut sums = by_object.lock().unwrap();
                    for (o, v) in per_object.iter().enumerate() {
                        sums[o] += open * v;
                    }
                }
                (bin, open, by_kind, g / RAYS as f64, escaped as f64 / RAYS as f64, directional, (read, read_open))
            })
            .collect();
        println!(
            "object {name}: Σ A·G (W) from the links (element, shares, far arrival, near arrival, uniform) vs rays"
        );
        for (bin, label) in ["facing down", "sideways", "facing up"].iter().enumerate() {
            let (mut a, mut kinds, mut rays, mut open, mut directional, mut read, mut read_open) =
                (0.0, [0.0f64; 5], 0.0, 0.0, 0.0, 0.0, 0.0);
            for (b, area, k, g, escaped, dir, sampled) in &rows {
                if *b == bin {
                    a += area;
                    directional += area * dir;
                    read += area * sampled.0;
                    read_open += area * sampled.1;
                    open += area * escaped;
                    for i in 0..5 {
                        kinds[i] += area * k[i];
                    }
                    rays += area * g;
                }
            }
            let links_total: f64 = kinds.iter().sum();
            println!(
                "  {label:>11} (area {a:.3}): links {links_total:.4} = {:.4} + {:.4} + {:.4} + {:.4} + {:.4}; rays {rays:.4} ({:+.1}%); rays escaping {:.1}%; directional cluster sources {:.4} ({:+.1}%); sampled reads {:.4} ({:+.1}%), unoccluded {:.4} ({:+.1}%)",
                kinds[0],
                kinds[1],
                kinds[2],
                kinds[3],
                kinds[4],
                100.0 * (links_total / rays - 1.0),
                100.0 * open / a.max(1e-30),
                directional,
                100.0 * (directional / rays - 1.0),
                read,
                100.0 * (read / rays - 1.0),
                read_open,
                100.0 * (read_open / rays - 1.0)
            );
        }
        if std::env::var("GATHERED_LINKS").is_ok() {
            let per_link = per_link.into_inner().unwrap();
            let mut order: Vec<(usize, (f64, f64))> = per_link.into_iter().collect();
            order.sort_by(|a, b| b.1 .1.total_cmp(&a.1 .1));
            let hi =
                radray::radiosity::hierarchy::visibility::VisibilityContext { rays: 64, seed: ctx.seed ^ 0xabc, ..ctx };
            let (mut landed_all, mut rays_all, mut scaled_all) = (0.0, 0.0, 0.0);
            println!("  near cluster links, most ray power first: link r <- s, A_r, members of r and s, shares?, F (again, facing samples, deviation), F with 384 samples, unoccluded, object area under r / A_r, landed W, rays W");
            for (rank, &(k, (landed, rays))) in order.iter().enumerate() {
                landed_all += landed;
                rays_all += rays;
                if rank >= 40 {
                    continue;
                }
                let r = receiver_of(links, k);
                let s = links.source[k] as usize;
                let f_hi = radray::radiosity::hierarchy::visibility::sampled_form_factor(&hi, nodes, r, s).form_factor;
                let own = radray::radiosity::hierarchy::visibility::sampled_form_factor(&ctx, nodes, r, s);
                let open_hi = radray::radiosity::hierarchy::visibility::sampled_form_factor(
                    &radray::radiosity::hierarchy::visibility::VisibilityContext {
                        rays: 64,
                        seed: ctx.seed ^ 0xabc,
                        ..open_ctx
                    },
                    nodes,
                    r,
                    s,
                )
                .form_factor;
                scaled_all += landed * f_hi / (links.form_factor[k] as f64).max(1e-30);
                let mut members = Vec::new();
                nodes.members(r, &mut members);
                let under: f64 = mine
                    .iter()
                    .filter(|&&e| ancestors_of(nodes, e).contains(&(r as u32)))
                    .map(|&e| nodes.open_area[e] as f64)
                    .sum();
                let mut sm = Vec::new();
                nodes.members(s, &mut sm);
                let i = k - links.range(r).start;
                println!(
                    "    {r} <- {s}: A_r {:.1} members {} {} shares {} F {:.3e} (again: {:.3e}, facing {}, deviation {:.3e}) F_hi {:.5} unoccluded {:.5} share {:.3} landed {:.3} rays {:.3}",
                    nodes.area[r],
                    members.len(),
                    sm.len(),
                    scales.receiver(r).has_shares(i),
                    links.form_factor[k],
                    own.form_factor,
                    own.facing,
                    own.deviation,
                    f_hi,
                    open_hi,
                    under / nodes.area[r] as f64,
                    landed,
                    rays
                );
            }
            println!("  all near cluster links: landed {landed_all:.2} rays {rays_all:.2}; top 40 landed rescaled to F_hi: {scaled_all:.2}");
        }
        println!("  by the link's kind (links, links with sampled reads, the reads over a cut of the source, rays through that kind of link):");
        let kinds = by_source_kind.into_inner().unwrap();
        for (label, v) in
            ["element leaf", "element split", "far cluster", "near cluster", "self", "none"].iter().zip(kinds)
        {
            println!(
                "    {label:>13}: links {:.2} W, sampled reads {:.2} W (over a cut of 4: {:.2}, of 16: {:.2}), rays {:.2} W",
                v[0], v[1], v[3], v[4], v[2]
            );
        }
        let sums = by_object.into_inner().unwrap();
        let n = objects_all.len();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| (sums[n + b] - sums[b]).abs().total_cmp(&(sums[n + a] - sums[a]).abs()));
        println!("  by source object (links with directional cluster sources vs rays), largest differences first:");
        for &o in order.iter().take(15) {
            println!(
                "    {:>10}: links {:.4} W, rays {:.4} W ({:+.4})",
                objects_all[o],
                sums[o],
                sums[n + o],
                sums[o] - sums[n + o]
            );
        }
    }
    ExitCode::SUCCESS
}

/// The `--coverage` report.
fn coverage(scene: &radray::scene::SceneDescription, name: &str) -> ExitCode {
    use rayon::prelude::*;
    let Some(structure) = solved(scene) else { return ExitCode::FAILURE };
    let (nodes, links, inputs) = (structure.nodes(), structure.links(), structure.inputs());
    let set = linked_pairs(links);
    let ancestors = |n: usize| ancestors_of(nodes, n);
    let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n]).collect();
    let object = |n: usize| &scene.surfaces[inputs.surface[nodes.input[n] as usize] as usize].object;
    let mine: Vec<usize> = leaves.iter().copied().filter(|&n| object(n) == name && nodes.open_area[n] > 0.0).collect();
    let sources: Vec<usize> = leaves.iter().copied().step_by(16).filter(|&n| nodes.open_area[n] > 0.0).collect();
    let source_up: Vec<Vec<u32>> = sources.iter().map(|&s| ancestors(s)).collect();
    let mean = |v: DVec3| (v.x + v.y + v.z) / 3.0;
    // (power of pairs with no link, with one, with more; pair counts).
    let mut objects: Vec<String> = scene.surfaces.iter().map(|s| s.object.clone()).collect();
    objects.sort();
    objects.dedup();
    let accel = scene_accel(scene);
    let offset = scene.diagonal() * 1e-5;
    use radray::radiosity::hierarchy::form_factor::quadrature_points;
    use radray::transport::hit::leave_surface;
    let rows: Vec<Vec<f64>> = mine
        .par_iter()
        .map(|&r| {
            let up = ancestors(r);
            let mut out = vec![0.0f64; 6 + objects.len()];
            for (i, &s) in sources.iter().enumerate() {
                if s == r {
                    continue;
                }
                let count =
                    up.iter().map(|&a| source_up[i].iter().filter(|&&b| set.contains(&(a, b))).count()).sum::<usize>();
                let (f, _) = element_to_element(&nodes.corners[r], nodes.normal[r], &nodes.corners[s]);
                if !(f > 0.0) {
                    continue;
                }
                let power = nodes.open_area[r] as f64 * f * mean(nodes.exitance[s]) * 16.0;
                let slot = count.min(2);
                out[slot] += power;
                out[3 + slot] += 1.0;
                if count == 0 {
                    // Visible share of the missing pair: rays from the receiver's quadrature points
                    // to the source's centroid.
                    let y = leave_surface(nodes.centre[s], nodes.normal[s], offset);
                    let seen = quadrature_points(&nodes.corners[r])
                        .iter()
                        .filter(|&&x| {
                            let xo = leave_surface(x, nodes.normal[r], offset);
                            !accel.occluded(xo, y - xo, 1.0)
                        })
                        .count();
                    let o = objects.iter().position(|n| n == object(s)).unwrap();
                    out[6 + o] += power * seen as f64 / 3.0;
                }
            }
            out
        })
        .collect();
    let mut total = vec![0.0f64; 6 + objects.len()];
    for row in rows {
        for i in 0..total.len() {
            total[i] += row[i];
        }
    }
    for (o, n) in objects.iter().enumerate() {
        println!("  missing pairs from {n}: visible power {:.4} W", total[6 + o]);
    }
    println!(
        "object {name}: unoccluded pair power with no link {:.4} W ({} pairs), one {:.4} W ({}), two or more {:.4} W ({})",
        total[0], total[3], total[1], total[4], total[2], total[5]
    );
    ExitCode::SUCCESS
}

/// Σ_c F_Rc·B_c over the leaves c below `source` (B the mean channel), by Monte Carlo over receiver
/// points x (uniform by area) and source leaves c (picked by area, every descent by area, element
/// pieces included): F(x → c)·(A_S/A_c)·V(x, y_c)·B_c, Lambert's exact point-to-polygon in the leaf.
fn leaf_weighted_form_factor(
    ctx: &radray::radiosity::hierarchy::visibility::VisibilityContext,
    nodes: &radray::radiosity::hierarchy::nodes::Nodes,
    receiver: usize,
    source: usize,
) -> f64 {
    use radray::radiosity::hierarchy::form_factor::point_to_polygon;
    use radray::radiosity::hierarchy::visibility::{sample_point, triangle_point};
    use radray::transport::hit::leave_surface;
    let mut state = radray::rng::splitmix64((receiver as u64) << 32 ^ source as u64);
    let mut uniform = || {
        state = radray::rng::splitmix64(state);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let n = ctx.rays as usize;
    let mut sum = 0.0;
    for _ in 0..n {
        let (x, nx) = sample_point(nodes, receiver, [uniform(), uniform()]);
        // Descend to a leaf by area.
        let mut at = source;
        while !nodes.is_leaf(at) {
            let total: f64 = nodes.children(at).map(|c| nodes.area[c] as f64).sum();
            let mut pick = uniform() * total;
            let mut chosen = nodes.children(at).last().unwrap();
            for c in nodes.children(at) {
                if pick < nodes.area[c] as f64 {
                    chosen = c;
                    break;
                }
                pick -= nodes.area[c] as f64;
            }
            at = chosen;
        }
        let corners = &nodes.corners[at];
        let f = point_to_polygon(x, nx, corners) * nodes.area[source] as f64 / nodes.area[at] as f64;
        if !(f > 0.0) {
            continue;
        }
        // Visibility to a point on the leaf that faces x (a few tries), else counted visible.
        let mut v = 1.0;
        for _ in 0..8 {
            let y = triangle_point(corners, uniform() as f32, uniform() as f32);
            let d = y - x;
            if nodes.normal[at].dot(d) < 0.0 && nx.dot(d) > 0.0 {
                let xo = leave_surface(x, nx, ctx.offset);
                let yo = leave_surface(y, nodes.normal[at], ctx.offset);
                v = if ctx.accel.occluded(xo, yo - xo, 1.0) { 0.0 } else { 1.0 };
                break;
            }
        }
        sum += f * v * nodes.exitance_mean[at];
    }
    sum / n as f64
}

/// The leaves below `node`.
fn radiosity_leaves(nodes: &radray::radiosity::hierarchy::nodes::Nodes, node: usize, out: &mut Vec<usize>) {
    let mut stack = vec![node];
    while let Some(n) = stack.pop() {
        if nodes.is_leaf(n) {
            out.push(n);
        } else {
            stack.extend(nodes.children(n));
        }
    }
}

/// The `--unlinked` report.
fn row_sums_by_object(scene: &radray::scene::SceneDescription, rays: usize) -> ExitCode {
    use rayon::prelude::*;
    let Some(structure) = solved(scene) else { return ExitCode::FAILURE };
    let (nodes, links, inputs) = (structure.nodes(), structure.links(), structure.inputs());
    let scales = ArrivalScales::new(nodes, links);
    let sums = radray::radiosity::hierarchy::row_sums::row_sums(nodes, links, &scales);
    // The same row sums with only one kind of link each: element pairs, far cluster links, near
    // self-links, other near links (their sum is `sums`).
    let kind_of = |r: usize, s: usize| {
        if !nodes.is_cluster[r] && !nodes.is_cluster[s] {
            0
        } else if r == s {
            2
        } else if is_near(nodes, r, s) {
            3
        } else {
            1
        }
    };
    let records = links.to_records();
    let by_kind: Vec<Vec<f64>> = (0..4)
        .map(|kind| {
            let kept: Vec<_> =
                records.iter().copied().filter(|l| kind_of(l.receiver as usize, l.source as usize) == kind).collect();
            let kept = radray::radiosity::hierarchy::links::Links::from_records(nodes.len(), kept);
            let kept_scales = ArrivalScales::reusing(nodes, &kept, Some(&scales));
            radray::radiosity::hierarchy::row_sums::row_sums(nodes, &kept, &kept_scales)
        })
        .collect();
    // Per kind: links, Σ A_R·F and Σ A_open,R·F (what they claim to deliver at unit exitance), and
    // Σ A_open·R over the receiving leaves (what the push delivers).
    println!("{:<6} {:>10} {:>14} {:>14} {:>14}", "kind", "links", "sum A_R F", "sum Aopen_R F", "sum Aopen R");
    for (kind, name) in ["elem", "far", "self", "near"].iter().enumerate() {
        let (mut count, mut claimed, mut claimed_open) = (0usize, 0.0f64, 0.0f64);
        for l in records.iter().filter(|l| kind_of(l.receiver as usize, l.source as usize) == kind) {
            let r = l.receiver as usize;
            count += 1;
            claimed += nodes.area[r] as f64 * l.form_factor as f64;
            claimed_open += nodes.open_area[r] as f64 * l.form_factor as f64;
        }
        let arrived: f64 = (0..nodes.len())
            .filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n])
            .map(|n| nodes.open_area[n] as f64 * by_kind[kind][n])
            .sum();
        println!("{name:<6} {count:>10} {claimed:>14.1} {claimed_open:>14.1} {arrived:>14.1}");
    }
    // With ROW_SUMS_REESTIMATE=SEED: every link estimated again with rays of another seed (no spread
    // cap, no threshold), independent of the estimate refinement judged it by; the same table.
    if let Some(seed) = std::env::var("ROW_SUMS_REESTIMATE").ok().and_then(|v| v.parse::<u64>().ok()) {
        use radray::radiosity::hierarchy::visibility::VisibilityContext;
        let params = radray::radiosity::hierarchical::hierarchy_params(scene);
        let accel = scene_accel(scene);
        let ctx = VisibilityContext {
            accel: &accel,
            rays: params.visibility_rays,
            offset: scene.diagonal() * 1e-5,
            seed: params.seed ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15),
        };
        let again: Vec<_> = records
            .par_iter()
            .map(|l| {
                let (r, s) = (l.receiver as usize, l.source as usize);
                let f =
                    radray::radiosity::hierarchy::links::estimate(nodes, &ctx, r, s, f32::INFINITY, f64::INFINITY, 0.0)
                        .map_or(0.0, |(f, _)| f);
                radray::radiosity::hierarchy::links::LinkRecord { form_factor: f, ..*l }
            })
            .collect();
        println!("re-estimated (seed {seed}):");
        println!("{:<6} {:>10} {:>14} {:>14} {:>14}", "kind", "links", "sum A_R F", "again", "Aopen R again");
        let mut total = vec![0.0f64; nodes.len()];
        for (kind, name) in ["elem", "far", "self", "near"].iter().enumerate() {
            let (mut count, mut before, mut after) = (0usize, 0.0f64, 0.0f64);
            let mut kept = Vec::new();
            for (l, a) in records.iter().zip(&again) {
                if kind_of(l.receiver as usize, l.source as usize) == kind {
                    count += 1;
                    before += nodes.area[l.receiver as usize] as f64 * l.form_factor as f64;
                    after += nodes.area[l.receiver as usize] as f64 * a.form_factor as f64;
                    kept.push(*a);
                }
            }
            let kept = radray::radiosity::hierarchy::links::Links::from_records(nodes.len(), kept);
            let kept_scales = ArrivalScales::reusing(nodes, &kept, Some(&scales));
            let sums = radray::radiosity::hierarchy::row_sums::row_sums(nodes, &kept, &kept_scales);
            let arrived: f64 = (0..nodes.len())
                .filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n])
                .map(|n| {
                    total[n] += sums[n];
                    nodes.open_area[n] as f64 * sums[n]
                })
                .sum();
            println!("{name:<6} {count:>10} {before:>14.1} {after:>14.1} {arrived:>14.1}");
        }
        let (mut a, mut ar) = (0.0f64, 0.0f64);
        for n in (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n]) {
            if nodes.open_area[n] > 0.0 && nodes.reflectance[n].max_element() > 0.0 {
                a += nodes.open_area[n] as f64;
                ar += nodes.open_area[n] as f64 * total[n];
            }
        }
        println!("R again (area-weighted over receiving leaves): {:.3}", ar / a);
    }
    drop(records);
    let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n]).collect();
    let tracer = LeafTracer::new(nodes, inputs, &leaves);
    let offset = scene.diagonal() * 1e-5;
    let receiving: Vec<usize> = leaves
        .iter()
        .copied()
        .filter(|&n| nodes.open_area[n] > 0.0 && nodes.reflectance[n].max_element() > 0.0)
        .collect();
    let seen: Vec<f64> = receiving
        .par_iter()
        .map(|&e| {
            let mut state = radray::rng::splitmix64(e as u64 ^ 0x0005_0335);
            let mut uniform = || {
                state = radray::rng::splitmix64(state);
                (state >> 40) as f32 / (1u64 << 24) as f32
            };
            let facing = (0..rays)
                .filter(|_| matches!(tracer.cosine_ray(nodes, e, offset, &mut uniform), RayEnd::Facing(_)))
                .count();
            facing as f64 / rays as f64
        })
        .collect();
    // Per (object, sheet): [area, Σ A·R, Σ A·rays, Σ A·|R − rays|, leaves, Σ A·R by kind ×4].
    let mut rows: std::collections::BTreeMap<(String, bool), [f64; 9]> = Default::default();
    let mut all = [0.0f64; 9];
    for (&e, &h) in receiving.iter().zip(&seen) {
        let input = nodes.input[e] as usize;
        let key = (scene.surfaces[inputs.surface[input] as usize].object.clone(), inputs.back[input]);
        let a = nodes.open_area[e] as f64;
        let add = [
            a,
            a * sums[e],
            a * h,
            a * (sums[e] - h).abs(),
            1.0,
            a * by_kind[0][e],
            a * by_kind[1][e],
            a * by_kind[2][e],
            a * by_kind[3][e],
        ];
        let row = rows.entry(key).or_insert([0.0; 9]);
        for i in 0..9 {
            row[i] += add[i];
            all[i] += add[i];
        }
    }
    let mut rows: Vec<_> = rows.into_iter().collect();
    rows.sort_by(|a, b| b.1[3].total_cmp(&a.1[3]));
    println!("{rays} cosine rays per leaf; R = the links' row sum, rays = the share meeting a facing surface");
    println!("R by link kind: element pairs, far cluster links, near self-links, other near links");
    println!(
        "{:<28} {:>5} {:>9} {:>12} {:>7} {:>7} {:>9} {:>7} {:>7} {:>7} {:>7}",
        "object", "sheet", "leaves", "area", "R", "rays", "|R-rays|", "elem", "far", "self", "near"
    );
    let line = |name: &str, sheet: &str, r: &[f64; 9]| {
        println!(
            "{name:<28} {sheet:>5} {:>9} {:>12.1} {:>7.3} {:>7.3} {:>9.3} {:>7.3} {:>7.3} {:>7.3} {:>7.3}",
            r[4] as usize,
            r[0],
            r[1] / r[0],
            r[2] / r[0],
            r[3] / r[0],
            r[5] / r[0],
            r[6] / r[0],
            r[7] / r[0],
            r[8] / r[0]
        )
    };
    line("all", "both", &all);
    for ((name, back), r) in rows.iter().take(40) {
        line(name, if *back { "back" } else { "front" }, r);
    }
    ExitCode::SUCCESS
}

fn unlinked(scene: &radray::scene::SceneDescription, name: &str) -> ExitCode {
    use rayon::prelude::*;
    let Some(structure) = solved(scene) else { return ExitCode::FAILURE };
    let (nodes, links, inputs) = (structure.nodes(), structure.links(), structure.inputs());
    let set = linked_pairs(links);
    let ancestors = |n: usize| ancestors_of(nodes, n);
    let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n]).collect();
    let tracer = LeafTracer::new(nodes, inputs, &leaves);
    let offset = scene.diagonal() * 1e-5;
    let object = |n: usize| &scene.surfaces[inputs.surface[nodes.input[n] as usize] as usize].object;
    let mut objects: Vec<String> = scene.surfaces.iter().map(|s| s.object.clone()).collect();
    objects.sort();
    objects.dedup();
    let mine: Vec<usize> = leaves.iter().copied().filter(|&n| object(n) == name && nodes.open_area[n] > 0.0).collect();
    let detail: usize = std::env::var("UNLINKED_DETAIL").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
    const RAYS: usize = 64;
    // Per receiver leaf: [linked B·A, unlinked B·A, linked rays, unlinked rays, then unlinked B·A by object], and
    // the unlinked pairs for the detail.
    let rows: Vec<UnlinkedRow> = mine
        .par_iter()
        .map(|&e| {
            let mut out = vec![0.0f64; 4 + objects.len()];
            let mut pairs = Vec::new();
            let up = ancestors(e);
            let mut state = radray::rng::splitmix64(e as u64 ^ 0xc0ffee);
            let mut uniform = || {
                state = radray::rng::splitmix64(state);
                (state >> 40) as f32 / (1u64 << 24) as f32
            };
            let w = nodes.open_area[e] as f64 / RAYS as f64;
            for _ in 0..RAYS {
                let RayEnd::Facing(l) = tracer.cosine_ray(nodes, e, offset, &mut uniform) else { continue };
                let bl = nodes.exitance_mean[l] - mean_channel(nodes.emission[l].as_dvec3());
                let theirs = ancestors(l);
                let linked = up.iter().any(|&a| theirs.iter().any(|&c| set.contains(&(a, c))));
                if linked {
                    out[0] += w * bl;
                    out[2] += 1.0;
                } else {
                    out[1] += w * bl;
                    out[3] += 1.0;
                    let o = objects.iter().position(|m| m == object(l)).unwrap();
                    out[4 + o] += w * bl;
                    if pairs.len() < 2 {
                        pairs.push((e, l));
                    }
                }
            }
            (out, pairs)
        })
        .collect();
    let mut total = vec![0.0f64; 4 + objects.len()];
    let mut pairs = Vec::new();
    for (row, p) in rows {
        for i in 0..total.len() {
            total[i] += row[i];
        }
        pairs.extend(p);
    }
    println!(
        "object {name}: {} leaves; indirect A·G the rays read: linked {:.4} W ({} rays), unlinked {:.4} W ({} rays, {:.1}% of the power)",
        mine.len(),
        total[0],
        total[2],
        total[1],
        total[3],
        100.0 * total[1] / (total[0] + total[1]).max(1e-30)
    );
    let mut by_object: Vec<(f64, &String)> = objects.iter().enumerate().map(|(o, m)| (total[4 + o], m)).collect();
    by_object.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (w, m) in by_object.iter().take(12) {
        println!("  unlinked from {m}: {w:.4} W");
    }
    let describe = |n: u32| {
        let n = n as usize;
        format!(
            "{}{} L{} A {:.3} r {:.2}",
            n,
            if nodes.is_cluster[n] { "c" } else { "e" },
            nodes.level[n],
            nodes.area[n],
            nodes.radius[n]
        )
    };
    for &(e, l) in pairs.iter().step_by((pairs.len() / detail.max(1)).max(1)).take(detail) {
        println!(
            "pair {e} ({}, back {}) <- {l} ({}, back {}), d {:.3}, B_l {:.4}",
            object(e),
            inputs.back[nodes.input[e] as usize],
            object(l),
            inputs.back[nodes.input[l] as usize],
            nodes.centre[e].distance(nodes.centre[l]),
            nodes.exitance_mean[l]
        );
        let (ue, ul) = (ancestors(e), ancestors(l));
        // The lowest common ancestor and the two chains up to it.
        let common = ue.iter().position(|a| ul.contains(a)).unwrap_or(ue.len() - 1);
        let lca = ue[common];
        let cl = ul.iter().position(|&a| a == lca).unwrap_or(ul.len() - 1);
        println!("  receiver chain: {}", ue[..=common].iter().map(|&a| describe(a)).collect::<Vec<_>>().join(" < "));
        println!("  source chain:   {}", ul[..=cl].iter().map(|&a| describe(a)).collect::<Vec<_>>().join(" < "));
        // Links out of each receiver ancestor into the source's subtree side: the sources that are
        // on the source chain's siblings (what the refinement did at each level).
        for &a in &ue[..=common] {
            let around: Vec<String> = links
                .range(a as usize)
                .filter(|&k| {
                    let s = links.source[k];
                    ul[..=cl].contains(&s) || ul[..=cl].contains(&nodes.parent[s as usize])
                })
                .map(|k| format!("{} F {:.2e}", describe(links.source[k]), links.form_factor[k]))
                .collect();
            if !around.is_empty() {
                println!("    links of {a} to the source chain or its children: {}", around.join("; "));
            }
        }
    }
    ExitCode::SUCCESS
}

fn mean_channel(v: DVec3) -> f64 {
    (v.x + v.y + v.z) / 3.0
}

/// Every (receiver, source) pair of the links.
fn linked_pairs(links: &radray::radiosity::hierarchy::links::Links) -> rustc_hash::FxHashSet<(u32, u32)> {
    let mut set = rustc_hash::FxHashSet::default();
    for r in 0..links.offsets.len().saturating_sub(1) {
        for k in links.range(r) {
            set.insert((r as u32, links.source[k]));
        }
    }
    set
}

/// Node `n` and its ancestors up to the root.
fn ancestors_of(nodes: &radray::radiosity::hierarchy::nodes::Nodes, n: usize) -> Vec<u32> {
    let mut out = Vec::new();
    let mut up = n as u32;
    while up != u32::MAX {
        out.push(up);
        up = nodes.parent[up as usize];
    }
    out
}

/// Where a cosine ray from a leaf ends (`LeafTracer::cosine_ray`).
enum RayEnd {
    /// On the leaf that faces the ray.
    Facing(usize),
    /// On the back of a one-sided leaf.
    Behind,
    /// Nowhere: it left the scene.
    Escaped,
}

/// Rays against the leaves, one acceleration structure per sheet: a two-sided sheet's front and back
/// leaves coincide, and a ray sees the one that faces it.
struct LeafTracer {
    front: Vec<usize>,
    back: Vec<usize>,
    accel_front: radray::accel::Accel,
    accel_back: radray::accel::Accel,
}

impl LeafTracer {
    fn new(
        nodes: &radray::radiosity::hierarchy::nodes::Nodes,
        inputs: &radray::radiosity::hierarchy::clusters::InputTriangles,
        leaves: &[usize],
    ) -> LeafTracer {
        let (back, front): (Vec<usize>, Vec<usize>) =
            leaves.iter().copied().partition(|&n| inputs.back[nodes.input[n] as usize]);
        let accel_of = |sheet: &[usize]| {
            let positions: Vec<glam::Vec3> = sheet.iter().flat_map(|&n| nodes.corners[n]).collect();
            let triangles: Vec<[u32; 3]> = (0..sheet.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
            radray::accel::Accel::build(&positions, &triangles)
        };
        let (accel_front, accel_back) = (accel_of(&front), accel_of(&back));
        LeafTracer { front, back, accel_front, accel_back }
    }

    /// A cosine-distributed ray from a uniform point of leaf `e` (moved `offset` off it): the nearest
    /// hit, and of two at the same distance (a two-sided sheet) the one facing the ray.
    fn cosine_ray(
        &self,
        nodes: &radray::radiosity::hierarchy::nodes::Nodes,
        e: usize,
        offset: f32,
        uniform: &mut impl FnMut() -> f32,
    ) -> RayEnd {
        use radray::radiosity::hierarchy::visibility::triangle_point;
        use radray::transport::hit::leave_surface;
        let n = nodes.normal[e];
        let p = triangle_point(&nodes.corners[e], uniform(), uniform());
        let d = radray::radiosity::hierarchy::ray_correction::cosine_direction(n, uniform(), uniform());
        let origin = leave_surface(p, n, offset);
        let hits = [
            self.accel_front.closest_hit(origin, d, 0.0, f32::INFINITY).map(|h| (h.t, self.front[h.triangle as usize])),
            self.accel_back.closest_hit(origin, d, 0.0, f32::INFINITY).map(|h| (h.t, self.back[h.triangle as usize])),
        ];
        let faces = |l: usize| nodes.normal[l].dot(d) < 0.0;
        let nearest = match hits {
            [Some(a), Some(b)] if (a.0 - b.0).abs() <= 1e-4 * a.0.max(b.0) => Some(if faces(a.1) { a } else { b }),
            [Some(a), Some(b)] => Some(if a.0 < b.0 { a } else { b }),
            [a, b] => a.or(b),
        };
        match nearest {
            Some((_, l)) if faces(l) => RayEnd::Facing(l),
            Some(_) => RayEnd::Behind,
            None => RayEnd::Escaped,
        }
    }
}

/// One receiver leaf's sums in the `--unlinked` report, and its first unlinked pairs.
type UnlinkedRow = (Vec<f64>, Vec<(usize, usize)>);

/// The scene solved at its own parameters, or `None` with the error printed.
/// What near link (receiver ← source) reads of its cluster source through its own samples: Σ_k
/// w_k B(t_k) / Σ_k w_k over the source elements the samples see (emission left out), leaf pair by
/// leaf pair (w = A_r F(r ← s) V) where the link is integrated that way; `None` when nothing is seen.
/// With `depth` > 0 each read counts for its ancestor `depth` levels below the source (a cut of at
/// most 2^depth clusters or elements, what per-link weights over such a cut could keep) and reads
/// that node's exitance.
fn sample_read(
    nodes: &radray::radiosity::hierarchy::nodes::Nodes,
    ctx: &radray::radiosity::hierarchy::visibility::VisibilityContext,
    receiver: usize,
    source: usize,
    depth: usize,
) -> Option<f64> {
    use radray::radiosity::hierarchy::links::{leaves_below, EXACT_NEAR_PAIRS};
    let mean = |v: DVec3| (v.x + v.y + v.z) / 3.0;
    let (mut rs, mut ss) = (Vec::new(), Vec::new());
    let mut reads = Vec::new();
    if leaves_below(nodes, receiver, EXACT_NEAR_PAIRS, &mut rs)
        && leaves_below(nodes, source, EXACT_NEAR_PAIRS, &mut ss)
        && rs.len() * ss.len() <= EXACT_NEAR_PAIRS
    {
        for &r in &rs {
            for &s in &ss {
                if r != s {
                    let (f, _) = element_to_element(&nodes.corners[r], nodes.normal[r], &nodes.corners[s]);
                    reads.push((s, nodes.area[r] as f64 * f));
                }
            }
        }
    } else {
        radray::radiosity::hierarchy::visibility::sampled_form_factor_reads(ctx, nodes, receiver, source, &mut reads);
    }
    let cut = |t: usize| {
        if depth == 0 {
            return t;
        }
        let mut path = vec![t];
        while *path.last().unwrap() != source {
            path.push(nodes.parent[*path.last().unwrap()] as usize);
        }
        path[path.len().saturating_sub(1 + depth)]
    };
    let total: f64 = reads.iter().map(|&(_, w)| w).sum();
    (total > 0.0).then(|| {
        reads
            .iter()
            .map(|&(t, w)| {
                let n = cut(t);
                w * mean(nodes.exitance[n] - nodes.emission[n].as_dvec3())
            })
            .sum::<f64>()
            / total
    })
}

/// The scene's surfaces fanned into triangles, for visibility and cosine rays.
fn scene_accel(scene: &radray::scene::SceneDescription) -> radray::accel::Accel {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for s in &scene.surfaces {
        let base = positions.len() as u32;
        positions.extend_from_slice(&s.vertices);
        for k in 1..s.vertices.len().saturating_sub(1) as u32 {
            triangles.push([base, base + k, base + k + 1]);
        }
    }
    radray::accel::Accel::build(&positions, &triangles)
}

fn solved(scene: &radray::scene::SceneDescription) -> Option<radray::radiosity::hierarchy::LinkStructure> {
    let params = radray::radiosity::hierarchical::hierarchy_params(scene);
    match solve_reusing(scene, Default::default(), &params, None, &mut |_| {}) {
        Ok((_, structure)) => Some(structure),
        Err(e) => {
            eprintln!("{e}");
            None
        }
    }
}

/// The receiver of link k.
fn receiver_of(links: &radray::radiosity::hierarchy::links::Links, k: usize) -> usize {
    links.offsets.partition_point(|&o| o as usize <= k) - 1
}
