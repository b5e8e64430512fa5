//! Diagnoses where the hierarchy and the full matrix disagree (issue 10): per-surface mean exitance of
//! both solvers, and link by link, by link type, the power each link delivers against the exact sum
//! over its leaf-element pairs (unoccluded, so exact on convex scenes such as cornell_empty), plus how
//! much of a cluster receiver's power lands on the wrong children, and the same against leaf pairs that all
//! take the source's mean exitance (the gap between the two is the source-side discretisation: a coarse
//! source whose leaves' exitance correlates with their form factor). Last, link coverage from sampled
//! leaves: every input triangle should reach a leaf through exactly one link of it or an ancestor.
//! `cargo run --release --example hierarchy_agreement -- SCENE.toml [EPSILON] [LINKS_PER_TYPE] [TOLERANCE]`.

use std::process::ExitCode;

use glam::DVec3;
use rayon::prelude::*;

use radray::accel::Accel;
use radray::mesh::Mesh;
use radray::radiosity::hierarchy::form_factor::element_to_element;
use radray::radiosity::hierarchy::links::{admissible, is_near, Links, EXACT_NEAR_PAIRS};
use radray::radiosity::hierarchy::nodes::{mean_channel, Nodes};
use radray::radiosity::hierarchy::refine::{refine, RefineSettings};
use radray::radiosity::hierarchy::visibility::{link_visibility, VisibilityContext};
use radray::radiosity::hierarchy::{clusters, solve as hsolve, HierarchyParams};
use radray::radiosity::{form_factors, solver};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: hierarchy_agreement SCENE.toml [EPSILON] [LINKS_PER_TYPE] [TOLERANCE]");
        return ExitCode::FAILURE;
    };
    let scene = match radray::scene::load(std::path::Path::new(path)) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let mut params = HierarchyParams::default();
    if let Some(eps) = args.get(2).and_then(|a| a.parse().ok()) {
        params.error_threshold = eps;
    }
    if let Some(t) = args.get(4).and_then(|a| a.parse().ok()) {
        params.tolerance = t;
    }
    let per_type: usize = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(400);
    let surfaces = scene.surfaces.len();

    // Full matrix, per-surface means of the front sides.
    let mesh = Mesh::build(&scene, scene.radiosity.max_element_edge);
    let ff = form_factors::compute(&mesh, &scene.radiosity, &|| {});
    let e = &mesh.elements;
    let (b, _) = solver::solve(&ff, &e.reflectance, &e.emission, &e.area, &scene.radiosity, &mut |_, _| {});
    let mut full = vec![(DVec3::ZERO, 0.0f64); surfaces];
    for (i, bi) in b.iter().enumerate() {
        if let Some(f) = full.get_mut(e.surface[i] as usize) {
            f.0 += bi.as_dvec3() * e.area[i] as f64;
            f.1 += e.area[i] as f64;
        }
    }

    // The hierarchy, as `hierarchy::solve` runs it, keeping its nodes and links.
    let (mut nodes, root, inputs, tracing) = clusters::build(&scene).expect("scene builds");
    let root = root as usize;
    let accel = Accel::build(&tracing.positions, &tracing.triangles);
    let diagonal = scene.diagonal();
    let ctx =
        VisibilityContext { accel: &accel, rays: params.visibility_rays, offset: diagonal * 1e-5, seed: params.seed };
    let (mut power, mut area) = (0.0, 0.0);
    for &n in &inputs.node {
        power += nodes.area[n as usize] as f64 * mean_channel(nodes.emission[n as usize].as_dvec3());
        area += nodes.area[n as usize] as f64;
    }
    let min_element_area = (diagonal / params.min_element_divisor).powi(2);
    let settings = RefineSettings {
        threshold: params.error_threshold * power / area,
        floor_area: min_element_area,
        min_element_area,
        budget_bytes: params.memory_bytes,
        reference_exitance: power / area,
        dark_receiver_floor: 1.0,
    };
    hsolve::reset_to_emission(&mut nodes, root);
    let mut links = Links::default();
    for pass in 1..=params.refinement_passes {
        let (records, self_links) =
            if pass == 1 { (Vec::new(), vec![root as u32]) } else { (links.to_records(), vec![]) };
        let settings = if pass == 1 {
            settings
        } else {
            RefineSettings { dark_receiver_floor: params.dark_receiver_floor, ..settings }
        };
        links = refine(&mut nodes, &ctx, records, self_links, &settings, &mut |_, _, _| {}).links;
        let (sweeps, converged) = hsolve::solve(
            &mut nodes,
            &links,
            root,
            params.relaxation,
            params.tolerance,
            params.max_sweeps,
            &mut |_, _| {},
        );
        println!("pass {pass}: {} links, {sweeps} sweeps, converged {converged}", links.len());
    }
    println!("hierarchy: {} nodes, {} links; matrix: {} elements", nodes.len(), links.len(), e.len());

    let mut hier = vec![(DVec3::ZERO, 0.0f64); surfaces];
    for n in 0..nodes.len() {
        if nodes.is_cluster[n] || !nodes.is_leaf(n) {
            continue;
        }
        let input = nodes.input[n] as usize;
        if inputs.back[input] {
            continue;
        }
        let h = &mut hier[inputs.surface[input] as usize];
        h.0 += nodes.exitance[n] * nodes.area[n] as f64;
        h.1 += nodes.area[n] as f64;
    }
    println!("surface  area  matrix B (r g b)  hierarchy/matrix (r g b)");
    for k in 0..surfaces {
        let (f, h) = (full[k].0 / full[k].1, hier[k].0 / hier[k].1);
        println!(
            "{k:3} {:9.0} {:8.3} {:8.3} {:8.3}   {:.3} {:.3} {:.3}",
            full[k].1,
            f.x,
            f.y,
            f.z,
            h.x / f.x,
            h.y / f.y,
            h.z / f.z
        );
    }

    // Surface-to-surface form factors F_{k←j} = (1/A_k) Σ A_r F_rs over front leaves: the matrix's rows,
    // and the hierarchy's links with each end split among surfaces by area.
    let mut fm = vec![vec![0.0f64; surfaces]; surfaces];
    for i in 0..e.len() {
        let k = e.surface[i] as usize;
        let (cols, vals) = ff.row(i);
        for (&c, &v) in cols.iter().zip(vals) {
            let j = e.surface[c as usize] as usize;
            if k < surfaces && j < surfaces {
                fm[k][j] += e.area[i] as f64 * v as f64 / full[k].1;
            }
        }
    }
    let mut share = vec![vec![0.0f64; surfaces]; nodes.len()];
    for (n, row) in share.iter_mut().enumerate() {
        for l in leaves(&nodes, n) {
            let input = nodes.input[l] as usize;
            if !inputs.back[input] {
                row[inputs.surface[input] as usize] += nodes.area[l] as f64;
            }
        }
    }
    let mut fh = vec![vec![0.0f64; surfaces]; surfaces];
    for l in links.to_records() {
        let (r, s) = (l.receiver as usize, l.source as usize);
        let a_s = nodes.area[s] as f64;
        for k in 0..surfaces {
            for j in 0..surfaces {
                fh[k][j] += share[r][k] * l.form_factor as f64 * share[s][j] / a_s / hier[k].1;
            }
        }
    }
    println!("F(k <- j): matrix / hierarchy");
    for k in 0..surfaces {
        let row: Vec<String> = (0..surfaces).map(|j| format!("{:.4}/{:.4}", fm[k][j], fh[k][j])).collect();
        let (sm, sh): (f64, f64) = (fm[k].iter().sum(), fh[k].iter().sum());
        println!("{k}: {}  sum {sm:.4}/{sh:.4}", row.join(" "));
    }

    // Link by link: delivered power A_R·F·B_S (mean channel) against Σ_r Σ_s A_r F(r ← s) B_s over the
    // leaf pairs (unoccluded), and the part of the exact power that the uniform push misplaces among
    // the receiver's leaves, Σ_r |A_r G_r − A_r G_exact,r| / 2.
    let kind = |r: usize, s: usize| -> usize {
        if !nodes.is_cluster[r] && !nodes.is_cluster[s] {
            0
        } else if !is_near(&nodes, r, s) && admissible(&nodes, r, s) {
            1
        } else if count_leaves(&nodes, r).saturating_mul(count_leaves(&nodes, s)) <= EXACT_NEAR_PAIRS {
            2
        } else {
            3
        }
    };
    let names = ["element<-element", "far cluster", "near, leaf pairs", "near, rays"];
    let records = links.to_records();
    let mut by_kind: Vec<Vec<usize>> = vec![Vec::new(); 4];
    for (i, l) in records.iter().enumerate() {
        by_kind[kind(l.receiver as usize, l.source as usize)].push(i);
    }
    let b_mean: Vec<f64> = nodes.exitance.iter().map(|&x| mean_channel(x)).collect();
    println!("link type            links   sampled  estimated W   exact W   est/exact  misplaced/exact");
    for (k, list) in by_kind.iter().enumerate() {
        let stride = (list.len() / per_type).max(1);
        let picked: Vec<usize> = list.iter().step_by(stride).copied().collect();
        let sums: Vec<(f64, f64, f64, f64)> = picked
            .par_iter()
            .map(|&i| {
                let l = &records[i];
                let (r, s) = (l.receiver as usize, l.source as usize);
                let estimated = nodes.area[r] as f64 * l.form_factor as f64 * b_mean[s];
                // Systematic subsamples of both leaf lists (spatially ordered), weighted by area.
                let (rs, r_scale) = subsample(&nodes, leaves(&nodes, r), 128);
                let (ss, s_scale) = subsample(&nodes, leaves(&nodes, s), 256);
                let g = estimated / nodes.area[r] as f64;
                let (mut exact, mut misplaced, mut flat) = (0.0, 0.0, 0.0);
                let mut per_leaf = Vec::with_capacity(rs.len());
                for &x in &rs {
                    let (mut p, mut q) = (0.0, 0.0);
                    for &y in &ss {
                        if x != y {
                            let (f, _) = element_to_element(&nodes.corners[x], nodes.normal[x], &nodes.corners[y]);
                            p += nodes.area[x] as f64 * f * b_mean[y];
                            q += nodes.area[x] as f64 * f * b_mean[s];
                        }
                    }
                    per_leaf.push(p * s_scale);
                    exact += p * s_scale * r_scale;
                    flat += q * s_scale * r_scale;
                }
                for (j, &x) in rs.iter().enumerate() {
                    misplaced += (nodes.area[x] as f64 * g - per_leaf[j]).abs() * r_scale;
                }
                (estimated, exact, 0.5 * misplaced, flat)
            })
            .collect();
        let (est, ex, mis, flat) =
            sums.iter().fold((0.0, 0.0, 0.0, 0.0), |a, s| (a.0 + s.0, a.1 + s.1, a.2 + s.2, a.3 + s.3));
        println!(
            "{:18} {:8} {:8} {:11.4e} {:11.4e} {:9.4} {:9.4}  est/exact-with-uniform-B_S {:.4}",
            names[k],
            list.len(),
            picked.len(),
            est * stride as f64,
            ex * stride as f64,
            est / ex,
            mis / ex,
            est / flat
        );
    }
    // Element ← element links, one sample of them for two checks. The estimator (unoccluded) against a
    // 768-point receiver quadrature (4 midpoint subdivisions × the three-point rule), power-weighted,
    // split by whether the pair is near. Visibility: the link's N-ray fraction against 256 rays, by
    // receiver surface, weighted by unoccluded power.
    let ee = &by_kind[0];
    let stride = (ee.len() / (50 * per_type)).max(1);
    let fine_ctx = VisibilityContext { rays: 256, ..ctx };
    let (rows, vis): (Vec<_>, Vec<_>) = ee
        .iter()
        .step_by(stride)
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&&i| {
            let l = &records[i];
            let (r, s) = (l.receiver as usize, l.source as usize);
            let (f, _) = element_to_element(&nodes.corners[r], nodes.normal[r], &nodes.corners[s]);
            let fine = fine_form_factor(&nodes.corners[r], nodes.normal[r], &nodes.corners[s]);
            let w = nodes.area[r] as f64 * b_mean[s];
            let near = nodes.centre[r].distance(nodes.centre[s]) < 1.5 * (nodes.radius[r] + nodes.radius[s]);
            let v = link_visibility(&ctx, &nodes, r, s).visible as f64;
            let v_fine = link_visibility(&fine_ctx, &nodes, r, s).visible as f64;
            let surface = inputs.surface[nodes.input[r] as usize] as usize;
            ((near, w * f, w * fine), (surface, w * f, w * f * v, w * f * v_fine))
        })
        .unzip();
    for k in 0..surfaces {
        let (w, v, vf) =
            vis.iter().filter(|x| x.0 == k).fold((0.0, 0.0, 0.0), |a, x| (a.0 + x.1, a.1 + x.2, a.2 + x.3));
        println!("receiver surface {k}: visible power share, link rays {:.4}, 256 rays {:.4}", v / w, vf / w);
    }
    for near in [true, false] {
        let (est, fine) = rows.iter().filter(|r| r.0 == near).fold((0.0, 0.0), |a, r| (a.0 + r.1, a.1 + r.2));
        println!(
            "element pairs near={near}: {} sampled, estimator/fine quadrature {:.4} (power {:.4e})",
            rows.iter().filter(|r| r.0 == near).count(),
            est / fine,
            fine * stride as f64
        );
    }
    coverage(&nodes, &links, &inputs, surfaces, per_type);
    ExitCode::SUCCESS
}

