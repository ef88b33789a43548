//! The particle filter converges from the initial spread on a known map (Schaefer 2020,
//! §12.4.3).

use nalgebra::Point2;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::Pose2;
use raypath_poles::{FilterParams, Pole, PoleFilter};

fn pole(x: f64, y: f64) -> Pole {
    Pole {
        x,
        y,
        z_start: 0.0,
        z_end: 3.0,
        width: 0.2,
        score: 0.8,
    }
}

/// Poles on both sides of a street along x, irregularly spaced.
fn street_map(rng: &mut ChaCha8Rng) -> Vec<Pole> {
    let mut poles = Vec::new();
    let mut x = -20.0;
    while x < 220.0 {
        let side = if rng.random::<bool>() { 1.0 } else { -1.0 };
        poles.push(pole(x, side * (5.0 + rng.random::<f64>() * 2.0)));
        x += 6.0 + rng.random::<f64>() * 10.0;
    }
    poles
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    #[test]
    fn the_filter_converges_from_the_initial_spread(seed in 0u64..1000) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let map = street_map(&mut rng);
        let params = FilterParams { particles: 2000, ..FilterParams::kitti() };
        // True start at the origin; the filter's prior is centred off by up to 2 m / 4°.
        let offset = Pose2::new(
            rng.random_range(-1.4..1.4),
            rng.random_range(-1.4..1.4),
            rng.random_range(-4f64..4.0).to_radians(),
        );
        let mut filter = PoleFilter::new(&map, params, offset, seed).expect("filter");
        let mut truth = Pose2::identity();
        let step = Pose2::new(1.0, 0.0, 0.0);
        let mut errors = Vec::new();
        for k in 0..150 {
            truth = truth * step;
            // Odometry with 2 % noise, stated to the filter.
            let noisy = Pose2::new(
                1.0 + 0.02 * rng.random_range(-1.0..1.0),
                0.02 * rng.random_range(-1.0..1.0),
                0.002 * rng.random_range(-1.0..1.0),
            );
            filter.predict(&noisy, [0.02, 0.02, 0.002]).expect("predict");
            if k % 3 == 0 {
                let robot_from_world = truth.inverse();
                let mut seen: Vec<Point2<f64>> = map
                    .iter()
                    .map(|p| robot_from_world.transform_point(&Point2::new(p.x, p.y)))
                    .filter(|p| p.coords.norm() < 15.0)
                    .map(|p| p + nalgebra::Vector2::new(rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05)))
                    .collect();
                // A pole that is not in the map.
                seen.push(Point2::new(rng.random_range(-10.0..10.0), 6.0));
                filter.update(&seen).expect("update");
            }
            let e = truth.inverse() * filter.estimate();
            errors.push((e.x().hypot(e.y()), e.theta().abs()));
        }
        let tail = &errors[100..];
        let mean_pos = tail.iter().map(|e| e.0).sum::<f64>() / tail.len() as f64;
        let max_heading = tail.iter().map(|e| e.1).fold(0.0, f64::max);
        prop_assert!(mean_pos < 0.25, "mean position error {} m after 100 m", mean_pos);
        prop_assert!(max_heading < 1.5f64.to_radians(), "heading error {} rad", max_heading);
    }
}
