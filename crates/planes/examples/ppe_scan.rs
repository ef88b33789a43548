//! Runs PPE on SynPEB-style PCD files and prints the Hoover metrics.
//!
//! `cargo run --release -p raypath-planes --example ppe_scan -- FILE.pcd… [--e E] [--lmax D]`

use std::time::Instant;

use raypath_io::pcd::{ReadOptions, read_pcd};
use raypath_planes::{HooverParams, PpeParams, compare, extract};

fn main() {
    let mut params = PpeParams::synpeb();
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
            _ => files.push(a),
        }
    }
    for f in files {
        let pcd = match read_pcd(std::path::Path::new(&f), &ReadOptions::synpeb()) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("{e}");
                continue;
            }
        };
        let cloud = pcd.cloud;
        let t = Instant::now();
        let seg = match extract(&cloud, &params) {
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
}
