//! Tests of the pose graph: a dense reference solver, finite-difference Jacobians, simulated
//! loops with drift and with a wrong loop closure, bad input.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use raypath_geometry::{Pose2, wrap_angle};

use super::se2::error_and_jacobians;
use super::*;

fn plain(method: Method, max_iterations: usize) -> SolverConfig {
    SolverConfig {
        method,
        max_iterations,
        loop_kernel: RobustKernel::None,
        sequential_kernel: RobustKernel::None,
        tolerance: 1e-14,
        ..SolverConfig::default()
    }
}

fn edge(
    from: usize,
    to: usize,
    measurement: Pose2,
    information: Matrix3<f64>,
    kind: EdgeKind,
) -> Edge {
    Edge {
        from,
        to,
        measurement,
        information,
        kind,
    }
}

/// A random symmetric positive definite information matrix with full off-diagonal terms.
fn random_information(rng: &mut ChaCha8Rng) -> Matrix3<f64> {
    let m = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
    m * m.transpose() * 20.0 + Matrix3::from_diagonal(&Vector3::new(50.0, 50.0, 200.0))
}

fn noisy(rng: &mut ChaCha8Rng, pose: Pose2, sigma_m: f64, sigma_rad: f64) -> Pose2 {
    let n = Normal::new(0.0, 1.0).unwrap();
    Pose2::new(
        pose.x() + sigma_m * n.sample(rng),
        pose.y() + sigma_m * n.sample(rng),
        pose.theta() + sigma_rad * n.sample(rng),
    )
}

// ---------------------------------------------------------------------------------------
// A dense Gauss–Newton written independently: homogeneous 3×3 matrices and DMatrix.

fn v2t(p: &Vector3<f64>) -> Matrix3<f64> {
    let (s, c) = p.z.sin_cos();
    Matrix3::new(c, -s, p.x, s, c, p.y, 0.0, 0.0, 1.0)
}

fn t2v(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(m[(0, 2)], m[(1, 2)], m[(1, 0)].atan2(m[(0, 0)]))
}

fn rot(theta: f64) -> Matrix2<f64> {
    let (s, c) = theta.sin_cos();
    Matrix2::new(c, -s, s, c)
}

/// e, A, B of Grisetti et al. 2010 in matrix form.
fn dense_terms(
    xi: &Vector3<f64>,
    xj: &Vector3<f64>,
    z: &Vector3<f64>,
) -> (Vector3<f64>, Matrix3<f64>, Matrix3<f64>) {
    let inv = |m: Matrix3<f64>| m.try_inverse().unwrap();
    let e = t2v(&(inv(v2t(z)) * inv(v2t(xi)) * v2t(xj)));
    let rzt = rot(z.z).transpose();
    let rit = rot(xi.z).transpose();
    let (s, c) = xi.z.sin_cos();
    let drit = Matrix2::new(-s, c, -c, -s);
    let tij = Vector2::new(xj.x - xi.x, xj.y - xi.y);
    let top = rzt * rit;
    let col = rzt * drit * tij;
    let a = Matrix3::new(
        -top[(0, 0)],
        -top[(0, 1)],
        col.x,
        -top[(1, 0)],
        -top[(1, 1)],
        col.y,
        0.0,
        0.0,
        -1.0,
    );
    let b = Matrix3::new(
        top[(0, 0)],
        top[(0, 1)],
        0.0,
        top[(1, 0)],
        top[(1, 1)],
        0.0,
        0.0,
        0.0,
        1.0,
    );
    (e, a, b)
}

