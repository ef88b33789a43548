//! Simulated 2-D data with intensities for the Khan ch. 3 experiments: calibration samples of
//! a reference surface and three test surfaces, and the failure-case room (8.5 m × 5.5 m,
//! ±60° field of view) with reflectivity panels on its walls.
//!
//! Intensities come from `raypath_sim::indoor::IntensityModel` (reflectivity × near-range
//! drop × non-Lambertian, range-dependent angular fall-off, relative and absolute noise).

use std::f64::consts::PI;

use anyhow::{Context, Result};
use nalgebra::Point2;
use raypath_geometry::{Pose2, Scan2, wrap_angle};
use raypath_reflectivity::lut::CalibrationSample;
use raypath_sim::indoor::IntensityModel;
use raypath_sim::rng::{SimRng, stream};
use raypath_sim::scene2::{Scene2, SceneBuilder2, Surface};

/// The reflectivity of the reference surface (white paper; ρ = 1 would saturate the
/// simulated receiver at its near-range peak).
pub const REFERENCE_REFLECTIVITY: f64 = 0.8;

/// SplitMix64: uniform and Gaussian draws for geometry (the intensity noise uses the
/// simulator's own streams).
pub struct Draw(u64);

impl Draw {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u = self.uniform(1e-12, 1.0);
        let v = self.uniform(0.0, 1.0);
        (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
    }
}

/// A calibration or test observation: true range and incidence, estimated incidence (with
/// normal noise), intensity.
pub fn observe(
    model: &IntensityModel,
    reflectivity: f64,
    range_m: f64,
    incidence_rad: f64,
    normal_sigma_rad: f64,
    draw: &mut Draw,
    rng: &mut SimRng,
) -> CalibrationSample {
    let intensity = model.sample(reflectivity, range_m, incidence_rad, rng);
    let alpha = (incidence_rad + normal_sigma_rad * draw.normal()).clamp(0.0, PI / 2.0);
    CalibrationSample {
        range_m,
        incidence_rad: alpha,
        intensity,
    }
}

/// Reference-surface samples over r ∈ [0.2, 19] m and α up to 80° near, 60° far (Khan
/// §3.3.1: the covered α range shrinks with distance).
pub fn reference_samples(model: &IntensityModel, n: usize, seed: u64) -> Vec<CalibrationSample> {
    let mut draw = Draw::new(seed);
    let mut rng = stream(seed, 1, 0);
    (0..n)
        .map(|_| {
            let r = draw.uniform(0.2, 19.0);
            let amax = (80.0 - 20.0 * (r - 0.2) / 18.8).to_radians();
            let a = draw.uniform(0.0, amax);
            observe(
                model,
                REFERENCE_REFLECTIVITY,
                r,
                a,
                1f64.to_radians(),
                &mut draw,
                &mut rng,
            )
        })
        .collect()
}

/// The three test surfaces of Khan Fig. 3.4 (reflectivity, range interval, angle interval):
/// surface 1 varies in range and angle, surfaces 2 and 3 mostly in angle.
pub const SURFACES: [(f64, [f64; 2], [f64; 2]); 3] = [
    (0.50, [1.0, 12.0], [0.0, 60.0]),
    (0.35, [2.5, 3.5], [0.0, 70.0]),
    (0.25, [2.5, 3.5], [0.0, 30.0]),
];

/// `n` observations of each test surface.
pub fn surface_samples(model: &IntensityModel, n: usize, seed: u64) -> Vec<Vec<CalibrationSample>> {
    SURFACES
        .iter()
        .enumerate()
        .map(|(k, (rho, r, a))| {
            let mut draw = Draw::new(seed + 100 + k as u64);
            let mut rng = stream(seed, 2, k as u64);
            (0..n)
                .map(|_| {
                    let range = draw.uniform(r[0], r[1]);
                    let alpha = draw.uniform(a[0], a[1]).to_radians();
                    observe(
                        model,
                        *rho,
                        range,
                        alpha,
                        1f64.to_radians(),
                        &mut draw,
                        &mut rng,
                    )
                })
                .collect()
        })
        .collect()
}

