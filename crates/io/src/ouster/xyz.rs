//! From ranges to points: the Ouster Sensor Docs' "Lidar Range Data To Sensor XYZ Coordinate
//! Frame" equations, as a per-pixel lookup table of a direction and an offset.
//!
//! For beam `i` of measurement id `m` of a frame of `W` columns, with range `r` (mm):
//!
//! ```text
//! θ_e = 2π (1 − m / W)                      encoder angle
//! θ_a = −2π · beam_azimuth_angles[i] / 360  beam azimuth offset
//! φ   =  2π · beam_altitude_angles[i] / 360 beam elevation
//! n   = beam_to_lidar_transform[0][3]       (= lidar_origin_to_beam_origin_mm)
//! z_b = beam_to_lidar_transform[2][3]       (0 except on sensors with a raised beam origin)
//! d   = √(n² + z_b²)
//! x = (r − d) cos(θ_e + θ_a) cos φ + n cos θ_e
//! y = (r − d) sin(θ_e + θ_a) cos φ + n sin θ_e
//! z = (r − d) sin φ + z_b
//! ```
//!
//! in the lidar frame, then `lidar_to_sensor_transform` (mm) takes the point to the sensor
//! frame, whose axes are REP-103 (x forward — away from the connector —, y left, z up).
//! Points are returned in metres.

use nalgebra::{Point3, Vector3};
use raypath_geometry::PointCloud;

use super::frame::OusterFrame;
use super::metadata::SensorInfo;
use crate::error::{Error, Location, Result};

/// Per destaggered pixel: the unit direction and the offset (metres) in the sensor frame, so
/// that `point = range_m · direction + offset`.
#[derive(Clone, Debug, PartialEq)]
pub struct XyzLut {
    width: usize,
    height: usize,
    direction: Vec<Vector3<f32>>,
    offset: Vec<Vector3<f32>>,
    source: std::path::PathBuf,
}

impl XyzLut {
    /// The table for a sensor (its beams, columns, pixel shifts and transforms); fails when
    /// [`SensorInfo::validate`] does.
    pub fn new(info: &SensorInfo) -> Result<Self> {
        info.validate()?;
        let (w, h) = (info.columns_per_frame, info.pixels_per_column);
        let n = info.beam_to_lidar_transform[(0, 3)];
        let z_b = info.beam_to_lidar_transform[(2, 3)];
        let d = if z_b != 0.0 { n.hypot(z_b) } else { n };
        let rotation = info
            .lidar_to_sensor_transform
            .fixed_view::<3, 3>(0, 0)
            .into_owned();
        let translation = info
            .lidar_to_sensor_transform
            .fixed_view::<3, 1>(0, 3)
            .into_owned();
        let mut direction = Vec::with_capacity(w * h);
        let mut offset = Vec::with_capacity(w * h);
        let tau = std::f64::consts::TAU;
        for r in 0..h {
            let shift = i64::from(info.pixel_shift_by_row[r]);
            let theta_a = -tau * info.beam_azimuth_angles_deg[r] / 360.0;
            let phi = tau * info.beam_altitude_angles_deg[r] / 360.0;
            for j in 0..w {
                // The measurement id whose beam r was destaggered into column j.
                let m = (j as i64 - shift).rem_euclid(w as i64) as f64;
                let theta_e = tau * (1.0 - m / w as f64);
                let dir = Vector3::new(
                    (theta_e + theta_a).cos() * phi.cos(),
                    (theta_e + theta_a).sin() * phi.cos(),
                    phi.sin(),
                );
                let off_mm = Vector3::new(
                    n * theta_e.cos() - d * dir.x,
                    n * theta_e.sin() - d * dir.y,
                    z_b - d * dir.z,
                );
                direction.push((rotation * dir).cast::<f32>());
                offset.push(((rotation * off_mm + translation) * 1e-3).cast::<f32>());
            }
        }
        Ok(Self {
            width: w,
            height: h,
            direction,
            offset,
            source: info.source.clone(),
        })
    }

    /// Columns `W`.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Beams `H`.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Points of a destaggered `H × W` range image (metres, 0 = no return): NaN where there
    /// is no return.
    pub fn points(&self, range_m: &[f32]) -> Result<Vec<Point3<f32>>> {
        if range_m.len() != self.direction.len() {
            return Err(Error::malformed(
                &self.source,
                Location::File,
                format!(
                    "a range image of {} pixels for metadata of {} × {}",
                    range_m.len(),
                    self.height,
                    self.width
                ),
            ));
        }
        Ok(range_m
            .iter()
            .zip(self.direction.iter().zip(&self.offset))
            .map(|(&r, (dir, off))| {
                if r > 0.0 {
                    Point3::from(dir * r + off)
                } else {
                    Point3::new(f32::NAN, f32::NAN, f32::NAN)
                }
            })
            .collect())
    }

    /// The first returns of `frame` as an organized `H × W` cloud in the sensor frame, NaN
    /// where there is no return, reflectivity as intensity.
    pub fn cloud(&self, frame: &OusterFrame) -> Result<PointCloud> {
        self.organized(&frame.range_m, &frame.reflectivity)
    }

    /// The second returns of a dual-return frame likewise (`None` for single-return frames).
    pub fn second_return_cloud(&self, frame: &OusterFrame) -> Result<Option<PointCloud>> {
        match (&frame.range2_m, &frame.reflectivity2) {
            (Some(range), Some(reflectivity)) => self.organized(range, reflectivity).map(Some),
            _ => Ok(None),
        }
    }

    fn organized(&self, range_m: &[f32], reflectivity: &[u8]) -> Result<PointCloud> {
        Ok(PointCloud {
            points: self.points(range_m)?,
            intensity: Some(reflectivity.iter().map(|&v| f32::from(v)).collect()),
            label: None,
            rgb: None,
            width: self.width,
            height: self.height,
        })
    }
}
