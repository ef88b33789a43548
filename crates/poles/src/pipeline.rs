//! The mapping and localization pipelines on a [`Drive`] (Schaefer 2020, §12.4.2–§12.5): local
//! maps along trajectory segments, the reference map, and particle-filter runs evaluated every
//! 1 m.

use std::time::Instant;

use nalgebra::{Point2, Point3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use raypath_geometry::{PointCloud, Pose2, Pose3};
use raypath_localizer::PoseTrack;
use raypath_localizer::eval::{EvaluationConfig, TrajectoryEvaluation, evaluate_trajectory};
use serde::{Deserialize, Serialize};

use crate::drive::Drive;
use crate::error::{PoleError, Result};
use crate::extract::{ExtractionStats, extract_poles_from_sweeps};
use crate::localize::{FilterParams, PoleFilter};
use crate::mapping::{SlidingWindowFilter, merge_poles, segments};
use crate::params::PoleParams;
use crate::pole::Pole;
use crate::reference::greedy_matches;
use crate::sweep::SweepMotion;

/// How local maps are laid along the trajectory (Schaefer 2020, §12.4.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentParams {
    /// Distance between segment starts, metres (NCLT 1.5, KITTI 3).
    pub interval_m: f64,
    /// Segment length, metres (NCLT 1.5, KITTI 5).
    pub length_m: f64,
    /// Map poles need this many detections in overlapping local maps (NCLT 3, KITTI 1).
    pub min_map_detections: usize,
    /// Online poles need `c` detections in the last `w` local maps (c = 2, w = 3).
    pub window_c: usize,
    /// See `window_c`.
    pub window_w: usize,
}

impl SegmentParams {
    /// NCLT (`ncltpoles.py`).
    pub fn nclt() -> Self {
        Self {
            interval_m: 1.5,
            length_m: 1.5,
            min_map_detections: 3,
            window_c: 2,
            window_w: 3,
        }
    }

    /// KITTI (`kittipoles.py`).
    pub fn kitti() -> Self {
        Self {
            interval_m: 3.0,
            length_m: 5.0,
            min_map_detections: 1,
            ..Self::nclt()
        }
    }
}

/// A preset of all parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Preset {
    /// Extraction.
    pub extraction: PoleParams,
    /// Segments and filters.
    pub segments: SegmentParams,
    /// Particle filter.
    pub filter: FilterParams,
}

impl Preset {
    /// NCLT.
    pub fn nclt() -> Self {
        Self {
            extraction: PoleParams::nclt(),
            segments: SegmentParams::nclt(),
            filter: FilterParams::nclt(),
        }
    }

    /// KITTI.
    pub fn kitti() -> Self {
        Self {
            extraction: PoleParams::kitti(),
            segments: SegmentParams::kitti(),
            filter: FilterParams::kitti(),
        }
    }
}

/// The poles of one local map.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalMap {
    /// The scans of the segment.
    pub scans: Vec<usize>,
    /// The centre scan.
    pub center: usize,
    /// Poles in the frame of the registration track (world for ground truth).
    pub poles: Vec<Pole>,
}

/// Totals of an extraction run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ExtractionTotals {
    /// Local maps built.
    pub local_maps: usize,
    /// Rays traced (a scan in two overlapping segments counts twice).
    pub rays: u64,
    /// Seconds tracing.
    pub trace_secs: f64,
    /// Seconds scoring and extracting.
    pub score_secs: f64,
    /// Seconds reading scans.
    pub read_secs: f64,
}

impl ExtractionTotals {
    /// Points per second of extraction (tracing + scoring, reading excluded).
    pub fn points_per_sec(&self) -> f64 {
        self.rays as f64 / (self.trace_secs + self.score_secs).max(1e-12)
    }

    fn add(&mut self, s: &ExtractionStats) {
        self.local_maps += 1;
        self.rays += s.rays;
        self.trace_secs += s.trace_secs;
        self.score_secs += s.score_secs;
    }
}

