//! Range images of scans stored ring by ring, the layout of KITTI's Velodyne files.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use super::{BeamDirections, RangeImage, SphericalProjection, pixel_count, spherical_direction};
use crate::{GeometryError, PointCloud};

/// The projection of a scan whose points are stored **ring by ring** (all returns of one
/// laser in firing order, then those of the next laser) into a `rings × cols` range image:
/// the row is the point's ring, the column its azimuth bin, the nearest point kept per pixel.
///
/// * **Ring**: a ring sweeps one full turn of azimuth and the next ring starts where the
///   azimuth steps across the seam `seam_rad` in the direction of the sweep, once the current
///   ring has swept at least half a turn (so points jittering about the seam do not start a
///   ring). Both sweep directions are recognized. The rings are then sorted by their mean
///   elevation, row 0 the highest (the [`RangeImage`] layout).
/// * **Column**: as [`SphericalProjection`] over a full turn, `⌊((π − η) mod 2π) / Δη⌋` with
///   `Δη = 2π / cols` (column 0 at azimuth π, behind the sensor).
///
/// KITTI odometry scans (Velodyne HDL-64E, Geiger et al. 2013) are stored this way: each
/// laser's returns start just counter-clockwise of the forward axis (azimuth 0⁺), sweep
/// counter-clockwise and end just clockwise of it, 64 rings from the highest laser down. A
/// uniform elevation grid ([`SphericalProjection`]) does not fit the HDL-64E, whose lasers are
/// about 1/3° apart in the upper block and 1/2° in the lower one (Velodyne HDL-64E S2
/// manual) and whose per-laser calibration moves each ring by tenths of a degree: two rings
/// share a row in the upper block and rows stay empty in the lower one. On KITTI 00 frame 0
/// at 64 × 2083 pixels the uniform grid over [−24.8°, 2°] keeps 80 % of the points, the rings
/// 92 % (the rest are returns of one laser that fall in one azimuth bin).
///
/// Points that are not finite or lie at the sensor origin are skipped and do not take part
/// in the ring detection. Units: metres and radians, the cloud's frame (REP-103).
///
/// ```
/// use nalgebra::Point3;
/// use raypath_geometry::{PointCloud, RingProjection};
///
/// // Two rings of four points each (elevations 0.1 and −0.1 rad), stored ring by ring,
/// // each sweeping counter-clockwise from just past the forward axis.
/// let mut points = Vec::new();
/// for elevation in [0.1_f64, -0.1] {
///     for k in 0..4 {
///         let azimuth = 0.1 + k as f64 * std::f64::consts::FRAC_PI_2;
///         let d = raypath_geometry::spherical_direction(elevation, azimuth).into_inner() * 5.0;
///         points.push(Point3::new(d.x as f32, d.y as f32, d.z as f32));
///     }
/// }
/// let projection = RingProjection::new(2, 4)?;
/// let image = projection.project(&PointCloud::from_points(points), &Point3::origin())?;
/// assert_eq!((image.rows(), image.cols(), image.num_returns()), (2, 4, 8));
/// # Ok::<(), raypath_geometry::GeometryError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RingProjection {
    /// Number of rings (rows); the scan must have exactly this many.
    pub rings: usize,
    /// Number of columns (azimuth bins over a full turn).
    pub cols: usize,
    /// Azimuth at which the rings start and end, radians (KITTI: 0, the forward axis).
    pub seam_rad: f64,
}

/// Where the points of a scan fall in a [`RingProjection`].
#[derive(Clone, Debug, PartialEq)]
pub struct RingAssignment {
    /// Per pixel (row-major, `rings × cols`): the index of the point kept there.
    pub pixel_point: Vec<Option<usize>>,
    /// Per point: its row (the ring sorted by elevation), `None` for skipped points.
    pub point_row: Vec<Option<usize>>,
    /// Per row: the mean elevation of its points, radians.
    pub row_elevation_rad: Vec<f64>,
}

