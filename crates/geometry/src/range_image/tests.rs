//! Tests of range images and the spherical projection.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{Point3, Vector3};
use proptest::prelude::*;

use super::*;
use crate::GeometryError;

/// A range image on the pixel centres of `projection` with ranges in `[0.5, 60]` m, about a
/// fifth of them no-returns, plus intensity and label channels.
fn image_on(projection: &SphericalProjection, seeds: &[u64]) -> RangeImage {
    let n = projection.rows * projection.cols;
    let ranges: Vec<f32> = (0..n)
        .map(|i| {
            let h = seeds[i % seeds.len()].wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (i as u64);
            if h % 5 == 0 {
                f32::NAN
            } else {
                0.5 + (h % 10_000) as f32 * 0.006
            }
        })
        .collect();
    let intensity = (0..n).map(|i| i as f32 * 0.25).collect();
    let label = (0..n).map(|i| (i % 7) as u32 + 1).collect();
    RangeImage::new(
        projection.rows,
        projection.cols,
        projection.directions(),
        ranges,
    )
    .and_then(|image| image.with_intensity(intensity))
    .and_then(|image| image.with_label(label))
    .unwrap()
}

/// Asserts that `projected` (from `f32` points seen from a sensor at distance `origin_m`
/// from the frame origin) equals `original` up to the rounding of those points.
fn assert_same_image(original: &RangeImage, projected: &RangeImage, origin_m: f64) {
    assert_eq!(
        (projected.rows(), projected.cols()),
        (original.rows(), original.cols())
    );
    for row in 0..original.rows() {
        for col in 0..original.cols() {
            let i = original.index(row, col).unwrap();
            let (a, b) = (original.ranges_m()[i], projected.ranges_m()[i]);
            assert_eq!(a.is_nan(), b.is_nan(), "pixel ({row}, {col}): {a} vs {b}");
            let (da, db) = (original.direction(row, col), projected.direction(row, col));
            let angle = da.unwrap().angle(&db.unwrap());
            if a.is_nan() {
                assert!(projected.intensity().unwrap()[i].is_nan());
                assert_eq!(projected.label().unwrap()[i], 0);
                assert!(angle < 1e-12, "empty pixel not at its centre");
            } else {
                // A few f32 ulps of the point coordinates, plus the f32 rounding of the range.
                let point_error = 4.0 * f64::from(f32::EPSILON) * (origin_m + f64::from(a));
                let range_error = point_error + f64::from(f32::EPSILON) * f64::from(a);
                assert!(
                    f64::from((a - b).abs()) <= range_error,
                    "pixel ({row}, {col}): {a} vs {b}"
                );
                assert!(
                    angle <= point_error / f64::from(a),
                    "pixel ({row}, {col}) direction off by {angle}"
                );
                assert_eq!(
                    projected.intensity().unwrap()[i],
                    original.intensity().unwrap()[i]
                );
                assert_eq!(projected.label().unwrap()[i], original.label().unwrap()[i]);
            }
        }
    }
}

#[test]
fn projecting_the_points_of_a_range_image_returns_it() {
    let projection = SphericalProjection::new(16, 90, -0.3, 0.2).unwrap();
    let original = image_on(&projection, &[1, 2, 3, 4, 5]);
    let origin = Point3::new(1.0, -2.0, 0.5);
    let cloud = original.to_point_cloud(&origin);
    assert_eq!((cloud.width, cloud.height), (90, 16));
    assert_eq!(cloud.num_valid(), original.num_returns());
    let projected = projection.project(&cloud, &origin).unwrap();
    assert_same_image(&original, &projected, origin.coords.norm());
    // The organized cloud converts back to the same image too.
    let converted = RangeImage::from_point_cloud(&cloud, &origin).unwrap();
    for (a, b) in original.ranges_m().iter().zip(converted.ranges_m()) {
        assert!(a.is_nan() && b.is_nan() || (a - b).abs() <= 1e-5 * a);
    }
    assert_eq!(converted.label(), original.label());
}

#[test]
fn partial_azimuth_window_round_trips_and_drops_outside_points() {
    let projection = SphericalProjection::new(8, 40, -0.2, 0.2)
        .unwrap()
        .with_azimuth_window(-1.0, 2.5)
        .unwrap();
    let original = image_on(&projection, &[7, 11]);
    let mut cloud = original.to_point_cloud(&Point3::origin());
    // Behind the sensor (azimuth π) and far above the window: both dropped.
    cloud.points.push(Point3::new(-5.0, 0.0, 0.0));
    cloud.points.push(Point3::new(1.0, 0.0, 3.0));
    cloud.intensity.as_mut().unwrap().extend([1.0, 2.0]);
    cloud.label.as_mut().unwrap().extend([1, 2]);
    cloud.width = cloud.points.len();
    cloud.height = 1;
    let projected = projection.project(&cloud, &Point3::origin()).unwrap();
    assert_same_image(&original, &projected, 0.0);
}

