//! Organized range images: the native layout of spinning lidars.
//!
//! A range image has `rows × cols` pixels, stored row by row (pixel `(row, col)` at index
//! `row · cols + col`). Each pixel is one beam: a unit direction ([`BeamDirections`]) and a
//! range in metres. For a spinning lidar, rows are the laser channels (row 0 the highest
//! elevation) and columns the firing azimuths (column 0 at the largest azimuth, so the image
//! reads left to right like a panorama seen from the sensor) — the layout that
//! [`SphericalProjection`] produces (as in Khan 2017, App. A.1, and the usual lidar
//! projections of RangeNet++ and friends). [`RingProjection`] builds the same layout from a
//! scan stored ring by ring (KITTI's Velodyne files), one row per laser.
//!
//! **No-returns** are kept: their range is `NaN` (`f32`), the same marker an organized
//! [`PointCloud`] uses for a missing point, so a no-return still knows its beam direction
//! (when the source recorded it) and can be traced as free space up to the maximum range.
//! Units: metres and radians; directions are in the image's frame (the sensor frame as read
//! from disk, REP-103), the sensor origin is given in that frame when converting.

mod directions;
mod rings;
mod spherical;

pub use directions::{BeamDirections, spherical_direction};
pub use rings::{RingAssignment, RingProjection};
pub use spherical::SphericalProjection;

use nalgebra::{Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::{GeometryError, PointCloud, Range, Ray3};

/// Most pixels a range image may have (2^28): a guard against absurd sizes.
pub const MAX_PIXELS: usize = 1 << 28;

/// An organized lidar scan: per pixel a beam direction, a range (NaN for no-return) and
/// optional intensity and label channels.
///
/// ```
/// use nalgebra::Point3;
/// use raypath_geometry::{BeamDirections, Range, RangeImage};
///
/// // Two channels (elevations ±0.1 rad) × three azimuths; one no-return.
/// let directions = BeamDirections::Spherical {
///     elevations_rad: vec![0.1, -0.1],
///     azimuths_rad: vec![1.0, 0.0, -1.0],
/// };
/// let image = RangeImage::new(2, 3, directions, vec![5.0, 6.0, f32::NAN, 7.0, 8.0, 9.0])?;
/// assert_eq!(image.range(0, 2), Some(Range::NoReturn));
/// let cloud = image.to_point_cloud(&Point3::origin());
/// assert_eq!((cloud.width, cloud.height, cloud.num_valid()), (3, 2, 5));
/// let back = RangeImage::from_point_cloud(&cloud, &Point3::origin())?;
/// assert!((back.ranges_m()[4] - 8.0).abs() < 1e-5);
/// # Ok::<(), raypath_geometry::GeometryError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RangeImage {
    rows: usize,
    cols: usize,
    directions: BeamDirections,
    ranges_m: Vec<f32>,
    intensity: Option<Vec<f32>>,
    label: Option<Vec<u32>>,
}

fn invalid<T>(reason: String) -> Result<T, GeometryError> {
    Err(GeometryError::InvalidRangeImage { reason })
}

/// Checks `rows × cols` against [`MAX_PIXELS`] and returns the pixel count.
pub(crate) fn pixel_count(rows: usize, cols: usize) -> Result<usize, GeometryError> {
    match rows.checked_mul(cols) {
        Some(n) if rows > 0 && cols > 0 && n <= MAX_PIXELS => Ok(n),
        _ => invalid(format!(
            "{rows} × {cols} pixels (allowed: 1 to {MAX_PIXELS} pixels)"
        )),
    }
}

impl RangeImage {
    /// A range image of `rows × cols` pixels. Fails when the sizes disagree, a direction is
    /// not a unit vector, a range is negative or infinite, or a pixel with a range has no
    /// direction.
    pub fn new(
        rows: usize,
        cols: usize,
        directions: BeamDirections,
        ranges_m: Vec<f32>,
    ) -> Result<Self, GeometryError> {
        let n = pixel_count(rows, cols)?;
        if ranges_m.len() != n {
            return invalid(format!(
                "{} ranges for {rows} × {cols} pixels",
                ranges_m.len()
            ));
        }
        directions.validate(rows, cols)?;
        for (i, &r) in ranges_m.iter().enumerate() {
            let (row, col) = (i / cols, i % cols);
            let valid = r.is_nan() || (r.is_finite() && r >= 0.0);
            if !valid {
                return invalid(format!(
                    "range of pixel ({row}, {col}) is {r} (expected ≥ 0 m, or NaN for no-return)"
                ));
            }
            if !r.is_nan() && directions.direction(cols, row, col).is_none() {
                return invalid(format!("pixel ({row}, {col}) has a range but no direction"));
            }
        }
        Ok(Self {
            rows,
            cols,
            directions,
            ranges_m,
            intensity: None,
            label: None,
        })
    }

    /// Adds an intensity channel (one value per pixel, the sensor's units).
    pub fn with_intensity(mut self, intensity: Vec<f32>) -> Result<Self, GeometryError> {
        if intensity.len() != self.len() {
            return invalid(format!(
                "{} intensities for {} pixels",
                intensity.len(),
                self.len()
            ));
        }
        self.intensity = Some(intensity);
        Ok(self)
    }

    /// Adds a label channel (one value per pixel).
    pub fn with_label(mut self, label: Vec<u32>) -> Result<Self, GeometryError> {
        if label.len() != self.len() {
            return invalid(format!("{} labels for {} pixels", label.len(), self.len()));
        }
        self.label = Some(label);
        Ok(self)
    }

