//! The held-back comparison of `cargo xtask eval dct` (Table 9.3: same patch, seed and
//! split) for chosen logs, sizes and prior densities, with the worst held-back ray of each
//! map — the measurement behind the crate docs' "Prior" entry:
//!
//! ```text
//! RAYPATH_DATA=… [RHO=0,1] [TOL=1e-3] [VERBOSE=1] \
//!   cargo run --release -p raypath-dct-map --example heldback -- 20,40 [LOG…]
//! ```
//!
//! Sizes are comma-separated; logs are named as under `carmen/corrected` (all when none are
//! named). `RHO` lists prior path densities (1/m; default: the crate's); a negative `-k`
//! stands for `k` times the empirical-Bayes density of Sec. 8.5 (`β = mean / variance` of
//! the observed rates of the `L × L` grid map, per cell area). `TOL` sets the relative
//! tolerance; `VERBOSE` describes the worst held-back ray.
#![allow(clippy::unwrap_used)]

use raypath_dct_map::experiment::{GroundTruth, cells_covering, draw_rays, seeded_patch};
use raypath_dct_map::{
    DctMap, FitConfig, FitProblem, GridRateMap, MapRay, Outcome, RangeLimits, Shape, fit,
    initial_map,
};
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};

/// `β / cell area` of the gamma prior fitted by moment matching to the grid map (Sec. 8.5).
fn empirical_bayes_density(grid: &GridRateMap, cell_m: f64) -> f64 {
    let v: Vec<f64> = (0..grid.rates().len())
        .filter(|i| grid.observed(*i))
        .map(|i| grid.rates()[i])
        .collect();
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64;
    mean / var / (cell_m * cell_m)
}