/// The failure-case room: walls of [0, 8.5] × [0, 5.5] m made of panels 0.3–1.2 m long with
/// reflectivities drawn from [0.1, 0.9].
pub fn room(seed: u64) -> Result<Scene2> {
    let mut draw = Draw::new(seed);
    let mut builder = SceneBuilder2::new();
    let corners: [[f64; 2]; 5] = [[0.0, 0.0], [8.5, 0.0], [8.5, 5.5], [0.0, 5.5], [0.0, 0.0]];
    let mut label = 1;
    for w in corners.windows(2) {
        let (a, b) = (w[0], w[1]);
        let length = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let mut s = 0.0;
        while s < length {
            let e = (s + draw.uniform(0.3, 1.2)).min(length);
            let reflectivity = draw.uniform(0.1, 0.9) as f32;
            let id = builder.add_surface(Surface {
                label,
                reflectivity,
            });
            label += 1;
            let p = |t: f64| {
                Point2::new(
                    a[0] + (b[0] - a[0]) * t / length,
                    a[1] + (b[1] - a[1]) * t / length,
                )
            };
            builder.add_segment(p(s), p(e), id);
            s = e;
        }
    }
    builder.build().context("building the failure-case room")
}

/// The robot's path: from the room centre to stops 0.7 m in front of the middle of each
/// wall, where it turns to face the wall (only that wall is in view with ±60°: one
/// direction unobservable by geometry), then turns towards the next stop; `laps` times
/// around. Sensor poses at `rate_hz`, 0.4 m/s and 0.6 rad/s.
pub fn path(laps: usize, rate_hz: f64) -> Vec<Pose2> {
    let (v, w, dt) = (0.4, 0.6, 1.0 / rate_hz);
    let mut poses = vec![Pose2::new(4.25, 2.75, 0.0)];
    let stops = [
        ([7.8, 2.75], 0.0),
        ([4.25, 4.8], PI / 2.0),
        ([0.7, 2.75], PI),
        ([4.25, 0.7], -PI / 2.0),
    ];
    let last = |p: &Vec<Pose2>| *p.last().unwrap_or(&Pose2::identity());
    let turn_to = |poses: &mut Vec<Pose2>, heading: f64| {
        let start = last(poses);
        let delta = wrap_angle(heading - start.theta());
        let steps = (delta.abs() / (w * dt)).ceil() as usize;
        for k in 1..=steps {
            poses.push(Pose2::new(
                start.x(),
                start.y(),
                start.theta() + delta * k as f64 / steps as f64,
            ));
        }
    };
    for _ in 0..laps {
        for (stop, facing) in stops {
            let start = last(&poses);
            let (dx, dy) = (stop[0] - start.x(), stop[1] - start.y());
            turn_to(&mut poses, dy.atan2(dx));
            let heading = last(&poses).theta();
            let steps = ((dx * dx + dy * dy).sqrt() / (v * dt)).ceil() as usize;
            for k in 1..=steps {
                let t = k as f64 / steps as f64;
                poses.push(Pose2::new(start.x() + dx * t, start.y() + dy * t, heading));
            }
            turn_to(&mut poses, facing);
            for _ in 0..(rate_hz as usize) {
                poses.push(last(&poses)); // a one-second pause facing the wall
            }
        }
    }
    poses
}

/// A scan of `scene` from `pose` with `beams` beams over ±`half_fov_rad`, σ = 1 cm range
/// noise, intensities from `model`.
pub fn scan(
    scene: &Scene2,
    pose: &Pose2,
    beams: usize,
    half_fov_rad: f64,
    model: &IntensityModel,
    draw: &mut Draw,
    rng: &mut SimRng,
) -> Scan2 {
    let increment = 2.0 * half_fov_rad / (beams - 1) as f64;
    let max_range_m = 30.0;
    let mut ranges = Vec::with_capacity(beams);
    let mut intensities = Vec::with_capacity(beams);
    let origin = Point2::new(pose.x(), pose.y());
    for i in 0..beams {
        let a = pose.theta() - half_fov_rad + i as f64 * increment;
        match scene.cast_angle(&origin, a, max_range_m) {
            Some(hit) => {
                let dir = nalgebra::Vector2::new(a.cos(), a.sin());
                let alpha = dir.dot(&hit.normal).abs().clamp(0.0, 1.0).acos();
                let rho = scene
                    .surface(hit.surface)
                    .map_or(0.5, |s| f64::from(s.reflectivity));
                ranges.push(hit.range_m + 0.01 * draw.normal());
                intensities.push(model.sample(rho, hit.range_m, alpha, rng));
            }
            None => {
                ranges.push(max_range_m + 10.0);
                intensities.push(0.0);
            }
        }
    }
    Scan2 {
        angle_min_rad: -half_fov_rad,
        angle_increment_rad: increment,
        max_range_m,
        ranges,
        intensities: Some(intensities),
    }
}