/// F(receiver ← source) with the three-point rule on 4^4 midpoint sub-triangles of the receiver.
fn fine_form_factor(receiver: &[glam::Vec3; 3], normal: glam::Vec3, source: &[glam::Vec3; 3]) -> f64 {
    use radray::radiosity::hierarchy::form_factor::{point_to_polygon, quadrature_points};
    let mut tris = vec![*receiver];
    for _ in 0..4 {
        tris = tris
            .into_iter()
            .flat_map(|[a, b, c]| {
                let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    let mut sum = 0.0;
    for t in &tris {
        for x in quadrature_points(t) {
            sum += point_to_polygon(x, normal, source);
        }
    }
    sum / (3 * tris.len()) as f64
}

fn leaves(nodes: &Nodes, node: usize) -> Vec<usize> {
    let (mut out, mut stack) = (Vec::new(), vec![node]);
    while let Some(n) = stack.pop() {
        if nodes.is_leaf(n) {
            out.push(n);
        } else {
            stack.extend(nodes.children(n));
        }
    }
    out
}

/// Every k-th leaf so that at most `limit` remain, and Σ area / Σ sampled area.
fn subsample(nodes: &Nodes, all: Vec<usize>, limit: usize) -> (Vec<usize>, f64) {
    let total: f64 = all.iter().map(|&n| nodes.area[n] as f64).sum();
    let stride = all.len().div_ceil(limit).max(1);
    let picked: Vec<usize> = all.into_iter().step_by(stride).collect();
    let sampled: f64 = picked.iter().map(|&n| nodes.area[n] as f64).sum();
    (picked, if sampled > 0.0 { total / sampled } else { 0.0 })
}

fn count_leaves(nodes: &Nodes, node: usize) -> usize {
    leaves(nodes, node).len()
}

/// One sampled leaf of `coverage`: its surface, Σ_t F(x ← t) exact, covered and linked, and the
/// uncovered F by source surface.
struct CoverageRow {
    surface: usize,
    exact: f64,
    delivered: f64,
    linked: f64,
    missing: Vec<(usize, f64)>,
}

/// Link coverage seen from sampled front leaves x: every input triangle t should reach x exactly once,
/// through one link (a ← S) with a = x or an ancestor and S covering part of t. Per receiver surface:
/// Σ_t F(x ← t) (exact, unoccluded), the same weighted by the covered share of t (what the links
/// deliver if their estimators were exact), and Σ F of x's links and its ancestors' (what they deliver).
fn coverage(
    nodes: &Nodes,
    links: &Links,
    inputs: &radray::radiosity::hierarchy::clusters::InputTriangles,
    surfaces: usize,
    per_type: usize,
) {
    let front: Vec<usize> = (0..nodes.len())
        .filter(|&n| !nodes.is_cluster[n] && nodes.is_leaf(n) && !inputs.back[nodes.input[n] as usize])
        .collect();
    let stride = (front.len() / (5 * per_type)).max(1);
    let rows: Vec<CoverageRow> = front
        .iter()
        .step_by(stride)
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&&x| {
            let mut covered = vec![0.0f64; inputs.node.len()];
            let mut linked = 0.0;
            let mut a = x;
            loop {
                for k in links.range(a) {
                    let s = links.source[k] as usize;
                    linked += links.form_factor[k] as f64;
                    for l in leaves(nodes, s) {
                        covered[nodes.input[l] as usize] += nodes.area[l] as f64;
                    }
                }
                let p = nodes.parent[a];
                if p == u32::MAX || p as usize == a {
                    break;
                }
                a = p as usize;
            }
            let (mut exact, mut delivered) = (0.0, 0.0);
            let mut missing = vec![(0usize, 0.0f64); 0];
            for (t, &node) in inputs.node.iter().enumerate() {
                let node = node as usize;
                if inputs.back[t] || t == nodes.input[x] as usize {
                    continue;
                }
                let (f, _) = element_to_element(&nodes.corners[x], nodes.normal[x], &nodes.corners[node]);
                let share = covered[t] / nodes.area[node] as f64;
                exact += f;
                delivered += f * share;
                if f > 0.0 && (share - 1.0).abs() > 1e-3 {
                    missing.push((inputs.surface[t] as usize, f * (1.0 - share)));
                }
            }
            CoverageRow { surface: inputs.surface[nodes.input[x] as usize] as usize, exact, delivered, linked, missing }
        })
        .collect();
    for k in 0..surfaces {
        let mine: Vec<_> = rows.iter().filter(|r| r.surface == k).collect();
        if mine.is_empty() {
            continue;
        }
        let n = mine.len() as f64;
        let (e, d, l) = mine.iter().fold((0.0, 0.0, 0.0), |a, r| (a.0 + r.exact, a.1 + r.delivered, a.2 + r.linked));
        let mut by_source = vec![0.0f64; surfaces];
        for r in &mine {
            for &(j, m) in &r.missing {
                by_source[j] += m / n;
            }
        }
        let worst: Vec<String> =
            by_source.iter().enumerate().filter(|x| x.1.abs() > 1e-5).map(|(j, m)| format!("{j}:{m:.4}")).collect();
        println!(
            "coverage receiver surface {k}: {} leaves, mean F exact {:.4}, covered {:.4}, linked {:.4}; uncovered by source [{}]",
            mine.len(),
            e / n,
            d / n,
            l / n,
            worst.join(" ")
        );
    }
}