/// Builds local maps along `track` (one pose per scan of `drive`: the ground truth for
/// mapping, the odometry for online poles) for the scans `first..end`. `progress` is called
/// with (done, total).
pub fn local_maps(
    drive: &Drive,
    track: &[Pose3],
    range: std::ops::Range<usize>,
    preset: &Preset,
    mut progress: impl FnMut(usize, usize),
) -> Result<(Vec<LocalMap>, ExtractionTotals)> {
    let end = range.end.min(track.len()).min(drive.len());
    let first = range.start.min(end);
    let positions: Vec<Point3<f64>> = track[first..end]
        .iter()
        .map(|p| Point3::from(p.translation()))
        .collect();
    let segs = segments(
        &positions,
        preset.segments.interval_m,
        preset.segments.length_m,
    );
    let motions = drive
        .sweep_timing
        .map(|timing| SweepMotion::from_poses(track, &drive.sweeps.stamps_secs, timing));
    let mut totals = ExtractionTotals::default();
    let mut out = Vec::with_capacity(segs.len());
    // Scans of the previous segment are kept (overlapping segments share them).
    let mut cache: Vec<(usize, PointCloud)> = Vec::new();
    for (k, seg) in segs.iter().enumerate() {
        let read = Instant::now();
        let wanted: Vec<usize> = seg.scans.iter().map(|&i| i + first).collect();
        cache.retain(|(i, _)| wanted.contains(i));
        for &i in &wanted {
            if !cache.iter().any(|(j, _)| *j == i) {
                cache.push((i, drive.sweeps.sweep(i)?));
            }
        }
        totals.read_secs += read.elapsed().as_secs_f64();
        // The scans with their sweep motions (when the drive has sweep timing), in step.
        let (scans, seg_motions): (Vec<(Pose3, &PointCloud)>, Vec<Option<SweepMotion>>) = wanted
            .iter()
            .filter_map(|&i| {
                let cloud = cache.iter().find(|(j, _)| *j == i).map(|(_, c)| c)?;
                let motion = motions.as_ref().and_then(|m| m.get(i).copied());
                Some(((*track.get(i)?, cloud), motion))
            })
            .unzip();
        let seg_motions: Option<Vec<SweepMotion>> = seg_motions.into_iter().collect();
        let center_index = seg.center + first;
        let center = track
            .get(center_index)
            .map(|p| Point3::from(p.translation()))
            .unwrap_or_else(Point3::origin);
        let (poles, stats) =
            extract_poles_from_sweeps(&scans, seg_motions.as_deref(), &center, &preset.extraction)?;
        totals.add(&stats);
        out.push(LocalMap {
            scans: wanted,
            center: center_index,
            poles,
        });
        progress(k + 1, segs.len());
    }
    Ok((out, totals))
}

/// The reference map from ground-truth local maps: overlap clusters with at least
/// `min_map_detections` members, score-weighted (Schaefer 2020, §12.4.2).
pub fn reference_map(local_maps: &[LocalMap], preset: &Preset) -> Vec<Pole> {
    let all: Vec<Pole> = local_maps
        .iter()
        .flat_map(|m| m.poles.iter().copied())
        .collect();
    merge_poles(&all, preset.segments.min_map_detections)
}

/// Odometry noise of a localization run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum OdometryNoise {
    /// Use the drive's odometry as recorded; the filter's standard deviations are the
    /// drive's `odometry_std` × `std_scale` (NCLT: × 2, i.e. covariance × 4), or `fallback`
    /// fractions of the increment when the drive states none.
    Recorded {
        /// Factor on the stated standard deviations.
        std_scale: f64,
        /// Fraction of the increment used as standard deviation when none is stated.
        fallback: f64,
    },
    /// Corrupt every increment `χ` with `N(0, diag((r χ)²))` and tell the filter the same
    /// (KITTI protocol: r = 0.02).
    Relative {
        /// The fraction `r`.
        fraction: f64,
    },
}

