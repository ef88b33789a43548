//! Building the statistics once and scoring every model variant on the test scans.

use std::time::Instant;

use nalgebra::{Point2, Point3, Vector2, Vector3};
use rayon::prelude::*;
use raypath_geometry::{Aabb2, Aabb3, Grid2, Grid3, Pose2, Pose3, Range, Ray3, Scan2};
use serde::{Deserialize, Serialize};

use crate::dimension::Dimension;
use crate::models::SensorModel;
use crate::scoring::metrics::{Divergences, disc_offsets, divergences};
use crate::scoring::{ScoringConfig, variants};
use crate::stats::DenseStats;
use crate::{MappingConfig, Reading, ScanLikelihood, SensorModelError, SensorRange};

/// The scores of one model variant over all test scans.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScoreRow {
    /// Model name (one of [`crate::scoring::MODEL_NAMES`]).
    pub model: String,
    /// True for the full-posterior (ch. 8) version of the model.
    pub posterior: bool,
    /// `D'(g‖h) = −Σ ln p(z_j | s_j, m)` over all scored rays at the true poses (Eq. 7.28),
    /// in nats.
    pub neg_log_likelihood: f64,
    /// The inverse KL `D(h‖g)` (Eq. 7.29) averaged over the test scans, in nats.
    pub inverse_kl: f64,
    /// The ground-truth KL `D_KL(p_gt‖p)` (Eq. 8.24) summed over the test scans, in nats.
    pub kl_ground_truth: f64,
    /// Ray-likelihood evaluations made for this row (`rays · (M + 1)`).
    pub evaluations: u64,
    /// Wall-clock time of this row's evaluations in seconds.
    pub seconds: f64,
}

impl ScoreRow {
    /// Ray-likelihood evaluations per second of wall-clock time.
    pub fn evaluations_per_second(&self) -> f64 {
        self.evaluations as f64 / self.seconds.max(1e-9)
    }
}

/// Everything one scoring run produced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScoreReport {
    /// One row per model variant, in the order of [`crate::scoring::MODEL_NAMES`] with the
    /// ML version before the posterior version.
    pub rows: Vec<ScoreRow>,
    /// Scans that built the map.
    pub mapping_scans: usize,
    /// Rays inserted into the map.
    pub mapping_rays: u64,
    /// Wall-clock time of map building (statistics only) in seconds.
    pub mapping_seconds: f64,
    /// Scans scored.
    pub test_scans: usize,
    /// Rays scored per pose (after `beam_step`), summed over the test scans.
    pub test_rays: u64,
    /// Cells per axis of the map (`[nx, ny, 1]` in 2-D).
    pub grid_dims: [usize; 3],
    /// Cell edge in metres.
    pub resolution_m: f64,
    /// Maximum range `r_max` the models used, in metres.
    pub max_range_m: f64,
}

impl ScoreReport {
    /// The row of `model` (ML or posterior version).
    pub fn row(&self, model: &str, posterior: bool) -> Option<&ScoreRow> {
        self.rows
            .iter()
            .find(|r| r.model == model && r.posterior == posterior)
    }

    /// Map-building speed in rays per second.
    pub fn mapping_rays_per_second(&self) -> f64 {
        self.mapping_rays as f64 / self.mapping_seconds.max(1e-9)
    }
}

/// Indices of the test scans kept: at most `max` evenly spaced ones.
fn thin(count: usize, max: Option<usize>) -> Vec<usize> {
    let step = max.map_or(1, |m| count.div_ceil(m.max(1)).max(1));
    (0..count).step_by(step).collect()
}

fn invalid(name: &'static str, reason: String) -> SensorModelError {
    SensorModelError::InvalidParameter { name, reason }
}

/// Scores every model variant of a 2-D log split by `config.split` (see [`score_planar`]).
/// `scans` are `(world_from_laser, scan)` in log order, with the reference (corrected)
/// poses.
pub fn score_log(
    scans: &[(Pose2, Scan2)],
    config: &ScoringConfig,
) -> Result<ScoreReport, SensorModelError> {
    let n = scans.len();
    let (test, map): (Vec<_>, Vec<_>) = scans
        .iter()
        .enumerate()
        .map(|(i, (pose, scan))| (i, (*pose, scan)))
        .partition(|(i, _)| config.split.is_test(*i, n));
    let map: Vec<(Pose2, &Scan2)> = map.into_iter().map(|(_, s)| s).collect();
    let test: Vec<(Pose2, &Scan2)> = test.into_iter().map(|(_, s)| s).collect();
    score_planar(&map, &test, config)
}

