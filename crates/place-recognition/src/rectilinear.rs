//! Rectilinear (pinhole) and cubic views of an equirectangular image (Khan 2017, App. A.2),
//! used to compare lidar images with camera images.
//!
//! A view of horizontal and vertical field of view `fov_h × fov_v` is a grid of points on the
//! tangent plane `c_z = 1` at distance 1 in front of the observer, `c_x ∈ [−tan(fov_h/2),
//! tan(fov_h/2)]` (positive to the left, REP-103 `+y`) and `c_y ∈ [−tan(fov_v/2), tan(fov_v/2)]`
//! (positive up), sampled at pixel centres. Each grid point looks along
//!
//! ```text
//! η = atan2(c_x, c_z) + η_front,   λ = atan2(c_y, √(c_x² + c_z²))
//! ```
//!
//! and takes the equirectangular image's value there, sampled **bilinearly**. The **cubic**
//! projection is the special case `fov_h = fov_v = 90°` with a square image; the back view is
//! the front view turned by `π` about z.
//!
//! ## Decisions
//!
//! * The thesis prints `η = arccos(−c_z / √(c_x² + c_z²))`, which loses the sign of `c_x` and
//!   points the image centre at `η = ±π`; we use `atan2(c_x, c_z) + η_front`. Its principal
//!   direction `η_front` is [`RectilinearConfig::yaw_rad`] (0 = the sensor's x axis).
//! * Columns run from left (`+c_x`, larger azimuth) to right, rows from top (`+c_y`) to bottom,
//!   as the equirectangular image's (see [`crate::equirectangular`]): the front view is not
//!   mirrored.
//! * Directions outside the equirectangular image's elevation span (a lidar sees about 27° to
//!   45° vertically) are 0, as empty equirectangular pixels; within half a pixel of the edge
//!   the edge row is used. Over a full azimuth circle the columns wrap.
//! * The field of view of the thesis' camera comparison is not given; the default is the
//!   cubic face, 90° × 90° (ours), 257 × 257 pixels so that the centre pixel looks exactly
//!   along the principal direction.

use image::GrayImage;

use crate::error::require_positive;
use crate::projection::EquirectGeometry;
use crate::{PlaceError, Result};

/// A rectilinear view of an equirectangular image.
#[derive(Clone, Debug, PartialEq)]
pub struct RectilinearConfig {
    /// Horizontal field of view, radians, in `(0, π)`. Default 90° (cubic, App. A.2).
    pub fov_h_rad: f64,
    /// Vertical field of view, radians, in `(0, π)`. Default 90° (cubic, App. A.2).
    pub fov_v_rad: f64,
    /// Image width in pixels. Default 257 (ours).
    pub width: u32,
    /// Image height in pixels. Default 257 (ours).
    pub height: u32,
    /// Azimuth of the principal direction, radians, counter-clockwise from x. Default 0
    /// (forward).
    pub yaw_rad: f64,
    /// The angles the equirectangular image covers. Default: that of
    /// [`EquirectConfig::default`](crate::EquirectConfig).
    pub equirect: EquirectGeometry,
}

impl Default for RectilinearConfig {
    fn default() -> Self {
        let (lo, hi) = ((-24.9f64).to_radians(), 2f64.to_radians());
        Self {
            fov_h_rad: std::f64::consts::FRAC_PI_2,
            fov_v_rad: std::f64::consts::FRAC_PI_2,
            width: 257,
            height: 257,
            yaw_rad: 0.0,
            equirect: EquirectGeometry::full_circle(lo, hi),
        }
    }
}

