//! The polyline benchmark of Schaefer (2020), chapter 10: random polygons seen by a 360° scanner
//! at their centre, with noisy ray angles and ranges and the ground-truth polygon kept.
//!
//! The protocol follows the thesis (§10.5, the simulated scans) and its reference
//! implementation (`polygon.rand(c, s)` of `acschaefer/ple`):
//!
//! * the number of vertices `n` is drawn uniformly from {3, 4, 5, 6, 12, 36, 180};
//! * vertex angles are `U + linspace(0, 2π(1 − 1/n), n)` with `U ~ U(0, 1)` (radians);
//! * vertex radii are `s·(Poisson(λ) + 1)/(λ + 1)` with `λ = n²/5` and the scale
//!   `s = 5 + 5·U(0, 1)` metres — the polygon is star-shaped around the sensor at the origin, so
//!   every ray hits it exactly once;
//! * each of the 360 rays gets Gaussian angle noise (σ = 0.2°), is intersected exactly with
//!   the polygon along its noisy direction, and its range gets Gaussian noise (σ = 0.03 m);
//!   the scan records the nominal angles, as a real scanner does.
//!
//! **Erratum.** The reference implementation behind the thesis' results lays the rays out as
//! `linspace(−180°, 180°, 360)`, which makes the first and the last ray coincide (−180° =
//! +180°) and spaces the others 360°/359 apart. By default the rays are spaced 1° over
//! [−180°, 180°) instead ([`AzimuthLayout::HalfOpen`]); [`AzimuthLayout::ThesisLinspace`]
//! reproduces that layout.
//!
//! **Output.** One CARMEN log `polygons.log` of `ROBOTLASER1` messages (they state the start
//! angle, field of view and resolution, so a 360° scan is unambiguous), one per polygon, with
//! laser and robot pose at the origin and timestamps 1 s apart; and `polygons.json` with the
//! configuration, the seed and, per scan, the ground-truth vertices (counter-clockwise).
//! Every ray hits its polygon, so the log has no no-returns: read it with
//! `NoReturnRange::Fixed(max_range_m)` (the stated maximum range). The reader's default
//! inference looks for a repeated top reading and can mistake the ranges of a near-circular
//! 180-gon, many of which fall into the same centimetre, for a no-return code.

use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};

use nalgebra::Point2;
use rand::Rng;
use rand_distr::{Distribution, Normal, Poisson};
use rayon::prelude::*;
use raypath_geometry::{Pose2, Scan2};
use raypath_io::carmen::{CarmenWriter, LaserKind, LaserMessage, RobotLaserInfo, Velocities};
use serde::Serialize;

use crate::dataset::{GeneratedSet, Progress};
use crate::error::{Result, SimError};
use crate::out2d;
use crate::rng::stream;
use crate::scene2::{SceneBuilder2, Surface};

/// Random-stream domain of the polygon scans.
const DOMAIN: u64 = 0x706f_6c79_676f_6e73; // "polygons"

/// How the rays of a scan are spread over the full circle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum AzimuthLayout {
    /// Ray `i` at −180° + i·360°/n: equally spaced, none repeated (default).
    #[default]
    HalfOpen,
    /// The layout of the thesis' experiments (its reference implementation)
    /// `linspace(−180°, 180°, n)`: ray `i` at −180° + i·360°/(n − 1), the first and the last
    /// ray coincide.
    ThesisLinspace,
}

impl AzimuthLayout {
    /// `(angle_min_rad, angle_increment_rad)` of `rays` rays.
    pub fn layout(self, rays: usize) -> (f64, f64) {
        let n = rays.max(2) as f64;
        match self {
            AzimuthLayout::HalfOpen => (-PI, TAU / n),
            AzimuthLayout::ThesisLinspace => (-PI, TAU / (n - 1.0)),
        }
    }
}