/// Dense Gauss–Newton with node 0 fixed; returns the states after `iterations` steps.
fn dense_gauss_newton(graph: &PoseGraph, iterations: usize) -> Vec<Vector3<f64>> {
    let mut x: Vec<Vector3<f64>> = graph
        .nodes()
        .iter()
        .map(|p| Vector3::new(p.x(), p.y(), p.theta()))
        .collect();
    let n = x.len() - 1;
    for _ in 0..iterations {
        let mut h = DMatrix::<f64>::zeros(3 * n, 3 * n);
        let mut b = DVector::<f64>::zeros(3 * n);
        for ed in graph.edges() {
            let z = Vector3::new(
                ed.measurement.x(),
                ed.measurement.y(),
                ed.measurement.theta(),
            );
            let (e, a, bj) = dense_terms(&x[ed.from], &x[ed.to], &z);
            let om = ed.information;
            let blocks = [(ed.from, a), (ed.to, bj)];
            for &(p, jp) in &blocks {
                if p == 0 {
                    continue;
                }
                let rp = 3 * (p - 1);
                let g = jp.transpose() * om * e;
                for r in 0..3 {
                    b[rp + r] += g[r];
                }
                for &(q, jq) in &blocks {
                    if q == 0 {
                        continue;
                    }
                    let rq = 3 * (q - 1);
                    let m = jp.transpose() * om * jq;
                    for r in 0..3 {
                        for c in 0..3 {
                            h[(rp + r, rq + c)] += m[(r, c)];
                        }
                    }
                }
            }
        }
        let dx = h.cholesky().unwrap().solve(&(-b));
        for k in 0..n {
            let d = Vector3::new(dx[3 * k], dx[3 * k + 1], dx[3 * k + 2]);
            let v = &mut x[k + 1];
            *v += d;
            v.z = wrap_angle(v.z);
        }
    }
    x
}

/// A ring of 8 poses on a circle of radius 3 m with noisy sequential edges, full information
/// matrices, one loop closure 7 → 0 and one chord 2 → 6; the initial guess is perturbed.
fn ring(seed: u64) -> (PoseGraph, Vec<Pose2>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let truth: Vec<Pose2> = (0..8)
        .map(|k| {
            let a = k as f64 * PI / 4.0;
            Pose2::new(3.0 * a.cos(), 3.0 * a.sin(), wrap_angle(a + FRAC_PI_2))
        })
        .collect();
    let mut graph = PoseGraph::new();
    for (k, t) in truth.iter().enumerate() {
        let guess = if k == 0 {
            *t
        } else {
            noisy(&mut rng, *t, 0.3, 0.2)
        };
        graph.add_node(guess);
    }
    let pairs = [
        (0, 1),
        (1, 2),
        (2, 3),
        (3, 4),
        (4, 5),
        (5, 6),
        (6, 7),
        (7, 0),
        (2, 6),
    ];
    for (k, &(i, j)) in pairs.iter().enumerate() {
        let z = noisy(&mut rng, truth[i].inverse() * truth[j], 0.05, 0.02);
        let kind = if k < 7 {
            EdgeKind::Sequential
        } else {
            EdgeKind::Loop
        };
        graph
            .add_edge(edge(i, j, z, random_information(&mut rng), kind))
            .unwrap();
    }
    (graph, truth)
}

fn max_difference(graph: &PoseGraph, reference: &[Vector3<f64>]) -> f64 {
    graph
        .nodes()
        .iter()
        .zip(reference)
        .map(|(p, r)| {
            let d = Vector3::new(p.x() - r.x, p.y() - r.y, wrap_angle(p.theta() - r.z));
            d.amax()
        })
        .fold(0.0, f64::max)
}

#[test]
fn sparse_solver_matches_dense_gauss_newton() {
    for seed in 0..4 {
        let (graph, _) = ring(seed);
        // One step: the same linear system.
        let mut one = graph.clone();
        one.optimize(&plain(Method::GaussNewton, 1)).unwrap();
        let dense_one = dense_gauss_newton(&graph, 1);
        let d1 = max_difference(&one, &dense_one);
        assert!(d1 < 1e-9, "seed {seed}: one step differs by {d1}");
        // Converged: the same minimum.
        let mut full = graph.clone();
        let report = full.optimize(&plain(Method::GaussNewton, 30)).unwrap();
        let dense_full = dense_gauss_newton(&graph, 30);
        let d = max_difference(&full, &dense_full);
        assert!(d < 1e-9, "seed {seed}: solutions differ by {d}");
        assert!(report.converged && report.final_chi2 < report.initial_chi2);
    }
}

