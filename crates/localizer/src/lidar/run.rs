//! Running the filter along a 2-D log: odometry increments, update thresholds, estimates.

use raypath_geometry::{Pose2, Scan2};
use serde::{Deserialize, Serialize};

use super::Scan2Measurement;
use crate::init::GaussianInit;
use crate::motion::{OdometryControl, OdometryMotionModel};
use crate::{Estimator, FilterConfig, LocalizerError, ParticleFilter, PoseTrack, Stamped};
use raypath_sensor_models::{Planar, SensorModel};

/// One laser scan of a 2-D log with the odometry pose at its time.
#[derive(Clone, Debug)]
pub struct PlanarStep {
    /// Time of the scan, seconds.
    pub stamp_secs: f64,
    /// The odometry pose `odom_from_robot` at the scan (only increments are used).
    pub odom_from_robot: Pose2,
    /// The scan.
    pub scan: Scan2,
    /// Force a filter update at this step (e.g. a step with ground truth).
    pub force_update: bool,
}

/// How [`track_planar`] runs the filter. Defaults follow ROS AMCL where the thesis is silent
/// (ch. 7 gives no motion model, resampling scheme, estimator or rays per scan).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackConfig {
    /// Number of particles. Default 1000.
    pub particles: usize,
    /// Update only after the odometry moved this far since the last update (AMCL
    /// `update_min_d`, default 0.2 m) …
    pub update_min_distance_m: f64,
    /// … or turned this much (AMCL `update_min_a` is π/6; default 0.2 rad).
    pub update_min_angle_rad: f64,
    /// The filter (ESS threshold 0.5, no KLD).
    pub filter: FilterConfig,
    /// The odometry motion model (α1..α4 = 0.2, AMCL).
    pub motion: OdometryMotionModel,
    /// The pose estimator (default mean of the best 10 %).
    pub estimator: Estimator,
}

impl Default for TrackConfig {
    fn default() -> Self {
        Self {
            particles: 1000,
            update_min_distance_m: 0.2,
            update_min_angle_rad: 0.2,
            filter: FilterConfig::default(),
            motion: OdometryMotionModel::default(),
            estimator: Estimator::BestFraction(0.1),
        }
    }
}

/// What [`track_planar`] produced.
#[derive(Clone, Debug)]
pub struct PlanarTrack {
    /// The estimate after every update (`world_from_robot`, map frame), with its step index;
    /// one per time stamp (the latest when a log repeats a stamp).
    pub estimates: Vec<(usize, Stamped<Pose2>)>,
    /// Number of filter updates.
    pub updates: usize,
    /// Updates skipped because every particle had likelihood zero (weights kept).
    pub failed_updates: usize,
    /// Resamplings.
    pub resamplings: usize,
}

impl PlanarTrack {
    /// The estimates as a [`PoseTrack`] (for [`crate::eval::evaluate_trajectory`]).
    pub fn track(&self) -> Result<PoseTrack<Pose2>, LocalizerError> {
        PoseTrack::new(self.estimates.iter().map(|(_, s)| *s))
    }
}

/// Runs MCL along `steps`: particles start from `init`; between updates the odometry
/// increment of `odom_from_robot` drives the odometry motion model; an update (weight with
/// `measurement`, resample when ESS / N < 0.5) happens at the first step, at forced steps
/// and whenever the odometry moved more than the thresholds of `config`.
pub fn track_planar<M: SensorModel<Planar>>(
    steps: &[PlanarStep],
    measurement: &Scan2Measurement<M>,
    init: &GaussianInit<Pose2>,
    config: &TrackConfig,
    seed: u64,
) -> Result<PlanarTrack, LocalizerError> {
    let mut filter = ParticleFilter::from_initializer(init, config.particles, config.filter, seed)?;
    let mut out = PlanarTrack {
        estimates: Vec::new(),
        updates: 0,
        failed_updates: 0,
        resamplings: 0,
    };
    let mut last_odom: Option<Pose2> = None;
    for (index, step) in steps.iter().enumerate() {
        if !step.odom_from_robot.is_finite() {
            return Err(LocalizerError::NonFinite {
                what: "odometry pose",
                index,
            });
        }
        if let Some(previous) = last_odom {
            let increment = previous.inverse() * step.odom_from_robot;
            let moved = increment.translation().norm() >= config.update_min_distance_m
                || increment.theta().abs() >= config.update_min_angle_rad;
            if !(moved || step.force_update) {
                continue;
            }
            let control = OdometryControl::from_poses(&previous, &step.odom_from_robot);
            filter.predict(&config.motion, &control);
        }
        last_odom = Some(step.odom_from_robot);
        let scan = measurement.prepare(&step.scan);
        match filter.update(measurement, &scan) {
            Ok(_) => {
                out.updates += 1;
                if filter.resample_if_needed().is_some() {
                    out.resamplings += 1;
                }
            }
            Err(LocalizerError::AllParticlesImpossible { .. }) => out.failed_updates += 1,
            Err(e) => return Err(e),
        }
        // Logs may repeat a time stamp; keep the latest estimate per stamp so that the
        // estimates form a track with strictly increasing times.
        if out
            .estimates
            .last()
            .is_some_and(|(_, last)| last.stamp_secs >= step.stamp_secs)
        {
            out.estimates.pop();
        }
        out.estimates.push((
            index,
            Stamped::new(step.stamp_secs, filter.estimate(config.estimator)),
        ));
    }
    Ok(out)
}
