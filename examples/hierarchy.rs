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
    if let Err(e) = apply_overrides(&args, &mut params) {
        eprintln!("{e}");
        return ExitCode::FAILURE;
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
        HierarchyProgress::TracingPhotons { pass, sources } => {
            eprintln!("[{:7.1}s] pass {pass}: tracing photons ({sources:?})", start.elapsed().as_secs_f64())
        }
        HierarchyProgress::MeasuringLinks { pass, receivers } => {
            eprintln!(
                "[{:7.1}s] pass {pass}: links of {receivers} receivers by hemicubes",
                start.elapsed().as_secs_f64()
            )
        }
        HierarchyProgress::Correcting { pass, round } => {
            eprintln!("[{:7.1}s] pass {pass}: ray correction, round {round}", start.elapsed().as_secs_f64())
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

/// The positional overrides EPSILON, MEMORY_MB, VISIBILITY_RAYS and MIN_ELEMENT_DIVISOR (arguments
/// 2 to 5); "-" or a missing argument keeps the default.
fn apply_overrides(args: &[String], params: &mut HierarchyParams) -> Result<(), String> {
    if let Some(e) = positional(args, 2)? {
        params.error_threshold = e;
    }
    if let Some(mb) = positional::<usize>(args, 3)? {
        params.memory_bytes = mb << 20;
    }
    if let Some(r) = positional(args, 4)? {
        params.visibility_rays = r;
    }
    if let Some(d) = positional(args, 5)? {
        params.min_element_divisor = d;
    }
    Ok(())
}

/// Argument `k` parsed, `None` when missing or "-".
fn positional<T: std::str::FromStr>(args: &[String], k: usize) -> Result<Option<T>, String>
where
    T::Err: std::fmt::Display,
{
    match args.get(k).filter(|a| a.as_str() != "-") {
        None => Ok(None),
        Some(a) => a.parse().map(Some).map_err(|e| format!("{a}: {e}")),
    }
}
