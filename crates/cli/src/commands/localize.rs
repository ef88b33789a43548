//! `raypath localize`: Monte-Carlo localization of a 2-D log on a map written by
//! `raypath map`.
//!
//! The map file (`raypath_sensor_models::export::binary`) holds per-cell statistics and
//! names a sensor model; the command builds that model (or `--model-override`), reads the
//! log's laser scans and odometry through `raypath_io::sequence` (a CARMEN log, `--laser`
//! front by default, or a rosbag2 bag's LaserScan topic with its odometry; the robot's
//! `world_from_robot` of each scan: wheel odometry in a raw log, corrected poses in a
//! corrected log; only increments are used), and runs the particle filter of
//! `raypath_localizer` (`lidar::track_planar`). With `--ground-truth` (a corrected CARMEN log,
//! a bag — its reference poses, else its logged poses — or a TUM pose file `t x y z qx qy qz
//! qw`) it evaluates the estimates every 1 m of ground-truth path and prints the error
//! summary.
//!
//! Initial particles: Gaussian (σ 1 m, 0.1 rad) around `--initial`, else the ground truth
//! at the first scan, else the log's first pose (right for corrected logs).
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record`): the map's picture values as
//! the `FLOAT32` Grid `/map` (at the first scan's time), every estimated scan at the estimate
//! (`/tf` `map → base_link`, `/scan` in `base_link`), the estimates as `/trajectory` and the
//! ground truth as `/ground_truth`.

use std::path::{Path, PathBuf};

use raypath_geometry::Pose2;
use raypath_io::foxglove::{GridValues, topic};
use raypath_io::sequence::PlanarFrame;
use raypath_localizer::eval::{EvaluationConfig, evaluate_trajectory};
use raypath_localizer::init::GaussianInit;
use raypath_localizer::lidar::{
    LidarConfig, LocalizeReport, ModelKind, ModelSpec, PlanarStep, Scan2Measurement, TrackConfig,
    track_planar,
};
use raypath_localizer::{PoseTrack, Stamped};
use raypath_sensor_models::DenseStats2;
use raypath_sensor_models::OpticalDepthConfig;
use raypath_sensor_models::export::{MapFile, MapKind, MapPicture, StoredStats, picture_values};

use super::Failure;
use super::record::{RecordArgs, Recording};
use super::source_args::{SourceArgs, is_bag, reference_track};

/// Largest gap between a ground-truth stamp and a scan stamp that pairs them (the corrected
/// CARMEN logs print the raw logger stamp with fewer digits), seconds.
const MATCH_TOLERANCE_SECS: f64 = 2e-3;

/// Values of `--model-override`: the sensor models `raypath_localizer` builds from a map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelArg {
    /// Decay-rate model (Schaefer 2020, Sec. 7.4), λ = H / R.
    DecayRate,
    /// Reflection model (Sec. 7.5.2), μ = H / (H + M).
    Reflection,
    /// Endpoint model: the likelihood field normalized per ray (Sec. 7.6.2).
    Endpoint,
    /// AMCL's likelihood field, unnormalized.
    LikelihoodField,
    /// Log-odds occupancy used as a reflection-type model.
    LogOdds,
}

impl From<ModelArg> for ModelKind {
    fn from(model: ModelArg) -> Self {
        match model {
            ModelArg::DecayRate => ModelKind::DecayRate,
            ModelArg::Reflection => ModelKind::Reflection,
            ModelArg::Endpoint => ModelKind::Endpoint,
            ModelArg::LikelihoodField => ModelKind::LikelihoodField,
            ModelArg::LogOdds => ModelKind::LogOdds,
        }
    }
}

/// Arguments of `raypath localize`.
#[derive(clap::Args)]
pub struct Args {
    /// The binary map written by `raypath map` (2-D).
    #[arg(long, value_name = "M")]
    pub map: PathBuf,
    /// A CARMEN log with laser scans and odometry (raw, or corrected), or a rosbag2 bag
    /// (directory with metadata.yaml, or .mcap file) with LaserScan and odometry.
    #[arg(long, value_name = "L")]
    pub log: PathBuf,
    /// Ground truth: a corrected CARMEN log, a bag (its reference poses) or a TUM pose file,
    /// matched by time.
    #[arg(long, value_name = "G")]
    pub ground_truth: Option<PathBuf>,
    /// Number of particles.
    #[arg(long, default_value_t = 1000)]
    pub particles: usize,
    /// Random seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Use this model instead of the one the map names.
    #[arg(long, value_enum, value_name = "MODEL")]
    pub model_override: Option<ModelArg>,
    /// Traverse the grid exactly instead of using optical-depth tables (slower).
    #[arg(long)]
    pub exact: bool,
    /// Use every k-th beam.
    #[arg(long, default_value_t = 1)]
    pub beam_step: usize,
    /// The scan counts as this many independent beams (likelihood exponent; 0 = none).
    #[arg(long, default_value_t = 8.0)]
    pub effective_beams: f64,
    /// Initial pose `x,y,theta` (map frame, metres and radians).
    #[arg(long, value_name = "X,Y,THETA", allow_hyphen_values = true)]
    pub initial: Option<String>,
    /// Write the estimates as a TUM trajectory (`t x y z qx qy qz qw`).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// How to read the log and the ground truth.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// Reads a TUM file `t x y z qx qy qz qw` (through `raypath_io::tum`), keeping x, y and the
/// yaw.
fn read_tum(path: &Path) -> Result<Vec<(f64, Pose2)>, Failure> {
    let out: Vec<(f64, Pose2)> = raypath_io::tum::read_tum(path)
        .map_err(Failure::input)?
        .into_iter()
        .map(|p| (p.time_s, p.pose.to_planar()))
        .collect();
    if out.is_empty() {
        return Err(Failure::input(format!(
            "{}: no poses (neither a CARMEN log with laser scans nor a TUM file)",
            path.display()
        )));
    }
    Ok(out)
}

fn parse_initial(text: &str) -> Result<Pose2, Failure> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| Failure::input(format!("--initial {text:?}: expected x,y,theta")))?;
    match v[..] {
        [x, y, theta] if v.iter().all(|c| c.is_finite()) => Ok(Pose2::new(x, y, theta)),
        _ => Err(Failure::input(format!(
            "--initial {text:?}: expected three finite numbers x,y,theta"
        ))),
    }
}

/// The ground truth as `(stamp, world_from_robot)`, strictly increasing in time: the
/// reference poses of a planar source (a bag, or a CARMEN log with laser scans), else a TUM
/// file.
fn read_ground_truth(
    path: &Path,
    source: &SourceArgs,
    robot_from_laser: Pose2,
) -> Result<Vec<(f64, Pose2)>, Failure> {
    let to_robot = |frames: Vec<PlanarFrame>| -> Vec<(f64, Pose2)> {
        let track = reference_track(&frames);
        frames
            .iter()
            .zip(track)
            .filter_map(|(f, pose)| Some((f.stamp_secs, pose? * robot_from_laser.inverse())))
            .collect()
    };
    let planar = if is_bag(path) {
        let poses = to_robot(source.read_frames(path).map_err(Failure::input)?);
        if poses.is_empty() {
            return Err(Failure::input(format!("{}: no poses", path.display())));
        }
        Some(poses)
    } else {
        // Not a CARMEN log with laser scans: a TUM file.
        source
            .read_frames(path)
            .ok()
            .map(to_robot)
            .filter(|poses| !poses.is_empty())
    };
    let mut poses = match planar {
        Some(poses) => poses,
        None => read_tum(path)?,
    };
    poses.sort_by(|a, b| a.0.total_cmp(&b.0));
    poses.dedup_by(|b, a| b.0 <= a.0);
    Ok(poses)
}

/// Runs `raypath localize`.
pub fn run(args: &Args) -> Result<(), Failure> {
    let json = super::console::json();
    if args.particles == 0 {
        return Err(Failure::input("--particles must be at least 1"));
    }
    if args.beam_step == 0 {
        return Err(Failure::input("--beam-step must be at least 1"));
    }
    if !(args.effective_beams.is_finite() && args.effective_beams >= 0.0) {
        return Err(Failure::input(
            "--effective-beams must be a finite number ≥ 0",
        ));
    }
    let initial = args.initial.as_deref().map(parse_initial).transpose()?;
    let mut recording = Recording::open(&args.record)?;
    let map = MapFile::read_file(&args.map).map_err(Failure::input)?;
    let StoredStats::Planar(stats) = &map.stats else {
        return Err(Failure::input(format!(
            "{}: a 3-D map; raypath localize handles 2-D maps",
            args.map.display()
        )));
    };
    let kind = match args.model_override {
        Some(model) => model.into(),
        None => match map.kind {
            MapKind::Statistics | MapKind::DecayRate => ModelKind::DecayRate,
            MapKind::Reflection => ModelKind::Reflection,
            MapKind::LogOdds => ModelKind::LogOdds,
            MapKind::LikelihoodField => ModelKind::LikelihoodField,
        },
    };
    let spec = ModelSpec {
        kind,
        posterior: map.posterior,
        tabulated: (!args.exact).then(OpticalDepthConfig::default),
    };
    let model = spec
        .build(stats, map.mapping.range)
        .map_err(|e| Failure::input(format!("{}: {e}", args.map.display())))?;

    let scans = args.source.read_frames(&args.log).map_err(Failure::input)?;
    let Some(first) = scans.first() else {
        return Err(Failure::input(format!(
            "{}: no laser scans",
            args.log.display()
        )));
    };
    let robot_from_laser = first.robot_from_laser();
    let ground_truth = args
        .ground_truth
        .as_deref()
        .map(|g| read_ground_truth(g, &args.source, robot_from_laser))
        .transpose()?;

    let gt_stamps: Vec<f64> = ground_truth.iter().flatten().map(|g| g.0).collect();
    let near_truth = |t: f64| {
        let i = gt_stamps.partition_point(|s| *s < t);
        [i.wrapping_sub(1), i]
            .iter()
            .filter_map(|&j| gt_stamps.get(j))
            .any(|s| (s - t).abs() <= MATCH_TOLERANCE_SECS)
    };
    let first_stamp = first.stamp_secs;
    let first_odometry = first.world_from_robot;
    let steps: Vec<PlanarStep> = scans
        .into_iter()
        .map(|f| PlanarStep {
            stamp_secs: f.stamp_secs,
            odom_from_robot: f.world_from_robot,
            force_update: near_truth(f.stamp_secs),
            scan: f.scan,
        })
        .collect();
    let truth_track = match &ground_truth {
        Some(g) => Some(
            PoseTrack::new(g.iter().map(|(t, p)| Stamped::new(*t, *p))).map_err(|e| {
                Failure::input(format!(
                    "{}: {e}",
                    args.ground_truth
                        .as_deref()
                        .unwrap_or(Path::new(""))
                        .display()
                ))
            })?,
        ),
        None => None,
    };
    let start = initial.unwrap_or_else(|| match &truth_track {
        Some(track) => track
            .pose_at(first_stamp)
            .unwrap_or_else(|_| track.poses().first().copied().unwrap_or(first_odometry)),
        None => first_odometry,
    });
    let lidar = LidarConfig {
        beam_step: args.beam_step,
        effective_beams: (args.effective_beams > 0.0).then_some(args.effective_beams),
        ..LidarConfig::default()
    };
    let measurement =
        Scan2Measurement::new(model.as_ref(), robot_from_laser, lidar).map_err(Failure::input)?;
    let config = TrackConfig {
        particles: args.particles,
        ..TrackConfig::default()
    };
    let spinner = super::console::spinner("localization");
    let started = std::time::Instant::now();
    let result = track_planar(
        &steps,
        &measurement,
        &GaussianInit::new(start),
        &config,
        args.seed,
    )
    .map_err(|e| Failure::input(format!("{}: {e}", args.log.display())))?;
    spinner.finish_and_clear();
    super::console::stage("localization", started);

    if let Some(out) = &args.out {
        raypath_io::tum::write_planar_tum(
            out,
            Some("raypath localize: t x y z qx qy qz qw (world_from_robot, map frame)"),
            result.estimates.iter().map(|(_, s)| (s.stamp_secs, s.pose)),
        )
        .map_err(Failure::internal)?;
    }
    // With ground truth paired to scans, evaluate the estimates at those scans only: between
    // them both tracks are interpolated over the same stamps.
    let paired = steps.iter().any(|s| s.force_update);
    let estimate_track = PoseTrack::new(
        result
            .estimates
            .iter()
            .filter(|(i, _)| !paired || steps.get(*i).is_some_and(|s| s.force_update))
            .map(|(_, s)| *s),
    )
    .map_err(Failure::internal)?;
    let evaluation = match &truth_track {
        Some(truth) => Some(
            evaluate_trajectory(truth, &estimate_track, &EvaluationConfig::default())
                .map_err(Failure::internal)?,
        ),
        None => None,
    };
    if let Some(recording) = &mut recording {
        let truth = truth_track
            .as_ref()
            .map(PoseTrack::poses)
            .unwrap_or_default();
        record(
            recording,
            stats,
            map.kind,
            &steps,
            &result.estimates,
            robot_from_laser,
            truth,
        )?;
    }
    let report = LocalizeReport::new(
        (
            args.map.display().to_string(),
            args.log.display().to_string(),
            spec.label(),
        ),
        args.particles,
        args.seed,
        steps.len(),
        &result,
        evaluation.as_ref(),
    );
    if json {
        let mut summary = super::to_json(&report)?;
        super::record::finish(recording, Some(&mut summary))?;
        println!("{summary:#}");
    } else {
        println!(
            "{}: {} scans, {} updates ({} failed), {} particles, model {}",
            args.log.display(),
            steps.len(),
            result.updates,
            result.failed_updates,
            args.particles,
            spec.label()
        );
        if let Some(e) = &evaluation {
            println!(
                "error over {:.1} m ({} points): position mean {:.3} m, RMSE {:.3} m; heading mean {:.2}°, RMSE {:.2}°; diverged: {} ({} episodes, {:.1} % of the time)",
                e.length_m,
                e.points.len(),
                e.position_m.mean_abs,
                e.position_m.rmse,
                e.heading_rad.mean_abs.to_degrees(),
                e.heading_rad.rmse.to_degrees(),
                if e.divergence.diverged() { "yes" } else { "no" },
                e.divergence.episodes,
                100.0 * e.divergence.fraction_of_time
            );
        }
        super::record::finish(recording, None)?;
    }
    Ok(())
}

/// `--record`: the map at the first scan's time, each estimated scan at its estimate, the
/// estimated trajectory and the ground truth.
fn record(
    recording: &mut Recording,
    stats: &DenseStats2,
    kind: MapKind,
    steps: &[PlanarStep],
    estimates: &[(usize, Stamped<Pose2>)],
    robot_from_laser: Pose2,
    truth: &[Pose2],
) -> Result<(), Failure> {
    let (picture, field) = match kind {
        MapKind::Reflection => (MapPicture::Reflection, "reflection"),
        MapKind::LogOdds | MapKind::LikelihoodField => (MapPicture::Occupancy, "occupancy"),
        MapKind::Statistics | MapKind::DecayRate => (MapPicture::DecayRate, "hit_probability"),
    };
    let values: Vec<f32> = picture_values(stats, picture)
        .into_iter()
        .map(|v| v.map_or(f32::NAN, |v| v as f32))
        .collect();
    let start = steps.first().map_or(0.0, |s| s.stamp_secs);
    recording.grid(
        topic::MAP,
        start,
        stats.grid(),
        field,
        GridValues::F32(&values),
    )?;
    for (i, estimate) in estimates {
        if let Some(step) = steps.get(*i) {
            recording.planar_scan(
                estimate.stamp_secs,
                &estimate.pose,
                &robot_from_laser,
                &step.scan,
            )?;
        }
    }
    let end = recording.end_stamp();
    let poses: Vec<Pose2> = estimates.iter().map(|(_, s)| s.pose).collect();
    recording.planar_trajectory(topic::TRAJECTORY, end, &poses)?;
    if !truth.is_empty() {
        recording.planar_trajectory(topic::GROUND_TRUTH, end, truth)?;
    }
    Ok(())
}