#[test]
fn rep103_pixel_layout() {
    let projection = SphericalProjection::new(10, 360, -0.5, 0.5).unwrap();
    let pixel = |x: f64, y: f64, z: f64| projection.pixel_of(&Vector3::new(x, y, z));
    // Column 0 at azimuth π (behind, seen as the left edge), +y (left) a quarter turn in,
    // +x (forward) in the middle, −y (right) three quarters in.
    assert_eq!(pixel(1.0, 0.0, 0.0), Some((5, 180)));
    assert_eq!(pixel(0.0, 1.0, 0.0), Some((5, 90)));
    assert_eq!(pixel(0.0, -1.0, 0.0), Some((5, 270)));
    assert_eq!(pixel(-1.0, 1e-9, 0.0), Some((5, 0)));
    assert_eq!(pixel(-1.0, -1e-9, 0.0), Some((5, 359)));
    // Row 0 is the top; the window's edges are inside.
    let up = 0.45f64;
    assert_eq!(pixel(up.cos(), 0.0, up.sin()), Some((0, 180)));
    assert_eq!(pixel(0.5f64.cos(), 0.0, 0.5f64.sin()), Some((0, 180)));
    assert_eq!(pixel((-0.5f64).cos(), 0.0, (-0.5f64).sin()), Some((9, 180)));
    assert_eq!(pixel(0.0, 0.0, 1.0), None);
    assert_eq!(pixel(0.0, 0.0, 0.0), None);
    assert_eq!(pixel(f64::NAN, 0.0, 0.0), None);
    // Pixel centres are inside their own pixel.
    for (row, col) in [(0, 0), (3, 17), (9, 359)] {
        let (elevation, azimuth) = projection.pixel_center_rad(row, col);
        let d = spherical_direction(elevation, azimuth);
        assert_eq!(projection.pixel_of(&d), Some((row, col)));
    }
}

#[test]
fn nearest_point_wins_and_origin_points_are_skipped() {
    let projection = SphericalProjection::new(4, 8, -0.4, 0.4).unwrap();
    let mut cloud = PointCloud::from_points(vec![
        Point3::new(5.0, 0.1, 0.0),
        Point3::new(3.0, 0.06, 0.0),
        Point3::new(4.0, 0.08, 0.0),
        Point3::origin(),
        Point3::new(f32::NAN, 0.0, 0.0),
    ]);
    cloud.label = Some(vec![1, 2, 3, 4, 5]);
    let image = projection.project(&cloud, &Point3::origin()).unwrap();
    assert_eq!(image.num_returns(), 1);
    let i = image.ranges_m().iter().position(|r| !r.is_nan()).unwrap();
    assert!((image.ranges_m()[i] - 3.0006).abs() < 1e-4);
    assert_eq!(image.label().unwrap()[i], 2);
    assert!(image.intensity().is_none());
}

#[test]
fn invalid_projections_are_errors() {
    let bad = |r: Result<SphericalProjection, GeometryError>| {
        assert!(
            matches!(r, Err(GeometryError::InvalidRangeImage { .. })),
            "{r:?}"
        )
    };
    bad(SphericalProjection::new(0, 10, -0.1, 0.1));
    bad(SphericalProjection::new(10, 0, -0.1, 0.1));
    bad(SphericalProjection::new(1 << 20, 1 << 20, -0.1, 0.1));
    bad(SphericalProjection::new(10, 10, 0.1, 0.1));
    bad(SphericalProjection::new(10, 10, 0.2, -0.1));
    bad(SphericalProjection::new(10, 10, -2.0, 0.1));
    bad(SphericalProjection::new(10, 10, -0.1, f64::NAN));
    let ok = SphericalProjection::new(10, 10, -FRAC_PI_2, FRAC_PI_2).unwrap();
    bad(ok.with_azimuth_window(1.0, 1.0));
    bad(ok.with_azimuth_window(-PI, 2.0 * PI));
    bad(ok.with_azimuth_window(f64::NEG_INFINITY, 0.0));
    assert!(
        ok.with_azimuth_window(0.0, 2.0 * PI)
            .unwrap()
            .is_full_turn()
    );
    // Invalid public fields are caught when projecting.
    let broken = SphericalProjection { rows: 0, ..ok };
    let cloud = PointCloud::from_points(vec![Point3::new(1.0, 0.0, 0.0)]);
    assert!(broken.project(&cloud, &Point3::origin()).is_err());
    assert!(
        ok.project(&cloud, &Point3::new(f64::NAN, 0.0, 0.0))
            .is_err()
    );
    let mut mismatched = cloud.clone();
    mismatched.label = Some(vec![]);
    assert!(matches!(
        ok.project(&mismatched, &Point3::origin()),
        Err(GeometryError::InvalidCloud { .. })
    ));
}

