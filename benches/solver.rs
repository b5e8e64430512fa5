//! Criterion benches of the solver stage on a synthetic form-factor matrix the size of a meshed
//! interior: 10k elements, ~5k stored form factors per row (one Gauss-Seidel sweep, one Jacobi sweep,
//! one progressive-refinement shot and selection, and full solves).
use criterion::{criterion_group, criterion_main, Criterion};
use glam::{DVec3, Vec3};
use radray::radiosity::solver::shooting::received_from_matrix;
use radray::radiosity::solver::{self, brightest_unshot, diagonal, gauss_seidel_sweep, jacobi_row, shoot};
use radray::radiosity::FormFactors;
use radray::rng::Pcg32;
use radray::scene::{RadiosityParams, SolverKind};
use rayon::prelude::*;

const ELEMENTS: usize = 10_000;
/// Each off-diagonal entry is stored with probability 1/2: ~5k per row, 50M in all (400 MB).
const KEEP_ONE_IN: u32 = 2;

struct Scene {
    ff: FormFactors,
    reflectance: Vec<Vec3>,
    emission: Vec<Vec3>,
    area: Vec<f32>,
}

/// A deterministic random sparse matrix with rows summing to 0.99 (an almost closed enclosure),
/// reflectances in [0.2, 0.8), 1% of the elements emitting, areas in [0.5, 1.5).
fn synthetic_scene() -> Scene {
    let mut rng = Pcg32::new(7, 0);
    let mut ff = FormFactors { row_start: Vec::with_capacity(ELEMENTS + 1), ..Default::default() };
    ff.row_start.push(0);
    ff.column.reserve(ELEMENTS * ELEMENTS / KEEP_ONE_IN as usize);
    ff.value.reserve(ELEMENTS * ELEMENTS / KEEP_ONE_IN as usize);
    for i in 0..ELEMENTS {
        let start = ff.value.len();
        for j in 0..ELEMENTS {
            if j != i && rng.next_u32().is_multiple_of(KEEP_ONE_IN) {
                ff.column.push(j as u32);
                ff.value.push(rng.next_f32() + 1e-3);
            }
        }
        let sum: f32 = ff.value[start..].iter().sum();
        ff.value[start..].iter_mut().for_each(|v| *v *= 0.99 / sum);
        ff.row_start.push(ff.value.len());
    }
    let reflectance =
        (0..ELEMENTS).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.6 + 0.2).collect();
    let emission =
        (0..ELEMENTS).map(|i| if i.is_multiple_of(100) { Vec3::new(50.0, 40.0, 30.0) } else { Vec3::ZERO }).collect();
    let area = (0..ELEMENTS).map(|_| 0.5 + rng.next_f32()).collect();
    Scene { ff, reflectance, emission, area }
}

fn benches(c: &mut Criterion) {
    let scene = synthetic_scene();
    let ff = &scene.ff;
    println!("synthetic matrix: {} rows, {} non-zeros ({:.0} MB)", ff.len(), ff.nnz(), ff.memory_bytes() as f64 / 1e6);
    let reflectance: Vec<DVec3> = scene.reflectance.iter().map(|r| r.as_dvec3()).collect();
    let emission: Vec<DVec3> = scene.emission.iter().map(|e| e.as_dvec3()).collect();
    let area: Vec<f64> = scene.area.iter().map(|&a| a as f64).collect();
    let diag = diagonal(ff);

    let mut g = c.benchmark_group("solver 10k x 5k");
    g.sample_size(10);
    let mut exitance = emission.clone();
    g.bench_function("gauss-seidel sweep (SOR 1.2)", |b| {
        b.iter(|| gauss_seidel_sweep(ff, &diag, &reflectance, &emission, 1.2, &mut exitance))
    });
    let previous = emission.clone();
    let mut next = vec![DVec3::ZERO; ELEMENTS];
    g.bench_function("jacobi sweep (serial)", |b| {
        b.iter(|| solver::jacobi_sweep(ff, &reflectance, &emission, &previous, &mut next))
    });
    g.bench_function("jacobi sweep (rayon rows)", |b| {
        b.iter(|| {
            next.par_iter_mut()
                .enumerate()
                .map(|(i, b)| {
                    *b = jacobi_row(ff, i, &reflectance, &emission, &previous);
                    (*b - previous[i]).abs().max_element()
                })
                .reduce(|| 0.0, f64::max)
        })
    });
    // Progressive refinement: the selection scan against one shot of an average row.
    let mut unshot = emission.clone();
    let mut shot_exitance = emission.clone();
    g.bench_function("progressive select (linear scan)", |b| b.iter(|| brightest_unshot(&area, &unshot)));
    let mut k = 0;
    let received_by = ff.transpose();
    g.bench_function("progressive shoot (one row)", |b| {
        b.iter(|| {
            k = (k + 1) % ELEMENTS;
            unshot[k] = DVec3::ONE;
            shoot(received_from_matrix(&received_by, k), k, &reflectance, &mut shot_exitance, &mut unshot)
        })
    });
    for (solver, name) in [
        (SolverKind::GaussSeidel, "full solve gauss-seidel (SOR 1.2, tol 1e-4)"),
        (SolverKind::Jacobi, "full solve jacobi (rayon rows, tol 1e-4)"),
        (SolverKind::Progressive, "full solve progressive (unshot 1e-4)"),
    ] {
        let params = RadiosityParams { solver, tolerance: 1e-4, ..Default::default() };
        let (_, stats) = solver::solve(ff, &scene.reflectance, &scene.emission, &scene.area, &params, &mut |_, _| {});
        println!("{name}: {} iterations, converged {}", stats.iterations, stats.converged);
        g.bench_function(name, |b| {
            b.iter(|| solver::solve(ff, &scene.reflectance, &scene.emission, &scene.area, &params, &mut |_, _| {}))
        });
    }
    g.finish();
}

criterion_group!(solver_benches, benches);
criterion_main!(solver_benches);