/// The result of one localization run.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// The evaluation against the ground truth (every 1 m).
    pub evaluation: TrajectoryEvaluation,
    /// Measurement updates done.
    pub updates: usize,
    /// Seconds spent in measurement updates.
    pub update_secs: f64,
}

/// Online poles for localization: the local maps built along the odometry, each passed
/// through the c-of-w filter and expressed in the odometry frame; paired with the scan index
/// at which the local map is complete.
pub fn online_poles(local_maps: &[LocalMap], preset: &Preset) -> Vec<(usize, Vec<Pole>)> {
    let mut window = SlidingWindowFilter::new(preset.segments.window_c, preset.segments.window_w);
    local_maps
        .iter()
        .map(|m| {
            let done = m.scans.last().copied().unwrap_or(m.center);
            (done, window.push(m.poles.clone()))
        })
        .collect()
}

/// One particle-filter run over the scans `range` of `drive`: motion updates at every scan
/// from the odometry (with `noise`), measurement updates with `online` poles (in the frame
/// of `registration`, e.g. the odometry) when their local map completes. Starts at the
/// ground truth of the first scan and is evaluated against the ground truth every 1 m.
#[allow(clippy::too_many_arguments)]
pub fn localize_run(
    drive: &Drive,
    range: std::ops::Range<usize>,
    map: &[Pole],
    online: &[(usize, Vec<Pole>)],
    registration: &[Pose3],
    filter_params: &FilterParams,
    noise: OdometryNoise,
    seed: u64,
) -> Result<RunResult> {
    let gt = drive.require_ground_truth()?;
    let end = range.end.min(drive.len()).min(gt.len());
    let first = range.start.min(end);
    let start = gt.get(first).map(Pose3::to_planar).unwrap_or_default();
    let (estimate, updates, update_secs) = filter_run(
        drive,
        first..end,
        map,
        online,
        registration,
        filter_params,
        noise,
        start,
        seed,
    )?;
    let gt_track = PoseTrack::from_parts(
        drive.sweeps.stamps_secs[first..end].to_vec(),
        gt[first..end].iter().map(Pose3::to_planar).collect(),
    )?;
    let evaluation = evaluate_trajectory(&gt_track, &estimate, &EvaluationConfig::default())?;
    Ok(RunResult {
        evaluation,
        updates,
        update_secs,
    })
}

