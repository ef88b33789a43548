//! Fits one DCT map on a CARMEN log's patch and prints the optimizer's progress:
//! `cargo run --release -p raypath-dct-map --example fit_log -- LOG L [x0 y0] [solver]`.
#![allow(clippy::unwrap_used)]

use std::time::Instant;

use raypath_dct_map::experiment::{auto_patch, draw_rays};
use raypath_dct_map::{FitConfig, FitProblem, Patch, RangeLimits, Shape, Solver, fit, initial_map};
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    let mut rays = Vec::new();
    for f in read_planar(std::path::Path::new(&args[1]), &options).unwrap() {
        rays.extend(f.scan.rays(f.world_from_laser));
    }
    let n: usize = args[2].parse().unwrap();
    let patch = if args.len() > 4 {
        Patch::square([args[3].parse().unwrap(), args[4].parse().unwrap()], 10.0)
    } else {
        auto_patch(&rays, 10.0).unwrap()
    };
    let solver = if args.get(5).is_some_and(|s| s == "lbfgs") {
        Solver::Lbfgs
    } else {
        Solver::TrustRegionNewton
    };
    let count: usize = args.get(6).map_or(10_000, |s| s.parse().unwrap());
    let (mapping, _) = draw_rays(&rays, &patch, &RangeLimits::default(), count, 500, 9);
    let shape = Shape { l: n, m: n };
    let t = Instant::now();
    let problem = FitProblem::new(patch.extent_m, shape, &mapping).unwrap();
    println!("moments {:.3}s", t.elapsed().as_secs_f64());
    let t = Instant::now();
    let init = initial_map(patch.extent_m, shape, &mapping).unwrap();
    println!("init {:.3}s", t.elapsed().as_secs_f64());
    let (_, report) = fit(
        &problem,
        init.coefficients(),
        &FitConfig {
            solver,
            ..FitConfig::default()
        },
    )
    .unwrap();
    println!("{report:?}");
}