impl RectilinearConfig {
    /// A cubic face (90° × 90°, `size × size` pixels) of an image with the given geometry,
    /// looking along `yaw_rad`.
    pub fn cubic(size: u32, yaw_rad: f64, equirect: EquirectGeometry) -> Self {
        Self {
            width: size,
            height: size,
            yaw_rad,
            equirect,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        for (name, fov) in [("fov_h_rad", self.fov_h_rad), ("fov_v_rad", self.fov_v_rad)] {
            require_positive(name, fov)?;
            if fov >= std::f64::consts::PI {
                return Err(PlaceError::InvalidParameter {
                    name,
                    reason: format!("a rectilinear view needs a field of view below π, got {fov}"),
                });
            }
        }
        if self.width == 0 || self.height == 0 {
            return Err(PlaceError::InvalidParameter {
                name: "width, height",
                reason: "must be at least 1 pixel".into(),
            });
        }
        if !self.yaw_rad.is_finite() {
            return Err(PlaceError::InvalidParameter {
                name: "yaw_rad",
                reason: "must be finite".into(),
            });
        }
        let g = &self.equirect;
        require_positive("equirect.azimuth_span_rad", g.azimuth_span_rad)?;
        require_positive(
            "equirect elevation span",
            g.elevation_max_rad - g.elevation_min_rad,
        )
    }
}

/// Bilinear sample at continuous pixel coordinates (pixel centres at integers); columns wrap
/// when `wraps`, otherwise they are clamped; rows are clamped. Out of range → `None`.
fn bilinear(image: &GrayImage, x: f64, y: f64, wraps: bool) -> Option<f64> {
    let (w, h) = (image.width() as i64, image.height() as i64);
    if y < -0.5 || y > h as f64 - 0.5 || (!wraps && (x < -0.5 || x > w as f64 - 0.5)) {
        return None;
    }
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let col = |c: i64| {
        if wraps {
            c.rem_euclid(w)
        } else {
            c.clamp(0, w - 1)
        }
    };
    let row = |r: i64| r.clamp(0, h - 1);
    let at = |c: i64, r: i64| f64::from(image.get_pixel(col(c) as u32, row(r) as u32).0[0]);
    let (c0, r0) = (x0 as i64, y0 as i64);
    let top = at(c0, r0) * (1.0 - fx) + at(c0 + 1, r0) * fx;
    let bottom = at(c0, r0 + 1) * (1.0 - fx) + at(c0 + 1, r0 + 1) * fx;
    Some(top * (1.0 - fy) + bottom * fy)
}

/// The rectilinear view of an equirectangular image (Khan 2017, App. A.2, with the corrected
/// azimuth `η = atan2(c_x, c_z) + η_front`).
pub fn rectilinear(equirect: &GrayImage, config: &RectilinearConfig) -> Result<GrayImage> {
    config.validate()?;
    if equirect.width() == 0 || equirect.height() == 0 {
        return Err(PlaceError::BadInput(
            "rectilinear: empty equirectangular image".into(),
        ));
    }
    let g = &config.equirect;
    let res_az = g.azimuth_span_rad / f64::from(equirect.width());
    let res_el = (g.elevation_max_rad - g.elevation_min_rad) / f64::from(equirect.height());
    let (tx, ty) = (
        (config.fov_h_rad / 2.0).tan(),
        (config.fov_v_rad / 2.0).tan(),
    );
    let (w, h) = (f64::from(config.width), f64::from(config.height));
    let wraps = g.wraps();
    let mut out = GrayImage::new(config.width, config.height);
    for (u, v, pixel) in out.enumerate_pixels_mut() {
        let cx = tx * (1.0 - 2.0 * (f64::from(u) + 0.5) / w);
        let cy = ty * (1.0 - 2.0 * (f64::from(v) + 0.5) / h);
        let horizontal = (cx * cx + 1.0).sqrt(); // c_z = 1
        let eta = cx.atan2(1.0) + config.yaw_rad;
        let lambda = cy.atan2(horizontal);
        let mut delta = g.azimuth_max_rad - eta;
        if wraps {
            delta = delta.rem_euclid(std::f64::consts::TAU);
        }
        let x = delta / res_az - 0.5;
        let y = (g.elevation_max_rad - lambda) / res_el - 0.5;
        if let Some(value) = bilinear(equirect, x, y, wraps) {
            pixel.0[0] = value.round().clamp(0.0, 255.0) as u8;
        }
    }
    Ok(out)
}

/// The front (`yaw_rad`) and back (`yaw_rad + π`) cubic faces, `size × size` pixels
/// (App. A.2: "front and back views").
pub fn cubic_front_back(
    equirect: &GrayImage,
    geometry: EquirectGeometry,
    size: u32,
    yaw_rad: f64,
) -> Result<[GrayImage; 2]> {
    let front = RectilinearConfig::cubic(size, yaw_rad, geometry);
    let back = RectilinearConfig::cubic(size, yaw_rad + std::f64::consts::PI, geometry);
    Ok([
        rectilinear(equirect, &front)?,
        rectilinear(equirect, &back)?,
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1025 × 65 pixels: azimuth 0 and elevation 0 fall on the centre of pixel (512, 32).
    fn geometry() -> EquirectGeometry {
        EquirectGeometry::full_circle(-20f64.to_radians(), 20f64.to_radians())
    }

    fn pattern() -> GrayImage {
        GrayImage::from_fn(1025, 65, |x, y| {
            image::Luma([((x * 3 + y * 17) % 251) as u8])
        })
    }

    #[test]
    fn front_view_centre_is_azimuth_and_elevation_zero() {
        let eq = pattern();
        let config = RectilinearConfig::cubic(65, 0.0, geometry());
        let view = rectilinear(&eq, &config).unwrap();
        assert_eq!(view.get_pixel(32, 32), eq.get_pixel(512, 32));
        // Back view: azimuth π, the left edge of column 0 (between the last and first column).
        let [_, back] = cubic_front_back(&eq, geometry(), 65, 0.0).unwrap();
        let expect =
            (f64::from(eq.get_pixel(0, 32).0[0]) + f64::from(eq.get_pixel(1024, 32).0[0])) / 2.0;
        assert_eq!(f64::from(back.get_pixel(32, 32).0[0]), expect.round());
    }

    #[test]
    fn front_view_is_not_mirrored() {
        // Left half of the panorama (azimuth > 0, columns < 512) dark, right half bright.
        let eq = GrayImage::from_fn(1025, 65, |x, _| {
            image::Luma([if x < 512 { 10 } else { 200 }])
        });
        let view = rectilinear(&eq, &RectilinearConfig::cubic(65, 0.0, geometry())).unwrap();
        assert_eq!(
            view.get_pixel(5, 32).0[0],
            10,
            "left of the view = left of the sensor"
        );
        assert_eq!(view.get_pixel(60, 32).0[0], 200);
        // The top and bottom of a 90° view lie outside the ±20° elevation span: no data.
        assert_eq!(view.get_pixel(32, 0).0[0], 0);
        assert_eq!(view.get_pixel(32, 64).0[0], 0);
    }

    #[test]
    fn looking_left_shows_the_quarter_turn() {
        let eq = pattern();
        // Azimuth π/2 is the centre of column 1025/4 − 0.5 = 255.75: bilinear between 255 and 256.
        let view = rectilinear(
            &eq,
            &RectilinearConfig::cubic(65, std::f64::consts::FRAC_PI_2, geometry()),
        )
        .unwrap();
        let (a, b) = (
            f64::from(eq.get_pixel(255, 32).0[0]),
            f64::from(eq.get_pixel(256, 32).0[0]),
        );
        assert_eq!(
            f64::from(view.get_pixel(32, 32).0[0]),
            (0.25 * a + 0.75 * b).round()
        );
        let bad = RectilinearConfig {
            fov_h_rad: 4.0,
            ..RectilinearConfig::default()
        };
        assert!(rectilinear(&eq, &bad).is_err());
    }
}
