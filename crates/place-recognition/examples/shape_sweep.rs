//! IBuILD with binary shape descriptors made on the scan (`PlanarDescriptors::Shape`) on a
//! corrected CARMEN log, online, for a list of matching thresholds δ: recall at 100 %
//! precision with and without the geometric check, beside IBuILD on rasterised scans.
//! The ground truth is the evaluation's (2 m, headings within ±90°, 50 frames apart).
//!
//! `cargo run --release -p raypath-place-recognition --example shape_sweep -- LOG STRIDE δ…`
//! (environment: `SPACING_M`, `RADIUS_M` override the descriptor's settings).

use raypath_geometry::Pose2;
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use raypath_place_recognition::{
    Exclusion, GeometricCheck, GeometricCheckConfig, GroundTruth, Ibuild, IbuildConfig,
    IbuildScore, LoopConfig, OwnedFrame, PlaceRecognizer, PlanarDescriptors, ScanShapeConfig,
    online_pr, run_online,
};

type Error = Box<dyn std::error::Error>;

fn env_or(name: &str, default: f64) -> Result<f64, Error> {
    Ok(std::env::var(name).map_or(Ok(default), |v| v.parse())?)
}

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: shape_sweep LOG STRIDE δ…")?;
    let stride: usize = args.get(2).map_or(Ok(1), |s| s.parse())?;
    let deltas: Vec<u32> = args[3.min(args.len())..]
        .iter()
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
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
    let exclusion = Exclusion {
        frames: gap,
        seconds: 0.0,
    };
    let truth = GroundTruth::from_planar_poses(&poses, None, 2.0, std::f64::consts::PI, exclusion)?;
    let scans: Vec<OwnedFrame> = frames
        .into_iter()
        .map(|f| OwnedFrame::Planar(f.scan))
        .collect();
    let shape = ScanShapeConfig {
        keypoint_spacing_m: env_or("SPACING_M", 0.5)?,
        radius_m: env_or("RADIUS_M", 4.0)?,
        ..ScanShapeConfig::default()
    };
    let check = GeometricCheckConfig {
        exclude_recent: gap,
        ..GeometricCheckConfig::default()
    };
    println!("{} scans; shape {shape:?}", scans.len());
    println!("δ score R@100P(plain) R@100P(+check) maxF1(plain) ms/query");
    for &delta in &deltas {
        for score in [IbuildScore::Printed, IbuildScore::Symmetric] {
            let config = IbuildConfig {
                delta,
                score,
                planar: PlanarDescriptors::Shape(shape.clone()),
                ..IbuildConfig::default()
            };
            let (plain, f1, ms) = recall(&mut Ibuild::new(config.clone())?, &scans, &truth, gap)?;
            let (checked, _, _) = recall(
                &mut GeometricCheck::new(Ibuild::new(config)?, check.clone())?,
                &scans,
                &truth,
                gap,
            )?;
            println!(
                "{delta} {score:?} {:.1} {:.1} {f1:.3} {ms:.2}",
                100.0 * plain,
                100.0 * checked
            );
        }
    }
    Ok(())
}

/// Online recall at 100 % precision, max F1 and ms per query.
fn recall<R: PlaceRecognizer>(
    method: &mut R,
    scans: &[OwnedFrame],
    truth: &GroundTruth,
    gap: usize,
) -> Result<(f64, f64, f64), Error> {
    let started = std::time::Instant::now();
    let run = run_online(method, scans.len(), |i| Ok(scans[i].clone()), gap)?;
    let ms = 1e3 * started.elapsed().as_secs_f64() / scans.len().max(1) as f64;
    let s = online_pr(&run.candidates, truth, &LoopConfig::default(), 200)?.summary();
    Ok((s.recall_at_100_precision, s.max_f1, ms))
}
