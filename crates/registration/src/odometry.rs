//! Frame-to-local-map lidar odometry in the manner of KISS-ICP (Vizzo et al. 2023): each scan
//! is registered to a voxel map of the previous scans, starting from a constant-velocity
//! prediction, with the adaptive correspondence threshold; then it joins the map.

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};
use serde::{Deserialize, Serialize};

use crate::adaptive::AdaptiveThreshold;
use crate::config::OdometryConfig;
use crate::error::Result;
use crate::icp::{Gate, Registration, align};
use crate::local_map::LocalMap;
use crate::preprocess::{crop, downsample, to_cloud};
use crate::target::{Target, with_normals};

/// What [`Odometry::register_frame`] found for one scan.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OdometryStep {
    /// The scan's pose in the odometry frame (the sensor frame of the first scan).
    pub world_from_sensor: Pose3,
    /// The constant-velocity prediction registration started from.
    pub prediction: Pose3,
    /// The registration to the local map (`None` for the first scan, which defines the frame).
    pub registration: Option<Registration>,
    /// The adaptive threshold σ used (gate 3σ, kernel scale σ / 3), metres.
    pub sigma_m: f64,
    /// Points in the local map after the scan joined it.
    pub map_points: usize,
}

/// Lidar odometry over a sequence of scans (each in its sensor frame, sensor at the origin).
///
/// Per scan: range crop; voxel grids at `v × target_voxel_scale` (map input, with PCA
/// normals) and `v × source_voxel_scale` (registration source); prediction
/// `T_{k−1} · (T_{k−2}⁻¹ T_{k−1})`; point-to-plane ICP to the local map gated at 3σ with
/// kernel scale σ / 3; σ updated from `prediction⁻¹ · T_k`; the map voxels farther than
/// `max_range_m` from the sensor are dropped. No deskewing: scans are taken as rigid.
#[derive(Clone, Debug)]
pub struct Odometry {
    config: OdometryConfig,
    map: LocalMap,
    threshold: AdaptiveThreshold,
    poses: Vec<Pose3>,
    last_delta: Pose3,
}

impl Odometry {
    /// Odometry with `config` (checked).
    pub fn new(config: OdometryConfig) -> Result<Self> {
        config.validate()?;
        let r = &config.registration;
        Ok(Self {
            map: LocalMap::new(r.voxel_size_m, config.max_points_per_voxel),
            threshold: AdaptiveThreshold::new(
                config.initial_threshold_m,
                config.min_motion_m,
                r.max_range_m,
            ),
            poses: Vec::new(),
            last_delta: Pose3::identity(),
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &OdometryConfig {
        &self.config
    }

    /// The poses of the scans registered so far (`world_from_sensor`).
    pub fn poses(&self) -> &[Pose3] {
        &self.poses
    }

    /// Points in the local map.
    pub fn map_len(&self) -> usize {
        self.map.len()
    }

    /// The σ the next scan will use, metres.
    pub fn sigma(&self) -> f64 {
        self.config
            .fixed_threshold_m
            .unwrap_or_else(|| self.threshold.sigma())
    }

    /// Registers the next scan. On an error (bad input, no overlap) the odometry is left as
    /// it was, so the caller may skip the scan.
    pub fn register_frame(&mut self, cloud: &PointCloud) -> Result<OdometryStep> {
        let r = &self.config.registration;
        let cropped = crop(cloud, r, "frame")?;
        let fine = downsample(&cropped, r.target_voxel_m())?;
        let source = downsample(&to_cloud(&fine), r.source_voxel_m())?;
        let (points, normals) = with_normals(fine, &Point3::origin(), r);
        let sigma = self.sigma();
        let last = self.poses.last().copied();
        let prediction = last.map_or_else(Pose3::identity, |p| p * self.last_delta);
        let registration = match last {
            Some(_) if !self.map.is_empty() => {
                let (map_points, map_normals) = self.map.points_and_normals();
                let target = Target::new(map_points, map_normals)?;
                let gate = Gate {
                    max_distance_m: 3.0 * sigma,
                    kernel_scale_m: sigma / 3.0,
                };
                Some(align(&source, &target, &prediction, &gate, r)?)
            }
            _ => None,
        };
        let pose = registration.map_or(prediction, |reg| reg.target_from_source);
        if registration.is_some() {
            self.threshold.update(&(prediction.inverse() * pose));
        }
        self.map.add(&pose, &points, &normals);
        self.map
            .remove_far(&Point3::from(pose.translation()), r.max_range_m);
        self.last_delta = last.map_or_else(Pose3::identity, |l| l.inverse() * pose);
        self.poses.push(pose);
        Ok(OdometryStep {
            world_from_sensor: pose,
            prediction,
            registration,
            sigma_m: sigma,
            map_points: self.map.len(),
        })
    }
}
