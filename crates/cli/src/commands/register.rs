//! `raypath register`: 3-D scan registration (`raypath_registration`) — two scans by
//! point-to-plane ICP, or a whole sequence by KISS-ICP-style odometry.
//!
//! ```text
//! raypath register <source> <target> [--json]       two scans (.bin, .pcd, x y z text)
//! raypath register <sequence> [--frames N] [--out poses.txt] [--json]
//!                  [--voxel-size M] [--max-range M] [--min-range M] [--kernel gm|huber|none]
//! ```
//!
//! **Two scans** (each in its sensor frame: a KITTI velodyne `.bin`, a PCD file or an `x y z`
//! point list): registers `source` to `target` from the identity and prints
//! `target_from_source` (translation, roll/pitch/yaw, quaternion), iterations, convergence,
//! fitness (share of the source's thinned points with a correspondence) and RMSE
//! (point-to-plane, metres).
//!
//! **A sequence** (a KITTI sequence directory, an NCLT session, an Ouster capture with its
//! metadata JSON, or a rosbag2 bag's PointCloud2 topic, read through
//! `raypath_io::sequence::SweepSequence`): the odometry over its sweeps, with per frame the
//! pose, iterations and time; when the sequence has reference poses (KITTI `poses.txt`
//! through `calib.txt`'s `Tr`, an Ouster `_poses_kitti.txt`), the error of each estimated
//! relative pose against the reference's (rotation °, translation m) and their summary.
//! `--out FILE` writes the estimated poses in the KITTI layout (12 numbers a line,
//! `world_from_sensor` with the first scan's sensor frame as the world).
//!
//! `--json` prints one object: for two scans `{"mode": "pair", "source", "target",
//! "target_from_source": {"translation_m", "rotation_xyzw", "rpy_deg"}, "iterations",
//! "converged", "fitness", "rmse_m", "correspondences", "source_points", "seconds"}`; for a
//! sequence `{"mode": "sequence", "input", "frames", "steps": [{"frame", "translation_m",
//! "rotation_xyzw", "iterations", "converged", "fitness", "rmse_m", "sigma_m", "seconds",
//! "error": {"rotation_deg", "translation_m", "distance_m"} | null}], "summary":
//! {"pairs", "rotation_error_deg_mean", "rotation_error_deg_max", "translation_error_m_mean",
//! "translation_error_m_max", "translation_error_percent", "seconds_median"} | null, "out"}`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use raypath_geometry::{PointCloud, Pose3};
use raypath_registration::report::{
    PairReport, SequenceReport, SequenceSummary, StepError, StepReport,
};
use raypath_registration::{Kernel, Odometry, OdometryConfig, RegistrationConfig, register};

use super::Failure;
use super::source_args::{SourceArgs, is_bag};

/// `--kernel`: the robust kernel of the point-to-plane residuals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum KernelArg {
    /// Geman–McClure (KISS-ICP's kernel; also spelled geman-mcclure).
    #[value(alias = "geman-mcclure")]
    Gm,
    /// Huber: linear beyond the scale.
    Huber,
    /// None: plain least squares.
    None,
}

/// Arguments of `raypath register`.
#[derive(clap::Args)]
pub struct Args {
    /// The source scan (.bin, .pcd, x y z text), or a sequence: a KITTI sequence directory,
    /// an NCLT session, an Ouster .pcap (metadata JSON beside it) or a rosbag2 bag.
    pub input: PathBuf,
    /// The target scan (two-scan mode).
    pub target: Option<PathBuf>,
    /// Sequences: register at most this many sweeps.
    #[arg(long, value_name = "N")]
    pub frames: Option<usize>,
    /// Sequences: write the estimated poses here (KITTI layout).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Voxel size v, metres (map grid v/2, source grid 1.5 v).
    #[arg(long, default_value_t = 1.0, value_name = "M")]
    pub voxel_size: f64,
    /// Drop returns farther than this from the sensor, metres.
    #[arg(long, default_value_t = 100.0, value_name = "M")]
    pub max_range: f64,
    /// Drop returns closer than this to the sensor, metres.
    #[arg(long, default_value_t = 0.0, value_name = "M")]
    pub min_range: f64,
    /// Robust kernel.
    #[arg(long, value_enum, default_value_t = KernelArg::Gm, value_name = "NAME")]
    pub kernel: KernelArg,
    /// How to read a bag.
    #[command(flatten)]
    pub source: SourceArgs,
}

fn config(args: &Args) -> Result<RegistrationConfig, Failure> {
    let kernel = match args.kernel {
        KernelArg::Gm => Kernel::GemanMcClure,
        KernelArg::Huber => Kernel::Huber,
        KernelArg::None => Kernel::None,
    };
    let config = RegistrationConfig {
        voxel_size_m: args.voxel_size,
        max_range_m: args.max_range,
        min_range_m: args.min_range,
        kernel,
        ..RegistrationConfig::default()
    };
    config.validate().map_err(Failure::input)?;
    Ok(config)
}

/// One scan file in its sensor frame ([`raypath_io::read_cloud`]).
fn read_scan(path: &Path) -> Result<PointCloud, Failure> {
    raypath_io::read_cloud(path).map_err(|e| match e {
        raypath_io::Error::UnknownFormat { .. } => {
            Failure::input(format!("{e} (or a sequence alone)"))
        }
        other => Failure::input(other),
    })
}