#[test]
fn analytic_jacobians_match_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let h = 1e-6;
    for _ in 0..200 {
        let random_pose = |r: &mut ChaCha8Rng| {
            Pose2::new(
                r.random_range(-5.0..5.0),
                r.random_range(-5.0..5.0),
                r.random_range(-PI..PI),
            )
        };
        let (xi, xj, z) = (
            random_pose(&mut rng),
            random_pose(&mut rng),
            random_pose(&mut rng),
        );
        let (e0, a, b) = error_and_jacobians(&xi, &xj, &z, true);
        let bump = |p: &Pose2, k: usize, d: f64| {
            let mut v = [p.x(), p.y(), p.theta()];
            v[k] += d;
            Pose2::new(v[0], v[1], v[2])
        };
        let diff = |plus: Vector3<f64>, minus: Vector3<f64>| {
            let mut d = plus - minus;
            d.z = wrap_angle(d.z);
            d / (2.0 * h)
        };
        for k in 0..3 {
            let ep = error_and_jacobians(&bump(&xi, k, h), &xj, &z, false).0;
            let em = error_and_jacobians(&bump(&xi, k, -h), &xj, &z, false).0;
            let fd = diff(ep, em);
            assert!(
                (fd - a.column(k)).amax() < 1e-6,
                "A col {k}: {fd} vs {}",
                a.column(k)
            );
            let ep = error_and_jacobians(&xi, &bump(&xj, k, h), &z, false).0;
            let em = error_and_jacobians(&xi, &bump(&xj, k, -h), &z, false).0;
            let fd = diff(ep, em);
            assert!(
                (fd - b.column(k)).amax() < 1e-6,
                "B col {k}: {fd} vs {}",
                b.column(k)
            );
        }
        // The error itself against the homogeneous-matrix definition.
        let v = |p: &Pose2| Vector3::new(p.x(), p.y(), p.theta());
        let (e_ref, _, _) = dense_terms(&v(&xi), &v(&xj), &v(&z));
        assert!((e0 - e_ref).amax() < 1e-12);
    }
}

#[test]
fn robust_costs_have_their_weights_as_derivatives() {
    let kernels = [
        RobustKernel::None,
        RobustKernel::Huber { delta: 1.5 },
        RobustKernel::Cauchy { c: 0.7 },
        RobustKernel::Dcs { phi: 1.0 },
        RobustKernel::Dcs { phi: 4.0 },
    ];
    for kernel in kernels {
        for chi2 in [0.01, 0.5, 0.9, 2.0, 3.7, 10.0, 100.0, 1e4] {
            let h = 1e-6 * chi2;
            let fd = (kernel.cost(chi2 + h) - kernel.cost(chi2 - h)) / (2.0 * h);
            assert!(
                (fd - kernel.weight(chi2)).abs() < 1e-6,
                "{kernel:?} at {chi2}"
            );
        }
    }
    // DCS's scale is the s of Agarwal et al. 2013.
    let phi: f64 = 1.0;
    let chi2: f64 = 9.0;
    let s = (2.0 * phi / (phi + chi2)).min(1.0);
    assert!((RobustKernel::Dcs { phi }.weight(chi2) - s * s).abs() < 1e-15);
}

// ---------------------------------------------------------------------------------------
// A square world: two laps around a 10 m square, 1 m steps.

struct Square {
    graph: PoseGraph,
    truth: Vec<Pose2>,
    /// Indices of the correct loop edges.
    loops: Vec<usize>,
}

