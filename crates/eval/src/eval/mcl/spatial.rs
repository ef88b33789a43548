//! 3-D MCL on the simulated urban drive (KITTI layout): 6-DOF, 300 particles, 0.5 m voxel
//! maps from the even scans, localization on the odd scans (Schaefer 2020, Sec. 7.6.1).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use nalgebra::Point3;
use raypath_geometry::{Aabb3, Grid3, PointCloud, Pose3, Range, Ray3};
use raypath_io::sequence::{SweepOptions, SweepSequence};
use raypath_localizer::eval::{EvaluationConfig, evaluate_trajectory};
use raypath_localizer::init::{GaussianInit, Initializer};
use raypath_localizer::lidar::{LidarConfig, Scan3Measurement};
use raypath_localizer::motion::Gaussian6DofMotionModel;
use raypath_localizer::{Estimator, FilterConfig, ParticleFilter, ParticleRng, PoseTrack, Stamped};
use raypath_sensor_models::{
    DecayRateConfig, DecayRateModel3, DecayRatePosteriorModel3, DenseStats3, GammaPosteriorConfig,
    LikelihoodFieldConfig, LikelihoodFieldModel3, MappingConfig, ReflectionConfig,
    ReflectionModel3, SensorModel, SensorRange, Spatial,
};

use super::common::{Cell, RunResult};

/// Voxel edge, metres (thesis Sec. 7.6).
pub const VOXEL_M: f64 = 0.5;
/// Particles (thesis Sec. 7.6.1).
pub const PARTICLES: usize = 300;
/// Rays kept per localization scan.
pub const RAYS_PER_SCAN: usize = 200;
/// Range limits of the simulated HDL-64E as used here, metres.
const RANGE_M: (f64, f64) = (1.0, 80.0);

/// The 3-D problem: map, localization scans (rays in the sensor frame), ground truth.
pub struct SpatialProblem {
    /// Map statistics.
    pub stats: DenseStats3,
    /// Range limits.
    pub range: SensorRange,
    /// Localization frames: stamp, `world_from_velo` ground truth, rays (sensor frame).
    pub frames: Vec<(f64, Pose3, Vec<Ray3>)>,
    /// Rays inserted into the map.
    pub map_rays: u64,
}

fn rays_of(cloud: &PointCloud) -> Vec<Ray3> {
    let valid: Vec<usize> = (0..cloud.len()).filter(|&i| cloud.is_valid(i)).collect();
    let step = (valid.len() / RAYS_PER_SCAN).max(1);
    valid
        .iter()
        .step_by(step)
        .filter_map(|&i| {
            let p = cloud.point_f64(i);
            Ray3::new(Point3::origin(), p.coords, Range::Hit(p.coords.norm()))
        })
        .collect()
}

/// Loads the first `frames` scans of sequence 00 under `root` (poses in the world frame of
/// [`SweepSequence`]: the velodyne frame of the first scan).
pub fn load(root: &Path, frames: usize) -> Result<SpatialProblem> {
    let seq = SweepSequence::open(&root.join("sequences/00"), &SweepOptions::default())
        .with_context(|| format!("opening {}", root.display()))?;
    let poses = seq.require_reference()?;
    let n = frames.min(seq.len());
    if n < 4 {
        bail!("urban-kitti: only {n} frames");
    }
    let world_from_velo = &poses[..n];
    let mut bounds = Aabb3::empty();
    for pose in world_from_velo {
        let t = pose.translation();
        bounds.extend(&Point3::new(t.x - 40.0, t.y - 40.0, t.z - 4.0));
        bounds.extend(&Point3::new(t.x + 40.0, t.y + 40.0, t.z + 16.0));
    }
    let grid = Grid3::covering(&bounds, VOXEL_M)?;
    let range = SensorRange::new(RANGE_M.0, RANGE_M.1)?;
    let mapping = MappingConfig {
        range,
        include_no_returns: false,
    };
    let mut stats = DenseStats3::new(grid);
    let mut frames_out = Vec::new();
    // Map from even frames (in batches to bound memory), localize on odd frames.
    let mut batch: Vec<(Pose3, PointCloud)> = Vec::new();
    for (i, pose) in world_from_velo.iter().enumerate() {
        let cloud = seq.sweep(i).with_context(|| format!("reading sweep {i}"))?;
        if i % 2 == 0 {
            batch.push((*pose, cloud));
            if batch.len() >= 16 {
                let refs: Vec<(Pose3, &PointCloud)> = batch.iter().map(|(p, c)| (*p, c)).collect();
                stats.insert_clouds_par(&refs, &mapping);
                batch.clear();
            }
        } else {
            frames_out.push((seq.stamps_secs[i], *pose, rays_of(&cloud)));
        }
    }
    let refs: Vec<(Pose3, &PointCloud)> = batch.iter().map(|(p, c)| (*p, c)).collect();
    stats.insert_clouds_par(&refs, &mapping);
    let map_rays = stats.summary().rays;
    Ok(SpatialProblem {
        stats,
        range,
        frames: frames_out,
        map_rays,
    })
}

