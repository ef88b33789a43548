//! Property tests of the radial plane fit and of PPE.

use nalgebra::Vector3;
use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use raypath_planes::{PlaneStats, PpeParams, extract_grid, fit_plane, radial_sse};

/// Rays of a `w × h` fan (`step` rad apart) around `axis` hitting the plane `{n·p = d}`,
/// with Gaussian radial noise `sigma`.
fn plane_rays(
    normal: Vector3<f64>,
    d: f64,
    w: usize,
    h: usize,
    step: f64,
    sigma: f64,
    seed: u64,
) -> Vec<Vector3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma.max(1e-300)).expect("valid sigma");
    let axis = normal;
    let u = axis
        .cross(&Vector3::z())
        .try_normalize(1e-9)
        .unwrap_or_else(|| axis.cross(&Vector3::x()).normalize());
    let t = axis.cross(&u);
    let mut out = Vec::new();
    for row in 0..h {
        for col in 0..w {
            let a = (col as f64 - (w as f64 - 1.0) / 2.0) * step;
            let b = (row as f64 - (h as f64 - 1.0) / 2.0) * step;
            let v = (axis + u * a.tan() + t * b.tan()).normalize();
            let r = d / normal.dot(&v)
                + if sigma > 0.0 {
                    noise.sample(&mut rng)
                } else {
                    0.0
                };
            out.push(v * r);
        }
    }
    out
}

fn unit(theta: f64, phi: f64) -> Vector3<f64> {
    Vector3::new(phi.cos() * theta.cos(), phi.cos() * theta.sin(), phi.sin())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// The fit recovers a known plane from noisy rays, and no plane explains them better
    /// than the fit (the true plane's error is an upper bound).
    #[test]
    fn fit_recovers_plane(theta in -3.1f64..3.1, phi in -0.6f64..0.6, d in 1.0f64..20.0,
                          sigma in 0.0f64..0.03, seed in 0u64..1000) {
        let n = unit(theta, phi);
        let pts = plane_rays(n, d, 12, 12, 0.02, sigma, seed);
        let fit = fit_plane(&pts).expect("fit");
        let truth = radial_sse(&(n / d), &pts);
        prop_assert!(fit.sse <= truth * (1.0 + 1e-9) + 1e-15, "fit {} > truth {}", fit.sse, truth);
        let angle = fit.normal().dot(&n).clamp(-1.0, 1.0).acos();
        // Tolerances: the fan spans 0.22 rad; noise σ/d relative.
        prop_assert!(angle < 1e-6 + 20.0 * sigma / d / 0.22 / 12.0, "angle {angle}");
        prop_assert!((fit.distance_m() - d).abs() < 1e-6 + 10.0 * sigma / 12.0 * (1.0 + d / 5.0), "distance {} vs {d}", fit.distance_m());
        prop_assert!(fit.rmse_m() <= sigma * 1.6 + 1e-9);
    }

    /// Splitting a plane's rays into two sets never lowers the error: the optimum over
    /// the union is at least the sum of the optima over the parts (sufficient statistics
    /// and the exact fit alike).
    #[test]
    fn splitting_never_lowers_error(theta in -3.1f64..3.1, phi in -0.6f64..0.6, d in 1.0f64..10.0,
                                    sigma in 0.0f64..0.05, split in 4usize..140, seed in 0u64..1000) {
        let pts = plane_rays(unit(theta, phi), d, 12, 12, 0.03, sigma, seed);
        let (a, b) = pts.split_at(split);
        let stats = |p: &[Vector3<f64>]| p.iter().fold(PlaneStats::default(), |mut s, q| { s.add(&PlaneStats::of_point(q)); s });
        let (sa, sb) = (stats(a), stats(b));
        let whole = sa.union(&sb).error();
        // A degenerate (collinear) part lies on infinitely many planes: error 0.
        let err = |s: &PlaneStats| { let e = s.error(); if e.is_finite() { e } else { 0.0 } };
        let parts = err(&sa) + err(&sb);
        prop_assert!(whole + 1e-9 * (1.0 + whole) >= parts, "whole {whole} < parts {parts}");
        let exact = fit_plane(&pts).expect("fit").sse;
        let exact_parts = fit_plane(a).map_or(0.0, |f| f.sse) + fit_plane(b).map_or(0.0, |f| f.sse);
        prop_assert!(exact + 1e-9 * (1.0 + exact) >= exact_parts, "exact {exact} < parts {exact_parts}");
    }
}

