//! Regression checks of PPE.
//!
//! * Fingerprints: the exact segmentation (labels, number of steps) and the plane parameters
//!   (to 1e-9 relative) on a simulated cluttered room and on the real 100 × 100 SynPEB
//!   sample, so that a change of the data structures is checked to return the same result.
//!   They pin the candidate order with ties broken by the action (`crate::ppe` docs);
//!   before that rule, ties fell to the binary heap's layout.
//! * Quality against the simulator's ground truth: the tie rule changes single
//!   segmentations, so the Hoover f and k of each configuration, averaged over six scenes,
//!   must stay within a stated margin of those of the implementation before the rule.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use raypath_planes::{HooverParams, PpeParams, Segmentation, compare, extract, extract_grid};

/// What a regression check compares: the exact labels (FNV-1a of the plane id of every
/// ray, `u32::MAX` for none), the step count, the plane count, and two sums of the plane
/// parameters weighted by the plane id (compared to 1e-9 relative).
#[derive(Debug, PartialEq)]
struct Print {
    planes: usize,
    steps: usize,
    labels: u64,
    w_sum: f64,
    sse: f64,
}

fn print(seg: &Segmentation) -> Print {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for l in &seg.labels {
        for byte in l.unwrap_or(u32::MAX).to_le_bytes() {
            h = (h ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    let w_sum = seg
        .planes
        .iter()
        .enumerate()
        .map(|(i, p)| (i + 1) as f64 * (p.fit.w.x + 2.0 * p.fit.w.y + 3.0 * p.fit.w.z))
        .sum();
    Print {
        planes: seg.planes.len(),
        steps: seg.steps,
        labels: h,
        w_sum,
        sse: seg.sse(),
    }
}

/// The cases whose fingerprint differs from the wanted one (all are printed).
fn mismatch(name: &str, seg: &Segmentation, want: &Print) -> Option<String> {
    let got = print(seg);
    println!("{name}: {got:?}");
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12);
    let same = got.planes == want.planes
        && got.steps == want.steps
        && got.labels == want.labels
        && close(got.w_sum, want.w_sum)
        && close(got.sse, want.sse);
    (!same).then(|| format!("{name}: got {got:?}, want {want:?}"))
}

/// Distance along unit ray `v` to the axis-aligned box `[lo, hi]` (slab method) and the
/// face it enters (`2 axis + side`).
fn hit_box(v: &Vector3<f64>, lo: [f64; 3], hi: [f64; 3]) -> Option<(f64, u32)> {
    let (mut t0, mut t1, mut face) = (0.0f64, f64::INFINITY, 0);
    for i in 0..3 {
        if v[i].abs() < 1e-12 {
            if !(lo[i]..=hi[i]).contains(&0.0) {
                return None;
            }
            continue;
        }
        let (a, b) = (lo[i] / v[i], hi[i] / v[i]);
        if a.min(b) > t0 {
            face = 2 * i as u32 + u32::from(a > b);
        }
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1 && t0 > 0.0).then_some((t0, face))
}

/// A simulated organized scan with the surface each ray hit (labels ≥ 10; `None`: no return).
struct Scene {
    points: Vec<Vector3<f64>>,
    truth: Vec<Option<u32>>,
}

/// A `w × h` fan (about 100° × 57°) inside a room with two boxes, a pillar and a table top,
/// with radial noise `sigma` and a sprinkle of no-returns.
fn cluttered_room(w: usize, h: usize, sigma: f64, seed: u64) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma).expect("valid sigma");
    let boxes = [
        ([1.5, -1.0, -1.2], [2.3, 0.2, -0.4]),
        ([2.8, 0.6, -1.2], [3.1, 0.9, 1.6]),
        ([2.0, 1.2, -0.45], [3.2, 2.4, -0.4]),
        ([3.5, -2.2, -1.2], [4.2, -1.4, 0.3]),
    ];
    let mut scene = Scene {
        points: Vec::with_capacity(w * h),
        truth: Vec::with_capacity(w * h),
    };
    for row in 0..h {
        for col in 0..w {
            let az = (col as f64 / (w - 1) as f64 - 0.5) * 1.75;
            let el = 0.45 - row as f64 / (h - 1) as f64;
            let v = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
            // The room's inside: the exit distance of the box [-3, 5] × [-3, 3.5] × [-1.2, 1.6].
            let (lo, hi) = ([-3.0, -3.0, -1.2], [5.0, 3.5, 1.6]);
            let (mut t, mut surface) = (0..3)
                .map(|i| match v[i] {
                    x if x > 1e-12 => (hi[i] / x, 2 * i as u32 + 1),
                    x if x < -1e-12 => (lo[i] / x, 2 * i as u32),
                    _ => (f64::INFINITY, 0),
                })
                .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a });
            for (i, (lo, hi)) in boxes.into_iter().enumerate() {
                if let Some((s, face)) = hit_box(&v, lo, hi)
                    && s < t
                {
                    (t, surface) = (s, 6 + 6 * i as u32 + face);
                }
            }
            if (row * 13 + col * 7) % 97 == 0 {
                scene.points.push(Vector3::repeat(f64::NAN));
                scene.truth.push(None);
            } else {
                scene.points.push(v * (t + noise.sample(&mut rng)));
                scene.truth.push(Some(10 + surface));
            }
        }
    }
    scene
}