/// The filter alone (no ground truth needed): particles drawn around `start` (the world
/// pose at the first scan of `range`). Returns the estimated track (one pose per scan), the
/// number of measurement updates and the seconds they took.
#[allow(
    clippy::too_many_arguments,
    clippy::needless_range_loop,
    clippy::type_complexity
)]
pub fn filter_run(
    drive: &Drive,
    range: std::ops::Range<usize>,
    map: &[Pole],
    online: &[(usize, Vec<Pole>)],
    registration: &[Pose3],
    filter_params: &FilterParams,
    noise: OdometryNoise,
    start: Pose2,
    seed: u64,
) -> Result<(PoseTrack<Pose2>, usize, f64)> {
    let end = range.end.min(drive.len());
    let first = range.start.min(end);
    if registration.len() < end || drive.odometry().len() < end {
        return Err(PoleError::Sequence {
            path: drive.sweeps.name.clone(),
            reason: "the registration or odometry track is shorter than the drive".into(),
        });
    }
    if end - first < 2 {
        return Err(PoleError::Sequence {
            path: drive.sweeps.name.clone(),
            reason: "fewer than two scans to localize on".into(),
        });
    }
    let planar = |p: &Pose3| p.to_planar();
    let mut filter = PoleFilter::new(map, filter_params.clone(), start, seed)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6f64_6f6d);
    let unit = Normal::new(0.0, 1.0).map_err(|e| PoleError::InvalidParameter {
        name: "noise",
        reason: e.to_string(),
    })?;
    let mut stamps = vec![drive.sweeps.stamps_secs[first]];
    let mut estimates = vec![filter.estimate()];
    let (mut updates, mut update_secs) = (0, 0.0);
    let mut next_online = online.iter().peekable();
    for k in first + 1..end {
        let increment = planar(&drive.odometry()[k - 1]).inverse() * planar(&drive.odometry()[k]);
        let (increment, std) = match noise {
            OdometryNoise::Relative { fraction } => {
                let std = [increment.x(), increment.y(), increment.theta()]
                    .map(|v| (fraction * v).abs().max(1e-6));
                let noisy = Pose2::new(
                    increment.x() + std[0] * unit.sample(&mut rng),
                    increment.y() + std[1] * unit.sample(&mut rng),
                    increment.theta() + std[2] * unit.sample(&mut rng),
                );
                (noisy, std)
            }
            OdometryNoise::Recorded {
                std_scale,
                fallback,
            } => {
                let stated = drive
                    .sweeps
                    .odometry_std
                    .as_ref()
                    .and_then(|s| s.get(k))
                    .copied();
                let std = match stated {
                    Some(s) => s.map(|v| (v * std_scale).max(1e-4)),
                    None => [increment.x(), increment.y(), increment.theta()]
                        .map(|v| (fallback * v).abs().max(1e-4)),
                };
                (increment, std)
            }
        };
        filter.predict(&increment, std)?;
        while let Some((done, poles)) = next_online.peek() {
            if *done > k {
                break;
            }
            if *done == k && !poles.is_empty() {
                // Poles of the registration frame → robot frame at scan k.
                let robot_from_reg = planar(&registration[k]).inverse();
                let observed: Vec<Point2<f64>> = poles
                    .iter()
                    .map(|p| robot_from_reg.transform_point(&Point2::new(p.x, p.y)))
                    .collect();
                let started = Instant::now();
                filter.update(&observed)?;
                update_secs += started.elapsed().as_secs_f64();
                updates += 1;
            }
            next_online.next();
        }
        stamps.push(drive.sweeps.stamps_secs[k]);
        estimates.push(filter.estimate());
    }
    let estimate = PoseTrack::from_parts(stamps, estimates)?;
    Ok((estimate, updates, update_secs))
}

/// Detection quality of extracted poles against ground-truth positions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DetectionQuality {
    /// Extracted poles.
    pub detected: usize,
    /// Ground-truth poles considered.
    pub truth: usize,
    /// Detections matched one-to-one to a ground-truth pole within the radius.
    pub matched: usize,
    /// matched / detected.
    pub precision: f64,
    /// matched / truth.
    pub recall: f64,
    /// Mean centre distance of the matches, metres.
    pub mean_centre_error_m: f64,
}

/// Greedy one-to-one matching (closest pairs first) within `radius_m`.
pub fn detection_quality(
    detected: &[Pole],
    truth: &[Point2<f64>],
    radius_m: f64,
) -> DetectionQuality {
    let d: Vec<(f64, f64)> = detected.iter().map(|p| (p.x, p.y)).collect();
    let t: Vec<(f64, f64)> = truth.iter().map(|p| (p.x, p.y)).collect();
    let distances: Vec<f64> = greedy_matches(&d, &t, radius_m)
        .iter()
        .map(|m| m.2)
        .collect();
    DetectionQuality::from_counts(detected.len(), truth.len(), &distances)
}

impl DetectionQuality {
    /// The quality of `detected` detections against `truth` references given the centre
    /// distances of the matched pairs.
    pub fn from_counts(detected: usize, truth: usize, matched_distances: &[f64]) -> Self {
        let matched = matched_distances.len();
        let ratio = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
        Self {
            detected,
            truth,
            matched,
            precision: ratio(matched, detected),
            recall: ratio(matched, truth),
            mean_centre_error_m: if matched == 0 {
                0.0
            } else {
                matched_distances.iter().sum::<f64>() / matched as f64
            },
        }
    }
}
