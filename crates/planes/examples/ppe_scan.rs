//! Runs PPE on SynPEB-style PCD files and prints the Hoover metrics.
//!
//! `cargo run --release -p raypath-planes --example ppe_scan -- FILE.pcd… [--e E] [--lmax D]`

use std::time::Instant;

use raypath_io::pcd::{ReadOptions, read_pcd};
use raypath_planes::{HooverParams, PeacParams, PpeParams, compare, extract, peac};

fn main() {
    let mut params = PpeParams::synpeb();
    let mut peac_params: Option<PeacParams> = None;
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--e" => {
                params.max_increment_m2 = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(params.max_increment_m2)
            }
            "--lmax" => {
                params.l_max_m = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(params.l_max_m)
            }
            "--refine" => {
                params.refine_rounds = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(params.refine_rounds)
            }
            "--min" => {
                params.min_points = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(params.min_points)
            }
            "--peac" => {
                let v: Vec<f64> = args
                    .next()
                    .unwrap_or_default()
                    .split(',')
                    .filter_map(|x| x.parse().ok())
                    .collect();
                let mut p = PeacParams::synpeb();
                if let [init, merge, minp, disc, sig] = v[..] {
                    p.init_tol_m = init;
                    p.merge_tol_m = merge;
                    p.min_points = minp as usize;
                    p.discontinuity_rel = disc;
                    p.depth_sigma_per_m = sig;
                }
                peac_params = Some(p);
            }
            _ => files.push(a),
        }
    }
    let mut sums = [0.0f64; 8];
    for f in files {
        let pcd = match read_pcd(std::path::Path::new(&f), &ReadOptions::synpeb()) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("{e}");
                continue;
            }
        };
        let cloud = pcd.cloud;
        let pts: Vec<nalgebra::Vector3<f64>> = cloud
            .points
            .iter()
            .map(|p| p.coords.cast::<f64>())
            .collect();
        let t = Instant::now();
        let result = match &peac_params {
            Some(pp) => peac(&pts, cloud.width, cloud.height, pp),
            None => extract(&cloud, &params),
        };
        let seg = match result {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{f}: {e}");
                continue;
            }
        };
        let secs = t.elapsed().as_secs_f64();
        let gt: Vec<Option<u32>> = cloud
            .label
            .clone()
            .unwrap_or_default()
            .into_iter()
            .map(Some)
            .collect();
        let Ok(h) = compare(&gt, &seg.labels, &HooverParams::default()) else {
            continue;
        };
        for (s, v) in sums.iter_mut().zip([
            1.0,
            100.0 * h.fraction_correct(),
            100.0 * h.k_value(),
            1000.0 * seg.rmse_m(),
            h.over as f64,
            h.missed as f64,
            h.noise as f64,
            secs,
        ]) {
            *s += v;
        }
        println!(
            "{f}: {}x{} planes {} f {:.1}% k {:.1}% rmse {:.1} mm n_o {} n_u {} n_m {} n_s {} ({} GT) {:.3} s",
            cloud.width,
            cloud.height,
            seg.planes.len(),
            100.0 * h.fraction_correct(),
            100.0 * h.k_value(),
            1000.0 * seg.rmse_m(),
            h.over,
            h.under,
            h.missed,
            h.noise,
            h.gt_regions,
            secs
        );
    }
    let n = sums[0].max(1.0);
    println!(
        "MEAN of {}: f {:.1} k {:.1} rmse {:.1} n_o {:.1} n_m {:.1} n_s {:.1} t {:.3}",
        sums[0],
        sums[1] / n,
        sums[2] / n,
        sums[3] / n,
        sums[4] / n,
        sums[5] / n,
        sums[6] / n,
        sums[7] / n
    );
}