impl RingProjection {
    /// A projection of `rings × cols` pixels with the seam on the forward axis (azimuth 0),
    /// the KITTI layout.
    pub fn new(rings: usize, cols: usize) -> Result<Self, GeometryError> {
        let projection = Self {
            rings,
            cols,
            seam_rad: 0.0,
        };
        projection.validate()?;
        Ok(projection)
    }

    /// Checks the sizes (at least one pixel, at most [`MAX_PIXELS`](super::MAX_PIXELS)) and
    /// that the seam is finite.
    pub fn validate(&self) -> Result<(), GeometryError> {
        pixel_count(self.rings, self.cols)?;
        if !self.seam_rad.is_finite() {
            return Err(GeometryError::InvalidRangeImage {
                reason: format!("ring seam azimuth {} rad is not finite", self.seam_rad),
            });
        }
        Ok(())
    }

    /// The column grid: a one-row spherical projection over a full turn.
    fn columns(&self) -> Result<SphericalProjection, GeometryError> {
        SphericalProjection::new(1, self.cols, -FRAC_PI_2, FRAC_PI_2)
    }

    /// Assigns the points of `cloud` (seen from `sensor_origin`, in the cloud's frame) to
    /// rows and pixels. Fails when the parameters are invalid, the cloud is inconsistent, or
    /// the scan does not have exactly `rings` rings (it is not stored ring by ring with its
    /// seam at `seam_rad`).
    pub fn assign(
        &self,
        cloud: &PointCloud,
        sensor_origin: &Point3<f64>,
    ) -> Result<RingAssignment, GeometryError> {
        self.validate()?;
        cloud.validate()?;
        if !sensor_origin.iter().all(|v| v.is_finite()) {
            return Err(GeometryError::InvalidRangeImage {
                reason: format!("sensor origin {sensor_origin:?} is not finite"),
            });
        }
        let columns = self.columns()?;
        let (ring_of, found, elevation_sum, counts) = self.detect(cloud, sensor_origin);
        if found != self.rings {
            return Err(GeometryError::InvalidRangeImage {
                reason: format!(
                    "found {found} rings, expected {}: the points are not stored ring by ring \
                     with the seam at azimuth {} rad",
                    self.rings, self.seam_rad
                ),
            });
        }
        // Rings sorted by mean elevation, highest first.
        let mean: Vec<f64> = (0..found)
            .map(|r| elevation_sum[r] / counts[r] as f64)
            .collect();
        let mut order: Vec<usize> = (0..found).collect();
        order.sort_by(|&a, &b| mean[b].total_cmp(&mean[a]));
        let mut row_of_ring = vec![0; found];
        for (row, &ring) in order.iter().enumerate() {
            row_of_ring[ring] = row;
        }
        let mut pixel_point: Vec<Option<usize>> = vec![None; self.rings * self.cols];
        let mut best_range = vec![f64::INFINITY; self.rings * self.cols];
        let mut point_row = vec![None; cloud.len()];
        for (i, ring) in ring_of.iter().enumerate() {
            let Some(ring) = *ring else { continue };
            let offset = cloud.points[i].cast::<f64>() - sensor_origin;
            let Some((_, col)) = columns.pixel_of(&offset) else {
                continue;
            };
            let row = row_of_ring[ring];
            point_row[i] = Some(row);
            let pixel = row * self.cols + col;
            let range = offset.norm();
            if range < best_range[pixel] {
                best_range[pixel] = range;
                pixel_point[pixel] = Some(i);
            }
        }
        Ok(RingAssignment {
            pixel_point,
            point_row,
            row_elevation_rad: order.iter().map(|&r| mean[r]).collect(),
        })
    }

