//! Property tests: no panic on any scan (NaN, infinite, negative ranges, empty and one-beam
//! scans, any fan), results within bounds, vertices within the scan's extent.

use proptest::prelude::*;
use raypath_geometry::Scan2;
use raypath_polylines::metrics::ray_metrics;
use raypath_polylines::{Method, Optimizer, PolylineConfig, extract};

fn range_value() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => 0.05f64..25.0,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(-1.0),
        1 => Just(0.0),
        1 => Just(30.0),
    ]
}

fn scan() -> impl Strategy<Value = Scan2> {
    (
        -4.0f64..4.0,
        prop_oneof![
            Just(std::f64::consts::TAU / 360.0),
            Just(std::f64::consts::PI / 179.0),
            -0.05f64..0.05,
        ],
        prop::collection::vec(range_value(), 0..400),
        any::<bool>(),
    )
        .prop_map(|(angle_min_rad, inc, mut ranges, smooth)| {
            if smooth {
                // Runs of nearby ranges, so that long polylines form.
                for i in 1..ranges.len() {
                    if ranges[i].is_finite() && ranges[i - 1].is_finite() && ranges[i - 1] > 0.0 {
                        ranges[i] = ranges[i - 1] + (ranges[i] - 12.0) * 0.005;
                    }
                }
            }
            Scan2 {
                angle_min_rad,
                angle_increment_rad: if inc == 0.0 { 0.01 } else { inc },
                max_range_m: 30.0,
                ranges,
                intensities: None,
            }
        })
}

fn method() -> impl Strategy<Value = (Method, Optimizer)> {
    prop_oneof![
        Just((Method::Ple, Optimizer::default())),
        Just((Method::PlePlus, Optimizer::LEVENBERG_MARQUARDT)),
        Just((Method::PlePlus, Optimizer::NELDER_MEAD)),
        Just((Method::Vvl, Optimizer::default())),
        Just((Method::Ief, Optimizer::default())),
        Just((Method::Sam, Optimizer::default())),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    #[test]
    fn any_scan_any_method(scan in scan(), (method, optimizer) in method(), j in 2usize..60) {
        let config = PolylineConfig { optimizer, ..PolylineConfig::new(method, j) };
        let map = extract(&scan, &config).expect("a valid fan never fails");
        prop_assert!(map.vertex_count() <= j, "{} vertices > J = {j}", map.vertex_count());
        let max_r = (0..scan.len())
            .filter_map(|k| scan.range(k).hit())
            .fold(0.0f64, f64::max);
        for line in &map.lines {
            prop_assert!(line.len() >= 2);
            prop_assert_eq!(line.len(), line.rays.len());
            for v in &line.vertices {
                prop_assert!(v.x.is_finite() && v.y.is_finite());
                let norm = v.coords.norm();
                match method {
                    // Vertices are scan endpoints.
                    Method::Ple | Method::Vvl | Method::Ief => {
                        prop_assert!(norm <= max_r + 1e-9, "{norm} beyond {max_r}")
                    }
                    // Projections onto lines through endpoint centroids (≤ 2 max_r), or
                    // corners at most 1 m from an endpoint.
                    Method::Sam => prop_assert!(norm <= 2.0 * max_r + 1.0 + 1e-9),
                    Method::PlePlus => prop_assert!(norm <= 3.0 * max_r + 1.0),
                }
            }
        }
        let m = ray_metrics(&scan, &map).expect("metrics");
        if m.returned > 0 {
            prop_assert!((0.0..=1.0).contains(&m.f));
        }
        prop_assert!(m.explained <= m.returned);
    }
}

#[test]
fn degenerate_scans_give_empty_maps() {
    let base = Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: 0.01,
        max_range_m: 10.0,
        ranges: vec![],
        intensities: None,
    };
    for ranges in [vec![], vec![1.0], vec![f64::NAN; 50], vec![20.0; 50]] {
        let scan = Scan2 {
            ranges,
            ..base.clone()
        };
        for method in Method::ALL {
            let map = extract(&scan, &PolylineConfig::new(method, 10)).expect("no error");
            assert_eq!(map.vertex_count(), 0, "{}", method.name());
        }
    }
}

#[test]
fn bad_parameters_and_fans_are_errors() {
    let scan = Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: 0.01,
        max_range_m: 10.0,
        ranges: vec![1.0; 20],
        intensities: None,
    };
    let bad_configs = [
        PolylineConfig::new(Method::Ple, 1),
        PolylineConfig {
            max_edge_m: f64::NAN,
            ..PolylineConfig::default()
        },
        PolylineConfig {
            removed_residual_m: -1.0,
            ..PolylineConfig::default()
        },
        PolylineConfig {
            radial_variance_m2: 0.0,
            ..PolylineConfig::default()
        },
    ];
    for config in bad_configs {
        assert!(extract(&scan, &config).is_err(), "{config:?}");
    }
    let bad_fan = Scan2 {
        angle_increment_rad: f64::NAN,
        ..scan.clone()
    };
    assert!(extract(&bad_fan, &PolylineConfig::default()).is_err());
    let zero = Scan2 {
        angle_increment_rad: 0.0,
        ..scan
    };
    assert!(extract(&zero, &PolylineConfig::default()).is_err());
}