/// Table 7.3 / 8.2 / 8.3 on 2-D data: builds the statistics of the `map` scans once (exact
/// traversal, corrected poses), every model variant from them, and scores the `test`
/// scans (poses `world_from_laser`).
///
/// The grid covers everything the mapping rays traversed (each ray up to its return, or up to
/// `r_max` for a no-return) and all poses (map and test) with `margin_m + disc_radius_m` around
/// them, so that the no-returns of the test scans cross mapped space rather than the models'
/// "outside the grid" prior, which would otherwise dominate their scores. The range limit is
/// `config.max_range_m` or the smallest `max_range_m` of the scans. Work is parallel over test
/// scans (rayon) and the result does not depend on the thread count.
pub fn score_planar(
    map: &[(Pose2, &Scan2)],
    test: &[(Pose2, &Scan2)],
    config: &ScoringConfig,
) -> Result<ScoreReport, SensorModelError> {
    config.validate()?;
    if map.is_empty() || test.is_empty() {
        return Err(invalid(
            "scans",
            format!(
                "need mapping and test scans, got {} and {}",
                map.len(),
                test.len()
            ),
        ));
    }
    let max_range_m = config.max_range_m.unwrap_or_else(|| {
        map.iter()
            .chain(test)
            .map(|(_, s)| s.max_range_m)
            .fold(f64::INFINITY, f64::min)
    });
    let range = SensorRange::new(0.0, max_range_m)?;
    let mut bounds = Aabb2::empty();
    let pad = config.margin_m + config.disc_radius_m;
    for (pose, scan) in map {
        for ray in scan.rays(*pose) {
            if let Some(length) = traced_length(range, ray.range) {
                let point = ray.at(length);
                if point.coords.iter().all(|v| v.is_finite()) {
                    bounds.extend(&point);
                }
            }
        }
    }
    for (pose, _) in map.iter().chain(test) {
        if !pose.is_finite() {
            return Err(invalid("pose", format!("not finite: {pose:?}")));
        }
        let p = Point2::new(pose.x(), pose.y());
        bounds.extend(&(p - Vector2::new(pad, pad)));
        bounds.extend(&(p + Vector2::new(pad, pad)));
    }
    let margin = Vector2::new(config.margin_m, config.margin_m);
    let bounds = Aabb2::new(bounds.min - margin, bounds.max + margin);
    let grid = Grid2::covering(&bounds, config.resolution_m)
        .map_err(|e| invalid("grid", e.to_string()))?;
    check_cells(grid.num_cells(), config)?;
    let mapping = MappingConfig {
        range,
        include_no_returns: true,
    };
    let started = Instant::now();
    let mut stats = DenseStats::planar(grid);
    stats.insert_scans_par(map, &mapping);
    let mapping_seconds = started.elapsed().as_secs_f64();

    let kept = thin(test.len(), config.max_test_scans);
    let prepared: Vec<(usize, (Pose2, &Scan2))> = kept.iter().map(|&i| (i, test[i])).collect();
    let test_rays = prepared
        .iter()
        .map(|(_, (_, s))| s.len().div_ceil(config.beam_step) as u64)
        .sum();
    let rows = score_rows(
        &stats,
        range,
        config,
        &prepared,
        test_rays,
        |model, item, offsets| {
            let (pose, scan) = *item;
            let adapter = ScanLikelihood::new(model).with_beam_step(config.beam_step);
            let beams = adapter.prepare(scan);
            offsets
                .iter()
                .map(|[dx, dy]| {
                    let shifted = Pose2::new(pose.x() + dx, pose.y() + dy, pose.theta());
                    adapter.log_likelihood_prepared(&shifted, &beams)
                })
                .collect()
        },
    )?;
    Ok(ScoreReport {
        rows,
        mapping_scans: map.len(),
        mapping_rays: stats.summary().rays,
        mapping_seconds,
        test_scans: prepared.len(),
        test_rays,
        grid_dims: [grid.dims()[0], grid.dims()[1], 1],
        resolution_m: config.resolution_m,
        max_range_m,
    })
}

