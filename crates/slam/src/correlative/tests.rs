//! Tests of the correlative matcher: branch and bound against brute force, known answers in
//! a synthetic room, the precomputed grids against a naive maximum, and grids from the
//! reflectivity crate's map.

use std::f64::consts::PI;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::Pose2;
use raypath_reflectivity::{MapConfig, MultiResMap, ScanPoints, export::observed_box};

use super::*;

/// A wall segment `[x0, y0, x1, y1]`, metres.
type Wall = [f64; 4];

/// A closed polygon as walls.
fn polygon(corners: &[[f64; 2]]) -> Vec<Wall> {
    (0..corners.len())
        .map(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
            [a[0], a[1], b[0], b[1]]
        })
        .collect()
}

/// An axis-aligned box `[x0, y0] – [x1, y1]` as walls.
fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Wall> {
    polygon(&[[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
}

fn distance_to_wall(p: [f64; 2], w: &Wall) -> f64 {
    let (dx, dy) = (w[2] - w[0], w[3] - w[1]);
    let len2 = dx * dx + dy * dy;
    let t = (((p[0] - w[0]) * dx + (p[1] - w[1]) * dy) / len2).clamp(0.0, 1.0);
    (p[0] - w[0] - t * dx).hypot(p[1] - w[1] - t * dy)
}

/// The grid of `walls` over `[x0, x0 + w·res) × [y0, y0 + h·res)`: `0.1 + 0.8·exp(−d²/2σ²)`
/// of the distance `d` from the cell centre to the nearest wall, or, with `sigma = 0`,
/// 1 in the cells a wall passes within half a cell of, 0 elsewhere (many exact ties).
fn room_grid(
    walls: &[Wall],
    res: f64,
    origin: [f64; 2],
    size: [usize; 2],
    sigma: f64,
) -> ProbabilityGrid {
    let values = (0..size[0] * size[1])
        .map(|k| {
            let c = [
                origin[0] + ((k % size[0]) as f64 + 0.5) * res,
                origin[1] + ((k / size[0]) as f64 + 0.5) * res,
            ];
            let d = walls
                .iter()
                .map(|w| distance_to_wall(c, w))
                .fold(f64::INFINITY, f64::min);
            if sigma > 0.0 {
                (0.1 + 0.8 * (-d * d / (2.0 * sigma * sigma)).exp()) as f32
            } else if d <= 0.5 * res + 1e-9 {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    ProbabilityGrid::new(res, origin, size[0], size[1], values).unwrap()
}

/// Range along the ray from `o` at heading `a` to the nearest wall.
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

/// A scan of `n` beams over 360° from `world_from_sensor`, in the sensor frame.
fn scan(walls: &[Wall], world_from_sensor: Pose2, n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .filter_map(|k| {
            let a = -PI + 2.0 * PI * k as f64 / n as f64;
            let r = cast(
                walls,
                [world_from_sensor.x(), world_from_sensor.y()],
                world_from_sensor.theta() + a,
            )?;
            Some([r * a.cos(), r * a.sin()])
        })
        .collect()
}

/// A random room: a box of 4–7 m × 3–6 m with one or two random boxes inside.
fn random_room(rng: &mut ChaCha8Rng) -> (Vec<Wall>, [f64; 2]) {
    let size = [rng.random_range(4.0..7.0), rng.random_range(3.0..6.0)];
    let mut walls = rect(0.0, 0.0, size[0], size[1]);
    for _ in 0..rng.random_range(1..=2) {
        let (x, y) = (
            rng.random_range(0.5..size[0] - 1.5),
            rng.random_range(0.5..size[1] - 1.5),
        );
        walls.extend(rect(
            x,
            y,
            x + rng.random_range(0.2..1.0),
            y + rng.random_range(0.2..1.0),
        ));
    }
    (walls, size)
}

/// (1) Branch and bound returns exactly the brute-force optimum: random rooms, grids (smooth,
/// binary with many ties, noisy), windows, depths, thresholds and angular steps.
#[test]
fn branch_and_bound_equals_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    let (mut found, mut pruned) = (0, 0usize);
    for case in 0..128 {
        let (walls, size) = random_room(&mut rng);
        let res = [0.1, 0.15, 0.2][case % 3];
        let origin = [rng.random_range(-1.0..-0.3), rng.random_range(-1.0..-0.3)];
        let cells = [
            ((size[0] + 1.5) / res) as usize,
            ((size[1] + 1.5) / res) as usize,
        ];
        let sigma = [0.0, res, 2.0 * res, 0.5 * res][case % 4];
        let mut grid = room_grid(&walls, res, origin, cells, sigma);
        if case % 5 == 4 {
            // Noise: values off the model everywhere.
            let values = (0..cells[0] * cells[1])
                .map(|k| {
                    (grid.value(k % cells[0], k / cells[0]) * rng.random_range(0.5f32..1.0))
                        .min(1.0)
                })
                .collect();
            grid = ProbabilityGrid::new(res, origin, cells[0], cells[1], values).unwrap();
        }
        let truth = Pose2::new(
            rng.random_range(1.0..size[0] - 1.0),
            rng.random_range(1.0..size[1] - 1.0),
            rng.random_range(-PI..PI),
        );
        let mut points = scan(&walls, truth, rng.random_range(30..80));
        for _ in 0..rng.random_range(0..5) {
            points.push([rng.random_range(-8.0..8.0), rng.random_range(-8.0..8.0)]); // clutter
        }
        let full_turn = case % 8 == 7;
        let window = SearchWindow {
            linear_m: if full_turn {
                rng.random_range(0.0..0.4)
            } else {
                rng.random_range(0.2..1.2)
            },
            angular_rad: if full_turn {
                PI
            } else {
                rng.random_range(0.0..0.5)
            },
        };
        let initial = Pose2::new(
            truth.x() + rng.random_range(-1.0..1.0) * window.linear_m,
            truth.y() + rng.random_range(-1.0..1.0) * window.linear_m,
            truth.theta() + rng.random_range(-1.0..1.0) * window.angular_rad.min(0.5),
        );
        let config = CorrelativeConfig {
            depth: rng.random_range(1..=8),
            min_score: [0.0, 0.3, 0.5, 0.6, 0.75][case % 5],
            angular_step_rad: (case % 3 == 1).then(|| rng.random_range(0.01..0.1)),
        };
        let step = config.angular_step(&points, res);
        // Half the cases search fewer levels than were precomputed.
        let grids = PrecomputedGrids::new(&grid, if case % 2 == 0 { config.depth } else { 8 });
        let fast = match_scan(&grids, &points, initial, &window, &config);
        let slow = match_scan_brute_force(&grid, &points, initial, &window, config.min_score, step);
        match (fast, slow) {
            (None, None) => {}
            (Some(f), Some(s)) => {
                assert_eq!(f.submap_from_sensor, s.submap_from_sensor, "case {case}");
                assert_eq!(f.score, s.score, "case {case}");
                assert!(f.score >= config.min_score && f.score <= 1.0);
                found += 1;
                pruned += usize::from(f.candidates_scored < s.candidates_scored);
            }
            (f, s) => panic!("case {case}: branch and bound {f:?}, brute force {s:?}"),
        }
    }
    // Most cases find a match, and branch and bound scores fewer candidates in most.
    assert!(found >= 40, "{found} matches");
    assert!(pruned * 4 >= found * 3, "{pruned} of {found}");
}

/// An asymmetric room: L-shaped, 10 m × 8 m, with a pillar and an inner wall.
fn known_room() -> Vec<Wall> {
    let mut walls = polygon(&[
        [0.0, 0.0],
        [10.0, 0.0],
        [10.0, 5.0],
        [6.0, 5.0],
        [6.0, 8.0],
        [0.0, 8.0],
    ]);
    walls.extend(rect(2.0, 2.0, 2.6, 2.4));
    walls.push([4.0, 6.0, 4.0, 8.0]);
    walls.push([7.5, 0.0, 7.5, 1.5]);
    walls
}

fn known_room_grid() -> ProbabilityGrid {
    room_grid(&known_room(), 0.05, [-0.5, -0.5], [220, 180], 0.05)
}

/// (2) A scan taken 1.3 m and 0.4 rad away from the initial guess is found within one cell
/// and one angular step.
#[test]
fn known_offset_is_recovered() {
    let grid = known_room_grid();
    let grids = PrecomputedGrids::new(&grid, 7);
    let truth = Pose2::new(3.2, 3.7, 0.3);
    let points = scan(&known_room(), truth, 180);
    let (a, d) = (35f64.to_radians(), 1.3);
    let initial = Pose2::new(
        truth.x() + d * a.cos(),
        truth.y() - d * a.sin(),
        truth.theta() - 0.4,
    );
    let window = SearchWindow {
        linear_m: 1.5,
        angular_rad: 0.5,
    };
    let config = CorrelativeConfig::default();
    let step = config.angular_step(&points, grid.resolution_m());
    let m = match_scan(&grids, &points, initial, &window, &config).unwrap();
    let pose = m.submap_from_sensor;
    assert!((pose.x() - truth.x()).abs() <= 0.05, "{pose:?}");
    assert!((pose.y() - truth.y()).abs() <= 0.05, "{pose:?}");
    assert!(
        raypath_geometry::wrap_angle(pose.theta() - truth.theta()).abs() <= step,
        "{pose:?}"
    );
    assert!(m.score > 0.8, "{}", m.score);
}

/// (3) No pose reaches `min_score` → `None`; exactly at the best score → `Some`; invalid
/// queries → `None`.
#[test]
fn below_min_score_is_none() {
    let grid = known_room_grid();
    let grids = PrecomputedGrids::new(&grid, 7);
    let truth = Pose2::new(3.0, 3.0, -0.2);
    let points = scan(&known_room(), truth, 90);
    let window = SearchWindow {
        linear_m: 0.3,
        angular_rad: 0.1,
    };
    let mut config = CorrelativeConfig::default();
    let best = match_scan(&grids, &points, truth, &window, &config).unwrap();
    config.min_score = best.score;
    assert_eq!(
        match_scan(&grids, &points, truth, &window, &config).map(|m| m.score),
        Some(best.score)
    );
    config.min_score = best.score + 1e-9;
    assert_eq!(match_scan(&grids, &points, truth, &window, &config), None);
    let step = config.angular_step(&points, 0.05);
    assert_eq!(
        match_scan_brute_force(&grid, &points, truth, &window, config.min_score, step),
        None
    );
    // The grid's maximum is 0.9: a threshold above it is never reached.
    config.min_score = 0.95;
    assert_eq!(match_scan(&grids, &points, truth, &window, &config), None);
    // A scan of another room (a long corridor) does not match.
    config.min_score = 0.55;
    let corridor = scan(&rect(-20.0, -0.8, 20.0, 0.8), Pose2::identity(), 90);
    let wide = SearchWindow {
        linear_m: 3.0,
        angular_rad: PI,
    };
    assert_eq!(match_scan(&grids, &corridor, truth, &wide, &config), None);
    // Points far outside the grid, no points, invalid window or config.
    let far: Vec<[f64; 2]> = points.iter().map(|p| [p[0] + 100.0, p[1]]).collect();
    assert_eq!(match_scan(&grids, &far, truth, &window, &config), None);
    assert_eq!(match_scan(&grids, &[], truth, &window, &config), None);
    let nan = SearchWindow {
        linear_m: f64::NAN,
        angular_rad: 0.1,
    };
    assert!(nan.validate().is_err());
    assert_eq!(match_scan(&grids, &points, truth, &nan, &config), None);
    let bad = CorrelativeConfig { depth: 0, ..config };
    assert!(bad.validate().is_err());
    assert_eq!(match_scan(&grids, &points, truth, &window, &bad), None);
    // Non-finite points count as misses: the score drops by their share.
    let mut with_nan = points.clone();
    with_nan.push([f64::NAN, 1.0]);
    config.min_score = 0.0;
    let m = match_scan(&grids, &with_nan, truth, &window, &config).unwrap();
    let expected = best.score * points.len() as f64 / with_nan.len() as f64;
    assert!((m.score - expected).abs() < 1e-12);
}

/// Naive maximum of the grid over the `k × k` window from `(i, j)` (0 outside).
fn naive_max(grid: &ProbabilityGrid, k: i64, i: i64, j: i64) -> f32 {
    let mut m = 0.0f32;
    for b in j..j + k {
        for a in i..i + k {
            if a >= 0 && b >= 0 {
                m = m.max(grid.value(a as usize, b as usize));
            }
        }
    }
    m
}

/// (4) Level h equals the naive maximum over its window, including windows that start left
/// of or below the grid; every level bounds the finer ones it covers.
#[test]
fn precomputed_levels_equal_naive_max() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for case in 0..12 {
        let (w, h) = (rng.random_range(1..40), rng.random_range(1..40));
        let values = (0..w * h)
            .map(|_| {
                if rng.random_bool(0.3) {
                    0.0
                } else {
                    rng.random::<f32>()
                }
            })
            .collect();
        let grid = ProbabilityGrid::new(0.1, [1.0, -2.0], w, h, values).unwrap();
        let depth = 1 + case % 7;
        let grids = PrecomputedGrids::new(&grid, depth);
        assert_eq!(grids.depth(), depth);
        assert_eq!(grids.grid(), &grid);
        for level in 0..depth {
            let k = 1i64 << level;
            for j in -k - 1..h as i64 + 1 {
                for i in -k - 1..w as i64 + 1 {
                    let v = grids.max_value(level, i, j);
                    assert_eq!(
                        v,
                        naive_max(&grid, k, i, j),
                        "case {case} level {level} ({i}, {j})"
                    );
                    if level > 0 {
                        let half = k / 2;
                        for (di, dj) in [(0, 0), (half, 0), (0, half), (half, half)] {
                            assert!(v >= grids.max_value(level - 1, i + di, j + dj));
                        }
                    }
                }
            }
        }
    }
}

/// (5) A grid from the reflectivity crate's map: probabilities in [0, 1], unknown cells at
/// [`UNKNOWN_PROBABILITY`], and the crop matches the full level.
#[test]
fn from_level_probabilities_and_crop() {
    let walls = rect(-2.02, -1.53, 2.47, 1.52); // off the cell boundaries
    let mut map = MultiResMap::new(&MapConfig {
        size_m: 10.0,
        ..MapConfig::default()
    })
    .unwrap();
    let mut points = ScanPoints::new();
    for p in scan(&walls, Pose2::identity(), 180) {
        points.push(p, f64::NAN);
    }
    map.update(&Pose2::identity(), &points);
    map.update(&Pose2::identity(), &points);
    let level = &map.levels()[0];
    let full = ProbabilityGrid::from_level(level, None);
    assert_eq!(
        (full.width(), full.height()),
        (level.width(), level.height())
    );
    assert_eq!(full.origin(), level.origin());
    let bbox = observed_box(level, 3).unwrap();
    let [i0, j0, i1, j1] = bbox;
    let crop = ProbabilityGrid::from_level(level, Some(bbox));
    assert_eq!((crop.width(), crop.height()), (i1 - i0, j1 - j0));
    assert!((crop.origin()[0] - (level.origin()[0] + i0 as f64 * 0.05)).abs() < 1e-12);
    assert!((crop.origin()[1] - (level.origin()[1] + j0 as f64 * 0.05)).abs() < 1e-12);
    let (mut occupied, mut free, mut unknown) = (0, 0, 0);
    for j in 0..crop.height() {
        for i in 0..crop.width() {
            let v = crop.value(i, j);
            assert!((0.0..=1.0).contains(&v));
            assert_eq!(v, full.value(i + i0, j + j0));
            let l = level.log_odds(i + i0, j + j0);
            if l == 0.0 {
                assert!((v - UNKNOWN_PROBABILITY).abs() < 1e-4);
                unknown += 1;
            } else if l > 0.0 {
                assert!(v > 0.5);
                occupied += 1;
            } else {
                assert!(v < 0.5);
                free += 1;
            }
        }
    }
    assert!(
        occupied > 100 && free > 1000 && unknown > 0,
        "{occupied} {free} {unknown}"
    );
    // The scan is found where it was inserted (one-cell walls: a lattice that holds the
    // true pose, and a modest threshold).
    let grids = PrecomputedGrids::new(&crop, 7);
    let window = SearchWindow {
        linear_m: 0.5,
        angular_rad: 0.2,
    };
    let config = CorrelativeConfig {
        min_score: 0.3,
        ..CorrelativeConfig::default()
    };
    let m = match_scan(
        &grids,
        points.points(),
        Pose2::new(0.2, -0.1, 0.0),
        &window,
        &config,
    )
    .unwrap();
    assert!(m.submap_from_sensor.translation().norm() < 0.06, "{m:?}");
    assert!(m.submap_from_sensor.theta().abs() < 0.02, "{m:?}");
    assert!(m.score > 0.6, "{m:?}");
    // Boxes beyond the level are clipped; an empty box gives an empty grid and no match.
    let clipped = ProbabilityGrid::from_level(level, Some([i0, j0, usize::MAX, usize::MAX]));
    assert_eq!(clipped.width(), level.width() - i0);
    let empty = ProbabilityGrid::from_level(level, Some([5, 5, 5, 9]));
    assert_eq!(empty.width(), 0);
    let none = match_scan(
        &PrecomputedGrids::new(&empty, 3),
        points.points(),
        Pose2::identity(),
        &SearchWindow::default(),
        &CorrelativeConfig::default(),
    );
    assert_eq!(none, None);
}

#[test]
fn grid_new_rejects_bad_input() {
    assert!(ProbabilityGrid::new(0.1, [0.0, 0.0], 2, 2, vec![0.5; 3]).is_err());
    assert!(ProbabilityGrid::new(0.1, [0.0, 0.0], 2, 1, vec![0.5, f32::NAN]).is_err());
    assert!(ProbabilityGrid::new(0.1, [0.0, 0.0], 2, 1, vec![0.5, 1.5]).is_err());
    assert!(ProbabilityGrid::new(0.0, [0.0, 0.0], 1, 1, vec![0.5]).is_err());
    assert!(ProbabilityGrid::new(0.1, [f64::INFINITY, 0.0], 1, 1, vec![0.5]).is_err());
    let g = ProbabilityGrid::new(0.1, [0.0, 0.0], 2, 1, vec![0.25, 1.0]).unwrap();
    assert!((g.value(0, 0) - 0.25).abs() < 1e-4);
    assert_eq!(g.value(1, 0), 1.0);
    assert_eq!(g.value(2, 0), 0.0);
}

/// Hess's angular step is the angle subtending one cell at `d_max` (≈ r / d_max when small).
#[test]
fn hess_step_subtends_one_cell() {
    let step = hess_angular_step(0.05, 10.0);
    assert!((2.0 * 10.0 * (step / 2.0).sin() - 0.05).abs() < 1e-12);
    assert_eq!(hess_angular_step(0.05, 0.0), PI);
    let config = CorrelativeConfig::default();
    assert_eq!(config.angular_step(&[[6.0, 8.0], [1.0, 0.0]], 0.05), step);
}

/// On a plateau (a corridor: every shift along it scores the same) the tie goes to the pose
/// nearest the initial guess, for both searches.
#[test]
fn ties_go_to_the_initial_guess() {
    let walls = vec![[-10.0, -1.0, 10.0, -1.0], [-10.0, 1.0, 10.0, 1.0]];
    let grid = room_grid(&walls, 0.1, [-10.0, -2.0], [200, 40], 0.0);
    let points: Vec<[f64; 2]> = (0..20)
        .flat_map(|k| [[k as f64 * 0.2 - 2.0, 0.95], [k as f64 * 0.2 - 2.0, -1.05]])
        .collect();
    let initial = Pose2::new(0.33, 0.0, 0.0);
    let window = SearchWindow {
        linear_m: 0.5,
        angular_rad: 0.0,
    };
    let config = CorrelativeConfig {
        min_score: 0.9,
        ..CorrelativeConfig::default()
    };
    let m = match_scan(
        &PrecomputedGrids::new(&grid, 4),
        &points,
        initial,
        &window,
        &config,
    )
    .unwrap();
    let b = match_scan_brute_force(&grid, &points, initial, &window, 0.9, 0.1).unwrap();
    assert_eq!(m.submap_from_sensor, b.submap_from_sensor);
    assert_eq!(m.submap_from_sensor, initial);
    assert_eq!(m.score, 1.0);
}
