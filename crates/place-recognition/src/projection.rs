//! Equirectangular lidar images: every point of a cloud becomes a pixel of an
//! azimuth × elevation grid holding its intensity or its range (Khan 2017, §4.5.1, App. A.1).
//!
//! For each finite point `p` with range `r = ‖p‖ > 0` the spherical coordinates are
//! `η = atan2(p_y, p_x)` (azimuth, REP-103: counter-clockwise from x forward) and
//! `λ = arcsin(p_z / r)` (elevation). The pixel is
//!
//! ```text
//! col = floor((η_max − η) / res_az),   res_az = (η_max − η_min) / width
//! row = floor((λ_max − λ) / res_el),   res_el = (λ_max − λ_min) / height
//! ```
//!
//! so the top row holds the highest elevation. When several points fall into one pixel their
//! values are **averaged incrementally** (App. A, Fig. A.4): `m_k = m_{k−1} + (x_k − m_{k−1}) / k`.
//! The range image is the mean range divided by the maximum range (Fig. 4.13, A.2), the
//! intensity image the mean intensity divided by an intensity scale; both are clamped to
//! `[0, 1]` and scaled to 8 bits (rounded). Pixels without a point are 0 (a point whose scaled
//! value rounds to 0 looks the same).
//!
//! ## Decisions (errata and items the thesis leaves open)
//!
//! * The printed pseudo-code divides `η` and `λ` by the resolution without subtracting the
//!   minimum, which gives negative indices; we offset by the span's edge and clamp the last
//!   index (elevation) or wrap it (a full azimuth circle).
//! * **Column direction.** Column 0 is the largest azimuth (the left, `+y`) and the column
//!   index grows as the azimuth decreases (towards the right, `−y`): the image is the panorama
//!   seen from the sensor, with forward (`η = 0`) in the middle of a full-circle image and left
//!   on the left. The thesis' `η − min η` would mirror it. The rectilinear views
//!   ([`rectilinear`](fn@crate::rectilinear)) rely on this to look forward unmirrored.
//! * **Angular span.** The thesis takes the span from the minimum and maximum of the cloud
//!   ([`AngularSpan::FromCloud`], kept as an option). By default ([`AngularSpan::Fixed`]) the
//!   azimuth span is the whole circle `[−π, π)` and the elevation span is the sensor's
//!   vertical field of view: then images of different scans align column for column and row
//!   for row, and a yaw rotation of the sensor is a circular column shift — what a global
//!   image descriptor compares. Points outside the elevation span go to the first or last row.
//! * **Range normalisation.** The thesis divides by the cloud's maximum range
//!   (`max_range_m: None`); by default we divide by a fixed 80 m (ours, about the useful range
//!   of an HDL-64E or an OS1), so that the grey level of a surface does not depend on the
//!   farthest point of the scan. Longer ranges saturate at 255.
//! * **Intensity scale** ([`IntensityScale`], not in the thesis): KITTI and the simulator give
//!   intensities in `[0, 1]`, Ouster reflectivity is 0–255. The default `Auto` picks 1 or 255
//!   from the cloud's maximum (or the maximum itself beyond 255).
//! * **Image size** (not in the thesis): by default about the native resolution of the scan,
//!   1024 × 64 for the HDL-64E (64 lasers; ~0.35° azimuth). The HDL-64E's lasers are not
//!   evenly spaced in elevation, so with uniform rows a few rows stay empty and others
//!   average two lasers.
//! * Non-finite points and points at range 0 (no return) are skipped; a non-finite intensity
//!   is left out of the intensity image only. An empty cloud (or one without a valid point)
//!   gives two images of zeros, not an error: a frame without returns is still a frame. A
//!   cloud without an intensity channel gives an intensity image of zeros.

use image::GrayImage;
use raypath_geometry::PointCloud;

use crate::error::require_positive;
use crate::{PlaceError, Result};

/// Which angles the image spans.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AngularSpan {
    /// The whole azimuth circle `[−π, π)` and a fixed elevation interval (default: the
    /// HDL-64E's −24.9°…+2°, its data sheet).
    Fixed {
        /// Elevation at the bottom edge of the image, radians.
        elevation_min_rad: f64,
        /// Elevation at the top edge of the image, radians.
        elevation_max_rad: f64,
    },
    /// The minimum and maximum azimuth and elevation of the cloud (Khan 2017, App. A.1).
    FromCloud,
}

