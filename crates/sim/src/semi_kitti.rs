//! Semi-synthetic KITTI: a street world built around a **real** trajectory and pole map
//! (`poses.txt`, `times.txt`, `poles.csv` as in `RAYPATH_DATA/kitti-poles/NN/`), scanned with
//! a simulated HDL-64E along the real drive and written in the KITTI odometry layout — real
//! pole layouts and real driving for the pole-localization evaluation (Schaefer 2020, ch. 12).
//!
//! **Frames.** The real poses are `world_from_cam0` (camera axes, identity at frame 0); the
//! pole map is in the lidar-aligned world frame, `(x, y) ≈ (z, −x)` of the camera poses up to
//! the lidar–camera offset. This module takes that frame to be the velodyne frame at frame 0:
//! the velodyne poses are `velo_from_cam0 · world_from_cam0 · cam0_from_velo` with the `Tr`
//! of KITTI sequences 00–02 ([`kitti_cam0_from_velo`]). The scene is built in that frame; the
//! ground follows the road 1.73 m below the velodyne ([`Scenery`]).
//!
//! The output is the layout of [`urban::kitti_out`](crate::urban::kitti_out): the poses written
//! are the real camera poses (of the frames used), the times the real times, and `poles.csv`
//! holds the real poles placed in the scene (`x,y,w,h,kind,id`; `id` is the row of the input
//! map) with the simulated kinds and sizes. Poles the trajectory passes within 1 m of are left
//! out (a car cannot drive through a pole; such entries are map or frame errors) and counted.

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::{Point2, Point3, Vector3};
use rand::Rng;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::kitti::{self, KittiLayout};
use raypath_io::point_csv::PointCsv;

use crate::error::{Result, SimError};
use crate::lidar3::{Lidar3, SimScan};
use crate::rng;
use crate::scene3::Scene3;
use crate::urban::along_path::{PathSample, Scenery, world_along_path};
use crate::urban::kinds::Pole;
use crate::urban::kitti_out::{KittiSequenceFiles, kitti_cam0_from_velo, write_sequence_with};
use crate::urban::output::{list_files, pole_counts_json, write_poles_csv};
use crate::urban::world::World;
use crate::{GeneratedSet, Progress};

const DOMAIN_LIDAR: u64 = 0x5345_4d49_4c49_4441;

/// Spacing of the trajectory samples the scenery is built around, metres.
const SAMPLE_SPACING_M: f64 = 2.0;

/// A real drive and pole map, and how to simulate it.
#[derive(Clone, Debug, PartialEq)]
pub struct SemiKittiConfig {
    /// Camera poses `world_from_cam0` (camera axes), one per frame, as in `poses.txt`.
    pub poses: Vec<Pose3>,
    /// Seconds, one per frame, as in `times.txt`.
    pub times: Vec<f64>,
    /// Pole positions `(x, y)` in the lidar-aligned world frame, as in `poles.csv`.
    pub poles: Vec<Point2<f64>>,
    /// Sequence name of the output.
    pub sequence: String,
    /// Scan every `stride`-th frame (1: all).
    pub stride: usize,
    /// At most this many scans (from the first frame).
    pub max_scans: Option<usize>,
    /// Firings per revolution of the HDL-64E (2083 at 10 Hz).
    pub firings: usize,
    /// Also write SemanticKITTI labels.
    pub labels: bool,
    /// The street scenery.
    pub scenery: Scenery,
    /// Scan de-skewed sweeps from the moving sensor ([`Lidar3::scan_moving`], the timing of
    /// KITTI's sweeps; the motion over a sweep from the neighbouring poses) instead of every
    /// beam from the scan's pose (default false).
    pub sweep_motion: bool,
}

impl SemiKittiConfig {
    /// A configuration for a drive and map with the defaults: every frame, full HDL-64E,
    /// labels, default scenery.
    pub fn new(poses: Vec<Pose3>, times: Vec<f64>, poles: Vec<Point2<f64>>) -> Self {
        Self {
            poses,
            times,
            poles,
            sequence: "00".into(),
            stride: 1,
            max_scans: None,
            firings: crate::lidar3::HDL64E_FIRINGS_10HZ,
            labels: true,
            scenery: Scenery::default(),
            sweep_motion: false,
        }
    }

    /// Reads the drive and map from files as in `RAYPATH_DATA/kitti-poles/NN/`: KITTI poses
    /// and times, and a point CSV whose first two columns are the pole `x, y`.
    pub fn from_files(poses: &Path, times: &Path, poles: &Path) -> Result<Self> {
        let pole_map = PointCsv::read(poles)?;
        let poles = pole_map
            .rows()
            .filter_map(|r| Some(Point2::new(*r.first()?, *r.get(1)?)))
            .collect();
        Ok(Self::new(
            kitti::read_poses(poses)?,
            kitti::read_times(times)?,
            poles,
        ))
    }

