//! 3-D lidar sensors: rotating multi-beam lidars with real beam patterns (Velodyne HDL-32E
//! and HDL-64E) and organized scanners over an elevation/azimuth window (SynPEB).
//!
//! A [`Lidar3`] is a spherical grid of beams: one elevation per row (a laser, or a row of an
//! organized scanner) and one azimuth per column (a firing). [`Lidar3::scan`] casts every beam
//! into a [`Scene3`](crate::scene3::Scene3) and returns a [`SimScan`]: an organized
//! [`PointCloud`](raypath_geometry::PointCloud) in the **sensor frame** (REP-103: x forward,
//! y left, z up; metres) with `height = rows`, `width = cols`, NaN points for no-returns,
//! intensities in `[0, 1]` and the label of the surface each beam hit.
//!
//! ## Layout
//!
//! * Rotating lidars: rows sorted by elevation, row 0 the highest laser
//!   ([`Lidar3::laser_ids`] maps rows back to hardware laser ids); column `c` of `n` firings
//!   has azimuth `π − (c + ½) · 2π / n`, so column 0 is at the back-left and azimuth decreases
//!   to the right, as the sensor spins clockwise — the layout of
//!   [`SphericalProjection`](raypath_geometry::SphericalProjection) over a full turn.
//! * Organized scanners ([`Lidar3::organized`]): `rows` elevations and `cols` azimuths spaced
//!   evenly from the first to the last value, both ends included (the SynPEB layout).
//!
//! ## Measurement model
//!
//! For each beam with nominal elevation `λ` and azimuth `η`:
//!
//! 1. the beam is cast along `(λ + δλ, η + δη)`, `δλ, δη ~ N(0, σ_ang²)` (angular noise);
//! 2. a hit closer than `min_range_m` or beyond `max_range_m` is a no-return;
//! 3. the measured range is `r + δr`, `δr ~ N(0, σ_r²)`, clamped at 0;
//! 4. with probability `dropout_probability` the return is lost, and so is a return whose
//!    noise-free intensity falls below the intensity model's detection threshold;
//! 5. the point is reported along the **nominal** direction at the measured range — a lidar
//!    reports its encoder angle and calibrated elevation, not where the beam really went (this
//!    is the sensor model of Schaefer 2020, ch. 11, and matches the real SynPEB sample, whose
//!    points lie exactly on the nominal grid).
//!
//! Intensities follow [`IntensityModel`]. [`Lidar3::scan`] starts all beams of a scan from one
//! pose. A de-skewed sweep of a moving sensor, such as KITTI's, holds its points in one frame
//! but fired each beam from where the sensor was at that moment (0.7 m apart over a sweep at
//! 25 km/h); [`Lidar3::scan_moving`] simulates that, which matters wherever free space is
//! traced along the beams.
//!
//! ## Determinism and parallelism
//!
//! Rows are scanned in parallel with rayon; row `i` of scan `scan_index` draws from its own
//! random stream ([`rng::stream`](crate::rng::stream)), so the scan is bit-identical whatever
//! the number of threads. Nothing is allocated per ray.

mod intensity;
mod patterns;
mod scan;

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use raypath_geometry::{BeamDirections, MAX_PIXELS};

pub use intensity::IntensityModel;
pub use patterns::{
    HDL32E_ELEVATIONS_DEG, HDL32E_FIRINGS_10HZ, HDL32E_MAX_RANGE_M, HDL64E_ELEVATIONS_RAD,
    HDL64E_FIRINGS_10HZ, HDL64E_MAX_RANGE_M,
};
pub use scan::SimScan;

use crate::error::{Result, SimError};

/// A lidar: a spherical grid of beams and its noise, range and intensity models.
#[derive(Clone, Debug, PartialEq)]
pub struct Lidar3 {
    /// A short name (`"HDL-64E"`), for reports.
    pub name: String,
    /// Elevation of each row in radians (row 0 first), in `[−π/2, π/2]`.
    pub elevations_rad: Vec<f64>,
    /// Hardware laser id of each row (the row index for organized scanners).
    pub laser_ids: Vec<u32>,
    /// Azimuth of each column in radians (`atan2(y, x)` in the sensor frame).
    pub azimuths_rad: Vec<f64>,
    /// Hits closer than this are no-returns, metres (≥ 0).
    pub min_range_m: f64,
    /// Hits beyond this are no-returns, metres.
    pub max_range_m: f64,
    /// Standard deviation of the Gaussian range noise, metres.
    pub range_noise_sigma_m: f64,
    /// Standard deviation of the Gaussian noise on each beam's elevation and azimuth, radians.
    pub angular_noise_sigma_rad: f64,
    /// Probability that a return is lost at random, in `[0, 1]`.
    pub dropout_probability: f64,
    /// How intensities are simulated.
    pub intensity: IntensityModel,
}