/// Table 7.3 / 8.2 / 8.3 on 3-D data: like [`score_planar`] for scans given as
/// `(world_from_sensor, rays in the sensor frame)`. All rays of the `map` scans build the
/// map; every `beam_step`-th ray of the `test` scans is scored. The disc is horizontal
/// (world x–y; the world frame must be z-up); height and attitude stay at the truth.
///
/// The grid covers the traced extent of the mapping rays (returns within `r_max`; returns
/// beyond and no-returns up to `r_max`) and the poses with the disc;
/// `config.max_range_m` is required.
pub fn score_spatial(
    map: &[(Pose3, &[Ray3])],
    test: &[(Pose3, &[Ray3])],
    config: &ScoringConfig,
) -> Result<ScoreReport, SensorModelError> {
    config.validate()?;
    let Some(max_range_m) = config.max_range_m else {
        return Err(invalid(
            "max_range_m",
            "3-D scoring needs the sensor's maximum range".into(),
        ));
    };
    if map.is_empty() || test.is_empty() {
        return Err(invalid(
            "scans",
            format!(
                "need mapping and test scans, got {} and {}",
                map.len(),
                test.len()
            ),
        ));
    }
    let range = SensorRange::new(0.0, max_range_m)?;
    let pad = config.margin_m + config.disc_radius_m;
    let mut bounds = Aabb3::empty();
    for (pose, rays) in map {
        if !pose.is_finite() {
            return Err(invalid("pose", format!("not finite: {pose:?}")));
        }
        for ray in *rays {
            if let Some(length) = traced_length(range, ray.range) {
                let point = pose.transform_point(&ray.at(length));
                if point.coords.iter().all(|v| v.is_finite()) {
                    bounds.extend(&point);
                }
            }
        }
    }
    for (pose, _) in map.iter().chain(test) {
        if !pose.is_finite() {
            return Err(invalid("pose", format!("not finite: {pose:?}")));
        }
        let p: Point3<f64> = pose.transform_point(&Point3::origin());
        bounds.extend(&(p - Vector3::new(pad, pad, config.margin_m)));
        bounds.extend(&(p + Vector3::new(pad, pad, config.margin_m)));
    }
    let margin = Vector3::new(config.margin_m, config.margin_m, config.margin_m);
    let bounds = Aabb3::new(bounds.min - margin, bounds.max + margin);
    let grid = Grid3::covering(&bounds, config.resolution_m)
        .map_err(|e| invalid("grid", e.to_string()))?;
    check_cells(grid.num_cells(), config)?;
    let mapping = MappingConfig {
        range,
        include_no_returns: true,
    };
    let started = Instant::now();
    let mut stats = DenseStats::spatial(grid);
    stats.insert_par(map, &mapping, |(pose, rays), sink| {
        for ray in *rays {
            sink(&Ray3 {
                origin: pose.transform_point(&ray.origin),
                direction: nalgebra::Unit::new_unchecked(
                    pose.transform_vector(ray.direction.as_ref()),
                ),
                range: ray.range,
            });
        }
    });
    let mapping_seconds = started.elapsed().as_secs_f64();

    let kept = thin(test.len(), config.max_test_scans);
    let prepared: Vec<(usize, (Pose3, &[Ray3]))> = kept.iter().map(|&i| (i, test[i])).collect();
    let test_rays = prepared
        .iter()
        .map(|(_, (_, r))| r.len().div_ceil(config.beam_step) as u64)
        .sum();
    let rows = score_rows(
        &stats,
        range,
        config,
        &prepared,
        test_rays,
        |model, item, offsets| {
            let (pose, rays) = *item;
            let adapter = ScanLikelihood::new(model).with_beam_step(config.beam_step);
            offsets
                .iter()
                .map(|[dx, dy]| {
                    let shifted = Pose3::from_parts(
                        pose.translation() + Vector3::new(*dx, *dy, 0.0),
                        pose.rotation(),
                    );
                    adapter.rays_log_likelihood(&shifted, rays)
                })
                .collect()
        },
    )?;
    Ok(ScoreReport {
        rows,
        mapping_scans: map.len(),
        mapping_rays: stats.summary().rays,
        mapping_seconds,
        test_scans: prepared.len(),
        test_rays,
        grid_dims: grid.dims(),
        resolution_m: config.resolution_m,
        max_range_m,
    })
}

