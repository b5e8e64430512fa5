//! Runs the hierarchical radiosity solver on a scene file or a procedural room and prints its
//! statistics: `cargo run --release --example hierarchy -- SCENE.toml|procedural:TRIANGLES [EPSILON]
//! [MEMORY_MB] [VISIBILITY_RAYS] [MIN_ELEMENT_DIVISOR]` (unset or `-`: `HierarchyParams::default()`'s).

use std::process::ExitCode;

use radray::radiosity::hierarchy::{self, procedural, HierarchyParams, HierarchyProgress};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let Some(what) = args.get(1) else {
        eprintln!(
            "usage: hierarchy SCENE.toml|procedural:TRIANGLES [EPSILON] [MEMORY_MB] [VISIBILITY_RAYS] \
             [MIN_ELEMENT_DIVISOR] (- keeps the default)"
        );
        return ExitCode::FAILURE;
    };
    let scene = if let Some(count) = what.strip_prefix("procedural:") {
        match count.parse::<usize>() {
            Ok(n) => procedural::room_with_objects(n),
            Err(e) => {
                eprintln!("{what}: {e}");
                return ExitCode::FAILURE;
            }
        }
    } else {
        match radray::scene::load(std::path::Path::new(what)) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::FAILURE;
            }
        }
    };
    let mut params = HierarchyParams::default();
    // Positional overrides; "-" or a missing argument keeps the default.
    let arg = |k: usize| args.get(k).filter(|a| a.as_str() != "-");
    if let Some(eps) = arg(2) {
        match eps.parse() {
            Ok(e) => params.error_threshold = e,
            Err(e) => {
                eprintln!("{eps}: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    if let Some(mb) = arg(3) {
        match mb.parse::<usize>() {
            Ok(m) => params.memory_bytes = m << 20,
            Err(e) => {
                eprintln!("{mb}: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    if let Some(rays) = arg(4) {
        match rays.parse() {
            Ok(r) => params.visibility_rays = r,
            Err(e) => {
                eprintln!("{rays}: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    if let Some(divisor) = arg(5) {
        match divisor.parse() {
            Ok(d) => params.min_element_divisor = d,
            Err(e) => {
                eprintln!("{divisor}: {e}");
                return ExitCode::FAILURE;
            }
        }
    }
    let start = std::time::Instant::now();
    let result = hierarchy::solve(&scene, &params, &mut |p| match p {
        HierarchyProgress::Refining { pass, round, links, nodes } => {
            if round % 4 == 0 {
                eprintln!(
                    "[{:7.1}s] pass {pass} round {round}: {links} links kept, {nodes} nodes",
                    start.elapsed().as_secs_f64()
                )
            }
        }
        HierarchyProgress::Sweeping { pass, sweep, max_change, max_exitance } => {
            if sweep % 10 == 0 {
                eprintln!(
                    "[{:7.1}s] pass {pass} sweep {sweep}: change {max_change:.3e} of {max_exitance:.3e}",
                    start.elapsed().as_secs_f64()
                )
            }
        }
    });
    match result {
        Ok(solution) => {
            println!("{:#?}", solution.stats);
            println!("wall {:.2}s", start.elapsed().as_secs_f64());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
