//! The spherical projection of a point cloud into a range image.

use std::f64::consts::{FRAC_PI_2, TAU};

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use super::{BeamDirections, RangeImage, pixel_count, spherical_direction};
use crate::{GeometryError, PointCloud};

/// Slack when comparing an azimuth span with a full turn, radians.
const FULL_TURN_SLACK_RAD: f64 = 1e-9;

/// The usual lidar projection of points into a `rows × cols` range image: the row from the
/// elevation, the column from the azimuth, keeping the nearest point per pixel.
///
/// For a point at offset `(x, y, z)` from the sensor (REP-103 frame):
///
/// * elevation `λ = atan2(z, √(x² + y²))`; row `⌊(λ_max − λ) / Δλ⌋` with
///   `Δλ = (λ_max − λ_min) / rows`, so row 0 is the highest elevation;
/// * azimuth `η = atan2(y, x)`; column `⌊((η_max − η) mod 2π) / Δη⌋` with
///   `Δη = (η_max − η_min) / cols`, so column 0 is the largest azimuth (the left edge of a
///   panorama) and azimuths wrap around for a full turn.
///
/// Points outside the elevation or azimuth window are dropped, the edges themselves are in.
/// This is Khan (2017, App. A.1)'s equirectangular projection with the offsets corrected
/// (rows from the top, columns from the window's edge), with a fixed window instead of the
/// cloud's own angle range so that images of different scans align.
///
/// ```
/// use nalgebra::Point3;
/// use raypath_geometry::{PointCloud, SphericalProjection};
///
/// let projection = SphericalProjection::new(16, 360, -0.26, 0.26)?;
/// // A point 10 m to the left (+y) at zero elevation: azimuth π/2, a quarter turn from the
/// // left edge (azimuth π) of the image.
/// let cloud = PointCloud::from_points(vec![Point3::new(0.0, 10.0, 0.0)]);
/// let image = projection.project(&cloud, &Point3::origin())?;
/// let pixel = image.ranges_m().iter().position(|r| !r.is_nan()).unwrap();
/// assert_eq!((pixel / 360, pixel % 360), (8, 90));
/// # Ok::<(), raypath_geometry::GeometryError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SphericalProjection {
    /// Number of rows (elevation bins).
    pub rows: usize,
    /// Number of columns (azimuth bins).
    pub cols: usize,
    /// Lower edge of the elevation window in radians (≥ −π/2).
    pub elevation_min_rad: f64,
    /// Upper edge of the elevation window in radians (≤ π/2).
    pub elevation_max_rad: f64,
    /// Lower edge of the azimuth window in radians.
    pub azimuth_min_rad: f64,
    /// Upper edge of the azimuth window in radians (at most one turn above the lower edge).
    pub azimuth_max_rad: f64,
}

impl SphericalProjection {
    /// A projection over the full 360° of azimuth (`[−π, π]`) and the elevation window
    /// `[elevation_min_rad, elevation_max_rad]`.
    pub fn new(
        rows: usize,
        cols: usize,
        elevation_min_rad: f64,
        elevation_max_rad: f64,
    ) -> Result<Self, GeometryError> {
        let projection = Self {
            rows,
            cols,
            elevation_min_rad,
            elevation_max_rad,
            azimuth_min_rad: -std::f64::consts::PI,
            azimuth_max_rad: std::f64::consts::PI,
        };
        projection.validate()?;
        Ok(projection)
    }

    /// The same projection restricted to the azimuth window `[azimuth_min_rad,
    /// azimuth_max_rad]` (for sensors with a limited horizontal field of view).
    pub fn with_azimuth_window(
        self,
        azimuth_min_rad: f64,
        azimuth_max_rad: f64,
    ) -> Result<Self, GeometryError> {
        let projection = Self {
            azimuth_min_rad,
            azimuth_max_rad,
            ..self
        };
        projection.validate()?;
        Ok(projection)
    }

    /// Checks the parameters: at least one row and column (at most
    /// [`MAX_PIXELS`](super::MAX_PIXELS) pixels), finite windows of positive size, elevations
    /// within `[−π/2, π/2]` and an azimuth span of at most one turn.
    pub fn validate(&self) -> Result<(), GeometryError> {
        let invalid = |reason: String| Err(GeometryError::InvalidRangeImage { reason });
        pixel_count(self.rows, self.cols)?;
        let (e0, e1) = (self.elevation_min_rad, self.elevation_max_rad);
        if !(e0.is_finite() && e1.is_finite() && -FRAC_PI_2 <= e0 && e0 < e1 && e1 <= FRAC_PI_2) {
            return invalid(format!(
                "elevation window [{e0}, {e1}] rad must satisfy −π/2 ≤ min < max ≤ π/2"
            ));
        }
        let (a0, a1) = (self.azimuth_min_rad, self.azimuth_max_rad);
        if !(a0.is_finite() && a1.is_finite() && a0 < a1 && a1 - a0 <= TAU + FULL_TURN_SLACK_RAD) {
            return invalid(format!(
                "azimuth window [{a0}, {a1}] rad must satisfy min < max ≤ min + 2π"
            ));
        }
        Ok(())
    }

    /// True when the azimuth window is a full turn (columns wrap around).
    pub fn is_full_turn(&self) -> bool {
        self.azimuth_max_rad - self.azimuth_min_rad >= TAU - FULL_TURN_SLACK_RAD
    }

