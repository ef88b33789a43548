//! Reading CARMEN logs for the matcher and scoring trajectories against reference poses.
//!
//! * [`read_laser_log`]: the front laser (`FLASER`, or `ROBOTLASER1` when the log has no
//!   `FLASER`) with its odometry pose and both timestamps (raypath-io reader; `RLASER` is
//!   skipped).
//! * [`pair_by_ranges`]: the SLAM benchmark's corrected logs are subsampled copies of the raw
//!   logs with the same range readings (data README), so each reference scan is paired with
//!   the next raw scan whose readings agree to the centimetre.
//! * [`relative_errors`]: the relative-motion error of Kümmerle et al., "On measuring the
//!   accuracy of SLAM algorithms" (Autonomous Robots 27(4), 2009): for relations between
//!   poses `i, j` with reference motion `δ*_ij = G_i⁻¹ G_j` and estimated `δ_ij = E_i⁻¹ E_j`,
//!   the error `δ*_ij⁻¹ δ_ij` split into its translation length and rotation angle, reported
//!   as mean ± standard deviation of the absolute values. Our relations join consecutive
//!   reference scans (the benchmark's own relation files are not in the data set).
//! * [`aligned_errors`]: absolute trajectory error after the least-squares rigid alignment
//!   (2-D Umeyama/Horn without scale) of the estimated positions onto the reference.

use std::collections::HashMap;
use std::path::Path;

use raypath_geometry::{Pose2, Scan2, wrap_angle};
use raypath_io::carmen::{CarmenReader, LaserKind, Record};
use serde::{Deserialize, Serialize};

use crate::calibration::IntensityCorrection;
use crate::error::{ReflectivityError, Result};
use crate::matcher::{MatchResult, MatcherConfig, ScanMatcher};
use crate::points::{PointFilter, ScanPoints};

/// One laser scan of a log.
#[derive(Clone, Debug, PartialEq)]
pub struct LogScan {
    /// The scan (angles from the reader's fan convention or the line).
    pub scan: Scan2,
    /// The logged laser pose (odometry in raw logs, the reference in corrected logs).
    pub world_from_laser: Pose2,
    /// IPC timestamp, seconds.
    pub ipc_timestamp_secs: f64,
    /// Logger timestamp, seconds.
    pub logger_timestamp_secs: f64,
    /// 1-based line number in the log.
    pub line: u64,
    /// The message type the scan came from.
    pub kind: LaserKind,
}

/// Reads the front-laser scans of a CARMEN log (module docs).
pub fn read_laser_log(path: &Path) -> Result<Vec<LogScan>> {
    let reader = CarmenReader::open(path)?;
    let mut front = Vec::new();
    let mut robot = Vec::new();
    for record in reader {
        if let Record::Laser(m) = record? {
            let s = LogScan {
                scan: m.scan,
                world_from_laser: m.world_from_laser,
                ipc_timestamp_secs: m.ipc_timestamp_secs,
                logger_timestamp_secs: m.logger_timestamp_secs,
                line: m.line,
                kind: m.kind,
            };
            match m.kind {
                LaserKind::Front => front.push(s),
                LaserKind::RobotLaser1 => robot.push(s),
                LaserKind::Rear => {}
            }
        }
    }
    let scans = if front.is_empty() { robot } else { front };
    if scans.is_empty() {
        return Err(ReflectivityError::BadInput(format!(
            "{}: no FLASER or ROBOTLASER1 scans",
            path.display()
        )));
    }
    Ok(scans)
}

/// Runs a matcher over the scans of a log: points by `filter` (ϱ̄ by `correction` when the
/// scans have intensities), odometry increments of the logged poses when `use_odometry`.
/// Returns the matcher (with its map) and one result per scan.
pub fn run_matcher(
    scans: &[LogScan],
    config: MatcherConfig,
    filter: &PointFilter,
    correction: Option<&IntensityCorrection>,
    use_odometry: bool,
) -> Result<(ScanMatcher, Vec<MatchResult>)> {
    let mut matcher = ScanMatcher::new(config)?;
    let mut points = ScanPoints::new();
    let mut results = Vec::with_capacity(scans.len());
    let mut previous: Option<Pose2> = None;
    for s in scans {
        points.fill_from_scan(&s.scan, filter, correction);
        let delta = match previous {
            Some(p) if use_odometry => Some(p.inverse() * s.world_from_laser),
            _ => None,
        };
        previous = Some(s.world_from_laser);
        results.push(matcher.process(&points, delta));
    }
    Ok((matcher, results))
}

fn key(scan: &Scan2) -> Vec<i64> {
    scan.ranges
        .iter()
        .map(|r| (r * 100.0).round() as i64)
        .collect()
}

/// Pairs each reference scan with a raw scan of the same readings (to 1 cm), in order:
/// returns `(raw index, reference index)` pairs.
pub fn pair_by_ranges(raw: &[LogScan], reference: &[LogScan]) -> Vec<(usize, usize)> {
    let mut by_key: HashMap<Vec<i64>, Vec<usize>> = HashMap::new();
    for (i, s) in raw.iter().enumerate() {
        by_key.entry(key(&s.scan)).or_default().push(i);
    }
    let mut pairs = Vec::new();
    let mut next = 0;
    for (j, s) in reference.iter().enumerate() {
        if let Some(list) = by_key.get(&key(&s.scan)) {
            if let Some(&i) = list.iter().find(|&&i| i >= next) {
                pairs.push((i, j));
                next = i + 1;
            }
        }
    }
    pairs
}

