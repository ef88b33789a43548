//! Diagnosis of the geometric check on a corrected CARMEN log: the best checked candidate of
//! every online query, sorted by support, with whether it is a true revisit, the true offset of
//! the two scans and the offset the alignment found.
//!
//! `cargo run --release -p raypath-place-recognition --example check_diagnosis -- LOG [STRIDE]`
//! (environment: `SUPPORT_M`, `TOP_K` override the check's settings).

use raypath_geometry::Pose2;
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use raypath_place_recognition::{
    Exclusion, Frame, GeometricCheck, GeometricCheckConfig, GroundTruth, PlaceRecognizer,
    PolarConfig, PolarContext,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: check_diagnosis LOG [STRIDE]")?;
    let stride: usize = args.get(2).map_or(Ok(1), |s| s.parse())?;
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    let frames: Vec<_> = read_planar(std::path::Path::new(path), &options)?
        .into_iter()
        .step_by(stride)
        .collect();
    let poses: Vec<Pose2> = frames.iter().map(|f| f.world_from_laser).collect();
    let gap = 50;
    let truth = GroundTruth::from_planar_poses(
        &poses,
        None,
        2.0,
        std::f64::consts::PI,
        Exclusion {
            frames: gap,
            seconds: 0.0,
        },
    )?;
    let mut check = GeometricCheck::new(
        PolarContext::new(PolarConfig::default())?,
        GeometricCheckConfig {
            min_support: 0.0,
            support_m: std::env::var("SUPPORT_M").map_or(Ok(0.1), |v| v.parse())?,
            top_k: std::env::var("TOP_K").map_or(Ok(3), |v| v.parse())?,
            ..GeometricCheckConfig::default()
        },
    )?;
    let mut rows = Vec::new();
    let started = std::time::Instant::now();
    for (t, f) in frames.iter().enumerate() {
        let d = check.describe(&Frame::Planar(&f.scan))?;
        let found = check.query(&d, t.saturating_sub(gap));
        check.insert(d);
        if let Some(best) = found.first() {
            let truth_pose = poses[best.frame].inverse() * poses[t];
            let m = check.match_scans(&frames[best.frame].scan, &f.scan);
            rows.push((
                best.score,
                t,
                best.frame,
                truth.is_revisit(t, best.frame),
                truth_pose,
                m.a_from_b,
            ));
        }
    }
    println!(
        "{:.2} ms per query (polar context + check, online)",
        1e3 * started.elapsed().as_secs_f64() / frames.len().max(1) as f64
    );
    let first_false = rows
        .iter()
        .filter(|r| !r.3)
        .map(|r| r.0)
        .fold(0.0, f64::max);
    let above = rows.iter().filter(|r| r.3 && r.0 > first_false).count();
    println!("{above} true best candidates above the best false one ({first_false:.3})");
    rows.sort_by(|a, b| b.0.total_cmp(&a.0));
    println!("support query cand revisit true_dist true_dθ° est_dist est_dθ° pose_err");
    for (s, t, j, ok, tp, ep) in rows.iter().take(12) {
        let err = (tp.inverse() * *ep).translation().norm();
        println!(
            "{s:.3} {t:5} {j:5} {ok:5} {:6.2} {:7.1} {:6.2} {:7.1} {err:6.2}",
            tp.translation().norm(),
            tp.theta().to_degrees(),
            ep.translation().norm(),
            ep.theta().to_degrees()
        );
    }
    Ok(())
}
