//! Filter update rate: 1000 particles × 180 beams, predict + weight + resample, on all cores.

use std::time::Instant;

use anyhow::Result;
use raypath_localizer::init::GaussianInit;
use raypath_localizer::lidar::{LidarConfig, ModelSpec, Scan2Measurement};
use raypath_localizer::motion::{OdometryControl, OdometryMotionModel};
use raypath_localizer::{FilterConfig, ParticleFilter};
use serde::{Deserialize, Serialize};

use super::planar::PlanarProblem;
use crate::eval::stages::float;

/// Particles of the speed table.
pub const PARTICLES: usize = 1000;

/// Measured rate of one model.
#[derive(Serialize, Deserialize)]
pub struct SpeedRow {
    /// Model label.
    pub model: String,
    /// Beams per scan.
    pub beams: usize,
    /// Filter updates per second.
    #[serde(with = "float")]
    pub updates_per_s: f64,
    /// Time to build the model (and its table), seconds.
    #[serde(with = "float")]
    pub build_secs: f64,
}

/// Measures `spec` on `problem`: `updates` full filter cycles (resampling every time) over
/// consecutive steps that carry a ground-truth pose.
pub fn measure(problem: &PlanarProblem, spec: &ModelSpec, updates: usize) -> Result<SpeedRow> {
    let started = Instant::now();
    let model = spec.build(&problem.stats, problem.mapping.range)?;
    let build_secs = started.elapsed().as_secs_f64();
    let lidar = LidarConfig {
        beam_step: 1,
        ..LidarConfig::default()
    };
    let measurement = Scan2Measurement::new(model.as_ref(), problem.robot_from_laser, lidar)?;
    let init = GaussianInit {
        sigma_xy_m: 0.3,
        sigma_rotation_rad: 0.05,
        ..GaussianInit::new(problem.ground_truth.poses()[0])
    };
    let config = FilterConfig {
        resample_ess_ratio: 1.0,
        ..FilterConfig::default()
    };
    let mut filter = ParticleFilter::from_initializer(&init, PARTICLES, config, 7)?;
    let motion = OdometryMotionModel::default();
    let steps: Vec<_> = problem.steps.iter().filter(|s| s.force_update).collect();
    let beams = steps.first().map_or(0, |s| s.scan.len());
    let started = Instant::now();
    let mut done = 0;
    for pair in steps.windows(2).cycle().take(updates) {
        let control =
            OdometryControl::from_poses(&pair[0].odom_from_robot, &pair[1].odom_from_robot);
        filter.predict(&motion, &control);
        let scan = measurement.prepare(&pair[1].scan);
        if filter.update(&measurement, &scan).is_ok() {
            filter.resample();
        }
        done += 1;
    }
    let seconds = started.elapsed().as_secs_f64();
    Ok(SpeedRow {
        model: spec.label(),
        beams,
        updates_per_s: done as f64 / seconds.max(1e-9),
        build_secs,
    })
}