#[test]
fn cluttered_room_segmentation_is_fixed() {
    let (w, h) = (200, 150);
    let noisy = cluttered_room(w, h, 0.02, 11).points;
    let quiet = cluttered_room(w, h, 0.005, 12).points;
    let cases = [
        (
            "synpeb",
            &noisy,
            PpeParams::synpeb(),
            Print {
                planes: 15,
                steps: 19657,
                labels: 8659478432847930775,
                w_sum: -35.803821592543926,
                sse: 11.715954606910376,
            },
        ),
        (
            "default",
            &noisy,
            PpeParams::default(),
            Print {
                planes: 140,
                steps: 19488,
                labels: 15532802296832190125,
                w_sum: -113994.47916070679,
                sse: 11.60968777108857,
            },
        ),
        (
            "max_planes",
            &noisy,
            PpeParams {
                max_planes: Some(2000),
                ..PpeParams::synpeb()
            },
            Print {
                planes: 16,
                steps: 18608,
                labels: 537794276556104908,
                w_sum: -69.01214501648403,
                sse: 11.556726515693011,
            },
        ),
        (
            "synpeb-0.5",
            &quiet,
            PpeParams::synpeb_noise("0.5").expect("preset"),
            Print {
                planes: 14,
                steps: 19396,
                labels: 5386980876773594259,
                w_sum: -77.39603012379565,
                sse: 0.7356195493265504,
            },
        ),
    ];
    let wrong: Vec<String> = cases
        .iter()
        .filter_map(|(name, pts, params, want)| {
            let seg = extract_grid(pts, w, h, params).expect("extract");
            mismatch(name, &seg, want)
        })
        .collect();
    assert!(wrong.is_empty(), "{wrong:#?}");
}

#[test]
fn real_synpeb_sample_segmentation_is_fixed() {
    let Some(path) = raypath_io::data::require("planes/synpeb-sample-100x100.pcd") else {
        return;
    };
    let pcd = raypath_io::pcd::read_pcd(&path, &raypath_io::pcd::ReadOptions::synpeb())
        .expect("read the sample");
    let cases = [
        (
            "synpeb",
            PpeParams::synpeb(),
            Print {
                planes: 11,
                steps: 6764,
                labels: 12651363733915217122,
                w_sum: -273.19063514867946,
                sse: 0.12076819752090058,
            },
        ),
        (
            "kitti",
            PpeParams::kitti(),
            Print {
                planes: 10,
                steps: 6708,
                labels: 11956032188602419705,
                w_sum: 17.463913309793035,
                sse: 0.20527316004611848,
            },
        ),
    ];
    let wrong: Vec<String> = cases
        .iter()
        .filter_map(|(name, params, want)| {
            let seg = extract(&pcd.cloud, params).expect("extract");
            mismatch(name, &seg, want)
        })
        .collect();
    assert!(wrong.is_empty(), "{wrong:#?}");
}

/// Mean Hoover f and k over six cluttered rooms for each configuration (σ, preset, seeds):
/// at most `F_MARGIN` and `K_MARGIN` below the means of the implementation before the tie
/// rule (recorded below; the current means are printed). On the generated 500 × 500 test
/// scans the rule moves the f of single scans by several points either way, while the mean f
/// of each noise level stays within two standard errors of no change.
#[test]
fn quality_on_cluttered_rooms_matches_the_previous_order() {
    const F_MARGIN: f64 = 0.05;
    const K_MARGIN: f64 = 0.01;
    let (w, h) = (200, 150);
    let thesis = PpeParams {
        max_increment_m2: 0.2 * 0.2,
        min_points: 10,
        ..PpeParams::default()
    };
    let preset = |level| PpeParams::synpeb_noise(level).expect("preset");
    // (σ, parameters, seeds, mean f and k before the tie rule)
    let cases = [
        (0.02, preset("2.0"), 21..27, (0.9762, 0.9983)),
        (0.005, preset("0.5"), 31..37, (1.0, 1.0)),
        (0.04, preset("4.0"), 41..47, (0.8810, 0.9903)),
        (0.02, thesis, 51..57, (0.6071, 0.4282)),
    ];
    for (sigma, params, seeds, (f_before, k_before)) in cases {
        let (mut f, mut k) = (0.0, 0.0);
        let n = seeds.clone().count() as f64;
        for seed in seeds {
            let scene = cluttered_room(w, h, sigma, seed);
            let seg = extract_grid(&scene.points, w, h, &params).expect("extract");
            let h = compare(&scene.truth, &seg.labels, &HooverParams::default()).expect("compare");
            f += h.fraction_correct() / n;
            k += h.k_value() / n;
        }
        println!("σ {sigma}: mean f {f:.4} (before {f_before}), k {k:.4} (before {k_before})");
        assert!(f >= f_before - F_MARGIN, "σ {sigma}: f {f} < {f_before}");
        assert!(k >= k_before - K_MARGIN, "σ {sigma}: k {k} < {k_before}");
    }
}