impl Lidar3 {
    /// A rotating lidar with the lasers `elevations_rad` (indexed by hardware laser id) and
    /// `firings` columns over a full turn; defaults: range 0.9–100 m, σ_r = 2 cm,
    /// σ_ang = 0.01°, 0.5 % dropout, the default intensity model.
    pub fn rotating(
        name: impl Into<String>,
        elevations_rad: &[f64],
        firings: usize,
    ) -> Result<Self> {
        let mut order: Vec<usize> = (0..elevations_rad.len()).collect();
        // Highest laser first; ties by laser id.
        order.sort_by(|&a, &b| elevations_rad[b].total_cmp(&elevations_rad[a]));
        let lidar = Self {
            name: name.into(),
            elevations_rad: order.iter().map(|&i| elevations_rad[i]).collect(),
            laser_ids: order.iter().map(|&i| i as u32).collect(),
            azimuths_rad: full_turn_azimuths(firings),
            min_range_m: 0.9,
            max_range_m: 100.0,
            range_noise_sigma_m: 0.02,
            angular_noise_sigma_rad: 0.01_f64.to_radians(),
            dropout_probability: 0.005,
            intensity: IntensityModel::default(),
        };
        lidar.validate()?;
        Ok(lidar)
    }

    /// The Velodyne HDL-32E (32 lasers, −30.67° … +10.67°) with 2170 firings per revolution
    /// (10 Hz) and a 100 m maximum range.
    pub fn hdl32e() -> Self {
        let elevations = patterns::hdl32e_elevations_rad();
        let mut lidar = Self::rotating("HDL-32E", &elevations, HDL32E_FIRINGS_10HZ)
            .unwrap_or_else(|_| unreachable!("the HDL-32E table is valid"));
        lidar.max_range_m = HDL32E_MAX_RANGE_M;
        lidar
    }

    /// The Velodyne HDL-64E (64 lasers of an S3 factory calibration, +1.96° … −24.56°) with
    /// 2083 firings per revolution (10 Hz) and a 120 m maximum range.
    pub fn hdl64e() -> Self {
        let mut lidar = Self::rotating("HDL-64E", &HDL64E_ELEVATIONS_RAD, HDL64E_FIRINGS_10HZ)
            .unwrap_or_else(|_| unreachable!("the HDL-64E table is valid"));
        lidar.max_range_m = HDL64E_MAX_RANGE_M;
        lidar
    }

    /// The same rotating lidar with `firings` columns per revolution (the azimuth
    /// resolution is `360° / firings`).
    pub fn with_firings(mut self, firings: usize) -> Result<Self> {
        self.azimuths_rad = full_turn_azimuths(firings);
        self.validate()?;
        Ok(self)
    }

    /// An organized scanner of `rows × cols` beams: elevations spaced evenly from
    /// `elevation_first_rad` (row 0) to `elevation_last_rad` (last row) and azimuths from
    /// `azimuth_first_rad` (column 0) to `azimuth_last_rad`, both ends included. No noise,
    /// no dropout, range 0–100 m, Lambertian intensities.
    pub fn organized(
        rows: usize,
        cols: usize,
        elevation_first_rad: f64,
        elevation_last_rad: f64,
        azimuth_first_rad: f64,
        azimuth_last_rad: f64,
    ) -> Result<Self> {
        let lidar = Self {
            name: format!("organized {rows}×{cols}"),
            elevations_rad: linspace(elevation_first_rad, elevation_last_rad, rows),
            laser_ids: (0..rows as u32).collect(),
            azimuths_rad: linspace(azimuth_first_rad, azimuth_last_rad, cols),
            min_range_m: 0.0,
            max_range_m: 100.0,
            range_noise_sigma_m: 0.0,
            angular_noise_sigma_rad: 0.0,
            dropout_probability: 0.0,
            intensity: IntensityModel::lambertian(),
        };
        lidar.validate()?;
        Ok(lidar)
    }

    /// Number of rows (lasers).
    pub fn rows(&self) -> usize {
        self.elevations_rad.len()
    }

    /// Number of columns (firings).
    pub fn cols(&self) -> usize {
        self.azimuths_rad.len()
    }

    /// Number of beams per scan, `rows × cols`.
    pub fn num_rays(&self) -> usize {
        self.rows() * self.cols()
    }

    /// The nominal beam directions as a spherical grid.
    pub fn directions(&self) -> BeamDirections {
        BeamDirections::Spherical {
            elevations_rad: self.elevations_rad.clone(),
            azimuths_rad: self.azimuths_rad.clone(),
        }
    }