/// A scan of an open box (floor, three walls) and a staircase of boxes with noise and
/// holes: labels are a partition, every plane's index matches its labels, each plane's SSE
/// is its exact radial error, and no ray joins a plane across an `l_max` gap.
fn box_scene(w: usize, h: usize, sigma: f64, seed: u64) -> Vec<Vector3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma.max(1e-300)).expect("valid sigma");
    let mut pts = Vec::with_capacity(w * h);
    for row in 0..h {
        for col in 0..w {
            let az = (col as f64 / (w - 1) as f64 - 0.5) * 1.6;
            let el = 0.3 - row as f64 / (h - 1) as f64 * 1.0;
            let v = unit(az, el);
            // Planes: x = 4, y = ±2.5, z = -1.2, and a box front face x = 2.5 for |y| < 0.5, z < -0.4.
            let mut t = f64::INFINITY;
            let mut try_plane = |n: Vector3<f64>, d: f64, ok: &dyn Fn(Vector3<f64>) -> bool| {
                let c = n.dot(&v);
                if c > 1e-9 {
                    let s = d / c;
                    if s < t && ok(v * s) {
                        t = s;
                    }
                }
            };
            try_plane(Vector3::x(), 4.0, &|_| true);
            try_plane(Vector3::y(), 2.5, &|_| true);
            try_plane(-Vector3::y(), 2.5, &|_| true);
            try_plane(-Vector3::z(), 1.2, &|_| true);
            try_plane(Vector3::x(), 2.5, &|p| p.y.abs() < 0.5 && p.z < -0.4);
            if (row * 7 + col * 3) % 23 == 0 || !t.is_finite() {
                pts.push(Vector3::repeat(f64::NAN));
            } else {
                pts.push(
                    v * (t + if sigma > 0.0 {
                        noise.sample(&mut rng)
                    } else {
                        0.0
                    }),
                );
            }
        }
    }
    pts
}

#[test]
fn labels_are_a_partition_and_errors_exact() {
    for (sigma, seed) in [(0.0, 1), (0.005, 2), (0.02, 3)] {
        let pts = box_scene(60, 40, sigma, seed);
        let e = 16.0 * sigma * sigma + 1e-6;
        let params = PpeParams {
            l_max_m: 0.3,
            max_increment_m2: e,
            ..PpeParams::default()
        };
        let seg = extract_grid(&pts, 60, 40, &params).expect("extract");
        assert_eq!(seg.labels.len(), pts.len());
        let mut count = vec![0usize; seg.planes.len()];
        for (i, l) in seg.labels.iter().enumerate() {
            if let Some(l) = l {
                assert!(pts[i].x.is_finite(), "no-return {i} labelled");
                count[*l as usize] += 1;
            }
        }
        for (id, p) in seg.planes.iter().enumerate() {
            assert_eq!(p.index.len(), count[id]);
            assert!(p.index.iter().all(|&i| seg.labels[i] == Some(id as u32)));
            assert!(p.index.len() >= params.min_points);
            let members: Vec<_> = p.index.iter().map(|&i| pts[i]).collect();
            let sse = radial_sse(&p.fit.w, &members);
            assert!((sse - p.fit.sse).abs() <= 1e-9 * (1.0 + sse));
        }
        // Five planes in the scene; the floor, back wall, two side walls and the box face.
        // Five surfaces: floor, back wall, two side walls, box face. Greedy fragments may
        // stay apart (over-segmentation), but the large planes cover the scan.
        let large: Vec<_> = seg.planes.iter().filter(|p| p.index.len() >= 50).collect();
        let covered: usize = large.iter().map(|p| p.index.len()).sum();
        let valid = pts.iter().filter(|p| p.x.is_finite()).count();
        assert!(
            (5..=8).contains(&large.len()),
            "σ {sigma}: {} large planes",
            large.len()
        );
        assert!(
            covered as f64 >= 0.85 * valid as f64,
            "σ {sigma}: {covered} of {valid} rays in large planes"
        );
        assert!(
            seg.rmse_m() <= sigma * 1.5 + 1e-3,
            "σ {sigma}: rmse {}",
            seg.rmse_m()
        );
    }
}