/// A boxed 3-D sensor model.
pub type BoxedSpatialModel = Box<dyn SensorModel<Spatial> + Send + Sync>;

/// The 3-D models of the table: decay-rate (MLM and FMP), reflection, endpoint.
pub fn models(problem: &SpatialProblem) -> Result<Vec<(String, BoxedSpatialModel)>> {
    let range = problem.range;
    let decay = DecayRateModel3::new(
        &problem.stats,
        DecayRateConfig {
            range,
            ..DecayRateConfig::default()
        },
    )?;
    // The full map posterior (Sec. 8.4.5), prior by the method of moments (Sec. 8.5).
    let decay_fmp =
        DecayRatePosteriorModel3::new(&problem.stats, GammaPosteriorConfig { range, prior: None })?;
    let reflection = ReflectionModel3::maximum_likelihood(
        &problem.stats,
        ReflectionConfig {
            range,
            ..ReflectionConfig::default()
        },
    )?;
    let endpoint = LikelihoodFieldModel3::new(
        &problem.stats,
        LikelihoodFieldConfig {
            range,
            normalize: true,
            ..LikelihoodFieldConfig::default()
        },
    )?;
    Ok(vec![
        ("decay-rate".to_owned(), Box::new(decay)),
        ("decay-rate (FMP)".to_owned(), Box::new(decay_fmp)),
        ("reflection".to_owned(), Box::new(reflection)),
        ("endpoint".to_owned(), Box::new(endpoint)),
    ])
}

/// Sets every 10th ray to a return at `r_min` (the thesis's campus*: 10 % sensor failures).
pub fn with_failures(problem: &SpatialProblem) -> Vec<(f64, Pose3, Vec<Ray3>)> {
    let r_min = problem.range.min_range_m;
    problem
        .frames
        .iter()
        .map(|(t, pose, rays)| {
            let rays = rays
                .iter()
                .enumerate()
                .map(|(k, ray)| {
                    let mut ray = *ray;
                    if k % 10 == 3 {
                        ray.range = Range::Hit(r_min);
                    }
                    ray
                })
                .collect();
            (*t, *pose, rays)
        })
        .collect()
}

/// Runs the 6-DOF filter with `model` over `frames` for each seed.
pub fn run_model(
    dataset: &str,
    label: &str,
    model: &(dyn SensorModel<Spatial> + Send + Sync),
    frames: &[(f64, Pose3, Vec<Ray3>)],
    seeds: &[u64],
    mut on_run: impl FnMut(),
) -> Result<Cell> {
    let measurement = Scan3Measurement::new(model, Pose3::identity(), LidarConfig::default())?;
    let scans: Vec<_> = frames
        .iter()
        .map(|(_, _, rays)| measurement.prepare_rays(rays))
        .collect();
    let truth = PoseTrack::new(frames.iter().map(|(t, p, _)| Stamped::new(*t, *p)))?;
    let motion = Gaussian6DofMotionModel::default();
    let mut runs = Vec::new();
    for &seed in seeds {
        let first = frames[0].1;
        let mean = GaussianInit::new(first).sample(&mut ParticleRng::seed_from_u64(seed ^ 0x3d));
        let init = GaussianInit::new(mean);
        let mut filter =
            ParticleFilter::from_initializer(&init, PARTICLES, FilterConfig::default(), seed)?;
        let started = Instant::now();
        let mut estimates = Vec::with_capacity(frames.len());
        for (k, ((stamp, pose, _), scan)) in frames.iter().zip(&scans).enumerate() {
            if k > 0 {
                let increment: Pose3 = frames[k - 1].1.inverse() * *pose;
                filter.predict(&motion, &increment);
            }
            if filter.update(&measurement, scan).is_ok() {
                filter.resample_if_needed();
            }
            estimates.push(Stamped::new(
                *stamp,
                filter.estimate(Estimator::BestFraction(0.1)),
            ));
        }
        let seconds = started.elapsed().as_secs_f64();
        let evaluation = evaluate_trajectory(
            &truth,
            &PoseTrack::new(estimates)?,
            &EvaluationConfig::default(),
        )?;
        runs.push(RunResult::from_evaluation(
            &evaluation,
            frames.len() as f64 / seconds.max(1e-9),
        ));
        on_run();
    }
    Ok(Cell {
        dataset: dataset.to_owned(),
        model: label.to_owned(),
        runs,
    })
}