    /// The indices of the frames scanned.
    pub fn frames(&self) -> Vec<usize> {
        let stride = self.stride.max(1);
        let mut frames: Vec<usize> = (0..self.poses.len()).step_by(stride).collect();
        if let Some(max) = self.max_scans {
            frames.truncate(max);
        }
        frames
    }

    fn validate(&self) -> Result<()> {
        let invalid =
            |name: &'static str, reason: String| Err(SimError::InvalidParameter { name, reason });
        if self.poses.is_empty() {
            return invalid("poses", "no poses".into());
        }
        if self.poses.len() != self.times.len() {
            return invalid(
                "times",
                format!("{} times for {} poses", self.times.len(), self.poses.len()),
            );
        }
        if self.stride == 0 || self.max_scans == Some(0) {
            return invalid("stride/max_scans", "must be at least 1".into());
        }
        if let Some(p) = self
            .poles
            .iter()
            .find(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return invalid("poles", format!("pole at {p} is not finite"));
        }
        if self.poses.iter().any(|p| !p.is_finite()) {
            return invalid("poses", "a pose is not finite".into());
        }
        Ok(())
    }
}

/// A semi-synthetic drive held in memory: the world built around the real trajectory, the
/// lidar, and per scan the velodyne pose and time; [`SemiKittiDrive::scan`] simulates one
/// scan on demand. Scan `i` is the `i`-th of [`SemiKittiConfig::frames`] and equals the
/// scan [`generate_semi_kitti`] writes as frame `i` (both go through
/// [`SemiKittiDrive::sim_scan`]), so an evaluation can stream a drive without writing
/// 2.6 GB of scans per sequence.
///
/// Frames: `world_from_velo` is in the world frame of the pole map (the velodyne frame of
/// input frame 0; REP-103 axes, metres), which is also the frame the scene is built in.
pub struct SemiKittiDrive {
    /// Sequence name.
    pub sequence: String,
    /// The input frame of each scan.
    pub frames: Vec<usize>,
    /// `world_from_velo` of each scan.
    pub world_from_velo: Vec<Pose3>,
    /// Time of each scan, seconds (the real times).
    pub times_s: Vec<f64>,
    /// The poles placed in the scene (`id` = row of the input map), in the world frame.
    pub poles: Vec<Pole>,
    /// Rows of the input pole map left out because the trajectory passes within 1 m.
    pub poles_left_out: Vec<usize>,
    /// Length of the trajectory driven (samples every 2 m), metres.
    pub trajectory_length_m: f64,
    /// The sensor's translation over each scan's sweep (velodyne frame, metres); zero unless
    /// [`SemiKittiConfig::sweep_motion`].
    pub sweep_translation_m: Vec<Vector3<f64>>,
    world: World,
    scene: Scene3,
    lidar: Lidar3,
    scan_seed: u64,
}

impl SemiKittiDrive {
    /// Builds the world around the frames of `config` driven (deterministic by `seed`).
    pub fn new(config: &SemiKittiConfig, seed: u64) -> Result<Self> {
        config.validate()?;
        let cam0_from_velo = kitti_cam0_from_velo();
        let world_from_velo = kitti::velodyne_poses_from_cam0(&config.poses, &cam0_from_velo);
        let frames = config.frames();
        let last = frames.last().copied().unwrap_or(0);
        let (samples, length_m) =
            path_samples(&world_from_velo[..=last], config.scenery.sensor_height_m)?;
        let (world, report) = world_along_path(&samples, &config.poles, &config.scenery, seed);
        let scene = world.build_scene()?;
        let lidar = Lidar3::hdl64e().with_firings(config.firings)?;
        let sweep_translation_m = frames
            .iter()
            .map(|&i| {
                if config.sweep_motion {
                    sweep_translation(&world_from_velo, &config.times, i)
                } else {
                    Vector3::zeros()
                }
            })
            .collect();
        Ok(Self {
            sweep_translation_m,
            sequence: config.sequence.clone(),
            world_from_velo: frames.iter().map(|&i| world_from_velo[i]).collect(),
            times_s: frames.iter().map(|&i| config.times[i]).collect(),
            frames,
            poles: world.pole_list(),
            poles_left_out: report.poles_on_trajectory,
            trajectory_length_m: length_m,
            world,
            scene,
            lidar,
            scan_seed: rng::stream(seed, DOMAIN_LIDAR, 0).random(),
        })
    }

