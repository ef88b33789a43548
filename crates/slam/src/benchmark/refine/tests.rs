use std::f64::consts::TAU;

use raypath_geometry::{Pose2, Scan2};

use super::*;

type Wall = ([f64; 2], [f64; 2]);

/// A 8 m × 5 m room with a pillar off the centre.
fn room() -> Vec<Wall> {
    let mut walls = rect([-4.0, -2.5], [4.0, 2.5]);
    walls.extend(rect([1.0, 0.5], [1.6, 1.1]));
    walls
}

/// A 40 m corridor, 2 m wide, with no end in sight.
fn corridor() -> Vec<Wall> {
    vec![([-20.0, -1.0], [20.0, -1.0]), ([-20.0, 1.0], [20.0, 1.0])]
}

fn rect(lo: [f64; 2], hi: [f64; 2]) -> Vec<Wall> {
    let c = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    (0..4).map(|k| (c[k], c[(k + 1) % 4])).collect()
}

/// A 360-beam scan of `walls` from `pose` (9 m maximum range), cast by the simulator.
fn scan_at(walls: &[Wall], pose: Pose2) -> Scan2 {
    use nalgebra::Point2;
    use raypath_sim::scene2::{SceneBuilder2, Surface};
    let mut builder = SceneBuilder2::new();
    let wall = builder.add_surface(Surface {
        label: 1,
        reflectivity: 0.5,
    });
    for (a, b) in walls {
        builder.add_segment(Point2::new(a[0], a[1]), Point2::new(b[0], b[1]), wall);
    }
    let scene = builder.build().unwrap();
    let n = 360;
    let origin = Point2::new(pose.x(), pose.y());
    let ranges = (0..n)
        .map(|k| {
            let a = pose.theta() + k as f64 * TAU / n as f64;
            scene.cast_angle(&origin, a, 9.0).map_or(9.0, |h| h.range_m)
        })
        .collect();
    Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: TAU / n as f64,
        max_range_m: 9.0,
        ranges,
        intensities: None,
    }
}

fn off_by(a: Pose2, b: Pose2) -> (f64, f64) {
    let d = a.inverse() * b;
    (d.translation().norm(), d.theta().abs())
}

/// A reference off by 4 cm and 0.6° is refined to the true relation.
#[test]
fn a_wrong_reference_is_refined_to_the_true_relation() {
    let walls = room();
    let (a, b) = (Pose2::new(-1.0, -0.5, 0.2), Pose2::new(-0.4, -0.3, 0.45));
    let truth = a.inverse() * b;
    let reference = truth * Pose2::new(0.03, -0.025, 0.6f64.to_radians());
    let (si, sj) = (scan_at(&walls, a), scan_at(&walls, b));
    let refined = refine(&si, &sj, reference, &RefineConfig::default()).unwrap();
    let (t, r) = off_by(truth, refined);
    assert!(t < 1e-3 && r < 1e-4, "{t} m, {r} rad off");
}

/// In a corridor the relation along it is free: refused, whatever the reference.
#[test]
fn a_corridor_is_refused() {
    let walls = corridor();
    let (a, b) = (Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.5, 0.1, 0.05));
    let (si, sj) = (scan_at(&walls, a), scan_at(&walls, b));
    let refusal = refine(&si, &sj, a.inverse() * b, &RefineConfig::default()).unwrap_err();
    assert!(
        matches!(refusal, Refusal::Ambiguous | Refusal::Unconstrained),
        "{refusal:?}"
    );
}

/// A reference 0.3 m off the truth, which the alignment still finds, is refused as too far:
/// the check cannot tell which of the two is wrong.
#[test]
fn a_large_correction_is_refused() {
    let walls = room();
    let (a, b) = (Pose2::new(-1.0, -0.5, 0.0), Pose2::new(-0.6, -0.4, 0.1));
    let truth = a.inverse() * b;
    let (si, sj) = (scan_at(&walls, a), scan_at(&walls, b));
    let config = RefineConfig::default();
    let reference = truth * Pose2::new(0.25, 0.0, 0.0);
    assert_eq!(
        refine(&si, &sj, reference, &config),
        Err(Refusal::FarFromReference)
    );
    let wide = RefineConfig {
        max_correction: (0.5, 0.1),
        ..config
    };
    let refined = refine(&si, &sj, reference, &wide).unwrap();
    assert!(off_by(truth, refined).0 < 1e-3);
}

