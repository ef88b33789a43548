//! Tests of the ring-by-ring projection on synthetic scans with known pixels.

use std::f64::consts::{PI, TAU};

use nalgebra::Point3;
use proptest::prelude::*;

use super::*;

/// Elevations of six lasers spaced unevenly like the HDL-64E's blocks (1/3° then 1/2°),
/// highest first, radians.
fn hdl_like_elevations() -> Vec<f64> {
    [2.0, 1.667, 1.333, -8.5, -9.0, -9.5]
        .iter()
        .map(|d: &f64| d.to_radians())
        .collect()
}

/// A known range for laser `ring` at column `col`.
fn range_of(ring: usize, col: usize) -> f64 {
    3.0 + ((ring * 31 + col * 7) % 50) as f64 * 0.5
}

/// A synthetic scan stored ring by ring: the lasers in `order`, each sweeping one turn from
/// just past `seam` (counter-clockwise, or clockwise) with one return per column centre of a
/// `cols`-column image unless `keep(ring, col)` is false. Labels are `1000 · ring + col`,
/// intensities `ring + col / 1000`.
fn scan(
    elevations: &[f64],
    order: &[usize],
    cols: usize,
    seam: f64,
    origin: &Point3<f64>,
    clockwise: bool,
    keep: impl Fn(usize, usize) -> bool,
) -> PointCloud {
    let step = TAU / cols as f64;
    let wrap = |a: f64| (a + PI).rem_euclid(TAU) - PI;
    let mut points = Vec::new();
    let (mut intensity, mut label) = (Vec::new(), Vec::new());
    for &ring in order {
        // Columns in sweep order: by azimuth past the seam.
        let mut columns: Vec<(f64, usize)> = (0..cols)
            .map(|col| {
                let azimuth = PI - (col as f64 + 0.5) * step;
                let past = wrap(azimuth - seam).rem_euclid(TAU);
                (if clockwise { TAU - past } else { past }, col)
            })
            .collect();
        columns.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (_, col) in columns {
            if !keep(ring, col) {
                continue;
            }
            let azimuth = PI - (col as f64 + 0.5) * step;
            let d = spherical_direction(elevations[ring], azimuth).into_inner();
            points.push((origin + d * range_of(ring, col)).cast::<f32>());
            intensity.push(ring as f32 + col as f32 / 1000.0);
            label.push((1000 * ring + col) as u32);
        }
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.intensity = Some(intensity);
    cloud.label = Some(label);
    cloud
}

/// Asserts that `image` holds laser `row`'s return of column `col` at pixel `(row, col)`
/// where `keep` says there is one (rows = lasers sorted by elevation, highest first).
fn assert_pixels(image: &RangeImage, origin_m: f64, keep: impl Fn(usize, usize) -> bool) {
    for row in 0..image.rows() {
        for col in 0..image.cols() {
            let i = image.index(row, col).unwrap();
            let r = image.ranges_m()[i];
            if keep(row, col) {
                let tolerance = 1e-6 * (origin_m + range_of(row, col));
                assert!(
                    (f64::from(r) - range_of(row, col)).abs() <= tolerance,
                    "pixel ({row}, {col}): {r}"
                );
                assert_eq!(image.label().unwrap()[i], (1000 * row + col) as u32);
                assert_eq!(
                    image.intensity().unwrap()[i],
                    row as f32 + col as f32 / 1000.0
                );
            } else {
                assert!(r.is_nan(), "pixel ({row}, {col}) should be empty: {r}");
                assert_eq!(image.label().unwrap()[i], 0);
            }
        }
    }
}

#[test]
fn unevenly_spaced_lasers_get_one_row_each() {
    let elevations = hdl_like_elevations();
    let order: Vec<usize> = (0..6).collect();
    let keep = |ring: usize, col: usize| (ring + col) % 9 != 0;
    let cloud = scan(
        &elevations,
        &order,
        180,
        0.0,
        &Point3::origin(),
        false,
        keep,
    );
    let projection = RingProjection::new(6, 180).unwrap();
    let image = projection.project(&cloud, &Point3::origin()).unwrap();
    assert_eq!(image.num_returns(), cloud.len());
    assert_pixels(&image, 0.0, keep);
    let assignment = projection.assign(&cloud, &Point3::origin()).unwrap();
    for (row, e) in assignment.row_elevation_rad.iter().enumerate() {
        assert!((e - elevations[row]).abs() < 1e-6, "row {row}: {e}");
    }
    // Empty pixels look along their row's elevation.
    let empty = (0..180).find(|&c| !keep(2, c)).unwrap();
    let d = image.direction(2, empty).unwrap();
    assert!((d.z.asin() - elevations[2]).abs() < 1e-9);
    // A uniform elevation grid over the same span cannot separate these lasers: rows
    // collide (the upper lasers are closer than a row) and points are lost.
    let uniform = SphericalProjection::new(6, 180, -9.75_f64.to_radians(), 2.25_f64.to_radians())
        .unwrap()
        .project(&cloud, &Point3::origin())
        .unwrap();
    assert!(uniform.num_returns() < cloud.len());
}

#[test]
fn rows_follow_elevation_not_storage_order() {
    let elevations = hdl_like_elevations();
    let order = [3, 0, 5, 1, 4, 2];
    let origin = Point3::new(2.0, -1.0, 1.5);
    let cloud = scan(&elevations, &order, 90, 0.0, &origin, false, |_, _| true);
    let image = RingProjection::new(6, 90)
        .unwrap()
        .project(&cloud, &origin)
        .unwrap();
    assert_pixels(&image, origin.coords.norm(), |_, _| true);
}

#[test]
fn clockwise_sweeps_and_other_seams() {
    let elevations = hdl_like_elevations();
    let order: Vec<usize> = (0..6).collect();
    for (seam, clockwise) in [(0.0, true), (1.0, false), (-2.5, true), (PI, false)] {
        let cloud = scan(
            &elevations,
            &order,
            120,
            seam,
            &Point3::origin(),
            clockwise,
            |_, _| true,
        );
        let projection = RingProjection {
            seam_rad: seam,
            ..RingProjection::new(6, 120).unwrap()
        };
        let image = projection.project(&cloud, &Point3::origin()).unwrap();
        assert_pixels(&image, 0.0, |_, _| true);
    }
}

#[test]
fn jitter_about_the_seam_does_not_split_a_ring() {
    let elevations = hdl_like_elevations();
    let order: Vec<usize> = (0..6).collect();
    let mut cloud = scan(
        &elevations,
        &order,
        60,
        0.0,
        &Point3::origin(),
        false,
        |_, _| true,
    );
    // Points just before and after the seam at the start of every ring, as lasers with
    // azimuth offsets produce: −0.1°, +0.1°, −0.05° after the first return of each ring.
    let mut points = Vec::new();
    for (k, chunk) in cloud.points.chunks(60).enumerate() {
        points.push(chunk[0]);
        for a in [-0.1_f64, 0.1, -0.05] {
            let d = spherical_direction(elevations[k], a.to_radians()).into_inner() * 1000.0;
            points.push(d.cast::<f32>().into());
        }
        points.extend_from_slice(&chunk[1..]);
    }
    cloud = PointCloud::from_points(points);
    let projection = RingProjection::new(6, 60).unwrap();
    let assignment = projection.assign(&cloud, &Point3::origin()).unwrap();
    // Each jittered point stays in its ring's row.
    for (k, chunk) in assignment.point_row.chunks(63).enumerate() {
        assert!(chunk.iter().all(|r| *r == Some(k)), "ring {k}: {chunk:?}");
    }
}

#[test]
fn nearest_point_wins_and_unusable_points_are_skipped() {
    let elevations = hdl_like_elevations();
    let order: Vec<usize> = (0..6).collect();
    let cloud = scan(
        &elevations,
        &order,
        40,
        0.0,
        &Point3::origin(),
        false,
        |_, _| true,
    );
    let mut points = Vec::new();
    let (mut intensity, mut label) = (Vec::new(), Vec::new());
    for (i, p) in cloud.points.iter().enumerate() {
        // Before each point: the same direction farther away, a NaN point and one at the
        // origin; none of them may win the pixel or break the ring detection.
        for extra in [p.coords * 2.0, Vector3::repeat(f32::NAN), Vector3::zeros()] {
            points.push(extra.into());
            intensity.push(-1.0);
            label.push(9999);
        }
        points.push(*p);
        intensity.push(cloud.intensity.as_ref().unwrap()[i]);
        label.push(cloud.label.as_ref().unwrap()[i]);
    }
    let mut noisy = PointCloud::from_points(points);
    noisy.intensity = Some(intensity);
    noisy.label = Some(label);
    let projection = RingProjection::new(6, 40).unwrap();
    let image = projection.project(&noisy, &Point3::origin()).unwrap();
    assert_pixels(&image, 0.0, |_, _| true);
    let assignment = projection.assign(&noisy, &Point3::origin()).unwrap();
    assert_eq!(assignment.point_row[1], None);
    assert_eq!(assignment.point_row[2], None);
    assert_eq!(assignment.point_row[0], Some(0));
}

#[test]
fn scans_not_stored_ring_by_ring_are_rejected() {
    let elevations = hdl_like_elevations();
    let order: Vec<usize> = (0..6).collect();
    let cloud = scan(
        &elevations,
        &order,
        50,
        0.0,
        &Point3::origin(),
        false,
        |_, _| true,
    );
    let err = RingProjection::new(7, 50)
        .unwrap()
        .project(&cloud, &Point3::origin())
        .unwrap_err();
    assert!(
        err.to_string().contains("found 6 rings, expected 7"),
        "{err}"
    );
    // Column-major storage (all lasers of one azimuth, then the next) is not ring by ring.
    let mut column_major = cloud.clone();
    let n = cloud.len();
    column_major.points = (0..n).map(|i| cloud.points[(i % 6) * 50 + i / 6]).collect();
    column_major.intensity = None;
    column_major.label = None;
    assert!(
        RingProjection::new(6, 50)
            .unwrap()
            .project(&column_major, &Point3::origin())
            .is_err()
    );
    // An empty cloud has no rings.
    let empty = PointCloud::from_points(Vec::new());
    assert!(
        RingProjection::new(6, 50)
            .unwrap()
            .project(&empty, &Point3::origin())
            .is_err()
    );
}

#[test]
fn bad_parameters_are_errors() {
    assert!(RingProjection::new(0, 10).is_err());
    assert!(RingProjection::new(10, 0).is_err());
    let seam = RingProjection {
        seam_rad: f64::NAN,
        ..RingProjection::new(2, 10).unwrap()
    };
    assert!(seam.validate().is_err());
    let cloud = PointCloud::from_points(vec![Point3::new(1.0, 0.0, 0.0)]);
    let nan_origin = Point3::new(f64::NAN, 0.0, 0.0);
    assert!(
        RingProjection::new(1, 10)
            .unwrap()
            .project(&cloud, &nan_origin)
            .is_err()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any number of lasers, columns, seam and sweep direction, with dropped returns: every
    /// kept return lands in its own pixel.
    #[test]
    fn every_return_lands_in_its_pixel(
        rings in 1usize..8,
        cols in 8usize..80,
        seam in -PI..PI,
        clockwise in any::<bool>(),
        drop in 0u64..1000,
    ) {
        let elevations: Vec<f64> = (0..rings).map(|r| 0.05 - r as f64 * 0.013).collect();
        let order: Vec<usize> = (0..rings).rev().collect();
        // Drop about a tenth of the returns, never a whole half turn of a ring.
        let keep = |ring: usize, col: usize| {
            let h = (drop ^ (ring as u64 * 7919 + col as u64)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            col % 2 == 0 || h >> 60 != 0
        };
        let cloud = scan(&elevations, &order, cols, seam, &Point3::origin(), clockwise, keep);
        let projection = RingProjection { seam_rad: seam, ..RingProjection::new(rings, cols).unwrap() };
        let image = projection.project(&cloud, &Point3::origin()).unwrap();
        prop_assert_eq!(image.num_returns(), cloud.len());
        assert_pixels(&image, 0.0, keep);
    }
}
