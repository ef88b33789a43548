//! Point clouds with optional per-point attributes, organized (rows × columns) or not.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::{Aabb3, GeometryError};

/// A set of 3-D points with optional intensity, label and colour channels.
///
/// Coordinates are `f32` metres — the precision of every lidar file format we read, and half
/// the memory of `f64` for scans of millions of points; convert to `f64` with
/// [`PointCloud::point_f64`] for geometry. The frame is the one the producer states (sensor
/// frame for a single scan as read from disk).
///
/// **Organized clouds** (`height > 1`, or a single-row scan kept as an image) store points row
/// by row: point `(row, col)` is at index `row * width + col`. A pixel without a return holds
/// non-finite coordinates (NaN), so the grid stays intact; [`PointCloud::is_valid`] tells the
/// two apart. Unorganized clouds have `height == 1` and `width == len`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointCloud {
    /// The points (NaN coordinates mark missing points of organized clouds).
    pub points: Vec<Point3<f32>>,
    /// Per-point intensity or reflectance, in the sensor's units.
    pub intensity: Option<Vec<f32>>,
    /// Per-point integer label (for example a ground-truth segment id).
    pub label: Option<Vec<u32>>,
    /// Per-point colour packed as `0x00RRGGBB`.
    pub rgb: Option<Vec<u32>>,
    /// Columns of an organized cloud; the number of points otherwise.
    pub width: usize,
    /// Rows of an organized cloud; 1 otherwise.
    pub height: usize,
}

impl PointCloud {
    /// An unorganized cloud of `points` without attributes.
    pub fn from_points(points: Vec<Point3<f32>>) -> Self {
        let width = points.len();
        Self {
            points,
            width,
            height: 1,
            ..Self::default()
        }
    }

    /// Number of points (including missing pixels of organized clouds).
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// True for a cloud with rows and columns (`height > 1`).
    pub fn is_organized(&self) -> bool {
        self.height > 1
    }

    /// True when point `i` has finite coordinates (it is a real return).
    pub fn is_valid(&self, i: usize) -> bool {
        self.points
            .get(i)
            .is_some_and(|p| p.iter().all(|v| v.is_finite()))
    }

    /// Number of points with finite coordinates.
    pub fn num_valid(&self) -> usize {
        self.points
            .iter()
            .filter(|p| p.iter().all(|v| v.is_finite()))
            .count()
    }

    /// Point `i` in `f64`.
    pub fn point_f64(&self, i: usize) -> Point3<f64> {
        self.points[i].cast::<f64>()
    }

    /// Index of pixel `(row, col)` of an organized cloud.
    pub fn index(&self, row: usize, col: usize) -> usize {
        row * self.width + col
    }

    /// The bounding box of the valid points (empty box for none).
    pub fn bounding_box(&self) -> Aabb3 {
        let mut aabb = Aabb3::empty();
        for p in &self.points {
            if p.iter().all(|v| v.is_finite()) {
                aabb.extend(&p.cast::<f64>());
            }
        }
        aabb
    }

    /// Checks that attribute lengths equal the number of points and that
    /// `width × height == len`.
    pub fn validate(&self) -> Result<(), GeometryError> {
        let n = self.points.len();
        if self.width.checked_mul(self.height) != Some(n) {
            return Err(GeometryError::InvalidCloud {
                reason: format!(
                    "width {} × height {} does not equal the number of points {n}",
                    self.width, self.height
                ),
            });
        }
        for (name, len) in [
            ("intensity", self.intensity.as_ref().map(Vec::len)),
            ("label", self.label.as_ref().map(Vec::len)),
            ("rgb", self.rgb.as_ref().map(Vec::len)),
        ] {
            if let Some(len) = len
                && len != n
            {
                return Err(GeometryError::InvalidCloud {
                    reason: format!("{name} has {len} values for {n} points"),
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validity_and_bbox() {
        let mut cloud = PointCloud::from_points(vec![
            Point3::new(1.0, 2.0, 3.0),
            Point3::new(f32::NAN, 0.0, 0.0),
            Point3::new(-1.0, 0.0, 5.0),
        ]);
        assert_eq!(cloud.num_valid(), 2);
        assert!(!cloud.is_valid(1));
        let aabb = cloud.bounding_box();
        assert_eq!(aabb.min, Point3::new(-1.0, 0.0, 3.0));
        assert!(cloud.validate().is_ok());
        cloud.label = Some(vec![1]);
        assert!(cloud.validate().is_err());
    }
}
