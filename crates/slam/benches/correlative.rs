//! Correlative branch-and-bound matching (Hess et al. 2016 §V) on a synthetic 30 m × 30 m
//! floor plan at 5 cm (600 × 600 cells; rooms, doorways, pillars; walls blurred with
//! σ = 5 cm, probabilities 0.1–0.9), one 180-point scan (360°, 2° apart):
//!
//! * `precompute/depth7`: building the seven max-pooled levels of the submap;
//! * `match/3m_30deg`: window ±3 m / ±30°, guess 1 m and 0.25 rad off (Hess's angular step);
//! * `match/7m_180deg`: window ±7 m / ±180°, guess 5 m and 2.5 rad off;
//! * `brute_force/3m_30deg`: the exhaustive search over the same lattice as `match/3m_30deg`.
//!
//! Run with `cargo bench -p raypath-slam --bench correlative`.
#![allow(missing_docs, clippy::unwrap_used)]

use std::f64::consts::PI;
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use raypath_geometry::Pose2;
use raypath_slam::correlative::{
    CorrelativeConfig, PrecomputedGrids, ProbabilityGrid, SearchWindow, match_scan,
    match_scan_brute_force,
};

type Wall = [f64; 4];

const RES: f64 = 0.05;
const CELLS: usize = 600;

/// Outer walls, an interior wall grid with doorways, pillars.
fn floor_plan() -> Vec<Wall> {
    let mut w = vec![
        [0.0, 0.0, 30.0, 0.0],
        [30.0, 0.0, 30.0, 30.0],
        [30.0, 30.0, 0.0, 30.0],
        [0.0, 30.0, 0.0, 0.0],
    ];
    // Walls at x = 10, 20 and y = 12, 21 with 1.2 m doorways at varying places.
    for (k, x) in [10.0, 20.0].into_iter().enumerate() {
        let door = 4.0 + 7.0 * k as f64;
        w.push([x, 0.0, x, door]);
        w.push([x, door + 1.2, x, 16.0]);
        w.push([x, 17.5 + 3.0 * k as f64, x, 30.0]);
    }
    for (k, y) in [12.0, 21.0].into_iter().enumerate() {
        let door = 3.0 + 5.0 * k as f64;
        w.push([0.0, y, door, y]);
        w.push([door + 1.2, y, 24.0 - 4.0 * k as f64, y]);
        w.push([25.5 - 4.0 * k as f64, y, 30.0, y]);
    }
    for (i, &(x, y)) in [
        (5.0, 5.0),
        (15.0, 7.0),
        (25.0, 16.0),
        (6.0, 25.0),
        (14.0, 17.0),
    ]
    .iter()
    .enumerate()
    {
        let s = 0.3 + 0.1 * i as f64;
        w.extend([
            [x, y, x + s, y],
            [x + s, y, x + s, y + s],
            [x + s, y + s, x, y + s],
            [x, y + s, x, y],
        ]);
    }
    w
}

fn distance(p: [f64; 2], w: &Wall) -> f64 {
    let (dx, dy) = (w[2] - w[0], w[3] - w[1]);
    let t = (((p[0] - w[0]) * dx + (p[1] - w[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    (p[0] - w[0] - t * dx).hypot(p[1] - w[1] - t * dy)
}

fn grid(walls: &[Wall]) -> ProbabilityGrid {
    let sigma = 0.05;
    let values = (0..CELLS * CELLS)
        .map(|k| {
            let c = [
                ((k % CELLS) as f64 + 0.5) * RES,
                ((k / CELLS) as f64 + 0.5) * RES,
            ];
            let d = walls
                .iter()
                .map(|w| distance(c, w))
                .fold(f64::INFINITY, f64::min);
            (0.1 + 0.8 * (-d * d / (2.0 * sigma * sigma)).exp()) as f32
        })
        .collect();
    ProbabilityGrid::new(RES, [0.0, 0.0], CELLS, CELLS, values).unwrap()
}

fn cast(walls: &[Wall], o: [f64; 2], a: f64) -> Option<f64> {
    let (dx, dy) = (a.cos(), a.sin());
    walls
        .iter()
        .filter_map(|w| {
            let (ex, ey) = (w[2] - w[0], w[3] - w[1]);
            let den = dx * ey - dy * ex;
            if den.abs() < 1e-12 {
                return None;
            }
            let (qx, qy) = (w[0] - o[0], w[1] - o[1]);
            let t = (qx * ey - qy * ex) / den;
            let u = (qx * dy - qy * dx) / den;
            (t > 1e-9 && (0.0..=1.0).contains(&u)).then_some(t)
        })
        .min_by(f64::total_cmp)
}

/// 180 beams over 360° from `pose`, sensor frame.
fn scan(walls: &[Wall], pose: Pose2) -> Vec<[f64; 2]> {
    (0..180)
        .filter_map(|k| {
            let a = -PI + 2.0 * PI * f64::from(k) / 180.0;
            let r = cast(walls, [pose.x(), pose.y()], pose.theta() + a)?;
            Some([r * a.cos(), r * a.sin()])
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let walls = floor_plan();
    let grid = grid(&walls);
    let config = CorrelativeConfig::default();
    let grids = PrecomputedGrids::new(&grid, config.depth);
    let truth = Pose2::new(14.2, 14.3, 0.4);
    let points = scan(&walls, truth);
    let cases = [
        (
            "3m_30deg",
            SearchWindow {
                linear_m: 3.0,
                angular_rad: 30f64.to_radians(),
            },
            Pose2::new(truth.x() + 0.8, truth.y() - 0.6, truth.theta() - 0.25),
        ),
        (
            "7m_180deg",
            SearchWindow {
                linear_m: 7.0,
                angular_rad: PI,
            },
            Pose2::new(truth.x() - 4.0, truth.y() + 3.0, truth.theta() + 2.5),
        ),
    ];
    for (name, window, initial) in &cases {
        let m = match_scan(&grids, &points, *initial, window, &config).unwrap();
        let p = m.submap_from_sensor;
        eprintln!(
            "{name}: {} points, error {:.3} m / {:.4} rad, score {:.3}, {} candidates scored",
            points.len(),
            (p.translation() - truth.translation()).norm(),
            raypath_geometry::wrap_angle(p.theta() - truth.theta()),
            m.score,
            m.candidates_scored,
        );
    }

    let mut group = c.benchmark_group("precompute");
    group.sample_size(20);
    group.bench_function("depth7", |b| {
        b.iter(|| PrecomputedGrids::new(black_box(&grid), 7));
    });
    group.finish();

    let mut group = c.benchmark_group("match");
    group.sample_size(20);
    for (name, window, initial) in &cases {
        group.bench_function(*name, |b| {
            b.iter(|| match_scan(&grids, black_box(&points), *initial, window, &config));
        });
    }
    group.finish();

    let mut group = c.benchmark_group("brute_force");
    group.sample_size(10);
    let (name, window, initial) = &cases[0];
    let step = config.angular_step(&points, RES);
    group.bench_function(*name, |b| {
        b.iter(|| match_scan_brute_force(&grid, black_box(&points), *initial, window, 0.55, step));
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