/// Mean ± standard deviation (and RMS, maximum) of absolute errors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Number of values.
    pub count: usize,
    /// Mean of the absolute values.
    pub mean: f64,
    /// Standard deviation of the absolute values.
    pub std: f64,
    /// Root mean square.
    pub rms: f64,
    /// Largest absolute value.
    pub max: f64,
}

impl Stats {
    /// Statistics of `values` (absolute values taken).
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let v: Vec<f64> = values.into_iter().map(f64::abs).collect();
        if v.is_empty() {
            return Self::default();
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        Self {
            count: v.len(),
            mean,
            std: var.sqrt(),
            rms: (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt(),
            max: v.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// Relative-motion errors (Kümmerle et al. 2009).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RelativeErrors {
    /// Translational error per relation, metres.
    pub translation_m: Stats,
    /// Rotational error per relation, radians.
    pub rotation_rad: Stats,
}

/// Relative-motion errors over relations `(i, j)` between poses of `reference` and
/// `estimate` (index-aligned slices).
pub fn relative_errors(
    reference: &[Pose2],
    estimate: &[Pose2],
    relations: &[(usize, usize)],
) -> RelativeErrors {
    let mut t = Vec::with_capacity(relations.len());
    let mut r = Vec::with_capacity(relations.len());
    for &(i, j) in relations {
        let (Some(gi), Some(gj), Some(ei), Some(ej)) = (
            reference.get(i),
            reference.get(j),
            estimate.get(i),
            estimate.get(j),
        ) else {
            continue;
        };
        let e = (gi.inverse() * *gj).inverse() * (ei.inverse() * *ej);
        t.push(e.translation().norm());
        r.push(wrap_angle(e.theta()));
    }
    RelativeErrors {
        translation_m: Stats::of(t),
        rotation_rad: Stats::of(r),
    }
}

/// Relations between consecutive poses: `(k, k + 1)`.
pub fn consecutive_relations(n: usize) -> Vec<(usize, usize)> {
    (1..n).map(|k| (k - 1, k)).collect()
}

/// Absolute position and heading errors after the rigid alignment of `estimate` onto
/// `reference` (index-aligned).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AlignedErrors {
    /// Position error per pose, metres.
    pub position_m: Stats,
    /// Heading error per pose, radians.
    pub heading_rad: Stats,
    /// The alignment `reference_from_estimate`.
    pub alignment: [f64; 3],
}

/// Rigidly aligns `estimate` to `reference` (least squares over positions) and measures
/// the remaining errors.
pub fn aligned_errors(reference: &[Pose2], estimate: &[Pose2]) -> AlignedErrors {
    let n = reference.len().min(estimate.len());
    if n == 0 {
        return AlignedErrors::default();
    }
    let (mut mr, mut me) = ([0.0; 2], [0.0; 2]);
    for (g, e) in reference.iter().zip(estimate) {
        mr = [mr[0] + g.x() / n as f64, mr[1] + g.y() / n as f64];
        me = [me[0] + e.x() / n as f64, me[1] + e.y() / n as f64];
    }
    let (mut sc, mut ss) = (0.0, 0.0);
    for (g, e) in reference.iter().zip(estimate) {
        let (a, b) = (
            [e.x() - me[0], e.y() - me[1]],
            [g.x() - mr[0], g.y() - mr[1]],
        );
        sc += a[0] * b[0] + a[1] * b[1];
        ss += a[0] * b[1] - a[1] * b[0];
    }
    let theta = ss.atan2(sc);
    let (c, s) = (theta.cos(), theta.sin());
    let t = [
        mr[0] - (c * me[0] - s * me[1]),
        mr[1] - (s * me[0] + c * me[1]),
    ];
    let align = Pose2::new(t[0], t[1], theta);
    let mut pos = Vec::with_capacity(n);
    let mut head = Vec::with_capacity(n);
    for (g, e) in reference.iter().zip(estimate) {
        let a = align * *e;
        pos.push((a.translation() - g.translation()).norm());
        head.push(wrap_angle(a.theta() - g.theta()));
    }
    AlignedErrors {
        position_m: Stats::of(pos),
        heading_rad: Stats::of(head),
        alignment: [t[0], t[1], theta],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alignment_removes_a_rigid_offset() {
        let reference: Vec<Pose2> = (0..20)
            .map(|k| Pose2::new(k as f64 * 0.3, (k as f64 * 0.4).sin(), k as f64 * 0.05))
            .collect();
        let offset = Pose2::new(3.0, -1.0, 0.7);
        let estimate: Vec<Pose2> = reference.iter().map(|g| offset * *g).collect();
        let a = aligned_errors(&reference, &estimate);
        assert!(a.position_m.max < 1e-9 && a.heading_rad.max < 1e-9);
        let r = relative_errors(&reference, &estimate, &consecutive_relations(20));
        assert!(r.translation_m.max < 1e-9 && r.rotation_rad.max < 1e-9);
        assert_eq!(r.translation_m.count, 19);
    }
}
