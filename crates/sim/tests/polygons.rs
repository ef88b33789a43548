//! Polygon benchmark: protocol statistics, noise within tolerance, determinism, and that the
//! log reads like a real CARMEN log.

#![allow(clippy::unwrap_used)]

use std::f64::consts::{PI, TAU};
use std::path::Path;

use raypath_io::carmen::{CarmenConfig, CarmenReader, LaserKind, NoReturnRange, Record};
use raypath_sim::no_progress;
use raypath_sim::polygons::{self, AzimuthLayout, PolygonsConfig, random_polygon};
use raypath_sim::rng::stream;

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn generated_set_reads_back_and_is_deterministic() {
    let config = PolygonsConfig {
        scans: 40,
        ..PolygonsConfig::default()
    };
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let set = polygons::generate(&config, 11, a.path(), no_progress()).unwrap();
    // Same seed, different thread count: same bytes.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    pool.install(|| polygons::generate(&config, 11, b.path(), no_progress()).unwrap());
    assert_eq!(files(a.path()), files(b.path()));
    assert_eq!(set.files.len(), 2);
    let c = tempfile::tempdir().unwrap();
    polygons::generate(&config, 12, c.path(), no_progress()).unwrap();
    assert_ne!(files(a.path()), files(c.path()));

    let log = a.path().join("polygons.log");
    // The log has no no-returns; read it with the stated maximum range as the threshold (the
    // default inference can take a repeated range of a near-circular 180-gon for a code).
    let reader = CarmenReader::open_with(
        &log,
        CarmenConfig {
            no_return: NoReturnRange::Fixed(config.max_range_m),
            ..CarmenConfig::default()
        },
    )
    .unwrap();
    let mut scans = 0;
    for record in reader {
        if let Record::Laser(l) = record.unwrap() {
            assert_eq!(l.kind, LaserKind::RobotLaser1);
            assert_eq!(l.scan.len(), 360);
            assert!((l.scan.angle_min_rad + PI).abs() < 1e-6);
            assert!((l.scan.angle_increment_rad - 1f64.to_radians()).abs() < 1e-6);
            assert!(
                l.scan
                    .ranges
                    .iter()
                    .all(|&r| r > 0.0 && r < l.scan.max_range_m)
            );
            assert_eq!(l.world_from_laser.translation().norm(), 0.0);
            scans += 1;
        }
    }
    assert_eq!(scans, 40);
    let summary = raypath_io::summarize(&log).unwrap();
    assert_eq!((summary.scans, summary.beams), (Some(40), Some(360)));

    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.path().join("polygons.json")).unwrap()).unwrap();
    let polys = json["polygons"].as_array().unwrap();
    assert_eq!(polys.len(), 40);
    for p in polys {
        let n = p["n"].as_u64().unwrap() as usize;
        assert!([3, 4, 5, 6, 12, 36, 180].contains(&n));
        assert_eq!(p["vertices"].as_array().unwrap().len(), n);
        assert!(p["area_m2"].as_f64().unwrap() > 0.0);
    }
    assert_eq!(json["seed"], 11);
    assert_eq!(set.stats["scans"], 40);
}

#[test]
fn polygons_follow_the_protocol() {
    let config = PolygonsConfig::default();
    let mut rng = stream(5, 1, 0);
    let mut counts = std::collections::BTreeMap::new();
    for k in 0..3500 {
        let p = random_polygon(&config, &mut rng, k);
        *counts.entry(p.n).or_insert(0) += 1;
        assert!((0.0..1.0).contains(&p.angle_offset_rad));
        assert!((5.0..10.0).contains(&p.scale_m));
        for (j, v) in p.vertices.iter().enumerate() {
            let expected = p.angle_offset_rad + TAU * j as f64 / p.n as f64;
            let got = v[1].atan2(v[0]);
            let diff = (got - expected + PI).rem_euclid(TAU) - PI;
            assert!(diff.abs() < 1e-9);
        }
    }
    // Uniform over the seven counts: 500 expected each.
    assert_eq!(counts.len(), 7);
    assert!(
        counts.values().all(|&c| (400..600).contains(&c)),
        "{counts:?}"
    );

    // Radii: s·(Poisson(λ) + 1)/(λ + 1) has mean s and variance s²·λ/(λ + 1)².
    for n in [3usize, 6] {
        let config = PolygonsConfig {
            vertex_counts: vec![n],
            ..PolygonsConfig::default()
        };
        let lambda = (n * n) as f64 / 5.0;
        let ratios: Vec<f64> = (0..4000)
            .flat_map(|k| {
                let p = random_polygon(&config, &mut rng, k);
                p.vertices
                    .iter()
                    .map(|v| v[0].hypot(v[1]) / p.scale_m)
                    .collect::<Vec<_>>()
            })
            .collect();
        let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
        let var = ratios.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / ratios.len() as f64;
        let want_var = lambda / (lambda + 1.0).powi(2);
        assert!((mean - 1.0).abs() < 0.02, "n = {n}: mean {mean}");
        assert!(
            (var / want_var - 1.0).abs() < 0.08,
            "n = {n}: var {var} vs {want_var}"
        );
    }
}

