//! The failure case (simulated, Khan Fig. 3.6): a room with reflectivity panels seen with a
//! ±60° field of view from stops facing single walls, matched with the occupancy,
//! reflectivity and combined residuals (and a ±90° control). One unit; it fits the simulated
//! calibration's LUT itself ([`super::simulated_lut`]).

use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use raypath_geometry::Pose2;
use raypath_io::carmen::LaserKind;
use raypath_reflectivity::benchmark::{
    LogScan, aligned_errors, consecutive_relations, relative_errors, run_matcher,
};
use raypath_reflectivity::{
    IntensityCorrection, MapConfig, MatcherConfig, PointFilter, ResidualMode,
};
use raypath_sim::indoor::IntensityModel;
use raypath_sim::rng::stream;
use raypath_sim::scene2::Scene2;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use super::{NAME, SEED, at, error_cells, reference_count, sim, simulated_lut};
use crate::eval::EvalContext;
use crate::table::{Table, fmt_num};

/// The scan rate (Hz).
const RATE_HZ: f64 = 20.0;

/// The unit's result.
#[derive(Debug, Serialize, Deserialize)]
pub(super) struct FailureUnit {
    /// Scans per run.
    pub scans: usize,
    /// Laps of the room.
    pub laps: usize,
    /// The page's JSON rows (`run`, `relative`, `aligned`, `final_error_m`, `scans_per_s`).
    pub rows: Vec<Value>,
}

/// Simulated scans along `truth` with `beams` beams over ±`half_fov_deg`.
fn make_scans(scene: &Scene2, truth: &[Pose2], half_fov_deg: f64, beams: usize) -> Vec<LogScan> {
    let model = IntensityModel::default();
    let mut draw = sim::Draw::new(SEED + 7);
    let mut rng = stream(SEED, 3, beams as u64);
    truth
        .iter()
        .enumerate()
        .map(|(k, pose)| LogScan {
            scan: sim::scan(
                scene,
                pose,
                beams,
                half_fov_deg.to_radians(),
                &model,
                &mut draw,
                &mut rng,
            ),
            world_from_laser: *pose,
            ipc_timestamp_secs: k as f64 / RATE_HZ,
            logger_timestamp_secs: k as f64 / RATE_HZ,
            line: k as u64 + 1,
            kind: LaserKind::RobotLaser1,
        })
        .collect()
}

/// Runs the four matcher runs in the room (the unit `failure-case`); writes the maps of two.
pub(super) fn measure(ctx: &EvalContext) -> Result<FailureUnit> {
    let lut = simulated_lut(reference_count(ctx.quick))?;
    let scene = sim::room(SEED)?;
    let laps = if ctx.quick { 1 } else { 3 };
    let truth = sim::path(laps, RATE_HZ);
    let narrow = make_scans(&scene, &truth, 60.0, 121);
    let wide = make_scans(&scene, &truth, 90.0, 181);
    let runs: [(&str, &[LogScan], ResidualMode, Option<&str>); 4] = [
        (
            "occupancy, ±60°",
            &narrow,
            ResidualMode::Occupancy,
            Some("room-occupancy-60"),
        ),
        (
            "reflectivity, ±60°",
            &narrow,
            ResidualMode::Reflectivity,
            None,
        ),
        (
            "combined, ±60°",
            &narrow,
            ResidualMode::Combined,
            Some("room-combined-60"),
        ),
        (
            "occupancy, ±90° (control)",
            &wide,
            ResidualMode::Occupancy,
            None,
        ),
    ];
    let mut rows = Vec::new();
    for (label, scans, mode, figure) in runs {
        rows.push(run(ctx, &lut, &truth, label, scans, mode, figure)?);
    }
    Ok(FailureUnit {
        scans: truth.len(),
        laps,
        rows,
    })
}