/// Configuration of the polygon benchmark.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PolygonsConfig {
    /// Number of scans (one random polygon each). Thesis: 260.
    pub scans: usize,
    /// The vertex counts `n` is drawn from, uniformly. Thesis: {3, 4, 5, 6, 12, 36, 180}.
    pub vertex_counts: Vec<usize>,
    /// Smallest polygon scale `s` in metres (thesis: 5).
    pub scale_min_m: f64,
    /// Width of the uniform scale distribution in metres (thesis: 5, so `s ~ U(5, 10)`).
    pub scale_span_m: f64,
    /// Rays per scan (thesis: 360).
    pub rays: usize,
    /// How the rays are spread (default: 1° steps over [−180°, 180°), see the erratum).
    pub azimuths: AzimuthLayout,
    /// Standard deviation of the ray-angle noise in radians (thesis: 0.2°).
    pub sigma_angle_rad: f64,
    /// Standard deviation of the range noise in metres (thesis: 0.03 m).
    pub sigma_range_m: f64,
    /// Maximum range stated in the `ROBOTLASER1` lines, metres. No polygon ray comes near it.
    pub max_range_m: f64,
    /// UNIX time of the first scan in seconds (scans are 1 s apart).
    pub start_unix_secs: f64,
}

impl Default for PolygonsConfig {
    fn default() -> Self {
        Self {
            scans: 260,
            vertex_counts: vec![3, 4, 5, 6, 12, 36, 180],
            scale_min_m: 5.0,
            scale_span_m: 5.0,
            rays: 360,
            azimuths: AzimuthLayout::HalfOpen,
            sigma_angle_rad: 0.2f64.to_radians(),
            sigma_range_m: 0.03,
            max_range_m: 81.9,
            start_unix_secs: 1_262_304_000.0,
        }
    }
}

impl PolygonsConfig {
    /// The quick set: the full protocol (260 small scans generate in milliseconds).
    pub fn quick() -> Self {
        Self::default()
    }

    fn validate(&self) -> Result<()> {
        let bad =
            |name: &'static str, reason: String| Err(SimError::InvalidParameter { name, reason });
        if self.scans == 0 {
            return bad("scans", "at least one scan".into());
        }
        if self.rays < 2 {
            return bad("rays", format!("at least 2 rays, got {}", self.rays));
        }
        if self.vertex_counts.is_empty() || self.vertex_counts.iter().any(|&n| n < 3) {
            return bad(
                "vertex_counts",
                format!("need vertex counts ≥ 3, got {:?}", self.vertex_counts),
            );
        }
        if !(self.scale_min_m > 0.0 && self.scale_span_m >= 0.0 && self.scale_span_m.is_finite()) {
            return bad(
                "scale_min_m",
                format!(
                    "scale must be positive, got {} + U·{}",
                    self.scale_min_m, self.scale_span_m
                ),
            );
        }
        for (name, sigma) in [
            ("sigma_angle_rad", self.sigma_angle_rad),
            ("sigma_range_m", self.sigma_range_m),
        ] {
            if !(sigma.is_finite() && sigma >= 0.0) {
                return bad(name, format!("must be finite and ≥ 0, got {sigma}"));
            }
        }
        if !(self.max_range_m.is_finite() && self.max_range_m > 0.0) {
            return bad(
                "max_range_m",
                format!("must be positive, got {}", self.max_range_m),
            );
        }
        Ok(())
    }
}

/// One ground-truth polygon and the parameters it was drawn with.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GroundTruthPolygon {
    /// Index of the scan (0-based, the order of the log).
    pub scan: usize,
    /// Number of vertices `n`.
    pub n: usize,
    /// The scale `s` in metres.
    pub scale_m: f64,
    /// The angle offset `U` of the first vertex in radians.
    pub angle_offset_rad: f64,
    /// Vertices `[x, y]` in metres in the sensor frame, counter-clockwise.
    pub vertices: Vec<[f64; 2]>,
    /// Polygon area in m² (shoelace formula).
    pub area_m2: f64,
}

/// One simulated scan with its polygon.
#[derive(Clone, Debug, PartialEq)]
pub struct PolygonScan {
    /// The ground truth.
    pub polygon: GroundTruthPolygon,
    /// The noisy scan (nominal angles, noisy ranges).
    pub scan: Scan2,
    /// The exact range along each ray's noisy direction (before range noise), metres.
    pub true_ranges_m: Vec<f64>,
}