#[test]
fn range_noise_has_the_configured_deviation() {
    let config = PolygonsConfig::default();
    let residuals: Vec<f64> = (0..60)
        .flat_map(|k| {
            let s = polygons::simulate_scan(&config, 3, k).unwrap();
            s.scan
                .ranges
                .iter()
                .zip(&s.true_ranges_m)
                .map(|(r, t)| r - t)
                .collect::<Vec<_>>()
        })
        .collect();
    let n = residuals.len() as f64;
    let mean = residuals.iter().sum::<f64>() / n;
    let std = (residuals.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(mean.abs() < 0.001, "{mean}");
    assert!((std / 0.03 - 1.0).abs() < 0.03, "{std}");
}

#[test]
fn angle_noise_has_the_configured_deviation() {
    // Triangles without range noise: along an edge with normal angle φₙ at distance d, the
    // exact range r fixes the true ray angle φ = φₙ ± acos(d/r).
    let config = PolygonsConfig {
        vertex_counts: vec![3],
        sigma_range_m: 0.0,
        ..PolygonsConfig::default()
    };
    let mut errors = Vec::new();
    for k in 0..300 {
        let s = polygons::simulate_scan(&config, 9, k).unwrap();
        let v = &s.polygon.vertices;
        for i in 0..s.scan.len() {
            let nominal = s.scan.angle(i);
            for e in 0..3 {
                let (a, b) = (v[e], v[(e + 1) % 3]);
                let (aa, ab) = (a[1].atan2(a[0]), b[1].atan2(b[0]));
                let span = (ab - aa).rem_euclid(TAU);
                let off = (nominal - aa).rem_euclid(TAU);
                // Well inside the edge's sector (away from the vertices).
                if off < 0.05 || off > span - 0.05 {
                    continue;
                }
                let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                let len = dx.hypot(dy);
                let (nx, ny) = (dy / len, -dx / len);
                let d = a[0] * nx + a[1] * ny;
                let (nx, ny, d) = if d < 0.0 { (-nx, -ny, -d) } else { (nx, ny, d) };
                let phi_n = ny.atan2(nx);
                let rel = (nominal - phi_n + PI).rem_euclid(TAU) - PI;
                if rel.abs() < 0.3 {
                    continue; // near-perpendicular incidence: the range hardly depends on φ
                }
                let phi = phi_n + rel.signum() * (d / s.scan.ranges[i]).min(1.0).acos();
                errors.push((phi - nominal + PI).rem_euclid(TAU) - PI);
            }
        }
    }
    let n = errors.len() as f64;
    assert!(n > 20_000.0, "{n}");
    let mean = errors.iter().sum::<f64>() / n;
    let std = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n).sqrt();
    assert!(mean.abs() < 0.01f64.to_radians(), "{mean}");
    assert!(
        (std / 0.2f64.to_radians() - 1.0).abs() < 0.04,
        "{}",
        std.to_degrees()
    );
}

#[test]
fn thesis_layout_repeats_the_first_ray() {
    let (min, inc) = AzimuthLayout::ThesisLinspace.layout(360);
    let last = min + 359.0 * inc;
    assert!((last - PI).abs() < 1e-12 && (min + PI).abs() < 1e-12);
    let (min, inc) = AzimuthLayout::HalfOpen.layout(360);
    assert!((min + 359.0 * inc - 179f64.to_radians()).abs() < 1e-12);
    let config = PolygonsConfig {
        azimuths: AzimuthLayout::ThesisLinspace,
        ..PolygonsConfig::default()
    };
    let s = polygons::simulate_scan(&config, 1, 0).unwrap();
    assert!((s.scan.angle_increment_rad - TAU / 359.0).abs() < 1e-15);
}

#[test]
fn bad_configurations_are_errors() {
    let tmp = tempfile::tempdir().unwrap();
    for config in [
        PolygonsConfig {
            scans: 0,
            ..PolygonsConfig::default()
        },
        PolygonsConfig {
            rays: 1,
            ..PolygonsConfig::default()
        },
        PolygonsConfig {
            vertex_counts: vec![2],
            ..PolygonsConfig::default()
        },
        PolygonsConfig {
            sigma_range_m: f64::NAN,
            ..PolygonsConfig::default()
        },
        PolygonsConfig {
            scale_min_m: 0.0,
            ..PolygonsConfig::default()
        },
    ] {
        assert!(polygons::generate(&config, 1, tmp.path(), no_progress()).is_err());
    }
}