/// What intensity is drawn white (255).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum IntensityScale {
    /// 1 when every intensity of the cloud is ≤ 1 (KITTI, the simulator), 255 when ≤ 255
    /// (Ouster 8-bit reflectivity), otherwise the cloud's maximum (ours).
    #[default]
    Auto,
    /// A fixed intensity drawn white; larger intensities saturate.
    Fixed(f64),
    /// The largest finite intensity of the cloud.
    CloudMax,
}

/// Size and scaling of equirectangular images.
#[derive(Clone, Debug, PartialEq)]
pub struct EquirectConfig {
    /// Image width in pixels (azimuth). Default 1024 (ours, ~native HDL-64E resolution).
    pub width: u32,
    /// Image height in pixels (elevation). Default 64 (ours, the HDL-64E's lasers).
    pub height: u32,
    /// Angular span of the image. Default: the whole circle × the HDL-64E's −24.9°…+2° (ours).
    pub span: AngularSpan,
    /// Range drawn white in the range image, metres; `None` = the cloud's maximum range
    /// (Khan 2017, Fig. 4.13). Default `Some(80.0)` (ours).
    pub max_range_m: Option<f64>,
    /// Intensity drawn white in the intensity image. Default [`IntensityScale::Auto`] (ours).
    pub intensity_scale: IntensityScale,
}

impl Default for EquirectConfig {
    fn default() -> Self {
        Self::kitti_hdl64()
    }
}

impl EquirectConfig {
    /// Velodyne HDL-64E (KITTI): 1024 × 64, elevation −24.9°…+2°, 80 m.
    pub fn kitti_hdl64() -> Self {
        Self {
            width: 1024,
            height: 64,
            span: AngularSpan::Fixed {
                elevation_min_rad: (-24.9f64).to_radians(),
                elevation_max_rad: 2f64.to_radians(),
            },
            max_range_m: Some(80.0),
            intensity_scale: IntensityScale::Auto,
        }
    }

    /// Ouster OS1-128: 1024 × 128, elevation −22.5°…+22.5° (the OS1's 45° field of view), 80 m.
    pub fn ouster_os1_128() -> Self {
        Self {
            height: 128,
            span: AngularSpan::Fixed {
                elevation_min_rad: (-22.5f64).to_radians(),
                elevation_max_rad: 22.5f64.to_radians(),
            },
            ..Self::kitti_hdl64()
        }
    }

    /// The angles a fixed span covers; `None` for [`AngularSpan::FromCloud`].
    pub fn geometry(&self) -> Option<EquirectGeometry> {
        match self.span {
            AngularSpan::Fixed {
                elevation_min_rad,
                elevation_max_rad,
            } => Some(EquirectGeometry::full_circle(
                elevation_min_rad,
                elevation_max_rad,
            )),
            AngularSpan::FromCloud => None,
        }
    }

    fn validate(&self) -> Result<()> {
        for (name, value) in [("width", self.width), ("height", self.height)] {
            if value == 0 {
                return Err(PlaceError::InvalidParameter {
                    name,
                    reason: "must be at least 1 pixel".into(),
                });
            }
        }
        if let AngularSpan::Fixed {
            elevation_min_rad,
            elevation_max_rad,
        } = self.span
        {
            require_positive("elevation span", elevation_max_rad - elevation_min_rad)?;
        }
        if let Some(r) = self.max_range_m {
            require_positive("max_range_m", r)?;
        }
        if let IntensityScale::Fixed(s) = self.intensity_scale {
            require_positive("intensity_scale", s)?;
        }
        Ok(())
    }
}

/// The angles an equirectangular image covers: column 0 starts at `azimuth_max_rad` and the
/// columns run towards smaller azimuths over `azimuth_span_rad`; row 0 starts at
/// `elevation_max_rad` and the rows run down to `elevation_min_rad`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EquirectGeometry {
    /// Azimuth of the left edge of column 0, radians.
    pub azimuth_max_rad: f64,
    /// Azimuth covered by all columns, radians (2π for a full circle).
    pub azimuth_span_rad: f64,
    /// Elevation of the top edge of row 0, radians.
    pub elevation_max_rad: f64,
    /// Elevation of the bottom edge of the last row, radians.
    pub elevation_min_rad: f64,
}