    /// Number of rows (lidar channels).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns (azimuth steps).
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of pixels, `rows × cols`.
    pub fn len(&self) -> usize {
        self.ranges_m.len()
    }

    /// Always false: an image has at least one pixel.
    pub fn is_empty(&self) -> bool {
        self.ranges_m.is_empty()
    }

    /// The beam directions.
    pub fn directions(&self) -> &BeamDirections {
        &self.directions
    }

    /// Ranges in metres, row by row; NaN for no-returns.
    pub fn ranges_m(&self) -> &[f32] {
        &self.ranges_m
    }

    /// The intensity channel, if any.
    pub fn intensity(&self) -> Option<&[f32]> {
        self.intensity.as_deref()
    }

    /// The label channel, if any.
    pub fn label(&self) -> Option<&[u32]> {
        self.label.as_deref()
    }

    /// Index of pixel `(row, col)`, `None` outside the image.
    pub fn index(&self, row: usize, col: usize) -> Option<usize> {
        (row < self.rows && col < self.cols).then(|| row * self.cols + col)
    }

    /// What pixel `(row, col)` saw; `None` outside the image.
    pub fn range(&self, row: usize, col: usize) -> Option<Range> {
        let r = self.ranges_m[self.index(row, col)?];
        Some(if r.is_nan() {
            Range::NoReturn
        } else {
            Range::Hit(f64::from(r))
        })
    }

    /// The beam direction of pixel `(row, col)`; `None` outside the image or for a
    /// no-return without a recorded direction.
    pub fn direction(&self, row: usize, col: usize) -> Option<Unit<Vector3<f64>>> {
        if row >= self.rows {
            return None;
        }
        self.directions.direction(self.cols, row, col)
    }

    /// The beam of pixel `(row, col)` from `sensor_origin` (hits and no-returns); `None`
    /// outside the image or without a direction.
    pub fn ray(&self, row: usize, col: usize, sensor_origin: &Point3<f64>) -> Option<Ray3> {
        Some(Ray3 {
            origin: *sensor_origin,
            direction: self.direction(row, col)?,
            range: self.range(row, col)?,
        })
    }

    /// All beams with a direction, row by row.
    pub fn rays(&self, sensor_origin: &Point3<f64>) -> impl Iterator<Item = Ray3> + '_ {
        let origin = *sensor_origin;
        (0..self.rows)
            .flat_map(move |row| (0..self.cols).map(move |col| (row, col)))
            .filter_map(move |(row, col)| self.ray(row, col, &origin))
    }

    /// The reflection point of pixel `(row, col)`; `None` for a no-return or outside.
    pub fn point(
        &self,
        row: usize,
        col: usize,
        sensor_origin: &Point3<f64>,
    ) -> Option<Point3<f64>> {
        self.ray(row, col, sensor_origin)?.endpoint()
    }

    /// Number of pixels with a return.
    pub fn num_returns(&self) -> usize {
        self.ranges_m.iter().filter(|r| !r.is_nan()).count()
    }

    /// The organized point cloud (`width = cols`, `height = rows`) of the returns seen from
    /// `sensor_origin`; no-return pixels hold NaN points. Intensity and label are carried.
    pub fn to_point_cloud(&self, sensor_origin: &Point3<f64>) -> PointCloud {
        let nan = Point3::new(f32::NAN, f32::NAN, f32::NAN);
        let mut points = Vec::with_capacity(self.len());
        for row in 0..self.rows {
            for col in 0..self.cols {
                let point = self.point(row, col, sensor_origin);
                points.push(point.map_or(nan, |p| p.cast::<f32>()));
            }
        }
        PointCloud {
            points,
            intensity: self.intensity.clone(),
            label: self.label.clone(),
            rgb: None,
            width: self.cols,
            height: self.rows,
        }
    }

    /// The range image of an organized cloud (`rows = height`, `cols = width`) seen from
    /// `sensor_origin`: per pixel the direction and distance of its point. Missing (NaN)
    /// points become no-returns without a direction, and so does a point exactly at the
    /// sensor origin (its direction is undefined; drivers write `(0, 0, 0)` for missing
    /// returns). Intensity and label are carried.
    pub fn from_point_cloud(
        cloud: &PointCloud,
        sensor_origin: &Point3<f64>,
    ) -> Result<Self, GeometryError> {
        cloud.validate()?;
        if !sensor_origin.iter().all(|v| v.is_finite()) {
            return invalid(format!("sensor origin {sensor_origin:?} is not finite"));
        }
        let (rows, cols) = (cloud.height, cloud.width);
        pixel_count(rows, cols)?;
        let missing = Vector3::repeat(f64::NAN);
        let mut directions = Vec::with_capacity(cloud.len());
        let mut ranges_m = Vec::with_capacity(cloud.len());
        for p in &cloud.points {
            let offset = p.cast::<f64>() - sensor_origin;
            let range = offset.norm();
            if range.is_finite() && range > 0.0 {
                directions.push(offset / range);
                ranges_m.push(range as f32);
            } else {
                directions.push(missing);
                ranges_m.push(f32::NAN);
            }
        }
        let mut image = Self::new(rows, cols, BeamDirections::PerPixel(directions), ranges_m)?;
        image.intensity = cloud.intensity.clone();
        image.label = cloud.label.clone();
        Ok(image)
    }
}

#[cfg(test)]
mod tests;
