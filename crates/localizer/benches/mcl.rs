//! One MCL filter update (predict + weight + resample) with 1000 particles × 180 beams per
//! sensor model, on the Intel Research Lab map (0.1 m, from the corrected log) when
//! `RAYPATH_DATA` has it, else on a synthetic 30 m × 20 m floor with walls and pillars.
//!
//! Models: likelihood field (AMCL, unnormalized), decay-rate with exact traversal and with
//! the optical-depth table, reflection with the table. All cores (rayon), likelihood
//! exponent as `LidarConfig::default()`.
//!
//! Run: `cargo bench -p raypath-localizer --bench mcl`.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_main};
use nalgebra::{Point2, Vector2};
use raypath_geometry::{Aabb2, Grid2, Pose2, Scan2};
use raypath_io::sequence::{LaserChoice, PlanarOptions, read_planar};
use raypath_localizer::init::GaussianInit;
use raypath_localizer::lidar::{LidarConfig, ModelKind, ModelSpec, Scan2Measurement};
use raypath_localizer::motion::{OdometryControl, OdometryMotionModel};
use raypath_localizer::{FilterConfig, ParticleFilter};
use raypath_sensor_models::{DenseStats2, MappingConfig};

const PARTICLES: usize = 1000;
const INTEL: &str = "carmen/corrected/intel-corrected.log.gz";

/// The Intel corrected scans, or `None` when absent.
fn intel() -> Option<Vec<(Pose2, Scan2)>> {
    let path = raypath_io::data::require(INTEL)?;
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    let frames = read_planar(&path, &options).ok()?;
    Some(
        frames
            .into_iter()
            .map(|f| (f.world_from_laser, f.scan))
            .collect(),
    )
}

/// A synthetic floor: outer walls, a corridor wall and pillars, scanned along a loop.
fn synthetic() -> Vec<(Pose2, Scan2)> {
    let segments: Vec<[f64; 4]> = {
        let mut s = vec![
            [0.0, 0.0, 30.0, 0.0],
            [30.0, 0.0, 30.0, 20.0],
            [30.0, 20.0, 0.0, 20.0],
            [0.0, 20.0, 0.0, 0.0],
            [5.0, 10.0, 25.0, 10.0],
        ];
        for k in 0..6 {
            let x = 4.0 + 4.0 * f64::from(k);
            s.push([x, 4.0, x + 0.5, 4.5]);
            s.push([x, 15.0, x + 0.5, 15.5]);
        }
        s
    };
    let cast = |o: Point2<f64>, a: f64| {
        let d = Vector2::new(a.cos(), a.sin());
        segments
            .iter()
            .filter_map(|[x0, y0, x1, y1]| {
                let e = Vector2::new(x1 - x0, y1 - y0);
                let den = d.x * e.y - d.y * e.x;
                if den.abs() < 1e-12 {
                    return None;
                }
                let w = Vector2::new(x0 - o.x, y0 - o.y);
                let t = (w.x * e.y - w.y * e.x) / den;
                let u = (w.x * d.y - w.y * d.x) / den;
                (t > 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
            })
            .fold(f64::INFINITY, f64::min)
    };
    (0..200)
        .map(|k| {
            let s = f64::from(k) / 200.0 * std::f64::consts::TAU;
            let pose = Pose2::new(15.0 + 11.0 * s.cos(), 10.0 + 7.0 * s.sin(), s + 1.6);
            let ranges = (0..180)
                .map(|i| {
                    let a = pose.theta() - std::f64::consts::FRAC_PI_2 + f64::from(i).to_radians();
                    cast(Point2::new(pose.x(), pose.y()), a).min(81.9)
                })
                .collect();
            let scan = Scan2 {
                angle_min_rad: -std::f64::consts::FRAC_PI_2,
                angle_increment_rad: 1f64.to_radians(),
                max_range_m: 81.9,
                ranges,
                intensities: None,
            };
            (pose, scan)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let (name, scans) = match intel() {
        Some(scans) => ("intel", scans),
        None => ("synthetic", synthetic()),
    };
    let mut bounds = Aabb2::empty();
    for (pose, scan) in &scans {
        bounds.extend(&Point2::new(pose.x(), pose.y()));
        for p in scan.points(*pose) {
            bounds.extend(&p);
        }
    }
    let margin = Vector2::new(1.0, 1.0);
    let Ok(grid) = Grid2::covering(&Aabb2::new(bounds.min - margin, bounds.max + margin), 0.1)
    else {
        return;
    };
    let mapping = MappingConfig::default();
    let mut stats = DenseStats2::new(grid);
    let refs: Vec<(Pose2, &Scan2)> = scans.iter().map(|(p, s)| (*p, s)).collect();
    stats.insert_scans_par(&refs, &mapping);

    let mut group = c.benchmark_group(format!("mcl_update_{name}_{PARTICLES}x180"));
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(4))
        .throughput(Throughput::Elements(1));
    let specs = [
        (
            "likelihood-field",
            ModelSpec::exact(ModelKind::LikelihoodField),
        ),
        ("decay-rate-exact", ModelSpec::exact(ModelKind::DecayRate)),
        (
            "decay-rate-tabulated",
            ModelSpec::tabulated(ModelKind::DecayRate),
        ),
        (
            "reflection-tabulated",
            ModelSpec::tabulated(ModelKind::Reflection),
        ),
    ];
    let motion = OdometryMotionModel::default();
    for (id, spec) in specs {
        let Ok(model) = spec.build(&stats, mapping.range) else {
            continue;
        };
        let Ok(measurement) =
            Scan2Measurement::new(model.as_ref(), Pose2::identity(), LidarConfig::default())
        else {
            continue;
        };
        let observations: Vec<_> = scans.iter().map(|(_, s)| measurement.prepare(s)).collect();
        group.bench_function(id, |b| {
            b.iter_custom(|iters| {
                let init = GaussianInit {
                    sigma_xy_m: 0.3,
                    sigma_rotation_rad: 0.05,
                    ..GaussianInit::new(scans[0].0)
                };
                let config = FilterConfig {
                    resample_ess_ratio: 1.0,
                    ..FilterConfig::default()
                };
                let Ok(mut filter) = ParticleFilter::from_initializer(&init, PARTICLES, config, 1)
                else {
                    return Duration::ZERO;
                };
                let started = Instant::now();
                for k in 0..iters as usize {
                    let i = k % (scans.len() - 1);
                    let control = OdometryControl::from_poses(&scans[i].0, &scans[i + 1].0);
                    filter.predict(&motion, &control);
                    if filter.update(&measurement, &observations[i + 1]).is_ok() {
                        filter.resample();
                    }
                    black_box(filter.len());
                }
                started.elapsed()
            });
        });
    }
    group.finish();
}

mod benches {
    criterion::criterion_group!(benches, super::bench);
}
criterion_main!(benches::benches);