impl EquirectGeometry {
    /// The whole azimuth circle `[−π, π)` and the given elevation interval.
    pub fn full_circle(elevation_min_rad: f64, elevation_max_rad: f64) -> Self {
        Self {
            azimuth_max_rad: std::f64::consts::PI,
            azimuth_span_rad: std::f64::consts::TAU,
            elevation_max_rad,
            elevation_min_rad,
        }
    }

    /// True when the columns wrap around the whole circle.
    pub fn wraps(&self) -> bool {
        self.azimuth_span_rad >= std::f64::consts::TAU - 1e-9
    }
}

/// The intensity and range images of one cloud.
#[derive(Clone, Debug)]
pub struct LidarImages {
    /// Mean intensity per pixel, scaled to 8 bits.
    pub intensity: GrayImage,
    /// Mean range per pixel divided by the maximum range, scaled to 8 bits.
    pub range: GrayImage,
    /// The angles the images cover (fixed, or taken from the cloud).
    pub geometry: EquirectGeometry,
}

/// Spherical coordinates `(r, η, λ)` of a point; `None` for non-finite points and range 0.
fn spherical(x: f64, y: f64, z: f64) -> Option<(f64, f64, f64)> {
    let r = (x * x + y * y + z * z).sqrt();
    if !r.is_finite() || r <= 0.0 {
        return None;
    }
    // App. A.1: η = atan2(y, x), λ = arcsin(z / r).
    Some((r, y.atan2(x), (z / r).clamp(-1.0, 1.0).asin()))
}

/// Minimum and maximum azimuth and elevation of the cloud's valid points.
fn cloud_geometry(cloud: &PointCloud) -> EquirectGeometry {
    let (mut az, mut el) = ((f64::MAX, f64::MIN), (f64::MAX, f64::MIN));
    for p in &cloud.points {
        if let Some((_, eta, lambda)) = spherical(p.x.into(), p.y.into(), p.z.into()) {
            az = (az.0.min(eta), az.1.max(eta));
            el = (el.0.min(lambda), el.1.max(lambda));
        }
    }
    if az.0 > az.1 {
        return EquirectGeometry::full_circle(
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
        );
    }
    // A single direction still needs a non-zero span (everything lands in pixel (0, 0)).
    EquirectGeometry {
        azimuth_max_rad: az.1,
        azimuth_span_rad: (az.1 - az.0).max(1e-9),
        elevation_max_rad: el.1,
        elevation_min_rad: el.1 - (el.1 - el.0).max(1e-9),
    }
}

/// The intensity drawn white.
fn intensity_scale(intensity: &[f32], scale: IntensityScale) -> f64 {
    let max = || {
        intensity
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, &v| m.max(v.into()))
    };
    let s = match scale {
        IntensityScale::Fixed(s) => s,
        IntensityScale::CloudMax => max(),
        IntensityScale::Auto => match max() {
            m if m <= 1.0 => 1.0,
            m if m <= 255.0 => 255.0,
            m => m,
        },
    };
    if s > 0.0 { s } else { 1.0 }
}

/// A running mean per pixel (App. A, Fig. A.4: incremental averaging).
struct MeanImage {
    mean: Vec<f64>,
    count: Vec<u32>,
}

impl MeanImage {
    fn new(n: usize) -> Self {
        Self {
            mean: vec![0.0; n],
            count: vec![0; n],
        }
    }

    fn add(&mut self, k: usize, value: f64) {
        self.count[k] += 1;
        self.mean[k] += (value - self.mean[k]) / f64::from(self.count[k]);
    }

    /// `mean / scale`, clamped to `[0, 1]`, as 8 bits; empty pixels 0.
    fn to_gray(&self, width: u32, height: u32, scale: f64) -> GrayImage {
        let pixels = self
            .mean
            .iter()
            .zip(&self.count)
            .map(|(&m, &c)| {
                if c == 0 {
                    0
                } else {
                    ((m / scale).clamp(0.0, 1.0) * 255.0).round() as u8
                }
            })
            .collect();
        GrayImage::from_raw(width, height, pixels).unwrap_or_else(|| GrayImage::new(width, height))
    }
}