/// Odometry that drifts: each 1 m step turns 5 mrad too far, on top of
/// σ = 5 mm, 1 mrad of noise; its information says σ = 2 cm and 10 mrad (covering the bias, as
/// a front-end's does). Loop closures every 2nd node of the second lap to the first with
/// σ = 1 cm, 2 mrad and the information that says so. The initial guess is the odometry
/// chained from node 0.
fn square(seed: u64) -> Square {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut truth = vec![Pose2::identity()];
    for k in 1..80 {
        let turn = if k % 10 == 0 { FRAC_PI_2 } else { 0.0 };
        truth.push(truth[k - 1] * Pose2::new(1.0, 0.0, turn));
    }
    let information = |sigma_m: f64, sigma_rad: f64| {
        Matrix3::from_diagonal(&Vector3::new(
            sigma_m.powi(-2),
            sigma_m.powi(-2),
            sigma_rad.powi(-2),
        ))
    };
    let mut graph = PoseGraph::new();
    graph.add_node(truth[0]);
    let mut guess = truth[0];
    let mut measurements = Vec::new();
    for k in 1..truth.len() {
        let relative = truth[k - 1].inverse() * truth[k];
        let biased = Pose2::new(relative.x(), relative.y(), relative.theta() + 0.005);
        let z = noisy(&mut rng, biased, 0.005, 0.001);
        guess = guess * z;
        graph.add_node(guess);
        measurements.push(z);
    }
    for (k, z) in measurements.into_iter().enumerate() {
        let info = information(0.02, 0.01);
        graph
            .add_edge(edge(k, k + 1, z, info, EdgeKind::Sequential))
            .unwrap();
    }
    let mut loops = Vec::new();
    for k in (40..80).step_by(2) {
        let z = noisy(&mut rng, truth[k - 40].inverse() * truth[k], 0.01, 0.002);
        let info = information(0.01, 0.002);
        loops.push(
            graph
                .add_edge(edge(k - 40, k, z, info, EdgeKind::Loop))
                .unwrap(),
        );
    }
    Square {
        graph,
        truth,
        loops,
    }
}

fn rms_position_error(graph: &PoseGraph, truth: &[Pose2]) -> f64 {
    let sum: f64 = graph
        .nodes()
        .iter()
        .zip(truth)
        .map(|(p, t)| (p.translation() - t.translation()).norm_squared())
        .sum();
    (sum / truth.len() as f64).sqrt()
}

#[test]
fn square_loop_with_drift_is_pulled_back_to_the_truth() {
    for seed in 0..3 {
        for (config, name) in [
            (
                SolverConfig::default(),
                "default (LM, DCS on loops, annealing)",
            ),
            (plain(Method::GaussNewton, 20), "Gauss–Newton, no kernel"),
        ] {
            let Square {
                mut graph,
                truth,
                loops,
            } = square(seed);
            let before = rms_position_error(&graph, &truth);
            let report = graph.optimize(&config).unwrap();
            let after = rms_position_error(&graph, &truth);
            assert!(
                before > 1.0,
                "{name}: the drift should be visible, rms {before}"
            );
            assert!(
                after * 10.0 < before,
                "{name}, seed {seed}: rms {before} → {after}, {report:?}"
            );
            assert!(report.converged, "{name}, seed {seed}: {report:?}");
            for &e in &loops {
                let w = graph.edge_weight(e);
                assert!(w > 0.5, "{name}, seed {seed}: loop edge {e} weight {w}");
            }
        }
    }
}

#[test]
fn dcs_without_annealing_ignores_correct_loops_far_from_the_guess() {
    // Why `SolverConfig::annealing` is on by default: the drift puts the correct loop
    // closures at χ² ≫ Φ, where DCS gives them almost no weight.
    let Square {
        mut graph,
        truth,
        loops,
    } = square(0);
    let before = rms_position_error(&graph, &truth);
    let config = SolverConfig {
        annealing: None,
        ..SolverConfig::default()
    };
    graph.optimize(&config).unwrap();
    let after = rms_position_error(&graph, &truth);
    assert!(after > 0.9 * before, "rms {before} → {after}");
    assert!(loops.iter().all(|&e| graph.edge_weight(e) < 0.05));
}

