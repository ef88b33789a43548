//! Per-relation diagnosis of a SLAM run against a benchmark relation file: one CSV row per
//! relation with its scans, time gap, the estimate's error, and how far the file's relation
//! sits from its own scans (point-to-line ICP of the two scans started at the file's relation,
//! `raypath_slam::benchmark::refine`).
//!
//! ```text
//! cargo run --release -p raypath-slam --example relation_diagnosis -- RAW.clf REL.relations OUT.csv
//! ```

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use raypath_geometry::Pose2;
use raypath_io::relations::read_relations;
use raypath_io::sequence::{PlanarOptions, read_planar};
use raypath_slam::benchmark::{
    RefineConfig, Refusal, file_relation_errors, match_relation_file, refine,
};
use raypath_slam::{Slam, SlamConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    let [raw, rel, out] = args.as_slice() else {
        eprintln!("usage: relation_diagnosis RAW REL OUT.csv");
        return Ok(());
    };
    let frames = read_planar(raw, &PlanarOptions::default())?;
    let mut config = SlamConfig::default();
    if let Ok(v) = std::env::var("SLAM_RES") {
        config.matcher.map.finest_resolution_m = v.parse()?;
    }
    if std::env::var("SLAM_NO_POLISH").is_ok() {
        config.polish = None;
    }
    if let (Some(p), Ok(v)) = (config.polish.as_mut(), std::env::var("POLISH_N")) {
        p.neighbours = v.parse()?;
    }
    if let (Some(p), Ok(v)) = (config.polish.as_mut(), std::env::var("POLISH_REV")) {
        p.revisits = v.parse()?;
    }
    if let (Some(p), Ok(v)) = (config.polish.as_mut(), std::env::var("POLISH_EFF")) {
        p.effective_points = v.parse()?;
    }
    let t0 = Instant::now();
    let mut slam = Slam::new(config)?;
    for f in &frames {
        slam.process(f)?;
    }
    let output = slam.finish()?;
    eprintln!(
        "slam {:.1} s: {} scans, {} nodes; polish {:.2} s, {} edges",
        t0.elapsed().as_secs_f64(),
        output.scans.len(),
        output.nodes.len(),
        output.stats.polish_seconds,
        output.stats.polish_edges
    );
    let est = &output.world_from_sensor;
    let stamps: Vec<_> = frames.iter().map(|f| f.ipc_stamp_secs).collect();
    let matched = match_relation_file(&stamps, &read_relations(rel)?);
    eprintln!(
        "summary {:?}, unmatched {}",
        file_relation_errors(est, &matched),
        matched.unmatched
    );
    let config = RefineConfig::default();
    let mut w = std::io::BufWriter::new(std::fs::File::create(out)?);
    writeln!(
        w,
        "i,j,dt,node_i,node_j,dist,dtheta,err_t,err_r,icp,file_icp_t,file_icp_r,est_icp_t,est_icp_r,spin_i,spin_j"
    )?;
    let spin = |k: usize| {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(est.len() - 1));
        let dt = frames[b].stamp_secs - frames[a].stamp_secs;
        let d = (est[a].inverse() * est[b]).theta().abs();
        if dt > 0.0 { d / dt } else { 0.0 }
    };
    for &(i, j, a_from_b) in &matched.relations {
        let e = a_from_b.inverse() * (est[i].inverse() * est[j]);
        let dt = (frames[j].stamp_secs - frames[i].stamp_secs).abs();
        let refined = refine(&frames[i].scan, &frames[j].scan, a_from_b, &config);
        let (status, ft, fr, et, er) = match refined {
            Ok(p) => {
                let f = a_from_b.inverse() * p;
                let g = p.inverse() * (est[i].inverse() * est[j]);
                (
                    "ok",
                    f.translation().norm(),
                    f.theta().abs(),
                    g.translation().norm(),
                    g.theta().abs(),
                )
            }
            Err(r) => (
                match r {
                    Refusal::Unaligned => "unaligned",
                    Refusal::Ambiguous => "ambiguous",
                    Refusal::Unconstrained => "unconstrained",
                    Refusal::Unsupported => "unsupported",
                    Refusal::FarFromReference => "far",
                },
                f64::NAN,
                f64::NAN,
                f64::NAN,
                f64::NAN,
            ),
        };
        writeln!(
            w,
            "{i},{j},{dt:.3},{},{},{:.4},{:.4},{:.5},{:.6},{status},{ft:.5},{fr:.6},{et:.5},{er:.6},{:.4},{:.4}",
            output.scans[i].node,
            output.scans[j].node,
            a_from_b.translation().norm(),
            a_from_b.theta(),
            e.translation().norm(),
            e.theta().abs(),
            spin(i),
            spin(j)
        )?;
    }
    let _ = Pose2::identity();
    Ok(())
}