#[test]
fn l_max_separates_and_params_are_checked() {
    let pts = box_scene(30, 20, 0.0, 4);
    let tight = PpeParams {
        l_max_m: 1e-4,
        ..PpeParams::default()
    };
    let seg = extract_grid(&pts, 30, 20, &tight).expect("extract");
    assert!(
        seg.planes.is_empty(),
        "{} planes with l_max 0.1 mm",
        seg.planes.len()
    );
    assert!(extract_grid(&pts, 31, 20, &PpeParams::default()).is_err());
    let bad = PpeParams {
        max_increment_m2: f64::NAN,
        ..PpeParams::default()
    };
    assert!(extract_grid(&pts, 30, 20, &bad).is_err());
    // Stopping by plane count: n = number of returned rays ⇒ nothing happens.
    let valid = pts.iter().filter(|p| p.x.is_finite()).count();
    let none = PpeParams {
        max_planes: Some(valid),
        ..PpeParams::default()
    };
    assert!(
        extract_grid(&pts, 30, 20, &none)
            .expect("extract")
            .planes
            .is_empty()
    );
}

/// A wall `x = 4 m` behind a full-height pillar (front face `x = 2.5 m`, `|y| < 0.4 m`),
/// seen by a `w × h` fan with radial noise `sigma`.
fn pillar_scene(w: usize, h: usize, sigma: f64, seed: u64) -> Vec<Vector3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma.max(1e-300)).expect("valid sigma");
    let mut pts = Vec::with_capacity(w * h);
    for row in 0..h {
        for col in 0..w {
            let v = unit(
                (col as f64 / (w - 1) as f64 - 0.5) * 1.0,
                0.3 - row as f64 / (h - 1) as f64 * 0.6,
            );
            let pillar = 2.5 / v.x;
            let t = if (v * pillar).y.abs() < 0.4 {
                pillar
            } else {
                4.0 / v.x
            };
            let n = if sigma > 0.0 {
                noise.sample(&mut rng)
            } else {
                0.0
            };
            pts.push(v * (t + n));
        }
    }
    pts
}

#[test]
fn refinement_joins_a_wall_split_by_an_occluder() {
    for (sigma, seed) in [(0.0, 5), (0.01, 6)] {
        let pts = pillar_scene(60, 30, sigma, seed);
        let plain = PpeParams {
            l_max_m: 0.3,
            max_increment_m2: 0.05 * 0.05,
            min_points: 10,
            ..PpeParams::default()
        };
        let wall_planes = |seg: &raypath_planes::Segmentation| {
            seg.planes
                .iter()
                .filter(|p| (p.fit.distance_m() - 4.0).abs() < 0.05 && p.index.len() >= 100)
                .count()
        };
        let seg = extract_grid(&pts, 60, 30, &plain).expect("extract");
        assert!(
            wall_planes(&seg) >= 2,
            "σ {sigma}: the pieces are not adjacent"
        );
        let refined = PpeParams {
            refine_rounds: 3,
            ..plain
        };
        let seg = extract_grid(&pts, 60, 30, &refined).expect("extract");
        assert_eq!(wall_planes(&seg), 1, "σ {sigma}: one wall after refinement");
        let wall = &seg.planes[0];
        assert!((wall.fit.distance_m() - 4.0).abs() < 0.01);
        // The pillar stays a plane of its own, and the labels remain a partition whose
        // plane fits are exact.
        assert!(
            seg.planes
                .iter()
                .any(|p| (p.fit.distance_m() - 2.5).abs() < 0.02 && p.index.len() >= 100)
        );
        for (id, p) in seg.planes.iter().enumerate() {
            assert!(p.index.iter().all(|&i| seg.labels[i] == Some(id as u32)));
            let members: Vec<_> = p.index.iter().map(|&i| pts[i]).collect();
            let sse = radial_sse(&p.fit.w, &members);
            assert!((sse - p.fit.sse).abs() <= 1e-9 * (1.0 + sse));
        }
        let labelled = seg.labels.iter().filter(|l| l.is_some()).count();
        assert_eq!(
            labelled,
            seg.planes.iter().map(|p| p.index.len()).sum::<usize>()
        );
    }
}