/// Adds to `square(seed)` the loop closure 15 → 55 (the same place of the two laps) but
/// `off_m` and 0.3 rad off, with the information of a good one.
fn square_with_wrong_loop(seed: u64, off_m: f64) -> (Square, usize) {
    let mut square = square(seed);
    let truth = &square.truth;
    let z = truth[15].inverse() * truth[55] * Pose2::new(off_m, 0.0, 0.3);
    let info = Matrix3::from_diagonal(&Vector3::new(1e4, 1e4, 2.5e5));
    let wrong = square
        .graph
        .add_edge(edge(15, 55, z, info, EdgeKind::Loop))
        .unwrap();
    (square, wrong)
}

#[test]
fn wrong_loop_edge_is_down_weighted() {
    for (seed, off_m) in [(0, 5.0), (1, 5.0), (2, 0.3)] {
        // Reference: the graph without the wrong edge, plain least squares.
        let Square {
            mut graph, truth, ..
        } = square(seed);
        graph
            .optimize(&plain(Method::LevenbergMarquardt, 50))
            .unwrap();
        let clean_error = rms_position_error(&graph, &truth);
        // Plain least squares with the wrong edge: the map is bent (clearly so at 5 m).
        let (Square { mut graph, .. }, _) = square_with_wrong_loop(seed, off_m);
        graph
            .optimize(&plain(Method::LevenbergMarquardt, 50))
            .unwrap();
        let naive_error = rms_position_error(&graph, &truth);
        assert!(
            off_m < 1.0 || naive_error > 5.0 * clean_error,
            "seed {seed}: rms {naive_error} vs clean {clean_error}"
        );
        for kernel in [
            SolverConfig::default().loop_kernel,
            RobustKernel::Dcs { phi: 1.0 },
            RobustKernel::Cauchy { c: 1.0 },
        ] {
            let (
                Square {
                    mut graph, loops, ..
                },
                wrong,
            ) = square_with_wrong_loop(seed, off_m);
            let config = SolverConfig {
                loop_kernel: kernel,
                ..SolverConfig::default()
            };
            let report = graph.optimize(&config).unwrap();
            let robust_error = rms_position_error(&graph, &truth);
            let name = format!("{kernel:?}, seed {seed}, {off_m} m off");
            assert!(
                robust_error < clean_error + 0.01,
                "{name}: rms {robust_error} vs clean {clean_error} (least squares {naive_error}), {report:?}"
            );
            let w = graph.edge_weight(wrong);
            assert!(w < 0.05, "{name}: wrong edge weight {w}");
            for &e in &loops {
                let w = graph.edge_weight(e);
                assert!(w > 0.5, "{name}: loop edge {e} weight {w}");
            }
        }
    }
}