    /// Ring index of every usable point in storage order, the number of rings found, and per
    /// ring the sum of elevations and the point count.
    #[allow(clippy::type_complexity)]
    fn detect(
        &self,
        cloud: &PointCloud,
        sensor_origin: &Point3<f64>,
    ) -> (Vec<Option<usize>>, usize, Vec<f64>, Vec<usize>) {
        let wrap = |a: f64| (a + PI).rem_euclid(TAU) - PI;
        let mut ring_of = vec![None; cloud.len()];
        let (mut ring, mut swept, mut previous) = (0usize, 0.0f64, None::<f64>);
        let (mut elevation_sum, mut counts) = (vec![0.0], vec![0usize]);
        for (i, p) in cloud.points.iter().enumerate() {
            let offset: Vector3<f64> = p.cast::<f64>() - sensor_origin;
            let horizontal = offset.x.hypot(offset.y);
            if !(horizontal.is_finite() && offset.z.is_finite()) || offset.norm() == 0.0 {
                continue;
            }
            let azimuth = wrap(offset.y.atan2(offset.x) - self.seam_rad);
            if let Some(before) = previous {
                let step = wrap(azimuth - before);
                let counter_clockwise = before < 0.0 && azimuth >= 0.0 && step > 0.0;
                let clockwise = before >= 0.0 && azimuth < 0.0 && step < 0.0;
                let crosses = (counter_clockwise && swept >= PI) || (clockwise && swept <= -PI);
                if crosses {
                    ring += 1;
                    swept = 0.0;
                    elevation_sum.push(0.0);
                    counts.push(0);
                } else {
                    swept += step;
                }
            }
            previous = Some(azimuth);
            ring_of[i] = Some(ring);
            elevation_sum[ring] += offset.z.atan2(horizontal);
            counts[ring] += 1;
        }
        let found = if previous.is_some() { ring + 1 } else { 0 };
        (ring_of, found, elevation_sum, counts)
    }

    /// Projects the usable points of `cloud` (see [`RingProjection::assign`]).
    ///
    /// The image has per-pixel directions: the direction of the kept point, or for an empty
    /// pixel (a no-return, range NaN) the mean elevation of its row at the column's centre
    /// azimuth. Intensity and label channels are carried (empty pixels: NaN intensity, label
    /// 0).
    pub fn project(
        &self,
        cloud: &PointCloud,
        sensor_origin: &Point3<f64>,
    ) -> Result<RangeImage, GeometryError> {
        let assignment = self.assign(cloud, sensor_origin)?;
        let columns = self.columns()?;
        let n = self.rings * self.cols;
        let mut directions = Vec::with_capacity(n);
        let mut ranges_m = Vec::with_capacity(n);
        for (pixel, kept) in assignment.pixel_point.iter().enumerate() {
            let (row, col) = (pixel / self.cols, pixel % self.cols);
            match *kept {
                Some(i) => {
                    let offset = cloud.points[i].cast::<f64>() - sensor_origin;
                    let range = offset.norm();
                    directions.push(offset / range);
                    ranges_m.push(range as f32);
                }
                None => {
                    let azimuth = columns.pixel_center_rad(0, col).1;
                    let elevation = assignment.row_elevation_rad[row];
                    directions.push(spherical_direction(elevation, azimuth).into_inner());
                    ranges_m.push(f32::NAN);
                }
            }
        }
        let mut image = RangeImage::new(
            self.rings,
            self.cols,
            BeamDirections::PerPixel(directions),
            ranges_m,
        )?;
        let kept = &assignment.pixel_point;
        if let Some(intensity) = &cloud.intensity {
            let channel = kept
                .iter()
                .map(|k| k.map_or(f32::NAN, |i| intensity[i]))
                .collect();
            image = image.with_intensity(channel)?;
        }
        if let Some(label) = &cloud.label {
            let channel = kept.iter().map(|k| k.map_or(0, |i| label[i])).collect();
            image = image.with_label(channel)?;
        }
        Ok(image)
    }
}

#[cfg(test)]
mod tests;
