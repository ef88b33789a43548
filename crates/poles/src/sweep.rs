//! Where a spinning lidar was when it measured each point of a de-skewed sweep.
//!
//! A de-skewed (motion-compensated) sweep holds every point in the sensor frame at one
//! reference time, but the beams were fired over a whole revolution from a moving sensor:
//! the ray of a point starts where the sensor was at its firing time, not at the frame's
//! origin. Tracing free space from the origin instead bends rays past the objects in front
//! of them — at 7 m/s a KITTI sweep spans 0.7 m, and a ray traced from up to 0.35 m beside
//! its true start crosses a thin pole it never passed. `docs/results/poles-kitti.md` compares
//! pole extraction on the real KITTI frames with rays traced from the scan origin and from
//! these origins.
//!
//! Model: constant velocity over the sweep; a point at azimuth `φ` was fired a fraction
//! `τ(φ) ∈ [−½, ½)` of a revolution after the reference time, and the sensor was at
//! `τ · t_sweep` in the frame of the sweep, with `t_sweep` the sensor's translation over
//! one revolution. Rotation during the sweep does not move the origin (the lasers turn
//! about it) and is ignored.

use nalgebra::{Point3, Vector3};
use raypath_geometry::Pose3;
use serde::{Deserialize, Serialize};

/// When the points of a sweep were measured, as a function of their azimuth.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepTiming {
    /// Azimuth (sensor frame, `atan2(y, x)`, radians) the sensor faced at the sweep's
    /// reference time, the time the points were de-skewed to.
    pub reference_azimuth_rad: f64,
    /// True when the sensor spins clockwise seen from above (azimuth decreasing with time).
    pub clockwise: bool,
    /// Duration of one revolution, seconds.
    pub period_s: f64,
}

impl SweepTiming {
    /// KITTI's Velodyne HDL-64E at 10 Hz: spins clockwise with its sweeps cut at the back, the points
    /// de-skewed to the time it faces forward, when it triggers the cameras (the trigger:
    /// Geiger et al., "Vision meets Robotics: The KITTI Dataset", IJRR 2013; the sense of
    /// rotation, the cut and the reference azimuth: the timing that minimizes see-through
    /// rays at the labelled poles of the real frames, module docs).
    pub fn kitti() -> Self {
        Self {
            reference_azimuth_rad: 0.0,
            clockwise: true,
            period_s: 0.1,
        }
    }

    /// The fraction of a revolution from the reference time to the firing of a point at
    /// `azimuth_rad`, in `[−½, ½)`.
    #[inline]
    pub fn offset(&self, azimuth_rad: f64) -> f64 {
        let turned = (azimuth_rad - self.reference_azimuth_rad) / std::f64::consts::TAU;
        let turned = if self.clockwise { -turned } else { turned };
        turned - (turned + 0.5).floor()
    }
}

/// The sensor's motion during one sweep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepMotion {
    /// The sensor's translation over one revolution, in the sweep's sensor frame, metres.
    pub translation_m: Vector3<f64>,
    /// When the points were measured.
    pub timing: SweepTiming,
}

impl SweepMotion {
    /// Where the sensor was (in the sweep's sensor frame) when it measured `point`.
    #[inline]
    pub fn origin(&self, point: &Point3<f64>) -> Point3<f64> {
        let tau = self.timing.offset(point.y.atan2(point.x));
        Point3::from(self.translation_m * tau)
    }

    /// The motion of every sweep of a drive with `world_from_sensor` poses at `stamps_s`
    /// (seconds): the velocity from the neighbouring poses (central differences, one-sided
    /// at the ends) times the sweep period, in each sweep's sensor frame. Zero motion where
    /// two stamps coincide or there is one pose.
    pub fn from_poses(poses: &[Pose3], stamps_s: &[f64], timing: SweepTiming) -> Vec<Self> {
        let period_s = timing.period_s;
        let n = poses.len().min(stamps_s.len());
        (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(n.saturating_sub(1)));
                let dt = stamps_s[b] - stamps_s[a];
                let moved = poses[b].translation() - poses[a].translation();
                let velocity = if dt > 0.0 && dt.is_finite() {
                    moved / dt
                } else {
                    Vector3::zeros()
                };
                Self {
                    translation_m: poses[i].rotation().inverse() * velocity * period_s,
                    timing,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_follow_the_sense_of_rotation() {
        let kitti = SweepTiming::kitti();
        let deg = |d: f64| d.to_radians();
        // Clockwise from the front: the right side (−90°) a quarter turn later, the left side
        // (+90°) a quarter turn earlier, the back at the cut.
        assert!(kitti.offset(0.0).abs() < 1e-12);
        assert!((kitti.offset(deg(-90.0)) - 0.25).abs() < 1e-12);
        assert!((kitti.offset(deg(90.0)) + 0.25).abs() < 1e-12);
        assert!((kitti.offset(deg(179.9)) + 0.5).abs() < 1e-3);
        assert!((kitti.offset(deg(-179.9)) - 0.5).abs() < 1e-3);
        let ccw = SweepTiming {
            clockwise: false,
            ..kitti
        };
        assert!((ccw.offset(deg(90.0)) - 0.25).abs() < 1e-12);
        for k in 0..720 {
            let tau = kitti.offset(deg(k as f64 * 0.5 - 180.0));
            assert!((-0.5..0.5).contains(&tau), "{tau}");
        }
    }

    #[test]
    fn motion_from_poses_is_the_velocity_over_a_sweep() {
        // 7 m/s along the world y axis, the sensor facing +y (yaw 90°): forward in its frame.
        let poses: Vec<Pose3> = (0..4)
            .map(|i| {
                Pose3::from_xyz_rpy(
                    0.0,
                    0.7 * i as f64,
                    0.0,
                    0.0,
                    0.0,
                    std::f64::consts::FRAC_PI_2,
                )
            })
            .collect();
        let stamps = [0.0, 0.1, 0.2, 0.3];
        let motions = SweepMotion::from_poses(&poses, &stamps, SweepTiming::kitti());
        assert_eq!(motions.len(), 4);
        for m in &motions {
            assert!((m.translation_m - Vector3::new(0.7, 0.0, 0.0)).norm() < 1e-9);
        }
        // A point on the right was measured a quarter turn late: 0.175 m ahead.
        let origin = motions[1].origin(&Point3::new(0.0, -5.0, 0.0));
        assert!((origin - Point3::new(0.175, 0.0, 0.0)).norm() < 1e-9);
        let still = SweepMotion::from_poses(&poses[..1], &stamps[..1], SweepTiming::kitti());
        assert_eq!(still[0].translation_m, Vector3::zeros());
    }
}