/// Draws the polygon of scan `index` (the thesis' `polygon.rand`).
pub fn random_polygon(
    config: &PolygonsConfig,
    rng: &mut impl Rng,
    index: usize,
) -> GroundTruthPolygon {
    let k = rng.random_range(0..config.vertex_counts.len());
    let n = config.vertex_counts.get(k).copied().unwrap_or(3);
    let offset: f64 = rng.random();
    let scale_m = config.scale_min_m + config.scale_span_m * rng.random::<f64>();
    let lambda = (n * n) as f64 / 5.0;
    let poisson = Poisson::new(lambda).ok();
    let vertices: Vec<[f64; 2]> = (0..n)
        .map(|j| {
            // linspace(0, 2π(1 − 1/n), n) is 2πj/n.
            let angle = offset + TAU * j as f64 / n as f64;
            let draw = poisson.as_ref().map_or(lambda, |p| p.sample(rng));
            let radius = scale_m * (draw + 1.0) / (lambda + 1.0);
            [radius * angle.cos(), radius * angle.sin()]
        })
        .collect();
    let area_m2 = 0.5
        * vertices
            .iter()
            .zip(vertices.iter().cycle().skip(1))
            .map(|(a, b)| a[0] * b[1] - b[0] * a[1])
            .sum::<f64>();
    GroundTruthPolygon {
        scan: index,
        n,
        scale_m,
        angle_offset_rad: offset,
        vertices,
        area_m2,
    }
}

/// Simulates scan `index` under `seed`: the polygon and the noisy 360° scan of it.
pub fn simulate_scan(config: &PolygonsConfig, seed: u64, index: usize) -> Result<PolygonScan> {
    config.validate()?;
    let mut rng = stream(seed, DOMAIN, index as u64);
    let polygon = random_polygon(config, &mut rng, index);
    let mut builder = SceneBuilder2::new();
    let surface = builder.add_surface(Surface {
        label: 1,
        reflectivity: 1.0,
    });
    let corners: Vec<Point2<f64>> = polygon
        .vertices
        .iter()
        .map(|v| Point2::new(v[0], v[1]))
        .collect();
    builder.add_polygon(&corners, surface);
    let scene = builder.build()?;
    let angle_noise =
        Normal::new(0.0, config.sigma_angle_rad).map_err(|e| SimError::InvalidParameter {
            name: "sigma_angle_rad",
            reason: e.to_string(),
        })?;
    let range_noise =
        Normal::new(0.0, config.sigma_range_m).map_err(|e| SimError::InvalidParameter {
            name: "sigma_range_m",
            reason: e.to_string(),
        })?;
    let (angle_min_rad, angle_increment_rad) = config.azimuths.layout(config.rays);
    let origin = Point2::origin();
    let mut ranges = Vec::with_capacity(config.rays);
    let mut true_ranges_m = Vec::with_capacity(config.rays);
    for i in 0..config.rays {
        let nominal = angle_min_rad + i as f64 * angle_increment_rad;
        let angle = nominal + angle_noise.sample(&mut rng);
        // The sensor is strictly inside the star-shaped polygon: every ray hits it.
        let hit =
            scene
                .cast_angle(&origin, angle, f64::MAX)
                .ok_or_else(|| SimError::InvalidScene {
                    reason: format!("ray {i} of polygon {index} left the polygon"),
                })?;
        true_ranges_m.push(hit.range_m);
        ranges.push(hit.range_m + range_noise.sample(&mut rng));
    }
    Ok(PolygonScan {
        polygon,
        scan: Scan2 {
            angle_min_rad,
            angle_increment_rad,
            max_range_m: config.max_range_m,
            ranges,
            intensities: None,
        },
        true_ranges_m,
    })
}

/// What `polygons.json` holds.
#[derive(Serialize)]
struct GroundTruthFile<'a> {
    generator: &'static str,
    seed: u64,
    config: &'a PolygonsConfig,
    log: &'static str,
    polygons: Vec<GroundTruthPolygon>,
}

