//! Beam directions of a range image.

use nalgebra::{Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::GeometryError;

/// Tolerance on the norm of a stored unit direction.
const UNIT_TOLERANCE: f64 = 1e-6;

/// The direction of every pixel's beam, in the frame of the image (the sensor frame for a
/// scan as read from disk; REP-103: x forward, y left, z up).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum BeamDirections {
    /// One unit vector per pixel, row by row. A pixel may lack a direction — all components
    /// NaN — when it is a no-return whose beam direction the source did not record (an
    /// organized point cloud stores only NaN for such pixels).
    PerPixel(Vec<Vector3<f64>>),
    /// The regular grid of a spinning lidar: every pixel of row `r` has elevation
    /// `elevations_rad[r]` (from the xy-plane towards +z) and every pixel of column `c` has
    /// azimuth `azimuths_rad[c]` (`atan2(y, x)`, counter-clockwise from +x).
    Spherical {
        /// Elevation of each row in radians, in `[−π/2, π/2]`.
        elevations_rad: Vec<f64>,
        /// Azimuth of each column in radians.
        azimuths_rad: Vec<f64>,
    },
}

/// The unit vector at `elevation_rad` above the xy-plane and azimuth `azimuth_rad`.
pub fn spherical_direction(elevation_rad: f64, azimuth_rad: f64) -> Unit<Vector3<f64>> {
    let (sin_el, cos_el) = elevation_rad.sin_cos();
    let (sin_az, cos_az) = azimuth_rad.sin_cos();
    Unit::new_unchecked(Vector3::new(cos_el * cos_az, cos_el * sin_az, sin_el))
}

impl BeamDirections {
    /// The direction of pixel `(row, col)` of an image with `cols` columns; `None` outside
    /// the image or for a pixel without a recorded direction.
    pub fn direction(&self, cols: usize, row: usize, col: usize) -> Option<Unit<Vector3<f64>>> {
        if col >= cols {
            return None;
        }
        match self {
            BeamDirections::PerPixel(directions) => {
                let v = directions.get(row.checked_mul(cols)?.checked_add(col)?)?;
                v.iter()
                    .all(|c| c.is_finite())
                    .then(|| Unit::new_unchecked(*v))
            }
            BeamDirections::Spherical {
                elevations_rad,
                azimuths_rad,
            } => Some(spherical_direction(
                *elevations_rad.get(row)?,
                *azimuths_rad.get(col)?,
            )),
        }
    }

    /// Checks the shape (`rows × cols`) and that every direction is a unit vector (or, per
    /// pixel, all NaN) and every angle finite.
    pub fn validate(&self, rows: usize, cols: usize) -> Result<(), GeometryError> {
        let invalid = |reason: String| Err(GeometryError::InvalidRangeImage { reason });
        match self {
            BeamDirections::PerPixel(directions) => {
                if Some(directions.len()) != rows.checked_mul(cols) {
                    return invalid(format!(
                        "{} per-pixel directions for {rows} × {cols} pixels",
                        directions.len()
                    ));
                }
                for (i, v) in directions.iter().enumerate() {
                    let missing = v.iter().all(|c| c.is_nan());
                    if !missing && (v.norm() - 1.0).abs() > UNIT_TOLERANCE {
                        return invalid(format!(
                            "direction of pixel ({}, {}) is not a unit vector: {:?}",
                            i / cols,
                            i % cols,
                            v.as_slice()
                        ));
                    }
                }
            }
            BeamDirections::Spherical {
                elevations_rad,
                azimuths_rad,
            } => {
                if elevations_rad.len() != rows || azimuths_rad.len() != cols {
                    return invalid(format!(
                        "{} row elevations and {} column azimuths for {rows} × {cols} pixels",
                        elevations_rad.len(),
                        azimuths_rad.len()
                    ));
                }
                let half_pi = std::f64::consts::FRAC_PI_2;
                if let Some(r) = elevations_rad
                    .iter()
                    .position(|e| !(e.is_finite() && e.abs() <= half_pi))
                {
                    return invalid(format!(
                        "elevation of row {r} is {} rad, outside [−π/2, π/2]",
                        elevations_rad[r]
                    ));
                }
                if let Some(c) = azimuths_rad.iter().position(|a| !a.is_finite()) {
                    return invalid(format!("azimuth of column {c} is not finite"));
                }
            }
        }
        Ok(())
    }
}