/// How far mapping traces a ray (its return, or `r_max` for a no-return; `None` for a
/// `sub` reading, which mapping ignores).
fn traced_length(range: SensorRange, reading: Range) -> Option<f64> {
    match range.classify(reading) {
        Reading::Hit(r) => Some(r),
        Reading::Sup => Some(range.max_range_m),
        Reading::Sub => None,
    }
}

fn check_cells(cells: usize, config: &ScoringConfig) -> Result<(), SensorModelError> {
    if cells > config.max_cells {
        return Err(invalid(
            "grid",
            format!(
                "the data need {cells} cells at {} m, more than the limit of {} \
                 (coarser resolution or a larger max_cells)",
                config.resolution_m, config.max_cells
            ),
        ));
    }
    Ok(())
}

/// The per-scan result of one model.
#[derive(Clone, Copy, Debug)]
struct ScanScore {
    at_truth: f64,
    divergences: Divergences,
}

/// Scores every variant on the prepared test scans `(scan index, item)`.
/// `scorer(model, item, offsets)` returns the scan's log-likelihood at the true pose
/// shifted by each position offset (so per-scan preparation happens once per model). Models run one after
/// another (for a clean per-model timing), test scans in parallel; per-scan results are
/// collected in order and summed sequentially, so the figures do not depend on the thread
/// count. The offsets of scan `i` depend only on `(seed, i)`: every model sees the same
/// samples.
fn score_rows<D, I>(
    stats: &DenseStats<D>,
    range: SensorRange,
    config: &ScoringConfig,
    tests: &[(usize, I)],
    test_rays: u64,
    scorer: impl Fn(&dyn SensorModel<D>, &I, &[[f64; 2]]) -> Vec<f64> + Sync,
) -> Result<Vec<ScoreRow>, SensorModelError>
where
    D: Dimension,
    I: Sync,
{
    let models = variants::build(stats, range, config.endpoint_sigma())?;
    let m = config.poses_per_scan;
    let mut rows = Vec::with_capacity(models.len());
    for variant in &models {
        let model: &dyn SensorModel<D> = variant.model.as_ref();
        let started = Instant::now();
        let per_scan: Vec<ScanScore> = tests
            .par_iter()
            .map(|(index, item)| {
                // Offset 0 is the true pose, offsets 1..=M the samples.
                let mut offsets = vec![[0.0, 0.0]];
                offsets.extend(disc_offsets(
                    config.seed,
                    *index as u64,
                    m,
                    config.disc_radius_m,
                ));
                let values = scorer(model, item, &offsets);
                let at_truth = values.first().copied().unwrap_or(f64::NEG_INFINITY);
                let samples = values.get(1..).unwrap_or_default();
                ScanScore {
                    at_truth,
                    divergences: divergences(
                        samples,
                        offsets.get(1..).unwrap_or_default(),
                        config.ground_truth_sigma_m,
                    ),
                }
            })
            .collect();
        let seconds = started.elapsed().as_secs_f64();
        let scans = per_scan.len().max(1) as f64;
        rows.push(ScoreRow {
            model: variant.name.to_owned(),
            posterior: variant.posterior,
            neg_log_likelihood: -per_scan.iter().map(|s| s.at_truth).sum::<f64>(), // Eq. (7.28)
            inverse_kl: per_scan
                .iter()
                .map(|s| s.divergences.inverse_kl)
                .sum::<f64>()
                / scans, // Eq. (7.29), mean over scans
            kl_ground_truth: per_scan.iter().map(|s| s.divergences.kl_ground_truth).sum(), // Eq. (8.24)
            evaluations: test_rays * (m as u64 + 1),
            seconds,
        });
    }
    Ok(rows)
}