fn pair(args: &Args, target_path: &Path, config: &RegistrationConfig) -> Result<(), Failure> {
    let source = read_scan(&args.input)?;
    let target = read_scan(target_path)?;
    let started = Instant::now();
    let found = register(&source, &target, &Pose3::identity(), config).map_err(Failure::input)?;
    let seconds = started.elapsed().as_secs_f64();
    let pose = found.target_from_source;
    if super::console::json() {
        let report = PairReport::new(
            args.input.display().to_string(),
            target_path.display().to_string(),
            &found,
            seconds,
        );
        super::print_json(&report)?;
        return Ok(());
    }
    let t = pose.translation();
    let (roll, pitch, yaw) = pose.rpy();
    println!("source: {} ({} points)", args.input.display(), source.len());
    println!(
        "target: {} ({} points)",
        target_path.display(),
        target.len()
    );
    println!(
        "target_from_source: translation ({:.4}, {:.4}, {:.4}) m, roll {:.4}°, pitch {:.4}°, yaw {:.4}°",
        t.x,
        t.y,
        t.z,
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees()
    );
    println!(
        "{} iterations ({}), fitness {:.3} ({} of {} thinned source points), rmse {:.4} m, {seconds:.3} s",
        found.iterations,
        if found.converged {
            "converged"
        } else {
            "iteration limit"
        },
        found.fitness,
        found.correspondences,
        found.source_points,
        found.rmse_m
    );
    Ok(())
}

fn sequence(args: &Args, config: RegistrationConfig) -> Result<(), Failure> {
    let bad = |e: raypath_io::Error| Failure::input(e);
    let sweeps = args.source.open_sweeps(&args.input).map_err(bad)?;
    let n = sweeps.len().min(args.frames.unwrap_or(usize::MAX));
    let reference = sweeps.reference.as_deref();
    let mut odometry = Odometry::new(OdometryConfig {
        registration: config,
        ..OdometryConfig::default()
    })
    .map_err(Failure::input)?;
    let mut steps = Vec::with_capacity(n);
    let bar = super::console::progress(n, "registration");
    for k in 0..n {
        bar.inc(1);
        let cloud = sweeps.sweep(k).map_err(bad)?;
        let started = Instant::now();
        let step = odometry
            .register_frame(&cloud)
            .map_err(|e| Failure::input(format!("{}: sweep {k}: {e}", args.input.display())))?;
        let seconds = started.elapsed().as_secs_f64();
        let poses = odometry.poses();
        let error = match (k, reference) {
            (1.., Some(truth)) => Some(StepError::new(
                &(truth[k - 1].inverse() * truth[k]),
                &(poses[k - 1].inverse() * poses[k]),
            )),
            _ => None,
        };
        let entry = StepReport::new(k, &step, seconds, error);
        if !super::console::json() {
            print_step(&entry);
        }
        steps.push(entry);
    }
    if let Some(out) = &args.out {
        raypath_io::kitti::write_poses(out, odometry.poses()).map_err(bad)?;
    }
    let summary = SequenceSummary::of(&steps);
    if super::console::json() {
        super::print_json(&SequenceReport {
            mode: "sequence",
            input: args.input.display().to_string(),
            frames: n,
            steps,
            summary,
            out: args.out.as_ref().map(|p| p.display().to_string()),
        })?;
    } else if let Some(s) = summary {
        println!(
            "{} pairs against the reference: rotation error mean {:.3}° (max {:.3}°), \
             translation error mean {:.3} m (max {:.3} m), {:.2} % of the distance",
            s.pairs,
            s.rotation_error_deg_mean,
            s.rotation_error_deg_max,
            s.translation_error_m_mean,
            s.translation_error_m_max,
            s.translation_error_percent,
        );
    } else {
        println!("{n} sweeps registered (no reference poses to compare with)");
    }
    Ok(())
}

/// The human line of one step (a non-finite figure prints as NaN, as it shows as null in
/// the JSON).
fn print_step(entry: &StepReport) {
    let finite = |v: f64| if v.is_finite() { v } else { f64::NAN };
    let t = entry.pose.translation_m;
    let mut line = format!(
        "frame {}: ({:.3}, {:.3}, {:.3}) m, yaw {:.3}°",
        entry.frame,
        finite(t[0]),
        finite(t[1]),
        finite(t[2]),
        finite(entry.pose.rpy_deg[2])
    );
    if let Some(it) = entry.iterations {
        line += &format!(", {it} iterations, {:.0} ms", finite(entry.seconds) * 1e3);
    }
    if let Some(e) = &entry.error {
        line += &format!(
            ", error {:.3}° {:.3} m",
            finite(e.rotation_deg),
            finite(e.translation_m)
        );
    }
    println!("{line}");
}

/// Runs `raypath register`.
pub fn run(args: &Args) -> Result<(), Failure> {
    let config = config(args)?;
    match &args.target {
        Some(target) => pair(args, target, &config),
        None if args.input.is_dir()
            || is_bag(&args.input)
            || raypath_io::ouster::is_capture_name(&args.input) =>
        {
            sequence(args, config)
        }
        None => Err(Failure::input(format!(
            "{}: one scan alone; give a target scan, or a sequence (KITTI directory, NCLT \
                 session, Ouster .pcap, rosbag2 bag)",
            args.input.display()
        ))),
    }
}
