//! Time-stamped pose tracks and pose interpolation by time.
//!
//! A [`PoseTrack`] holds poses with strictly increasing time stamps (seconds). Between two
//! stamps the pose is interpolated linearly in the translation and along the shorter arc in
//! the rotation (slerp for SE(3)). It serves two purposes:
//!
//! * the **odometry increment** between two times, `Δ = odom_from(t₀)⁻¹ · odom_from(t₁)`,
//!   the control of the motion models when odometry and sensor clocks differ
//!   ([`PoseTrack::increment`], [`PoseTrack::odometry_control`]);
//! * the ground-truth and estimated trajectories of the [`crate::eval`] module.

use raypath_geometry::Pose2;
use serde::{Deserialize, Serialize};

use crate::error::LocalizerError;
use crate::motion::OdometryControl;
use crate::state::FilterState;

/// A pose with a time stamp in seconds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stamped<S> {
    /// Time stamp in seconds.
    pub stamp_secs: f64,
    /// The pose (e.g. `world_from_robot`).
    pub pose: S,
}

impl<S> Stamped<S> {
    /// A stamped pose.
    pub fn new(stamp_secs: f64, pose: S) -> Self {
        Self { stamp_secs, pose }
    }
}

/// Poses with strictly increasing, finite time stamps (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseTrack<S> {
    stamps_secs: Vec<f64>,
    poses: Vec<S>,
}

impl<S: FilterState> PoseTrack<S> {
    /// The track of `samples`, which must be non-empty, finite and strictly increasing in
    /// time (errors name the first offending index).
    pub fn new(samples: impl IntoIterator<Item = Stamped<S>>) -> Result<Self, LocalizerError> {
        let (stamps_secs, poses) = samples.into_iter().map(|s| (s.stamp_secs, s.pose)).unzip();
        Self::from_parts(stamps_secs, poses)
    }

    /// The track from parallel vectors of stamps (seconds) and poses.
    pub fn from_parts(stamps_secs: Vec<f64>, poses: Vec<S>) -> Result<Self, LocalizerError> {
        if stamps_secs.len() != poses.len() {
            return Err(LocalizerError::InvalidParameter {
                name: "poses",
                reason: format!("{} stamps but {} poses", stamps_secs.len(), poses.len()),
            });
        }
        if stamps_secs.is_empty() {
            return Err(LocalizerError::Empty { what: "pose track" });
        }
        for (index, (stamp, pose)) in stamps_secs.iter().zip(&poses).enumerate() {
            if !stamp.is_finite() {
                return Err(LocalizerError::NonFinite {
                    what: "pose track stamp",
                    index,
                });
            }
            if !pose.is_finite() {
                return Err(LocalizerError::NonFinite {
                    what: "pose track pose",
                    index,
                });
            }
        }
        if let Some(index) = stamps_secs.windows(2).position(|w| w[1] <= w[0]) {
            return Err(LocalizerError::UnsortedStamps {
                what: "pose track",
                index: index + 1,
                stamp_secs: stamps_secs.get(index + 1).copied().unwrap_or(f64::NAN),
            });
        }
        Ok(Self { stamps_secs, poses })
    }

    /// Number of poses (at least 1).
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Always false: a track holds at least one pose.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// The time stamps in seconds.
    pub fn stamps_secs(&self) -> &[f64] {
        &self.stamps_secs
    }

    /// The poses.
    pub fn poses(&self) -> &[S] {
        &self.poses
    }

    /// The first time stamp in seconds.
    pub fn start_secs(&self) -> f64 {
        self.stamps_secs.first().copied().unwrap_or(f64::NAN)
    }

    /// The last time stamp in seconds.
    pub fn end_secs(&self) -> f64 {
        self.stamps_secs.last().copied().unwrap_or(f64::NAN)
    }