/// One matcher run scored against `truth`: the page's JSON row. Writes the map pictures
/// `<figure>-*.png` when `figure` is given.
fn run(
    ctx: &EvalContext,
    lut: &IntensityCorrection,
    truth: &[Pose2],
    label: &str,
    scans: &[LogScan],
    mode: ResidualMode,
    figure: Option<&str>,
) -> Result<Value> {
    let config = MatcherConfig {
        mode,
        map: MapConfig {
            size_m: 30.0,
            ..MapConfig::default()
        },
        ..MatcherConfig::default()
    };
    let t = Instant::now();
    let (matcher, results) = run_matcher(scans, config, &PointFilter::default(), Some(lut), false)?;
    let seconds = t.elapsed().as_secs_f64();
    if let (Some(file), Some(level)) = (figure, matcher.map().levels().first()) {
        let dir = ctx.figure_dir(NAME)?;
        write_occupancy_png(level, &dir.join(format!("{file}-occupancy.png")))?;
        if mode != ResidualMode::Occupancy {
            raypath_reflectivity::export::write_reflectivity_png(
                level,
                &dir.join(format!("{file}-reflectivity.png")),
            )?;
        }
    }
    // The map frame starts at the first scan: express the estimate in the world frame.
    let start = truth.first().copied().unwrap_or_else(Pose2::identity);
    let est: Vec<Pose2> = results
        .iter()
        .map(|r| start * r.world_from_sensor)
        .collect();
    let relations = consecutive_relations(truth.len());
    let final_err = match (truth.last(), est.last()) {
        (Some(g), Some(e)) => (g.translation() - e.translation()).norm(),
        _ => f64::NAN,
    };
    Ok(json!({
        "run": label,
        "relative": relative_errors(truth, &est, &relations),
        "aligned": aligned_errors(truth, &est),
        "final_error_m": final_err,
        "scans_per_s": scans.len() as f64 / seconds,
    }))
}

/// The section's text, table and pictures.
pub(super) fn markdown(unit: &FailureUnit) -> Result<String> {
    let mut table = Table::new([
        "residual, field of view",
        "rel. transl. mm (mean ± std)",
        "rel. rot. ° (mean ± std)",
        "ATE RMSE m",
        "ATE max m",
        "final error m",
        "scans/s",
    ]);
    for row in &unit.rows {
        let [transl, rot, rmse, max] = error_cells(row, 1000.0, 1, 3);
        table.row([
            row["run"].as_str().unwrap_or_default().to_owned(),
            transl,
            rot,
            rmse,
            max,
            fmt_num(at(row, "/final_error_m"), 3),
            fmt_num(at(row, "/scans_per_s"), 0),
        ]);
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Room [0, 8.5] × [0, 5.5] m, walls of panels 0.3–1.2 m long with ρ ∈ [0.1, 0.9]; {} scans \
         at {RATE_HZ} Hz ({} lap(s)): from the centre to stops 0.7 m in front of each wall's \
         middle, where the robot turns to face the wall (with ±60° only that wall is in view, so \
         the position along it is unobservable from geometry) and pauses 1 s. 0.4 m/s, 0.6 rad/s, \
         σ_r = 1 cm, no odometry (as Hector). ϱ̄ from the LUT above with PCA normals of the scan.\n",
        unit.scans, unit.laps
    );
    let _ = writeln!(md, "{}", table.to_markdown()?);
    let _ = writeln!(
        md,
        "Maps (finest level, 5 cm) after the run: occupancy-only (left: the map smears where \
         the position along a wall slid) and combined (right), and the combined run's mean \
         reflectivity per cell (bottom; brighter = higher ϱ̄).\n\n\
         ![occupancy-only map](scan-matching/room-occupancy-60-occupancy.png) \
         ![combined map](scan-matching/room-combined-60-occupancy.png)\n\n\
         ![reflectivity map](scan-matching/room-combined-60-reflectivity.png)\n"
    );
    Ok(md)
}

/// Writes the occupancy of a level as a PNG (free white, occupied black, unknown grey),
/// cropped to the observed cells.
fn write_occupancy_png(level: &raypath_reflectivity::GridLevel, path: &Path) -> Result<()> {
    let (mut i0, mut j0, mut i1, mut j1) = (usize::MAX, usize::MAX, 0, 0);
    for j in 0..level.height() {
        for i in 0..level.width() {
            if level.log_odds(i, j) != 0.0 {
                (i0, j0, i1, j1) = (i0.min(i), j0.min(j), i1.max(i + 1), j1.max(j + 1));
            }
        }
    }
    if i1 == 0 {
        return Ok(());
    }
    let mut img = image::GrayImage::new((i1 - i0) as u32, (j1 - j0) as u32);
    for (row, j) in (j0..j1).rev().enumerate() {
        for (col, i) in (i0..i1).enumerate() {
            let l = level.log_odds(i, j);
            let v = if l == 0.0 {
                160
            } else {
                (255.0 * (1.0 - raypath_reflectivity::probability(l))) as u8
            };
            img.put_pixel(col as u32, row as u32, image::Luma([v]));
        }
    }
    img.save(path)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
