//! Runs SLAM on a raw log without reference (the large-loop logs: fr-clinic, ual, mit-killian)
//! and prints the loop closures, the loop-search counters and the submap disagreement
//! ([`raypath_slam::benchmark::submap_disagreement`]); with `--png FILE` it paints the map
//! (the finished submaps at their optimised poses, as `cargo xtask eval slam` does) with the
//! trajectory in blue and the accepted loop closures in red (rejected ones in orange).
//!
//! ```text
//! cargo run --release -p raypath-slam --example large_loops -- RAW [--png MAP.png] [--no-loops] [--list]
//! ```

use std::path::PathBuf;
use std::time::Instant;

use raypath_io::sequence::{PlanarOptions, read_planar};
use raypath_slam::benchmark::submap_disagreement;
use raypath_slam::{Slam, SlamConfig, SlamOutput};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |f: &str| args.iter().any(|a| a == f);
    let value = |f: &str| {
        args.iter()
            .position(|a| a == f)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let Some(raw) = args
        .first()
        .filter(|a| !a.starts_with("--"))
        .map(PathBuf::from)
    else {
        eprintln!("usage: large_loops RAW [--png MAP.png] [--no-loops] [--list]");
        return Ok(());
    };
    let frames = read_planar(&raw, &PlanarOptions::default())?;
    let mut config = SlamConfig::default();
    if flag("--no-loops") {
        config.loops = None;
    }
    // Knobs for experiments: SLAM_NO_GATE (no loop consistency test), SLAM_CHI2,
    // SLAM_SUPPORT, SLAM_REF_TRAVEL, SLAM_DRIFT_T, SLAM_DRIFT_R, SLAM_HOLD, SLAM_LSIG_T,
    // SLAM_LSIG_R (degrees): the fields of `ConsistencyConfig`; SLAM_ROT_GROWTH, SLAM_REJECT,
    // SLAM_ANNEAL (the annealing's `max_start`), SLAM_PHI (DCS Φ of loop edges).
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    if env("SLAM_NO_GATE").is_some() {
        config.consistency = None;
    }
    if let Some(c) = config.consistency.as_mut() {
        if let Some(v) = env("SLAM_CHI2") {
            c.chi2_gate = v;
        }
        if let Some(v) = env("SLAM_SUPPORT") {
            c.min_support = v as usize;
        }
        if let Some(v) = env("SLAM_REF_TRAVEL") {
            c.reference_travel_m = v;
        }
        if let Some(v) = env("SLAM_DRIFT_T") {
            c.drift[0] = v;
        }
        if let Some(v) = env("SLAM_DRIFT_R") {
            c.drift[1] = v;
        }
        if let Some(v) = env("SLAM_HOLD") {
            c.hold_travel_m = v;
        }
        if let Some(v) = env("SLAM_LSIG_T") {
            c.loop_sigma[0] = v;
        }
        if let Some(v) = env("SLAM_LSIG_R") {
            c.loop_sigma[1] = v.to_radians();
        }
    }
    if let Some(v) = env("SLAM_TRACK_SCORE") {
        config.tracking.min_score = (v > 0.0).then_some(v);
    }
    if let Some(v) = env("SLAM_RANGE") {
        config.filter.max_range_m = v;
    }
    if let Some(v) = env("SLAM_ROT_GROWTH") {
        config.submaps.rotation_window_growth = v;
    }
    if let Some(v) = env("SLAM_REJECT") {
        config.reject_weight = v;
    }
    if let (Some(v), Some(a)) = (env("SLAM_ANNEAL"), config.solver.annealing.as_mut()) {
        a.max_start = v;
    }
    if let Some(v) = env("SLAM_PHI") {
        config.solver.loop_kernel = raypath_slam::graph::RobustKernel::Dcs { phi: v };
    }
    let t0 = Instant::now();
    let mut slam = Slam::new(config)?;
    for f in &frames {
        slam.process(f)?;
    }
    let out = slam.finish()?;
    let secs = t0.elapsed().as_secs_f64();
    let (d, compared) = submap_disagreement(&out);
    println!(
        "{} scans, {} nodes, {} submaps, {} loop closures ({} rejected) in {secs:.1} s; \
         submap disagreement {:.2} % of {compared} cells",
        out.scans.len(),
        out.nodes.len(),
        out.submaps.len(),
        out.loop_closures.len(),
        out.rejected_loop_closures.len(),
        100.0 * d
    );
    println!("{:?}", out.stats);
    if flag("--list") {
        for (kind, list) in [
            ("accepted", &out.loop_closures),
            ("rejected", &out.rejected_loop_closures),
        ] {
            for c in list.iter() {
                let (a, b) = (out.nodes[c.anchor], out.nodes[c.node]);
                println!(
                    "{kind} node {} (scan {}) -> submap {} (anchor {}, scan {}) score {:.3} {:?} \
                     weight {:.2} span {:.1} m",
                    c.node,
                    out.node_scan[c.node],
                    c.submap,
                    c.anchor,
                    out.node_scan[c.anchor],
                    c.score,
                    c.source,
                    out.graph.edge_weight(c.edge),
                    (a.translation() - b.translation()).norm(),
                );
            }
        }
    }
    if let Some(png) = value("--png") {
        write_png(&out, &PathBuf::from(png))?;
    }
    Ok(())
}