#[test]
fn a_switched_off_edge_no_longer_acts() {
    // The wrong loop under plain least squares bends the graph; switched off, the result is
    // the graph without it, to the solver's precision.
    let config = plain(Method::LevenbergMarquardt, 50);
    let Square { mut graph, .. } = square(0);
    graph.optimize(&config).unwrap();
    let clean = graph.nodes().to_vec();
    let (Square { mut graph, .. }, wrong) = square_with_wrong_loop(0, 5.0);
    graph.switch_off(wrong);
    graph.optimize(&config).unwrap();
    let difference = graph
        .nodes()
        .iter()
        .zip(&clean)
        .map(|(a, b)| (a.translation() - b.translation()).norm())
        .fold(0.0, f64::max);
    assert!(difference < 1e-6, "{difference}");
    assert_eq!(graph.edge_chi2(wrong), 0.0);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let mut graph = PoseGraph::new();
    graph.add_node(Pose2::identity());
    graph.add_node(Pose2::new(1.0, 0.0, 0.0));
    let info = Matrix3::identity();
    let good = edge(0, 1, Pose2::new(1.0, 0.0, 0.0), info, EdgeKind::Sequential);
    let cases = [
        ("missing node", Edge { to: 2, ..good }),
        ("self loop", Edge { to: 0, ..good }),
        (
            "NaN measurement",
            Edge {
                measurement: Pose2::new(f64::NAN, 0.0, 0.0),
                ..good
            },
        ),
        (
            "inf information",
            Edge {
                information: info * f64::INFINITY,
                ..good
            },
        ),
        (
            "negative definite",
            Edge {
                information: -info,
                ..good
            },
        ),
        (
            "indefinite",
            Edge {
                information: Matrix3::from_diagonal(&Vector3::new(1.0, -0.5, 1.0)),
                ..good
            },
        ),
        (
            "asymmetric",
            Edge {
                information: Matrix3::new(1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
                ..good
            },
        ),
    ];
    for (name, e) in cases {
        match graph.add_edge(e) {
            Err(SlamError::BadInput(message)) => {
                assert!(message.contains("edge 0"), "{name}: {message}")
            }
            other => panic!("{name}: {other:?}"),
        }
    }
    assert!(graph.edges().is_empty());
    // Semi-definite information is accepted (e.g. no heading information).
    let semi = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 0.0));
    graph
        .add_edge(Edge {
            information: semi,
            ..good
        })
        .unwrap();
    // A non-finite pose and bad parameters are reported by optimize.
    let mut broken = graph.clone();
    broken.set_node(1, Pose2::new(f64::INFINITY, 0.0, 0.0));
    assert!(matches!(
        broken.optimize(&SolverConfig::default()),
        Err(SlamError::BadInput(_))
    ));
    for config in [
        SolverConfig {
            loop_kernel: RobustKernel::Cauchy { c: 0.0 },
            ..SolverConfig::default()
        },
        SolverConfig {
            sequential_kernel: RobustKernel::Huber { delta: f64::NAN },
            ..SolverConfig::default()
        },
        SolverConfig {
            loop_kernel: RobustKernel::Dcs { phi: -1.0 },
            ..SolverConfig::default()
        },
        SolverConfig {
            tolerance: -1.0,
            ..SolverConfig::default()
        },
        SolverConfig {
            lm_tau: 0.0,
            ..SolverConfig::default()
        },
    ] {
        assert!(matches!(
            graph.optimize(&config),
            Err(SlamError::InvalidParameter { .. })
        ));
    }
    // Semi-definite information leaves θ of node 1 unobservable: Gauss–Newton reports it,
    // Levenberg–Marquardt's damping copes.
    let mut gn = graph.clone();
    assert!(matches!(
        gn.optimize(&plain(Method::GaussNewton, 5)),
        Err(SlamError::Solver(_))
    ));
    let report = graph.optimize(&SolverConfig::default()).unwrap();
    assert!(report.final_chi2 < 1e-12);
}

#[test]
fn gauss_newton_and_levenberg_marquardt_agree() {
    for seed in 0..3 {
        let Square { graph, .. } = square(10 + seed);
        let mut gn = graph.clone();
        let mut lm = graph.clone();
        let gn_report = gn.optimize(&plain(Method::GaussNewton, 30)).unwrap();
        let lm_report = lm
            .optimize(&plain(Method::LevenbergMarquardt, 100))
            .unwrap();
        assert!(
            gn_report.converged && lm_report.converged,
            "{gn_report:?} {lm_report:?}"
        );
        let reference: Vec<Vector3<f64>> = gn
            .nodes()
            .iter()
            .map(|p| Vector3::new(p.x(), p.y(), p.theta()))
            .collect();
        let d = max_difference(&lm, &reference);
        assert!(d < 1e-7, "seed {seed}: GN and LM differ by {d}");
        assert!((gn_report.final_chi2 - lm_report.final_chi2).abs() < 1e-9 * gn_report.final_chi2);
    }
    let (graph, _) = ring(3);
    let mut gn = graph.clone();
    let mut lm = graph.clone();
    gn.optimize(&plain(Method::GaussNewton, 30)).unwrap();
    lm.optimize(&plain(Method::LevenbergMarquardt, 100))
        .unwrap();
    let reference: Vec<Vector3<f64>> = gn
        .nodes()
        .iter()
        .map(|p| Vector3::new(p.x(), p.y(), p.theta()))
        .collect();
    assert!(max_difference(&lm, &reference) < 1e-7);
}

