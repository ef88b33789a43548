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
use raypath_registration::{
    Kernel, Odometry, OdometryConfig, Registration, RegistrationConfig, register,
};
use serde_json::{Value, json};

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

fn pose_json(pose: &Pose3) -> Value {
    let q = pose.rotation();
    let (roll, pitch, yaw) = pose.rpy();
    json!({
        "translation_m": pose.translation().as_slice(),
        "rotation_xyzw": [q.i, q.j, q.k, q.w],
        "rpy_deg": [roll.to_degrees(), pitch.to_degrees(), yaw.to_degrees()],
    })
}

fn registration_json(r: &Registration) -> Value {
    json!({
        "iterations": r.iterations,
        "converged": r.converged,
        "fitness": r.fitness,
        "rmse_m": r.rmse_m,
        "correspondences": r.correspondences,
        "source_points": r.source_points,
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
        let mut out = json!({
            "mode": "pair",
            "source": args.input.display().to_string(),
            "target": target_path.display().to_string(),
            "target_from_source": pose_json(&pose),
            "seconds": seconds,
        });
        merge(&mut out, registration_json(&found));
        println!("{out}");
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

fn merge(into: &mut Value, from: Value) {
    if let (Some(into), Value::Object(from)) = (into.as_object_mut(), from) {
        into.extend(from);
    }
}

/// Error of an estimated relative pose against the reference's.
fn step_error(truth: &Pose3, estimate: &Pose3) -> Value {
    let d = truth.inverse() * *estimate;
    json!({
        "rotation_deg": d.rotation().angle().to_degrees(),
        "translation_m": d.translation().norm(),
        "distance_m": truth.translation().norm(),
    })
}

fn summary(steps: &[Value]) -> Option<Value> {
    let errors: Vec<&Value> = steps
        .iter()
        .filter_map(|s| s.get("error"))
        .filter(|e| !e.is_null())
        .collect();
    if errors.is_empty() {
        return None;
    }
    let field =
        |name: &str| -> Vec<f64> { errors.iter().filter_map(|e| e[name].as_f64()).collect() };
    let (rot, trans, dist) = (
        field("rotation_deg"),
        field("translation_m"),
        field("distance_m"),
    );
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let mut seconds: Vec<f64> = steps
        .iter()
        .filter(|s| !s["iterations"].is_null())
        .filter_map(|s| s["seconds"].as_f64())
        .collect();
    seconds.sort_by(f64::total_cmp);
    Some(json!({
        "pairs": errors.len(),
        "rotation_error_deg_mean": mean(&rot),
        "rotation_error_deg_max": max(&rot),
        "translation_error_m_mean": mean(&trans),
        "translation_error_m_max": max(&trans),
        "translation_error_percent": 100.0 * trans.iter().sum::<f64>() / dist.iter().sum::<f64>(),
        "seconds_median": seconds.get(seconds.len() / 2),
    }))
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
            (1.., Some(truth)) => step_error(
                &(truth[k - 1].inverse() * truth[k]),
                &(poses[k - 1].inverse() * poses[k]),
            ),
            _ => Value::Null,
        };
        let mut entry = json!({
            "frame": k,
            "sigma_m": step.sigma_m,
            "map_points": step.map_points,
            "seconds": seconds,
            "error": error,
        });
        merge(&mut entry, pose_json(&step.world_from_sensor));
        match &step.registration {
            Some(r) => merge(&mut entry, registration_json(r)),
            None => merge(&mut entry, json!({"iterations": null})),
        }
        if !super::console::json() {
            print_step(&entry);
        }
        steps.push(entry);
    }
    if let Some(out) = &args.out {
        raypath_io::kitti::write_poses(out, odometry.poses()).map_err(bad)?;
    }
    let summary = summary(&steps);
    if super::console::json() {
        println!(
            "{}",
            json!({
                "mode": "sequence",
                "input": args.input.display().to_string(),
                "frames": n,
                "steps": steps,
                "summary": summary,
                "out": args.out.as_ref().map(|p| p.display().to_string()),
            })
        );
    } else if let Some(s) = summary {
        println!(
            "{} pairs against the reference: rotation error mean {:.3}° (max {:.3}°), \
             translation error mean {:.3} m (max {:.3} m), {:.2} % of the distance",
            s["pairs"],
            s["rotation_error_deg_mean"].as_f64().unwrap_or(f64::NAN),
            s["rotation_error_deg_max"].as_f64().unwrap_or(f64::NAN),
            s["translation_error_m_mean"].as_f64().unwrap_or(f64::NAN),
            s["translation_error_m_max"].as_f64().unwrap_or(f64::NAN),
            s["translation_error_percent"].as_f64().unwrap_or(f64::NAN),
        );
    } else {
        println!("{n} sweeps registered (no reference poses to compare with)");
    }
    Ok(())
}

fn print_step(entry: &Value) {
    let t: Vec<f64> = entry["translation_m"]
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default();
    let yaw = entry["rpy_deg"][2].as_f64().unwrap_or(f64::NAN);
    let mut line = format!(
        "frame {:>4}: ({:.3}, {:.3}, {:.3}) m, yaw {:.3}°",
        entry["frame"],
        t.first().copied().unwrap_or(f64::NAN),
        t.get(1).copied().unwrap_or(f64::NAN),
        t.get(2).copied().unwrap_or(f64::NAN),
        yaw
    );
    if let Some(it) = entry["iterations"].as_u64() {
        line += &format!(
            ", {it} iterations, {:.0} ms",
            entry["seconds"].as_f64().unwrap_or(f64::NAN) * 1e3
        );
    }
    if let Some(e) = entry["error"].as_object() {
        line += &format!(
            ", error {:.3}° {:.3} m",
            e["rotation_deg"].as_f64().unwrap_or(f64::NAN),
            e["translation_m"].as_f64().unwrap_or(f64::NAN)
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