/// Relations with a missing reference or scan are counted, the others kept in order with the
/// correction they made.
#[test]
fn relations_are_refined_or_counted() {
    let walls = room();
    let poses = [
        Pose2::new(-1.0, -0.5, 0.2),
        Pose2::new(-0.5, -0.4, 0.3),
        Pose2::new(0.0, -0.6, 0.5),
    ];
    let scans: Vec<Scan2> = poses.iter().map(|p| scan_at(&walls, *p)).collect();
    let refs: Vec<&Scan2> = scans.iter().collect();
    let reference = [
        Some(poses[0]),
        Some(poses[1] * Pose2::new(0.02, 0.0, 0.0)),
        None,
    ];
    let out = refine_relations(
        &refs,
        &reference,
        &[(0, 1), (1, 2), (0, 7)],
        &RefineConfig::default(),
    )
    .unwrap();
    assert_eq!(out.dropped.unaligned, 2);
    assert_eq!(out.relations.len(), 1);
    let (i, j, rel) = out.relations[0];
    assert_eq!((i, j), (0, 1));
    assert!(off_by(poses[0].inverse() * poses[1], rel).0 < 1e-3);
    assert!((out.corrections_m[0] - 0.02).abs() < 2e-3);
    let (mean, std) = out.correction_m();
    assert!(mean == out.corrections_m[0] && std == 0.0);
    assert_eq!(Refined::default().correction_m(), (0.0, 0.0));
}

/// With range noise (σ 1 cm, seeded), a reference off by 3 cm and 0.5° lands within a few
/// millimetres of the truth: the refinement removes a corrected log's local error.
#[test]
fn noisy_scans_refine_to_millimetres() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let noise = Normal::new(0.0, 0.01).unwrap();
    let mut noisy = |s: Scan2| Scan2 {
        ranges: s
            .ranges
            .iter()
            .map(|r| r + noise.sample(&mut rng))
            .collect(),
        ..s
    };
    let walls = room();
    let config = RefineConfig::default();
    let mut worst: f64 = 0.0;
    for k in 0..8 {
        let a = Pose2::new(-1.5 + 0.3 * k as f64, -0.8, 0.1 * k as f64);
        let b = a * Pose2::new(0.4, 0.05, 0.08);
        let (si, sj) = (noisy(scan_at(&walls, a)), noisy(scan_at(&walls, b)));
        let truth = a.inverse() * b;
        let reference = truth * Pose2::new(-0.02, 0.025, -0.5f64.to_radians());
        let refined = refine(&si, &sj, reference, &config).unwrap();
        worst = worst.max(off_by(truth, refined).0);
    }
    assert!(worst < 5e-3, "worst {worst} m");
}

/// Empty scans, no-return (NaN, infinite) ranges and a non-finite reference are refusals,
/// never panics.
#[test]
fn bad_input_is_refused() {
    let walls = room();
    let good = scan_at(&walls, Pose2::new(0.0, -1.0, 0.0));
    let empty = Scan2 {
        ranges: Vec::new(),
        ..good.clone()
    };
    let broken = Scan2 {
        ranges: vec![f64::NAN, f64::INFINITY, -1.0, 0.0],
        ..good.clone()
    };
    let config = RefineConfig::default();
    for (a, b) in [
        (&good, &empty),
        (&empty, &good),
        (&broken, &good),
        (&good, &broken),
    ] {
        assert_eq!(
            refine(a, b, Pose2::identity(), &config),
            Err(Refusal::Unaligned)
        );
    }
    let nan = Pose2::new(f64::NAN, 0.0, 0.0);
    assert_eq!(refine(&good, &good, nan, &config), Err(Refusal::Unaligned));
}

/// Settings out of range are errors naming the field.
#[test]
fn bad_settings_are_errors() {
    let ok = RefineConfig::default();
    assert!(ok.validate().is_ok());
    let cases = [
        RefineConfig {
            gates_m: vec![],
            ..ok.clone()
        },
        RefineConfig {
            gates_m: vec![0.3, f64::NAN],
            ..ok.clone()
        },
        RefineConfig {
            kernel_m: 0.0,
            ..ok.clone()
        },
        RefineConfig {
            max_correction: (0.2, -1.0),
            ..ok.clone()
        },
        RefineConfig {
            min_constraint: 0.7,
            ..ok.clone()
        },
    ];
    let names = [
        "gates_m / iterations",
        "gates_m",
        "kernel_m",
        "max_correction.1",
        "min_constraint",
    ];
    for (config, name) in cases.iter().zip(names) {
        let err = refine_relations(&[], &[], &[(0, 1)], config).unwrap_err();
        assert!(err.to_string().contains(name), "{err}");
    }
}