#[test]
fn cached_structure_is_reused_and_rebuilt_when_the_graph_grows() {
    let Square {
        mut graph, truth, ..
    } = square(3);
    let config = plain(Method::LevenbergMarquardt, 50);
    let start = graph.nodes().to_vec();
    graph.optimize(&config).unwrap();
    let version = graph.cache.0.as_ref().map(|s| s.version);
    let solution = graph.nodes().to_vec();
    // Same structure, new initial guess: the cache is reused and the answer is the same.
    for (i, p) in start.iter().enumerate() {
        graph.set_node(i, *p);
    }
    graph.optimize(&config).unwrap();
    assert_eq!(graph.cache.0.as_ref().map(|s| s.version), version);
    for (a, b) in graph.nodes().iter().zip(&solution) {
        assert!((a.translation() - b.translation()).norm() < 1e-9);
    }
    // A new node and edge: rebuilt, and the new node is placed by its edge.
    let last = graph.nodes().len() - 1;
    let n = graph.add_node(Pose2::new(0.0, 0.0, 0.0));
    let step = Pose2::new(1.0, 0.0, 0.0);
    let info = Matrix3::from_diagonal_element(100.0);
    graph
        .add_edge(edge(last, n, step, info, EdgeKind::Sequential))
        .unwrap();
    graph.optimize(&config).unwrap();
    assert_ne!(graph.cache.0.as_ref().map(|s| s.version), version);
    let expected = graph.nodes()[last] * step;
    assert!((graph.nodes()[n].translation() - expected.translation()).norm() < 1e-6);
    assert!(rms_position_error(&graph, &truth) < 0.2);
}

#[test]
fn components_without_a_fixed_node_are_anchored() {
    let mut graph = PoseGraph::new();
    for k in 0..6 {
        graph.add_node(Pose2::new(k as f64, 0.3 * k as f64, 0.0));
    }
    let info = Matrix3::identity();
    let step = Pose2::new(1.0, 0.0, 0.0);
    graph
        .add_edge(edge(0, 1, step, info, EdgeKind::Sequential))
        .unwrap();
    graph
        .add_edge(edge(3, 4, step, info, EdgeKind::Sequential))
        .unwrap();
    graph
        .add_edge(edge(4, 5, step, info, EdgeKind::Sequential))
        .unwrap();
    // Node 2 has no edge; nodes 3–5 are not connected to the fixed node 0.
    let start = graph.nodes().to_vec();
    let report = graph.optimize(&plain(Method::GaussNewton, 10)).unwrap();
    assert!(report.converged && report.final_chi2 < 1e-20, "{report:?}");
    assert_eq!(graph.nodes()[2], start[2]);
    assert_eq!(graph.nodes()[3], start[3]);
    let expected = start[3] * step * step;
    assert!((graph.nodes()[5].translation() - expected.translation()).norm() < 1e-9);
    // Everything fixed: nothing to do.
    for k in 0..6 {
        graph.set_fixed(k, true);
    }
    let report = graph.optimize(&SolverConfig::default()).unwrap();
    assert_eq!(report.iterations, 0);
    assert!(report.converged);
}

#[test]
fn fixed_nodes_stay_and_loop_edge_with_fixed_ends_is_constant() {
    let (mut graph, truth) = ring(5);
    graph.set_fixed(4, true);
    let before = graph.nodes()[4];
    graph
        .optimize(&plain(Method::LevenbergMarquardt, 50))
        .unwrap();
    assert_eq!(graph.nodes()[4], before);
    assert_eq!(graph.nodes()[0], truth[0]);
}