/// Pixel size of the picture, metres.
const PIXEL_M: f64 = 0.1;

fn write_png(out: &SlamOutput, path: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    let mut cells: Vec<(f32, f64, f64)> = Vec::new();
    for s in &out.submaps {
        let (Some(pose), Some(level)) = (out.nodes.get(s.anchor()), s.levels().first()) else {
            continue;
        };
        let (res, o) = (level.resolution_m(), level.origin());
        for j in (0..level.height()).step_by(2) {
            for i in (0..level.width()).step_by(2) {
                let l = level.log_odds(i, j);
                if l != 0.0 {
                    let p = *pose
                        * nalgebra::Point2::new(
                            o[0] + (i as f64 + 0.5) * res,
                            o[1] + (j as f64 + 0.5) * res,
                        );
                    cells.push((l, p.x, p.y));
                }
            }
        }
    }
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for &(_, x, y) in &cells {
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    let w = (((x1 - x0) / PIXEL_M) as usize + 1).min(4000);
    let h = (((y1 - y0) / PIXEL_M) as usize + 1).min(4000);
    let mut sum = vec![0f32; w * h];
    let pix = |x: f64, y: f64| {
        let i = ((x - x0) / PIXEL_M).clamp(0.0, (w - 1) as f64) as usize;
        let j = ((y1 - y) / PIXEL_M).clamp(0.0, (h - 1) as f64) as usize;
        (i, j)
    };
    for &(l, x, y) in &cells {
        let (i, j) = pix(x, y);
        sum[j * w + i] += l.clamp(-2.0, 4.0);
    }
    let mut img = image::RgbImage::from_fn(w as u32, h as u32, |i, j| {
        let v = sum[j as usize * w + i as usize];
        let g = if v > 1.0 {
            0
        } else if v < -0.5 {
            255
        } else {
            200
        };
        image::Rgb([g, g, g])
    });
    let mut line = |a: (f64, f64), b: (f64, f64), colour: [u8; 3]| {
        let n = (((b.0 - a.0).hypot(b.1 - a.1) / PIXEL_M) as usize).max(1);
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let (i, j) = pix(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            img.put_pixel(i as u32, j as u32, image::Rgb(colour));
        }
    };
    for p in out.nodes.windows(2) {
        line((p[0].x(), p[0].y()), (p[1].x(), p[1].y()), [60, 90, 255]);
    }
    for (list, colour) in [
        (&out.rejected_loop_closures, [255, 150, 0]),
        (&out.loop_closures, [230, 0, 0]),
    ] {
        for c in list.iter() {
            let (a, b) = (out.nodes[c.anchor], out.nodes[c.node]);
            line((a.x(), a.y()), (b.x(), b.y()), colour);
        }
    }
    img.save(path)?;
    println!("map: {}", path.display());
    Ok(())
}