#[test]
fn invalid_range_images_are_errors() {
    let spherical = || BeamDirections::Spherical {
        elevations_rad: vec![0.0],
        azimuths_rad: vec![0.0, 1.0],
    };
    let bad = |r: Result<RangeImage, GeometryError>| {
        assert!(
            matches!(r, Err(GeometryError::InvalidRangeImage { .. })),
            "{r:?}"
        )
    };
    bad(RangeImage::new(1, 2, spherical(), vec![1.0]));
    bad(RangeImage::new(0, 2, spherical(), vec![]));
    bad(RangeImage::new(1, 2, spherical(), vec![1.0, -1.0]));
    bad(RangeImage::new(1, 2, spherical(), vec![1.0, f32::INFINITY]));
    bad(RangeImage::new(2, 1, spherical(), vec![1.0, 1.0]));
    let elevations = BeamDirections::Spherical {
        elevations_rad: vec![2.0],
        azimuths_rad: vec![0.0, 1.0],
    };
    bad(RangeImage::new(1, 2, elevations, vec![1.0, 1.0]));
    let not_unit = BeamDirections::PerPixel(vec![Vector3::x(), Vector3::new(1.0, 1.0, 0.0)]);
    bad(RangeImage::new(1, 2, not_unit, vec![1.0, 1.0]));
    let nan = Vector3::repeat(f64::NAN);
    // A no-return may lack a direction, a return may not.
    let missing = BeamDirections::PerPixel(vec![Vector3::x(), nan]);
    let image = RangeImage::new(1, 2, missing.clone(), vec![1.0, f32::NAN]).unwrap();
    assert_eq!(image.direction(0, 1), None);
    assert_eq!(image.range(0, 1), Some(Range::NoReturn));
    assert_eq!(image.rays(&Point3::origin()).count(), 1);
    bad(RangeImage::new(1, 2, missing, vec![1.0, 1.0]));
    bad(image.clone().with_intensity(vec![1.0]));
    bad(image.with_label(vec![1, 2, 3]));
}

#[test]
fn accessors_and_rays() {
    let projection = SphericalProjection::new(2, 4, -0.1, 0.1).unwrap();
    let image = RangeImage::new(
        2,
        4,
        projection.directions(),
        vec![1.0, 2.0, f32::NAN, 4.0, 5.0, 6.0, 7.0, 8.0],
    )
    .unwrap();
    assert_eq!((image.len(), image.num_returns()), (8, 7));
    assert_eq!(image.index(1, 3), Some(7));
    assert_eq!(image.index(2, 0), None);
    assert_eq!(image.range(0, 4), None);
    assert_eq!(image.range(1, 0), Some(Range::Hit(5.0)));
    let origin = Point3::new(0.0, 0.0, 2.0);
    let rays: Vec<_> = image.rays(&origin).collect();
    assert_eq!(rays.len(), 8);
    assert_eq!(rays[2].range, Range::NoReturn);
    let p = image.point(1, 0, &origin).unwrap();
    assert!(((p - origin).norm() - 5.0).abs() < 1e-12);
    assert_eq!(projection.pixel_of(&(p - origin)), Some((1, 0)));
    assert!(image.point(0, 2, &origin).is_none());
}

#[test]
fn from_point_cloud_rejects_bad_input() {
    let mut cloud = PointCloud::from_points(vec![Point3::new(1.0, 0.0, 0.0); 6]);
    cloud.width = 4;
    assert!(RangeImage::from_point_cloud(&cloud, &Point3::origin()).is_err());
    cloud.width = 3;
    cloud.height = 2;
    let image = RangeImage::from_point_cloud(&cloud, &Point3::origin()).unwrap();
    assert_eq!((image.rows(), image.cols()), (2, 3));
    let origin_inf = Point3::new(f64::INFINITY, 0.0, 0.0);
    assert!(RangeImage::from_point_cloud(&cloud, &origin_inf).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random windows and sizes: projecting the points of an image on the pixel centres
    /// returns the image.
    #[test]
    fn projection_round_trip(
        rows in 1usize..24,
        cols in 1usize..200,
        e0 in -1.5..0.0f64,
        de in 0.01..1.5f64,
        a0 in -4.0..4.0f64,
        da in 0.1..(2.0 * PI),
        full in any::<bool>(),
        seed in any::<u64>(),
        origin in (-50.0..50.0f64, -50.0..50.0f64, -5.0..5.0f64),
    ) {
        let mut projection = SphericalProjection::new(rows, cols, e0, e0 + de).unwrap();
        if !full {
            projection = projection.with_azimuth_window(a0, a0 + da).unwrap();
        }
        let original = image_on(&projection, &[seed, seed ^ 0xABCD]);
        let origin = Point3::new(origin.0, origin.1, origin.2);
        let projected = projection.project(&original.to_point_cloud(&origin), &origin).unwrap();
        assert_same_image(&original, &projected, origin.coords.norm());
    }
}