    /// Number of scans.
    pub fn len(&self) -> usize {
        self.world_from_velo.len()
    }

    /// True when there are no scans.
    pub fn is_empty(&self) -> bool {
        self.world_from_velo.is_empty()
    }

    /// The simulated lidar.
    pub fn lidar(&self) -> &Lidar3 {
        &self.lidar
    }

    /// The world built around the drive.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Simulates scan `index` in full (organized, with no-returns, labels and surfaces).
    pub fn sim_scan(&self, index: usize) -> Result<SimScan> {
        let pose = self
            .world_from_velo
            .get(index)
            .ok_or_else(|| SimError::InvalidParameter {
                name: "scan",
                reason: format!("no scan {index} (the drive has {})", self.len()),
            })?;
        let motion = self
            .sweep_translation_m
            .get(index)
            .copied()
            .unwrap_or_else(Vector3::zeros);
        self.lidar
            .scan_moving(&self.scene, pose, &motion, self.scan_seed, index as u64)
    }

    /// Simulates scan `index` as written to `velodyne/NNNNNN.bin` (and `labels/`): the
    /// returns only (no-returns dropped), in the velodyne frame (REP-103, metres), with
    /// intensity and SemanticKITTI label, in the order of the organized scan.
    pub fn scan(&self, index: usize) -> Result<PointCloud> {
        Ok(returns_only(&self.sim_scan(index)?.cloud))
    }
}

/// The sensor's translation over one sweep (10 Hz) at frame `i`, in its velodyne frame:
/// the velocity from the neighbouring frames (central differences, one-sided at the ends).
fn sweep_translation(world_from_velo: &[Pose3], times: &[f64], i: usize) -> Vector3<f64> {
    const SWEEP_S: f64 = 0.1;
    let last = world_from_velo.len().min(times.len()).saturating_sub(1);
    let (a, b) = (i.saturating_sub(1).min(last), (i + 1).min(last));
    let dt = times[b] - times[a];
    if !(dt > 0.0 && dt.is_finite()) {
        return Vector3::zeros();
    }
    let moved = world_from_velo[b].translation() - world_from_velo[a].translation();
    world_from_velo[i.min(last)].rotation().inverse() * moved * (SWEEP_S / dt)
}

/// The returns of an organized cloud (finite points), keeping intensity and label.
fn returns_only(cloud: &PointCloud) -> PointCloud {
    let keep: Vec<usize> = (0..cloud.len())
        .filter(|&i| cloud.points[i].iter().all(|v| v.is_finite()))
        .collect();
    let mut out = PointCloud::from_points(keep.iter().map(|&i| cloud.points[i]).collect());
    out.intensity = pick(&keep, &cloud.intensity);
    out.label = pick(&keep, &cloud.label);
    out
}

/// The entries `keep` of an optional per-point channel.
fn pick<T: Copy>(keep: &[usize], values: &Option<Vec<T>>) -> Option<Vec<T>> {
    values
        .as_ref()
        .map(|v| keep.iter().filter_map(|&i| v.get(i).copied()).collect())
}

/// Trajectory samples every 2 m (with the ground below the sensor) and the length driven.
fn path_samples(world_from_velo: &[Pose3], height: f64) -> Result<(Vec<PathSample>, f64)> {
    let mut samples: Vec<PathSample> = Vec::new();
    let mut length_m = 0.0;
    for pose in world_from_velo {
        let planar = pose.to_planar();
        let position = Point2::new(planar.x(), planar.y());
        let ground = pose.transform_point(&Point3::new(0.0, 0.0, -height));
        let sample = PathSample {
            position,
            heading_rad: planar.theta(),
            ground_z: ground.z,
        };
        match samples.last() {
            Some(prev) if (prev.position - position).norm() < SAMPLE_SPACING_M => {}
            Some(prev) => {
                length_m += (prev.position - position).norm();
                samples.push(sample);
            }
            None => samples.push(sample),
        }
    }
    if samples.len() < 2 {
        // A vehicle standing still: a second sample ahead gives the road a direction.
        let first = samples
            .first()
            .copied()
            .ok_or_else(|| SimError::InvalidParameter {
                name: "poses",
                reason: "no poses".into(),
            })?;
        let ahead = first.position
            + nalgebra::Vector2::new(first.heading_rad.cos(), first.heading_rad.sin())
                * SAMPLE_SPACING_M;
        samples.push(PathSample {
            position: ahead,
            ..first
        });
    }
    Ok((samples, length_m))
}