/// Projects a cloud (sensor frame, REP-103) into equirectangular intensity and range images
/// (Khan 2017, App. A.1); see the module docs for the conventions.
///
/// Errors: a zero-size image, a non-positive span, range or intensity scale, or an intensity
/// channel whose length differs from the points'.
pub fn equirectangular(cloud: &PointCloud, config: &EquirectConfig) -> Result<LidarImages> {
    config.validate()?;
    let intensity = cloud.intensity.as_deref();
    if let Some(i) = intensity
        && i.len() != cloud.points.len()
    {
        return Err(PlaceError::BadInput(format!(
            "equirectangular: {} intensities for {} points",
            i.len(),
            cloud.points.len()
        )));
    }
    let geometry = config.geometry().unwrap_or_else(|| cloud_geometry(cloud));
    let (w, h) = (config.width as usize, config.height as usize);
    let res_az = geometry.azimuth_span_rad / w as f64;
    let res_el = (geometry.elevation_max_rad - geometry.elevation_min_rad) / h as f64;
    let wraps = geometry.wraps();

    let mut range = MeanImage::new(w * h);
    let mut inten = MeanImage::new(w * h);
    let mut max_range = 0.0f64;
    for (j, p) in cloud.points.iter().enumerate() {
        let Some((r, eta, lambda)) = spherical(p.x.into(), p.y.into(), p.z.into()) else {
            continue;
        };
        let c = ((geometry.azimuth_max_rad - eta) / res_az).floor() as i64;
        let col = if wraps {
            c.rem_euclid(w as i64) as usize
        } else {
            c.clamp(0, w as i64 - 1) as usize
        };
        let row = ((geometry.elevation_max_rad - lambda) / res_el)
            .floor()
            .clamp(0.0, (h - 1) as f64) as usize;
        let k = row * w + col;
        range.add(k, r);
        max_range = max_range.max(r);
        if let Some(v) = intensity.map(|i| f64::from(i[j]))
            && v.is_finite()
        {
            inten.add(k, v);
        }
    }
    let range_scale = config
        .max_range_m
        .unwrap_or(if max_range > 0.0 { max_range } else { 1.0 });
    let intensity_scale = intensity.map_or(1.0, |i| intensity_scale(i, config.intensity_scale));
    Ok(LidarImages {
        intensity: inten.to_gray(config.width, config.height, intensity_scale),
        range: range.to_gray(config.width, config.height, range_scale),
        geometry,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::{PI, TAU};

    fn point(r: f64, eta: f64, lambda: f64) -> Point3<f32> {
        Point3::new(
            (r * lambda.cos() * eta.cos()) as f32,
            (r * lambda.cos() * eta.sin()) as f32,
            (r * lambda.sin()) as f32,
        )
    }

    fn cloud(points: Vec<Point3<f32>>, intensity: Vec<f32>) -> PointCloud {
        PointCloud {
            intensity: Some(intensity),
            ..PointCloud::from_points(points)
        }
    }

    /// 8 × 4 pixels of 45° × 10° over ±20° elevation.
    fn small() -> EquirectConfig {
        EquirectConfig {
            width: 8,
            height: 4,
            span: AngularSpan::Fixed {
                elevation_min_rad: -20f64.to_radians(),
                elevation_max_rad: 20f64.to_radians(),
            },
            max_range_m: Some(80.0),
            intensity_scale: IntensityScale::Fixed(1.0),
        }
    }

    #[test]
    fn points_land_in_the_expected_pixels() {
        let d = |deg: f64| deg.to_radians();
        let c = cloud(
            vec![
                point(40.0, d(22.5), d(15.0)), // left of forward, top row → (col 3, row 0)
                point(80.0, d(-22.5), d(-15.0)), // right of forward, bottom → (col 4, row 3)
                point(20.0, d(157.5), d(5.0)), // behind-left → (col 0, row 1)
                point(60.0, d(-157.5), d(-5.0)), // behind-right → (col 7, row 2)
            ],
            vec![0.5, 1.0, 0.2, 2.0],
        );
        let img = equirectangular(&c, &small()).unwrap();
        let expect = [
            ((3, 0), 128, 128),
            ((4, 3), 255, 255),
            ((0, 1), 64, 51),
            ((7, 2), 191, 255),
        ];
        for ((col, row), range, intensity) in expect {
            assert_eq!(
                img.range.get_pixel(col, row).0[0],
                range,
                "range at {col},{row}"
            );
            assert_eq!(img.intensity.get_pixel(col, row).0[0], intensity);
        }
        let lit = img.range.pixels().filter(|p| p.0[0] > 0).count();
        assert_eq!(lit, 4, "every other pixel is empty");
    }

    #[test]
    fn two_points_in_one_pixel_are_averaged() {
        let d = |deg: f64| deg.to_radians();
        let c = cloud(
            vec![point(20.0, d(20.0), d(12.0)), point(52.0, d(25.0), d(18.0))],
            vec![0.2, 0.6],
        );
        let img = equirectangular(&c, &small()).unwrap();
        assert_eq!(img.range.get_pixel(3, 0).0[0], 115); // 36 m / 80 m · 255 = 114.75
        assert_eq!(img.intensity.get_pixel(3, 0).0[0], 102); // 0.4 · 255
    }

    #[test]
    fn yaw_rotation_is_a_column_shift() {
        let config = EquirectConfig {
            width: 64,
            height: 16,
            ..small()
        };
        let (w, h) = (64usize, 16usize);
        let (res_az, res_el) = (TAU / w as f64, 40f64.to_radians() / h as f64);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut cells = Vec::new();
        for row in 0..h {
            for col in 0..w {
                let eta = PI - (col as f64 + 0.5) * res_az;
                let lambda = 20f64.to_radians() - (row as f64 + 0.5) * res_el;
                cells.push((
                    rng.random_range(1.0..80.0),
                    eta,
                    lambda,
                    rng.random::<f32>(),
                ));
            }
        }
        let project = |yaw: f64| {
            let points = cells
                .iter()
                .map(|&(r, e, l, _)| point(r, e + yaw, l))
                .collect();
            let c = cloud(points, cells.iter().map(|c| c.3).collect());
            equirectangular(&c, &config).unwrap()
        };
        let base = project(0.0);
        for k in [1usize, 5, 63] {
            let rotated = project(TAU * k as f64 / w as f64);
            for row in 0..h as u32 {
                for col in 0..w as u32 {
                    let src = (col as usize + k) % w; // larger azimuth = smaller column
                    assert_eq!(
                        rotated.range.get_pixel(col, row),
                        base.range.get_pixel(src as u32, row)
                    );
                    assert_eq!(
                        rotated.intensity.get_pixel(col, row),
                        base.intensity.get_pixel(src as u32, row)
                    );
                }
            }
        }
    }

    #[test]
    fn invalid_points_are_skipped_and_empty_clouds_give_zeros() {
        let nan = Point3::new(f32::NAN, 0.0, 0.0);
        let c = cloud(
            vec![nan, Point3::origin(), point(10.0, 0.1, 0.0)],
            vec![1.0, 1.0, f32::NAN],
        );
        let img = equirectangular(&c, &small()).unwrap();
        assert_eq!(img.range.pixels().filter(|p| p.0[0] > 0).count(), 1);
        assert!(img.intensity.pixels().all(|p| p.0[0] == 0));
        let empty = equirectangular(&PointCloud::default(), &EquirectConfig::default()).unwrap();
        assert_eq!(empty.range.dimensions(), (1024, 64));
        assert!(
            empty
                .range
                .pixels()
                .chain(empty.intensity.pixels())
                .all(|p| p.0[0] == 0)
        );
        let zero = EquirectConfig {
            width: 0,
            ..small()
        };
        assert!(equirectangular(&c, &zero).is_err());
        let short = PointCloud {
            intensity: Some(vec![1.0]),
            ..c
        };
        assert!(equirectangular(&short, &small()).is_err());
    }

    #[test]
    fn cloud_span_and_scales_follow_the_cloud() {
        let d = |deg: f64| deg.to_radians();
        let c = cloud(
            vec![
                point(10.0, d(-30.0), d(-10.0)),
                point(20.0, d(30.0), d(10.0)),
            ],
            vec![100.0, 200.0],
        );
        let config = EquirectConfig {
            span: AngularSpan::FromCloud,
            max_range_m: None,
            intensity_scale: IntensityScale::Auto,
            ..small()
        };
        let img = equirectangular(&c, &config).unwrap();
        assert!((img.geometry.azimuth_span_rad - d(60.0)).abs() < 1e-6);
        // Largest azimuth and elevation in the top-left pixel, the others clamped bottom-right.
        assert_eq!(img.range.get_pixel(0, 0).0[0], 255);
        assert_eq!(img.range.get_pixel(7, 3).0[0], 128);
        assert_eq!(img.intensity.get_pixel(0, 0).0[0], 200);
    }
}