    /// Checks every parameter: a non-empty grid of at most
    /// [`MAX_PIXELS`] beams, elevations in `[−π/2, π/2]`, finite
    /// azimuths, one laser id per row, `0 ≤ min_range_m < max_range_m` finite, finite
    /// non-negative noise, a dropout probability in `[0, 1]` and a valid intensity model.
    pub fn validate(&self) -> Result<()> {
        let invalid =
            |name: &'static str, reason: String| Err(SimError::InvalidParameter { name, reason });
        let (rows, cols) = (self.rows(), self.cols());
        if rows == 0 || cols == 0 || rows.checked_mul(cols).is_none_or(|n| n > MAX_PIXELS) {
            return invalid(
                "beams",
                format!("{rows} rows × {cols} columns (allowed: 1 to {MAX_PIXELS} beams)"),
            );
        }
        if let Some(e) = self
            .elevations_rad
            .iter()
            .find(|e| !(e.is_finite() && e.abs() <= FRAC_PI_2))
        {
            return invalid("elevations_rad", format!("{e} is outside [−π/2, π/2]"));
        }
        if self.azimuths_rad.iter().any(|a| !a.is_finite()) {
            return invalid("azimuths_rad", "not all finite".into());
        }
        if self.laser_ids.len() != rows {
            return invalid(
                "laser_ids",
                format!("{} ids for {rows} rows", self.laser_ids.len()),
            );
        }
        let (lo, hi) = (self.min_range_m, self.max_range_m);
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi) {
            return invalid(
                "min_range_m/max_range_m",
                format!("[{lo}, {hi}] must satisfy 0 ≤ min < max, finite"),
            );
        }
        for (name, sigma) in [
            ("range_noise_sigma_m", self.range_noise_sigma_m),
            ("angular_noise_sigma_rad", self.angular_noise_sigma_rad),
        ] {
            if !(sigma.is_finite() && sigma >= 0.0) {
                return invalid(name, format!("{sigma} (expected a finite value ≥ 0)"));
            }
        }
        let p = self.dropout_probability;
        if !(0.0..=1.0).contains(&p) {
            return invalid("dropout_probability", format!("{p} is outside [0, 1]"));
        }
        self.intensity.validate()
    }
}

/// `n` azimuths over a full turn, column 0 at `π − π/n`, decreasing.
fn full_turn_azimuths(n: usize) -> Vec<f64> {
    (0..n)
        .map(|c| PI - (c as f64 + 0.5) * TAU / n as f64)
        .collect()
}

/// `n` values from `first` to `last`, both included (`first` alone for `n = 1`).
fn linspace(first: f64, last: f64, n: usize) -> Vec<f64> {
    if n <= 1 {
        return vec![first; n];
    }
    let step = (last - first) / (n - 1) as f64;
    (0..n)
        .map(|i| {
            if i == n - 1 {
                last
            } else {
                first + step * i as f64
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_have_the_published_patterns() {
        let l32 = Lidar3::hdl32e();
        assert_eq!((l32.rows(), l32.cols()), (32, 2170));
        assert!((l32.elevations_rad[0].to_degrees() - 10.67).abs() < 1e-9);
        assert!((l32.elevations_rad[31].to_degrees() + 30.67).abs() < 1e-9);
        assert_eq!((l32.laser_ids[0], l32.laser_ids[31]), (31, 0));
        let l64 = Lidar3::hdl64e();
        assert_eq!((l64.rows(), l64.cols()), (64, 2083));
        assert!(l64.elevations_rad.windows(2).all(|w| w[0] >= w[1]));
        assert_eq!(l64.max_range_m, 120.0);
        let step = l64.azimuths_rad[0] - l64.azimuths_rad[1];
        assert!((step - TAU / 2083.0).abs() < 1e-12);
    }

    #[test]
    fn organized_grid_includes_both_ends() {
        let l = Lidar3::organized(5, 3, 0.5, -0.5, -0.2, 0.2).unwrap();
        assert_eq!(l.elevations_rad, vec![0.5, 0.25, 0.0, -0.25, -0.5]);
        assert_eq!(l.azimuths_rad, vec![-0.2, 0.0, 0.2]);
    }

    #[test]
    fn invalid_parameters_are_errors() {
        assert!(Lidar3::organized(0, 3, 0.5, -0.5, -0.2, 0.2).is_err());
        assert!(Lidar3::organized(3, 3, 2.0, -0.5, -0.2, 0.2).is_err());
        assert!(Lidar3::hdl32e().with_firings(0).is_err());
        let mut l = Lidar3::hdl64e();
        l.dropout_probability = 1.5;
        assert!(l.validate().is_err());
        l.dropout_probability = 0.0;
        l.min_range_m = 200.0;
        assert!(l.validate().is_err());
    }
}