    /// Elevation bin height in radians.
    pub fn elevation_step_rad(&self) -> f64 {
        (self.elevation_max_rad - self.elevation_min_rad) / self.rows as f64
    }

    /// Azimuth bin width in radians.
    pub fn azimuth_step_rad(&self) -> f64 {
        (self.azimuth_max_rad - self.azimuth_min_rad) / self.cols as f64
    }

    /// The pixel `(row, col)` a direction (any non-zero length) falls in, `None` outside
    /// the window or for a zero or non-finite vector.
    pub fn pixel_of(&self, direction: &Vector3<f64>) -> Option<(usize, usize)> {
        let horizontal = direction.x.hypot(direction.y);
        if !(horizontal.is_finite() && direction.z.is_finite())
            || (horizontal == 0.0 && direction.z == 0.0)
        {
            return None;
        }
        let elevation = direction.z.atan2(horizontal);
        if elevation < self.elevation_min_rad || elevation > self.elevation_max_rad {
            return None;
        }
        let row = ((self.elevation_max_rad - elevation) / self.elevation_step_rad()).floor();
        let azimuth = direction.y.atan2(direction.x);
        let from_left = (self.azimuth_max_rad - azimuth).rem_euclid(TAU);
        let span = self.azimuth_max_rad - self.azimuth_min_rad;
        let col = if self.is_full_turn() || from_left <= span {
            (from_left / self.azimuth_step_rad()).floor()
        } else if TAU - from_left <= FULL_TURN_SLACK_RAD {
            // Just left of the left edge by rounding of the modulo: the left edge itself.
            0.0
        } else {
            return None;
        };
        // The lower and right edges belong to the last row and column.
        Some((
            (row as usize).min(self.rows - 1),
            (col as usize).min(self.cols - 1),
        ))
    }

    /// Elevation and azimuth (radians) of the centre of pixel `(row, col)`.
    pub fn pixel_center_rad(&self, row: usize, col: usize) -> (f64, f64) {
        (
            self.elevation_max_rad - (row as f64 + 0.5) * self.elevation_step_rad(),
            self.azimuth_max_rad - (col as f64 + 0.5) * self.azimuth_step_rad(),
        )
    }

    /// The pixel-centre directions as a spherical grid.
    pub fn directions(&self) -> BeamDirections {
        BeamDirections::Spherical {
            elevations_rad: (0..self.rows)
                .map(|row| self.pixel_center_rad(row, 0).0)
                .collect(),
            azimuths_rad: (0..self.cols)
                .map(|col| self.pixel_center_rad(0, col).1)
                .collect(),
        }
    }

    /// Projects the valid points of `cloud`, seen from `sensor_origin` (in the cloud's
    /// frame), keeping the nearest point per pixel (the first one on equal ranges).
    ///
    /// The image has per-pixel directions: the direction of the kept point, or the pixel
    /// centre for an empty pixel (a no-return, range NaN). When the cloud has intensity or
    /// label channels, the kept point's values are carried; empty pixels get NaN intensity
    /// and label 0. Points at the sensor origin are skipped.
    pub fn project(
        &self,
        cloud: &PointCloud,
        sensor_origin: &Point3<f64>,
    ) -> Result<RangeImage, GeometryError> {
        self.validate()?;
        cloud.validate()?;
        if !sensor_origin.iter().all(|v| v.is_finite()) {
            return Err(GeometryError::InvalidRangeImage {
                reason: format!("sensor origin {sensor_origin:?} is not finite"),
            });
        }
        let n = pixel_count(self.rows, self.cols)?;
        // Per pixel: the index of the nearest point and its range.
        let mut nearest: Vec<Option<(usize, f64)>> = vec![None; n];
        for (i, p) in cloud.points.iter().enumerate() {
            let offset = p.cast::<f64>() - sensor_origin;
            let range = offset.norm();
            if !(range.is_finite() && range > 0.0) {
                continue;
            }
            let Some((row, col)) = self.pixel_of(&offset) else {
                continue;
            };
            let slot = &mut nearest[row * self.cols + col];
            if slot.is_none_or(|(_, best)| range < best) {
                *slot = Some((i, range));
            }
        }
        let mut directions = Vec::with_capacity(n);
        let mut ranges_m = Vec::with_capacity(n);
        for (pixel, slot) in nearest.iter().enumerate() {
            match *slot {
                Some((i, range)) => {
                    directions.push((cloud.points[i].cast::<f64>() - sensor_origin) / range);
                    ranges_m.push(range as f32);
                }
                None => {
                    let (elevation, azimuth) =
                        self.pixel_center_rad(pixel / self.cols, pixel % self.cols);
                    directions.push(spherical_direction(elevation, azimuth).into_inner());
                    ranges_m.push(f32::NAN);
                }
            }
        }
        let mut image = RangeImage::new(
            self.rows,
            self.cols,
            BeamDirections::PerPixel(directions),
            ranges_m,
        )?;
        if let Some(intensity) = &cloud.intensity {
            let channel = nearest
                .iter()
                .map(|slot| slot.map_or(f32::NAN, |(i, _)| intensity[i]))
                .collect();
            image = image.with_intensity(channel)?;
        }
        if let Some(label) = &cloud.label {
            let channel = nearest
                .iter()
                .map(|slot| slot.map_or(0, |(i, _)| label[i]))
                .collect();
            image = image.with_label(channel)?;
        }
        Ok(image)
    }
}
