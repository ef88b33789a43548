//! Planar laser scans: a fan of beams at equally spaced angles.

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::{GeometryError, Pose2, Range, Ray2};

/// A 2-D laser scan in the sensor frame: beam `i` points at
/// `angle_min_rad + i · angle_increment_rad` (counter-clockwise from the sensor's x axis,
/// REP-103), like ROS `sensor_msgs/LaserScan`.
///
/// Ranges are metres. A reading is a no-return when it is not finite, not positive, or at or
/// above `max_range_m` (lasers report their maximum, or a code above it, when nothing
/// reflected).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scan2 {
    /// Angle of the first beam in radians.
    pub angle_min_rad: f64,
    /// Angle between neighbouring beams in radians.
    pub angle_increment_rad: f64,
    /// Maximum range in metres; readings at or above it are no-returns.
    pub max_range_m: f64,
    /// Range readings in metres.
    pub ranges: Vec<f64>,
    /// Optional per-beam intensity (remission) in the sensor's units.
    pub intensities: Option<Vec<f64>>,
}

impl Scan2 {
    /// Checks parameters: finite angles, a positive maximum range, and as many intensities as
    /// ranges.
    pub fn validate(&self) -> Result<(), GeometryError> {
        if !self.angle_min_rad.is_finite() || !self.angle_increment_rad.is_finite() {
            return Err(GeometryError::InvalidScan {
                reason: "beam angles must be finite".into(),
            });
        }
        if self.max_range_m.is_nan() || self.max_range_m <= 0.0 {
            return Err(GeometryError::InvalidScan {
                reason: format!("maximum range must be positive, got {}", self.max_range_m),
            });
        }
        if let Some(intensities) = &self.intensities
            && intensities.len() != self.ranges.len()
        {
            return Err(GeometryError::InvalidScan {
                reason: format!(
                    "{} intensities for {} ranges",
                    intensities.len(),
                    self.ranges.len()
                ),
            });
        }
        Ok(())
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.ranges.len()
    }

    /// True when the scan has no beams.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// The angle of beam `i` in radians.
    pub fn angle(&self, i: usize) -> f64 {
        self.angle_min_rad + i as f64 * self.angle_increment_rad
    }

    /// The angle of the last beam in radians.
    pub fn angle_max_rad(&self) -> f64 {
        self.angle(self.ranges.len().saturating_sub(1))
    }

    /// Beam `i`'s reading as a [`Range`].
    pub fn range(&self, i: usize) -> Range {
        let r = self.ranges[i];
        if r.is_finite() && r > 0.0 && r < self.max_range_m {
            Range::Hit(r)
        } else {
            Range::NoReturn
        }
    }

    /// The beams as rays in the frame of `frame_from_sensor` (pass the identity for the
    /// sensor frame).
    pub fn rays(&self, frame_from_sensor: Pose2) -> impl Iterator<Item = Ray2> + '_ {
        let origin = Point2::new(frame_from_sensor.x(), frame_from_sensor.y());
        let theta = frame_from_sensor.theta();
        (0..self.len()).map(move |i| Ray2::from_angle(origin, theta + self.angle(i), self.range(i)))
    }

    /// The reflection points of all hits, in the frame of `frame_from_sensor`.
    pub fn points(&self, frame_from_sensor: Pose2) -> impl Iterator<Item = Point2<f64>> + '_ {
        self.rays(frame_from_sensor)
            .filter_map(|ray| ray.endpoint())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn rays_and_no_returns() {
        let scan = Scan2 {
            angle_min_rad: -FRAC_PI_2,
            angle_increment_rad: FRAC_PI_2,
            max_range_m: 10.0,
            ranges: vec![1.0, 10.0, 2.0],
            intensities: None,
        };
        assert!(scan.validate().is_ok());
        assert_eq!(scan.range(1), Range::NoReturn);
        let points: Vec<_> = scan.points(Pose2::new(1.0, 0.0, 0.0)).collect();
        assert_eq!(points.len(), 2);
        assert!((points[0] - Point2::new(1.0, -1.0)).norm() < 1e-12);
        assert!((points[1] - Point2::new(1.0, 2.0)).norm() < 1e-12);
    }
}
