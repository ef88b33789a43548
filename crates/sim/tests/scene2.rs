//! 2-D scene: ray hits against analytic answers (segments, a square from inside and outside,
//! a circle as a polygon) and against a brute-force reference on random segment soups.

#![allow(clippy::unwrap_used)]

use std::f64::consts::{PI, TAU};

use nalgebra::{Point2, Unit, Vector2};
use proptest::prelude::*;
use raypath_geometry::Pose2;
use raypath_sim::scene2::{SceneBuilder2, Surface};

fn surface(label: u32) -> Surface {
    Surface {
        label,
        reflectivity: 0.5,
    }
}

fn dir(angle: f64) -> Unit<Vector2<f64>> {
    Unit::new_normalize(Vector2::new(angle.cos(), angle.sin()))
}

#[test]
fn single_segment_hits_and_misses() {
    let mut b = SceneBuilder2::new();
    let s = b.add_surface(surface(7));
    b.add_segment(Point2::new(2.0, -1.0), Point2::new(2.0, 1.0), s);
    let scene = b.build().unwrap();
    let origin = Point2::origin();
    let hit = scene.cast(&origin, &dir(0.0), 10.0).unwrap();
    assert!((hit.range_m - 2.0).abs() < 1e-12);
    assert_eq!(hit.segment, 0);
    assert_eq!(scene.surface(hit.surface).unwrap().label, 7);
    assert!((hit.normal.into_inner() - Vector2::new(-1.0, 0.0)).norm() < 1e-12);
    // 45°: x = 2, y = 2 is past the end of the segment.
    assert!(scene.cast(&origin, &dir(PI / 4.0), 10.0).is_none());
    // 26.565°: y = 1 exactly at x = 2 (the end point).
    let hit = scene.cast(&origin, &dir(0.5f64.atan()), 10.0).unwrap();
    assert!((hit.range_m - 5f64.sqrt()).abs() < 1e-9);
    // From behind: the normal still faces the ray.
    let hit = scene.cast(&Point2::new(5.0, 0.5), &dir(PI), 10.0).unwrap();
    assert!((hit.range_m - 3.0).abs() < 1e-12);
    assert!(hit.normal.x > 0.99);
    // Range limit and direction.
    assert!(scene.cast(&origin, &dir(0.0), 1.99).is_none());
    assert!(scene.cast(&origin, &dir(PI), 10.0).is_none());
    assert!(!scene.is_free(&origin, &Point2::new(3.0, 0.0)));
    assert!(scene.is_free(&origin, &Point2::new(1.9, 0.0)));
    // Distances: to the segment's interior and to its end points.
    assert!((scene.distance(&origin) - 2.0).abs() < 1e-12);
    assert!((scene.distance(&Point2::new(2.0, 4.0)) - 3.0).abs() < 1e-12);
    assert!((scene.distance(&Point2::new(5.0, -5.0)) - 5.0).abs() < 1e-12);
}

#[test]
fn square_from_inside_and_outside() {
    let mut b = SceneBuilder2::new();
    let sides = [10, 11, 12, 13].map(|l| b.add_surface(surface(l)));
    b.add_rectangle(&Pose2::new(1.0, 2.0, 0.0), Vector2::new(2.0, 3.0), sides);
    let scene = b.build().unwrap();
    assert_eq!(scene.num_segments(), 4);
    let c = Point2::new(1.0, 2.0);
    for (angle, range, label) in [
        (PI, 2.0, 10),
        (0.0, 2.0, 11),
        (-PI / 2.0, 3.0, 12),
        (PI / 2.0, 3.0, 13),
    ] {
        let d = dir(angle);
        let hit = scene.cast(&c, &d, 100.0).unwrap();
        assert!((hit.range_m - range).abs() < 1e-12, "{angle}");
        assert_eq!(scene.surface(hit.surface).unwrap().label, label);
        assert!(hit.normal.dot(&d) < -0.999);
    }
    // Inside, at an angle: the ray leaves through the +x side at x = 3.
    let a: f64 = 0.3;
    let hit = scene.cast(&c, &dir(a), 100.0).unwrap();
    assert!((hit.range_m - 2.0 / a.cos()).abs() < 1e-12);
    // Outside: the near side.
    let hit = scene
        .cast(&Point2::new(-5.0, 2.5), &dir(0.0), 100.0)
        .unwrap();
    assert!((hit.range_m - 4.0).abs() < 1e-12);
    assert_eq!(scene.surface(hit.surface).unwrap().label, 10);
    // A rotated square: the distance to a side is the half extent.
    let mut b = SceneBuilder2::new();
    let s = b.add_surface(surface(1));
    b.add_rectangle(&Pose2::new(0.0, 0.0, 0.7), Vector2::new(1.5, 1.5), [s; 4]);
    let scene = b.build().unwrap();
    for k in 0..4 {
        let hit = scene
            .cast(&Point2::origin(), &dir(0.7 + k as f64 * PI / 2.0), 10.0)
            .unwrap();
        assert!((hit.range_m - 1.5).abs() < 1e-12);
    }
}

