//! Runs PPE on SynPEB-style PCD files and prints the Hoover metrics.
//!
//! `cargo run --release -p raypath-planes --example ppe_scan -- FILE.pcd… [--e E] [--lmax D]
//! [--refine R] [--min M] [--peac INIT,MERGE,MIN,DISC,SIG] [--hash]`
//!
//! `--hash` adds a fingerprint of each segmentation (FNV-1a of the labels, the step count
//! and id-weighted sums of the plane parameters) to compare two builds of PPE.

use std::time::Instant;

use raypath_io::pcd::{ReadOptions, read_pcd};
use raypath_planes::{HooverParams, PeacParams, PpeParams, compare, extract, peac};

fn main() {
    let mut params = PpeParams::synpeb();
    let mut peac_params: Option<PeacParams> = None;
    let mut files = Vec::new();
    let mut hash = false;
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
            "--hash" => hash = true,
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
        if hash {
            println!("{f}: {}", fingerprint(&seg));
        }
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

/// FNV-1a of the labels, the step count and id-weighted sums of the plane parameters.
fn fingerprint(seg: &raypath_planes::Segmentation) -> String {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for l in &seg.labels {
        for byte in l.unwrap_or(u32::MAX).to_le_bytes() {
            h = (h ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    let w_sum: f64 = seg
        .planes
        .iter()
        .enumerate()
        .map(|(i, p)| (i + 1) as f64 * (p.fit.w.x + 2.0 * p.fit.w.y + 3.0 * p.fit.w.z))
        .sum();
    format!(
        "labels {h:016x} steps {} w_sum {w_sum:.12e} sse {:.12e}",
        seg.steps,
        seg.sse()
    )
}