/// Builds the world around the drive, scans the selected frames and writes the KITTI layout
/// under `out_dir`. Deterministic by seed; the scans are those of [`SemiKittiDrive::scan`].
pub fn generate_semi_kitti(
    config: &SemiKittiConfig,
    seed: u64,
    out_dir: &Path,
    progress: Progress,
) -> Result<GeneratedSet> {
    let started = Instant::now();
    let drive = SemiKittiDrive::new(config, seed)?;
    let layout = KittiLayout::new(out_dir, config.sequence.clone());
    let scan_stats = write_sequence_with(
        &KittiSequenceFiles {
            layout: &layout,
            world_from_velo: &drive.world_from_velo,
            times_s: &drive.times_s,
            labels: config.labels,
        },
        &|i| drive.sim_scan(i),
        progress,
    )?;
    write_poles_csv(
        &layout.sequence_dir().join("poles.csv"),
        &drive.poles,
        &Pose3::identity(),
    )?;
    let elapsed = started.elapsed().as_secs_f64();
    let times = &drive.times_s;
    let world = drive.world();
    let stats = serde_json::json!({
        "sequence": config.sequence,
        "frames_in_input": config.poses.len(),
        "stride": config.stride,
        "lidar": drive.lidar.name,
        "rays_per_scan": drive.lidar.num_rays(),
        "scans": scan_stats.to_json(),
        "trajectory_length_m": drive.trajectory_length_m,
        "duration_s": times.last().copied().unwrap_or(0.0) - times.first().copied().unwrap_or(0.0),
        "poles_in_input": config.poles.len(),
        "poles_placed": pole_counts_json(&drive.poles),
        "poles_left_out_on_trajectory": drive.poles_left_out.len(),
        "world": {
            "triangles": drive.scene.num_triangles(),
            "buildings": world.buildings.len(),
            "parked_cars": world.cars.len(),
            "sidewalk_pieces": world.slabs.len(),
        },
        "elapsed_s": elapsed,
        "rays_per_s": scan_stats.rays as f64 / elapsed.max(1e-9),
    });
    Ok(GeneratedSet {
        name: format!("semi-kitti-{}", config.sequence),
        description:
            "Simulated HDL-64E scans along a real KITTI trajectory through a street world \
                      built around the real pole map (KITTI odometry layout with the real poses \
                      and the placed poles)"
                .into(),
        files: list_files(out_dir)?,
        stats,
    })
}

/// Which real sequence of `RAYPATH_DATA/kitti-poles` to simulate, for the named data set.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SemiKittiSetConfig {
    /// Sequence (`00`–`07`).
    pub sequence: String,
    /// Scan every `stride`-th frame.
    pub stride: usize,
    /// At most this many scans.
    pub max_scans: Option<usize>,
    /// Firings per revolution of the HDL-64E.
    pub firings: usize,
    /// Also write SemanticKITTI labels.
    pub labels: bool,
}

impl Default for SemiKittiSetConfig {
    /// Sequence 07 at full rate: 1101 scans (110 s, 0.7 km).
    fn default() -> Self {
        Self {
            sequence: "07".into(),
            stride: 1,
            max_scans: None,
            firings: crate::lidar3::HDL64E_FIRINGS_10HZ,
            labels: true,
        }
    }
}

impl SemiKittiSetConfig {
    /// Sequence 07, every 10th frame: 111 scans over the whole drive.
    pub fn quick() -> Self {
        Self {
            stride: 10,
            ..Self::default()
        }
    }
}

/// The directory of a real sequence under the data directory (`RAYPATH_DATA`).
pub fn real_sequence_dir(sequence: &str) -> Result<PathBuf> {
    let relative = Path::new("kitti-poles").join(sequence);
    raypath_io::data::find(&relative).ok_or_else(|| SimError::InvalidParameter {
        name: "sequence",
        reason: format!(
            "{} not found (set RAYPATH_DATA to the data directory)",
            raypath_io::data::data_dir().join(relative).display()
        ),
    })
}

/// Generates the semi-synthetic set of a real sequence from `RAYPATH_DATA/kitti-poles/NN`.
pub fn generate(
    config: &SemiKittiSetConfig,
    seed: u64,
    out_dir: &Path,
    progress: Progress,
) -> Result<GeneratedSet> {
    let dir = real_sequence_dir(&config.sequence)?;
    let mut semi = SemiKittiConfig::from_files(
        &dir.join("poses.txt"),
        &dir.join("times.txt"),
        &dir.join("poles.csv"),
    )?;
    semi.sequence.clone_from(&config.sequence);
    semi.stride = config.stride;
    semi.max_scans = config.max_scans;
    semi.firings = config.firings;
    semi.labels = config.labels;
    generate_semi_kitti(&semi, seed, out_dir, progress)
}
