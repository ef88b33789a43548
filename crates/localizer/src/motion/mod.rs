//! Motion models (the prediction step) and the control inputs they take.
//!
//! | model | state | control | reference |
//! | --- | --- | --- | --- |
//! | [`OdometryMotionModel`] | SE(2) | [`OdometryControl`] (two odometry poses) | Thrun et al. 2005, §5.4, Table 5.6 |
//! | [`PlanarGaussianMotionModel`] | SE(2) | [`PlanarIncrement`] (increment + covariance) | Schaefer 2020, ch. 12 |
//! | [`Gaussian6DofMotionModel`] | SE(3) | [`Pose3`](raypath_geometry::Pose3) increment | ours (ch. 7 leaves it open) |
//!
//! All increments are **body-frame**: the new particle is `x' = x · Δ̃` with the noisy increment
//! Δ̃ (right multiplication: Schaefer 2020, §12.4.3, prints `Δ · x`; the reference
//! implementation and the physics of relative odometry use `x · Δ`).
//! [`crate::PoseTrack::increment`] computes Δ between two time stamps from an odometry track.

mod gaussian3;
mod odometry;
mod planar;

pub use gaussian3::Gaussian6DofMotionModel;
pub use odometry::{OdometryControl, OdometryMotionModel};
pub use planar::{PlanarGaussianMotionModel, PlanarIncrement};
