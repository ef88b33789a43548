//! Pose-graph optimisation time on synthetic Manhattan-world graphs (M3500-style: a random
//! walk on a unit grid with odometry edges and a loop closure at most revisits).
//!
//! - `pose_graph/m3500_style_optimize`: 3 500 nodes, a fresh graph each time (AMD ordering and
//!   symbolic factorisation included), the default solver (LM, DCS with annealing, ≤ 20
//!   iterations) from the odometry initial guess.
//! - `pose_graph/corridor_10k_lm_iteration`: 10 000 nodes walking long straight stretches in
//!   a 400 m × 400 m grid world, odometry edges to the last two nodes and a loop edge at each
//!   revisit (≈ 23 000 edges), one Levenberg–Marquardt iteration with the cached structure
//!   (the brief's aim: a few ms); the Cholesky factor fills in ≈ 2×.
//! - `pose_graph/grid_10k_lm_iteration`: 10 000 nodes in a 60 m × 60 m grid world (every cell
//!   visited ≈ 3 times, a loop edge at each revisit, ≈ 16 000 edges): a mesh-like graph whose
//!   Cholesky factor fills in ≈ 9×, the hard case.
//! - `pose_graph/grid_10k_cold_iteration`: the same with the structure (AMD ordering,
//!   symbolic factorisation) built first.
#![allow(missing_docs, clippy::unwrap_used)]

use std::collections::HashMap;
use std::f64::consts::FRAC_PI_2;
use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use raypath_geometry::Pose2;
use raypath_slam::graph::{Edge, EdgeKind, Method, PoseGraph, SolverConfig};

/// A synthetic Manhattan world.
struct World {
    /// Number of nodes (1 m steps).
    nodes: usize,
    /// The walk stays within `side × side` cells (it turns back at the walls).
    side: i64,
    /// Probability of a ±90° turn per step.
    turn_probability: f64,
    /// Probability of a loop edge when a cell visited at least 10 steps earlier is revisited
    /// (to its latest earlier visit).
    loop_probability: f64,
    /// Also an odometry edge to the node two steps back (as a front-end matching against the
    /// local submap gives).
    skip_edges: bool,
}

/// The graph of a random walk in `world`: measurements with σ = 5 cm, 10 mrad, the initial
/// guess chained from the odometry.
fn manhattan(world: &World, seed: u64) -> PoseGraph {
    let n = world.nodes;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, 1.0).unwrap();
    let (sigma_m, sigma_rad): (f64, f64) = (0.05, 0.01);
    let information = Matrix3::from_diagonal(&Vector3::new(
        sigma_m.powi(-2),
        sigma_m.powi(-2),
        sigma_rad.powi(-2),
    ));
    let noisy = |rng: &mut ChaCha8Rng, p: Pose2| {
        Pose2::new(
            p.x() + sigma_m * normal.sample(rng),
            p.y() + sigma_m * normal.sample(rng),
            p.theta() + sigma_rad * normal.sample(rng),
        )
    };
    let mut truth = vec![Pose2::identity()];
    let (mut cx, mut cy, mut heading) = (0i64, 0i64, 0i64);
    let mut visits: HashMap<(i64, i64), usize> = HashMap::from([((0, 0), 0)]);
    let mut graph = PoseGraph::new();
    graph.add_node(truth[0]);
    let mut guess = truth[0];
    let mut edges = Vec::new();
    for k in 1..n {
        let mut turn = if rng.random_bool(world.turn_probability) {
            if rng.random_bool(0.5) { 1 } else { -1 }
        } else {
            0
        };
        let step = |h: i64| [(1, 0), (0, 1), (-1, 0), (0, -1)][h.rem_euclid(4) as usize];
        let (dx, dy) = step(heading + turn);
        if (cx + dx).abs() > world.side / 2 || (cy + dy).abs() > world.side / 2 {
            turn = 2;
        }
        heading += turn;
        let (dx, dy) = step(heading);
        cx += dx;
        cy += dy;
        let pose = Pose2::new(
            cx as f64,
            cy as f64,
            heading.rem_euclid(4) as f64 * FRAC_PI_2,
        );
        let z = noisy(&mut rng, truth[k - 1].inverse() * pose);
        truth.push(pose);
        guess = guess * z;
        graph.add_node(guess);
        edges.push((k - 1, k, z, EdgeKind::Sequential));
        if world.skip_edges && k >= 2 {
            let z = noisy(&mut rng, truth[k - 2].inverse() * pose);
            edges.push((k - 2, k, z, EdgeKind::Sequential));
        }
        if let Some(&m) = visits.get(&(cx, cy))
            && k - m >= 10
            && rng.random_bool(world.loop_probability)
        {
            let z = noisy(&mut rng, truth[m].inverse() * pose);
            edges.push((m, k, z, EdgeKind::Loop));
        }
        visits.insert((cx, cy), k);
    }
    for (from, to, measurement, kind) in edges {
        let edge = Edge {
            from,
            to,
            measurement,
            information,
            kind,
        };
        graph.add_edge(edge).unwrap();
    }
    graph
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("pose_graph");
    group.sample_size(20);

    let m3500 = manhattan(
        &World {
            nodes: 3_500,
            side: 40,
            turn_probability: 0.3,
            loop_probability: 0.6,
            skip_edges: false,
        },
        1,
    );
    eprintln!(
        "m3500-style: {} nodes, {} edges",
        m3500.nodes().len(),
        m3500.edges().len()
    );
    let config = SolverConfig::default();
    let report = m3500.clone().optimize(&config).unwrap();
    eprintln!("m3500-style default solve: {report:?}");
    group.bench_function("m3500_style_optimize", |b| {
        b.iter_batched(
            || m3500.clone(),
            |mut graph| black_box(graph.optimize(&config).unwrap()),
            BatchSize::LargeInput,
        )
    });

    let corridor = manhattan(
        &World {
            nodes: 10_000,
            side: 400,
            turn_probability: 0.05,
            loop_probability: 1.0,
            skip_edges: true,
        },
        3,
    );
    let grid = manhattan(
        &World {
            nodes: 10_000,
            side: 60,
            turn_probability: 0.3,
            loop_probability: 1.0,
            skip_edges: false,
        },
        2,
    );
    let one = SolverConfig {
        method: Method::LevenbergMarquardt,
        max_iterations: 1,
        annealing: None,
        ..SolverConfig::default()
    };
    for (name, graph) in [
        ("corridor_10k_lm_iteration", &corridor),
        ("grid_10k_lm_iteration", &grid),
    ] {
        eprintln!(
            "{name}: {} nodes, {} edges",
            graph.nodes().len(),
            graph.edges().len()
        );
        let start = graph.nodes().to_vec();
        let mut warm = graph.clone();
        warm.optimize(&one).unwrap();
        group.bench_function(name, |b| {
            b.iter(|| {
                for (i, p) in start.iter().enumerate() {
                    warm.set_node(i, *p);
                }
                black_box(warm.optimize(&one).unwrap())
            })
        });
    }
    group.bench_function("grid_10k_cold_iteration", |b| {
        b.iter_batched(
            || grid.clone(),
            |mut graph| black_box(graph.optimize(&one).unwrap()),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