#[test]
fn circle_as_a_polygon() {
    let (n, r) = (64usize, 2.0);
    let mut b = SceneBuilder2::new();
    let s = b.add_surface(surface(3));
    let center = Point2::new(5.0, -1.0);
    b.add_circle(center, r, n, s);
    let scene = b.build().unwrap();
    let sector = TAU / n as f64;
    // From the centre: the inscribed n-gon's distance at angle φ.
    for k in 0..500 {
        let phi = k as f64 * TAU / 500.0;
        let hit = scene.cast(&center, &dir(phi), 10.0).unwrap();
        let off = phi.rem_euclid(sector) - sector / 2.0;
        let expected = r * (sector / 2.0).cos() / off.cos();
        assert!((hit.range_m - expected).abs() < 1e-9, "{phi}");
    }
    // From outside along the centre's x axis: a vertex of the polygon (at angle π) lies on it.
    let hit = scene
        .cast(&Point2::new(0.0, -1.0), &dir(0.0), 20.0)
        .unwrap();
    assert!((hit.range_m - (5.0 - r)).abs() < 1e-9, "{}", hit.range_m);
    // A ray passing above the circle misses it.
    assert!(
        scene
            .cast(&Point2::new(0.0, -1.0 + r * 1.01), &dir(0.0), 20.0)
            .is_none()
    );
}

#[test]
fn invalid_scenes_are_errors() {
    assert!(SceneBuilder2::new().build().is_err());
    let mut b = SceneBuilder2::new();
    b.add_segment(Point2::origin(), Point2::new(1.0, 0.0), 3);
    assert!(b.build().is_err());
    let mut b = SceneBuilder2::new();
    let s = b.add_surface(surface(0));
    b.add_segment(Point2::origin(), Point2::origin(), s);
    b.add_segment(Point2::origin(), Point2::new(f64::NAN, 0.0), s);
    assert_eq!(b.num_segments(), 0);
}

/// Brute force: the nearest crossing of the ray with any segment.
fn reference(
    segments: &[[Point2<f64>; 2]],
    o: Point2<f64>,
    d: Vector2<f64>,
) -> Option<(f64, usize)> {
    let cross = |a: Vector2<f64>, b: Vector2<f64>| a.x * b.y - a.y * b.x;
    let mut best: Option<(f64, usize)> = None;
    for (i, [a, b]) in segments.iter().enumerate() {
        let e = b - a;
        let denom = cross(d, e);
        if denom.abs() < 1e-12 {
            continue;
        }
        let w = a - o;
        let t = cross(w, e) / denom;
        let s = cross(w, d) / denom;
        if t >= 0.0 && (0.0..=1.0).contains(&s) && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, i));
        }
    }
    best
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn random_soups_match_brute_force(
        coords in prop::collection::vec((-10.0f64..10.0, -10.0f64..10.0, -10.0f64..10.0, -10.0f64..10.0), 1..40),
        rays in prop::collection::vec((-10.0f64..10.0, -10.0f64..10.0, 0.0f64..TAU), 20),
    ) {
        let mut b = SceneBuilder2::new();
        let mut segments = Vec::new();
        for (i, &(x0, y0, x1, y1)) in coords.iter().enumerate() {
            let s = b.add_surface(surface(i as u32));
            let (p, q) = (Point2::new(x0, y0), Point2::new(x1, y1));
            if (q - p).norm() > 1e-3 {
                b.add_segment(p, q, s);
                segments.push([p, q]);
            }
        }
        prop_assume!(!segments.is_empty());
        let scene = b.build().unwrap();
        for &(x, y, a) in &rays {
            let o = Point2::new(x, y);
            let d = dir(a);
            let got = scene.cast(&o, &d, 100.0);
            let want = reference(&segments, o, d.into_inner());
            match (got, want) {
                (Some(h), Some((t, _))) => {
                    prop_assert!((h.range_m - t).abs() < 1e-7, "{} vs {}", h.range_m, t);
                    // The segment reported is at that range (ties between segments allowed).
                    let [p, q] = scene.segment(h.segment).unwrap();
                    let point = o + d.into_inner() * h.range_m;
                    let e = q - p;
                    let dist = ((point - p).x * e.y - (point - p).y * e.x).abs() / e.norm();
                    prop_assert!(dist < 1e-6);
                    prop_assert!(h.normal.dot(&d) <= 1e-12);
                    let label = scene.surface(h.surface).unwrap().label;
                    prop_assert_eq!(scene.segment_surface(h.segment), Some(h.surface));
                    prop_assert!((label as usize) < coords.len());
                }
                (None, None) => {}
                // Grazing hits at segment ends may go either way within rounding.
                (g, w) => {
                    let near_end = segments.iter().any(|[p, q]| {
                        let dd = d.into_inner();
                        [p, q].iter().any(|v| {
                            let w = *v - o;
                            (w.x * dd.y - w.y * dd.x).abs() < 1e-9
                        })
                    });
                    prop_assert!(near_end, "got {g:?}, want {w:?}");
                }
            }
        }
    }
}