fn describe_worst(map: &DctMap, grid: &GridRateMap, held: &[MapRay]) {
    let ll: Vec<f64> = held.iter().map(|r| map.ray_log_likelihood(r)).collect();
    let k = (0..held.len())
        .min_by(|a, b| ll[*a].total_cmp(&ll[*b]))
        .unwrap();
    let r = &held[k];
    let max_along = (0..=400)
        .map(|i| map.rate_at(r.at(r.length_m * i as f64 / 400.0)))
        .fold(0.0, f64::max);
    let max_map = map
        .rates_on_lattice(200, 200)
        .into_iter()
        .fold(0.0, f64::max);
    let worst_hit = held
        .iter()
        .zip(&ll)
        .filter(|(r, _)| r.outcome == Outcome::Hit)
        .map(|(_, l)| *l)
        .fold(f64::INFINITY, f64::min);
    println!(
        "    worst ray: {:?}, {:.2} m from {:.2?}, optical depth {:.1} (grid {:.1}), max λ along it \
         {max_along:.3e}, max λ of the map {max_map:.3e}; worst held-back hit {worst_hit:.1}",
        r.outcome,
        r.length_m,
        r.origin,
        map.optical_depth(r),
        grid.ray_log_likelihood(r).min(0.0).abs(),
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(sizes) = args.get(1) else {
        eprintln!("usage: heldback SIZES [LOG…]");
        return;
    };
    let sizes: Vec<usize> = sizes.split(',').map(|s| s.parse().unwrap()).collect();
    let rhos: Vec<Option<f64>> = std::env::var("RHO").map_or(vec![None], |v| {
        v.split(',').map(|s| Some(s.parse().unwrap())).collect()
    });
    let tolerance: f64 = std::env::var("TOL").map_or(1e-3, |t| t.parse().unwrap());
    let verbose = std::env::var_os("VERBOSE").is_some();
    let Some(dir) = raypath_io::data::require("carmen/corrected") else {
        return;
    };
    let mut logs: Vec<String> = args[2..].to_vec();
    if logs.is_empty() {
        logs = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .filter_map(|e| {
                let n = e.file_name().to_string_lossy().into_owned();
                n.strip_suffix("-corrected.log.gz").map(str::to_owned)
            })
            .collect();
        logs.sort();
    }
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    println!(
        "log size ρ[1/m] | LL DCT, LL grid, Δ | worst ray DCT, grid | RMSE DCT, grid | iterations"
    );
    // (size, RHO entry, Δ, RMSE DCT, RMSE grid)
    let mut results: Vec<(usize, usize, f64, f64, f64)> = Vec::new();
    for log in &logs {
        let mut rays = Vec::new();
        for f in read_planar(&dir.join(format!("{log}-corrected.log.gz")), &options).unwrap() {
            rays.extend(f.scan.rays(f.world_from_laser));
        }
        let patch = seeded_patch(&rays, 10.0, 0.75, 9).unwrap();
        let (mapping, held) = draw_rays(&rays, &patch, &RangeLimits::default(), 10_000, 500, 9);
        let extent = patch.extent_m;
        let truth = GroundTruth::new(extent, 0.05, &mapping).unwrap();
        for &n in &sizes {
            let shape = Shape { l: n, m: n };
            let cell = extent[0] / n as f64;
            let grid =
                GridRateMap::from_rays(cell, cells_covering(extent, cell), &mapping).unwrap();
            let init = initial_map(extent, shape, &mapping).unwrap();
            for (ri, rho) in rhos.iter().enumerate() {
                let mut problem = FitProblem::new(extent, shape, &mapping).unwrap();
                match rho {
                    Some(k) if *k < 0.0 => {
                        problem.set_prior_path_density(-k * empirical_bayes_density(&grid, cell))
                    }
                    Some(r) => problem.set_prior_path_density(*r),
                    None => {}
                }
                let config = FitConfig {
                    relative_tolerance: tolerance,
                    ..FitConfig::default()
                };
                let (map, report) = fit(&problem, init.coefficients(), &config).unwrap();
                let (ll, grid_ll) = (map.log_likelihood(&held), grid.log_likelihood(&held));
                let worst =
                    |f: &dyn Fn(&MapRay) -> f64| held.iter().map(f).fold(f64::INFINITY, f64::min);
                let (rmse, grid_rmse) = (
                    truth.rmse(|p| map.rate_at(p)),
                    truth.rmse(|p| grid.rate_at(p)),
                );
                println!(
                    "{log} {n}² {:.3} | {ll:.1}, {grid_ll:.1}, {:.1} | {:.1}, {:.1} | {rmse:.4}, \
                     {grid_rmse:.4} | {}",
                    problem.prior_path_density(),
                    ll - grid_ll,
                    worst(&|r| map.ray_log_likelihood(r)),
                    worst(&|r| grid.ray_log_likelihood(r)),
                    report.iterations
                );
                if verbose {
                    describe_worst(&map, &grid, &held);
                }
                results.push((n, ri, ll - grid_ll, rmse, grid_rmse));
            }
        }
    }
    for &n in &sizes {
        for (ri, rho) in rhos.iter().enumerate() {
            let sel: Vec<_> = results.iter().filter(|x| x.0 == n && x.1 == ri).collect();
            let k = sel.len() as f64;
            let mean = sel.iter().map(|x| x.2).sum::<f64>() / k;
            let std =
                (sel.iter().map(|x| (x.2 - mean).powi(2)).sum::<f64>() / (k - 1.0).max(1.0)).sqrt();
            println!(
                "{n}², ρ {}: Δ mean {mean:.1} σ {std:.1} min {:.1}, DCT higher {}/{}; mean RMSE \
                 DCT {:.4} grid {:.4}",
                rho.map_or("default".to_owned(), |r| r.to_string()),
                sel.iter().map(|x| x.2).fold(f64::INFINITY, f64::min),
                sel.iter().filter(|x| x.2 > 0.0).count(),
                sel.len(),
                sel.iter().map(|x| x.3).sum::<f64>() / k,
                sel.iter().map(|x| x.4).sum::<f64>() / k,
            );
        }
    }
}