/// Generates the benchmark under `out_dir`: `polygons.log` and `polygons.json`.
pub fn generate(
    config: &PolygonsConfig,
    seed: u64,
    out_dir: &Path,
    progress: Progress,
) -> Result<GeneratedSet> {
    config.validate()?;
    out2d::create_dir(out_dir)?;
    let counter = out2d::Counter::new(config.scans as u64, progress);
    let scans: Vec<PolygonScan> = (0..config.scans)
        .into_par_iter()
        .map(|k| {
            let scan = simulate_scan(config, seed, k);
            counter.tick();
            scan
        })
        .collect::<Result<_>>()?;

    let log_name = "polygons.log";
    let log_path = out_dir.join(log_name);
    let mut writer = CarmenWriter::new(Vec::new(), &log_path);
    writer.header().map_err(out2d::io_error)?;
    writer
        .comment(
            "raypath-sim polygon benchmark (Schaefer 2020, ch. 10); ground truth in polygons.json",
        )
        .map_err(out2d::io_error)?;
    writer
        .param("robot_front_laser_max", &format!("{}", config.max_range_m))
        .map_err(out2d::io_error)?;
    for (k, s) in scans.iter().enumerate() {
        let n = s.scan.ranges.len();
        let stamp = k as f64;
        writer
            .laser(&LaserMessage {
                kind: LaserKind::RobotLaser1,
                scan: s.scan.clone(),
                world_from_laser: Pose2::identity(),
                world_from_robot: Pose2::identity(),
                velocities: Some(Velocities {
                    tv_mps: 0.0,
                    rv_radps: 0.0,
                }),
                robot_laser: Some(RobotLaserInfo {
                    laser_type: 0,
                    fov_rad: (n.saturating_sub(1)) as f64 * s.scan.angle_increment_rad,
                    stated_max_range_m: config.max_range_m,
                    accuracy_m: config.sigma_range_m,
                    remission_mode: 0,
                    forward_safety_m: 0.0,
                    side_safety_m: 0.0,
                    turn_axis: 0.0,
                }),
                ipc_timestamp_secs: config.start_unix_secs + stamp,
                hostname: "raypath-sim".into(),
                logger_timestamp_secs: stamp,
                line: 0,
            })
            .map_err(out2d::io_error)?;
    }
    let bytes = writer.finish().map_err(out2d::io_error)?;
    out2d::write_file(&log_path, &bytes)?;

    let json_name = "polygons.json";
    let stats = statistics(config, &scans);
    out2d::write_json(
        &out_dir.join(json_name),
        &GroundTruthFile {
            generator: "raypath-sim polygons",
            seed,
            config,
            log: log_name,
            polygons: scans.iter().map(|s| s.polygon.clone()).collect(),
        },
    )?;
    Ok(GeneratedSet {
        name: "polygons".into(),
        description: "Random polygons seen by a 360° scanner at the origin (Schaefer 2020 ch. 10 \
                      polyline benchmark), as a CARMEN ROBOTLASER1 log with ground-truth polygons \
                      in JSON"
            .into(),
        files: out2d::sorted(vec![PathBuf::from(log_name), PathBuf::from(json_name)]),
        stats,
    })
}

fn statistics(config: &PolygonsConfig, scans: &[PolygonScan]) -> serde_json::Value {
    let mut by_n = std::collections::BTreeMap::new();
    for s in scans {
        *by_n.entry(s.polygon.n.to_string()).or_insert(0u64) += 1;
    }
    let ranges = scans.iter().flat_map(|s| s.scan.ranges.iter().copied());
    let (mut min, mut max, mut sum, mut count) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0u64);
    for r in ranges {
        min = min.min(r);
        max = max.max(r);
        sum += r;
        count += 1;
    }
    let residuals: Vec<f64> = scans
        .iter()
        .flat_map(|s| {
            s.scan
                .ranges
                .iter()
                .zip(&s.true_ranges_m)
                .map(|(r, t)| r - t)
        })
        .collect();
    let residual_std =
        (residuals.iter().map(|d| d * d).sum::<f64>() / residuals.len().max(1) as f64).sqrt();
    let areas: Vec<f64> = scans.iter().map(|s| s.polygon.area_m2).collect();
    serde_json::json!({
        "scans": scans.len(),
        "rays_per_scan": config.rays,
        "azimuths": config.azimuths,
        "scans_per_vertex_count": by_n,
        "range_m": { "min": min, "mean": sum / count.max(1) as f64, "max": max },
        "range_noise_std_m": residual_std,
        "area_m2": {
            "min": areas.iter().copied().fold(f64::INFINITY, f64::min),
            "mean": areas.iter().sum::<f64>() / areas.len().max(1) as f64,
            "max": areas.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        },
    })
}