    /// The stamped poses in time order.
    pub fn iter(&self) -> impl Iterator<Item = Stamped<S>> + '_ {
        self.stamps_secs
            .iter()
            .zip(&self.poses)
            .map(|(&stamp_secs, &pose)| Stamped { stamp_secs, pose })
    }

    /// True when `stamp_secs` lies within the track's span.
    pub fn covers(&self, stamp_secs: f64) -> bool {
        stamp_secs >= self.start_secs() && stamp_secs <= self.end_secs()
    }

    /// The pose at `stamp_secs`, interpolated between the neighbouring samples; an error when
    /// the time lies outside the track's span (no extrapolation).
    pub fn pose_at(&self, stamp_secs: f64) -> Result<S, LocalizerError> {
        let out_of_span = || LocalizerError::OutOfSpan {
            what: "pose track",
            stamp_secs,
            start_secs: self.start_secs(),
            end_secs: self.end_secs(),
        };
        if !self.covers(stamp_secs) {
            return Err(out_of_span());
        }
        // First sample strictly after the requested time.
        let after = self.stamps_secs.partition_point(|&s| s <= stamp_secs);
        if after == self.stamps_secs.len() {
            return self.poses.last().copied().ok_or_else(out_of_span);
        }
        let before = after.saturating_sub(1);
        match (
            self.stamps_secs.get(before),
            self.stamps_secs.get(after),
            self.poses.get(before),
            self.poses.get(after),
        ) {
            (Some(&t0), Some(&t1), Some(p0), Some(p1)) => {
                let fraction = (stamp_secs - t0) / (t1 - t0);
                Ok(p0.interpolate(p1, fraction))
            }
            _ => Err(out_of_span()),
        }
    }

    /// The body-frame increment `pose(t₀)⁻¹ · pose(t₁)` between two times: the odometry
    /// control between them when the track is an odometry track.
    pub fn increment(&self, from_secs: f64, to_secs: f64) -> Result<S, LocalizerError> {
        let from = self.pose_at(from_secs)?;
        let to = self.pose_at(to_secs)?;
        Ok(from.inverse().compose(&to))
    }
}

impl PoseTrack<Pose2> {
    /// The [`OdometryControl`] between two times of an odometry track.
    pub fn odometry_control(
        &self,
        from_secs: f64,
        to_secs: f64,
    ) -> Result<OdometryControl, LocalizerError> {
        Ok(OdometryControl::from_poses(
            &self.pose_at(from_secs)?,
            &self.pose_at(to_secs)?,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track() -> PoseTrack<Pose2> {
        PoseTrack::new([
            Stamped::new(0.0, Pose2::new(0.0, 0.0, 0.0)),
            Stamped::new(1.0, Pose2::new(2.0, 0.0, 0.5)),
            Stamped::new(3.0, Pose2::new(2.0, 4.0, 1.5)),
        ])
        .unwrap()
    }

    #[test]
    fn interpolates_and_refuses_to_extrapolate() {
        let t = track();
        let p = t.pose_at(0.5).unwrap();
        assert!((p.x() - 1.0).abs() < 1e-12 && (p.theta() - 0.25).abs() < 1e-12);
        let p = t.pose_at(2.0).unwrap();
        assert!((p.y() - 2.0).abs() < 1e-12 && (p.theta() - 1.0).abs() < 1e-12);
        assert_eq!(t.pose_at(3.0).unwrap(), Pose2::new(2.0, 4.0, 1.5));
        assert_eq!(t.pose_at(0.0).unwrap(), Pose2::new(0.0, 0.0, 0.0));
        assert!(matches!(
            t.pose_at(3.1),
            Err(LocalizerError::OutOfSpan { .. })
        ));
        assert!(t.pose_at(f64::NAN).is_err());
    }

    #[test]
    fn increment_composes_back() {
        let t = track();
        let delta = t.increment(0.5, 2.0).unwrap();
        let end = t.pose_at(0.5).unwrap() * delta;
        let expected = t.pose_at(2.0).unwrap();
        assert!((end.translation() - expected.translation()).norm() < 1e-12);
    }

    #[test]
    fn rejects_bad_tracks() {
        let p = Pose2::identity();
        assert!(matches!(
            PoseTrack::new([Stamped::new(1.0, p), Stamped::new(1.0, p)]),
            Err(LocalizerError::UnsortedStamps { index: 1, .. })
        ));
        assert!(PoseTrack::<Pose2>::new([]).is_err());
        assert!(PoseTrack::new([Stamped::new(f64::INFINITY, p)]).is_err());
        assert!(PoseTrack::new([Stamped::new(0.0, Pose2::new(f64::NAN, 0.0, 0.0))]).is_err());
    }
}
