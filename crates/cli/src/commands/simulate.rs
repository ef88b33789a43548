//! `raypath simulate`: generate simulated data in real formats.

use std::path::PathBuf;

use raypath_sim::{GeneratedSet, SimError, corridor, indoor, polygons, semi_kitti, synpeb, urban};

use super::Failure;

/// The scene kinds `raypath simulate` generates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// Random polygons scanned by a 360-ray sensor (Schaefer ch. 10): CARMEN + ground truth.
    Polygons,
    /// 2-D indoor worlds: corrected and raw CARMEN logs with odometry.
    Indoor,
    /// The 1-D corridor of Schaefer ch. 8.
    Corridor,
    /// SynPEB-style rooms: organized 500 × 500 PCD scans with plane labels.
    Synpeb,
    /// Procedural streets with an HDL-64E, KITTI odometry layout.
    UrbanKitti,
    /// Sessions of a changing street world with an HDL-32E, NCLT layout.
    UrbanNclt,
    /// Streets built around a real KITTI trajectory and pole map (--poses, --times, --poles).
    SemiKitti,
}

/// Arguments of `raypath simulate`.
#[derive(clap::Args)]
pub struct Args {
    /// What to simulate.
    #[arg(value_enum)]
    pub kind: Kind,
    /// Output directory (created if needed).
    #[arg(long)]
    pub out: PathBuf,
    /// Seed: the same seed writes byte-identical files.
    #[arg(long, default_value_t = raypath_sim::datasets::DEFAULT_SEED)]
    pub seed: u64,
    /// The smaller configuration (what `cargo xtask datasets generate --quick` writes).
    #[arg(long)]
    pub quick: bool,
    /// Number of scans (polygons, urban-kitti; scans per session for urban-nclt; at most this
    /// many for semi-kitti).
    #[arg(long)]
    pub scans: Option<usize>,
    /// semi-kitti: KITTI `poses.txt` of the drive (camera-0 poses).
    #[arg(long, required_if_eq("kind", "semi-kitti"))]
    pub poses: Option<PathBuf>,
    /// semi-kitti: KITTI `times.txt` of the drive.
    #[arg(long, required_if_eq("kind", "semi-kitti"))]
    pub times: Option<PathBuf>,
    /// semi-kitti: pole map CSV (`x,y` header, lidar-aligned world frame).
    #[arg(long, required_if_eq("kind", "semi-kitti"))]
    pub poles: Option<PathBuf>,
    /// semi-kitti: scan every N-th frame.
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// semi-kitti: sequence name of the output (`sequences/NN`).
    #[arg(long, default_value = "00")]
    pub sequence: String,
}

/// Runs `raypath simulate`.
pub fn run(args: &Args) -> Result<(), Failure> {
    let bar = super::console::progress(0, "simulation");
    let progress = |done: u64, total: u64| {
        bar.set_length(total);
        bar.set_position(done);
    };
    let result = generate(args, &progress);
    bar.finish_and_clear();
    let set = result.map_err(|e| match e {
        SimError::InvalidParameter { .. } | SimError::Io(_) => Failure::input(e),
        other => Failure::internal(other.to_string()),
    })?;
    if super::console::json() {
        let text =
            serde_json::to_string_pretty(&set).map_err(|e| Failure::internal(e.to_string()))?;
        println!("{text}");
    } else {
        println!(
            "{}: {} files written to {}",
            set.name,
            set.files.len(),
            args.out.display()
        );
        println!("{}", set.description);
    }
    Ok(())
}

fn generate(args: &Args, progress: raypath_sim::Progress) -> raypath_sim::Result<GeneratedSet> {
    let (quick, seed, out) = (args.quick, args.seed, args.out.as_path());
    match args.kind {
        Kind::Polygons => {
            let mut config = if quick {
                polygons::PolygonsConfig::quick()
            } else {
                polygons::PolygonsConfig::default()
            };
            if let Some(scans) = args.scans {
                config.scans = scans;
            }
            polygons::generate(&config, seed, out, progress)
        }
        Kind::Indoor => {
            let config = if quick {
                indoor::IndoorConfig::quick()
            } else {
                indoor::IndoorConfig::default()
            };
            indoor::generate(&config, seed, out, progress)
        }
        Kind::Corridor => {
            let config = if quick {
                corridor::CorridorConfig::quick()
            } else {
                corridor::CorridorConfig::default()
            };
            corridor::generate(&config, seed, out, progress)
        }
        Kind::Synpeb => {
            let config = if quick {
                synpeb::SynpebConfig::quick()
            } else {
                synpeb::SynpebConfig::default()
            };
            synpeb::generate(&config, seed, out, progress)
        }
        Kind::UrbanKitti => {
            let mut config = if quick {
                urban::UrbanKittiConfig::quick()
            } else {
                urban::UrbanKittiConfig::default()
            };
            if let Some(scans) = args.scans {
                config.scans = scans;
            }
            urban::generate_kitti(&config, seed, out, progress)
        }
        Kind::UrbanNclt => {
            let mut config = if quick {
                urban::UrbanNcltConfig::quick()
            } else {
                urban::UrbanNcltConfig::default()
            };
            if let Some(scans) = args.scans {
                config.scans_per_session = scans;
            }
            urban::generate_nclt(&config, seed, out, progress)
        }
        Kind::SemiKitti => {
            let (Some(poses), Some(times), Some(poles)) = (&args.poses, &args.times, &args.poles)
            else {
                return Err(SimError::InvalidParameter {
                    name: "semi-kitti",
                    reason: "needs --poses, --times and --poles".into(),
                });
            };
            let mut config = semi_kitti::SemiKittiConfig::from_files(poses, times, poles)?;
            config.stride = args.stride.max(1);
            config.max_scans = args.scans;
            config.sequence = args.sequence.clone();
            semi_kitti::generate_semi_kitti(&config, seed, out, progress)
        }
    }
}
