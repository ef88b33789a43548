//! Reading CARMEN logs for the matcher and scoring trajectories against reference poses.
//!
//! * [`run_matcher`] runs the matcher over any [`LoggedScan`]s: the [`PlanarFrame`]s of
//!   `raypath_io::sequence` (CARMEN logs with an explicit laser choice, rosbag2 bags) or
//!   [`LogScan`]s.
//! * [`read_laser_log`]: the front laser (`FLASER`, or `ROBOTLASER1` when the log has no
//!   `FLASER`) of a CARMEN log with its odometry pose, both timestamps, its line and message
//!   kind (the CARMEN-specific fields a corrected copy of the log needs; other readers go
//!   through [`raypath_io::sequence::read_planar`]).
//! * [`pair_by_ranges`]: the SLAM benchmark's corrected logs are subsampled copies of the raw
//!   logs with the same range readings (data README), so each reference scan is paired with
//!   the next raw scan whose readings agree to the centimetre
//!   ([`raypath_io::sequence::pair_by_ranges`], for [`LogScan`]s).
//! * [`relative_errors`]: the relative-motion error of Kümmerle et al., "On measuring the
//!   accuracy of SLAM algorithms" (Autonomous Robots 27(4), 2009): for relations between
//!   poses `i, j` with reference motion `δ*_ij = G_i⁻¹ G_j` and estimated `δ_ij = E_i⁻¹ E_j`,
//!   the error `δ*_ij⁻¹ δ_ij` split into its translation length and rotation angle, reported
//!   as mean ± standard deviation of the absolute values. Our relations join consecutive
//!   reference scans (the benchmark's own relation files are not in the data set).
//! * [`aligned_errors`]: absolute trajectory error after the least-squares rigid alignment
//!   (2-D Umeyama/Horn without scale) of the estimated positions onto the reference.

use std::path::Path;

use raypath_geometry::{Pose2, Scan2, wrap_angle};
use raypath_io::carmen::{CarmenReader, LaserKind, Record};
use raypath_io::sequence::PlanarFrame;
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

/// Reads the front-laser scans of a CARMEN log with their CARMEN-specific fields (module
/// docs); the scans are those of [`raypath_io::sequence::CarmenScans`] with
/// [`raypath_io::sequence::LaserChoice::Front`].
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

/// A scan with its logged laser pose, the input of [`run_matcher`].
pub trait LoggedScan {
    /// The scan in the laser frame.
    fn scan(&self) -> &Scan2;
    /// The logged `world_from_laser` (the odometry in raw logs).
    fn world_from_laser(&self) -> Pose2;
}

impl LoggedScan for LogScan {
    fn scan(&self) -> &Scan2 {
        &self.scan
    }

    fn world_from_laser(&self) -> Pose2 {
        self.world_from_laser
    }
}

impl LoggedScan for PlanarFrame {
    fn scan(&self) -> &Scan2 {
        &self.scan
    }

    fn world_from_laser(&self) -> Pose2 {
        self.world_from_laser
    }
}

/// Runs a matcher over the scans of a log: points by `filter` (ϱ̄ by `correction` when the
/// scans have intensities), odometry increments of the logged poses when `use_odometry`.
/// Returns the matcher (with its map) and one result per scan.
pub fn run_matcher<S: LoggedScan>(
    scans: &[S],
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
        points.fill_from_scan(s.scan(), filter, correction);
        let world_from_laser = s.world_from_laser();
        let delta = match previous {
            Some(p) if use_odometry => Some(p.inverse() * world_from_laser),
            _ => None,
        };
        previous = Some(world_from_laser);
        results.push(matcher.process(&points, delta));
    }
    Ok((matcher, results))
}

/// Pairs each reference scan with a raw scan of the same readings (to 1 cm), in order:
/// returns `(raw index, reference index)` pairs ([`raypath_io::sequence::pair_by_ranges`]).
pub fn pair_by_ranges(raw: &[LogScan], reference: &[LogScan]) -> Vec<(usize, usize)> {
    raypath_io::sequence::pair_by_ranges(
        raw.iter().map(|s| &s.scan),
        reference.iter().map(|s| &s.scan),
    )
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
    let (t, r) = relation_error_lists(|i| reference.get(i), estimate, relations);
    RelativeErrors {
        translation_m: Stats::of(t),
        rotation_rad: Stats::of(r),
    }
}

/// The errors [`relation_error`] of the relations `(i, j)` whose four poses exist, in
/// relation order: translations (m) and signed wrapped angles (rad). `reference(i)` is the
/// reference pose of scan `i` (`None` skips the relations of the scan); `estimate` is
/// index-aligned with it.
pub fn relation_error_lists<'a>(
    reference: impl Fn(usize) -> Option<&'a Pose2>,
    estimate: &[Pose2],
    relations: &[(usize, usize)],
) -> (Vec<f64>, Vec<f64>) {
    let mut t = Vec::with_capacity(relations.len());
    let mut r = Vec::with_capacity(relations.len());
    for &(i, j) in relations {
        let (Some(gi), Some(gj), Some(ei), Some(ej)) =
            (reference(i), reference(j), estimate.get(i), estimate.get(j))
        else {
            continue;
        };
        let (dt, dr) = relation_error(gi, gj, ei, ej);
        t.push(dt);
        r.push(dr);
    }
    (t, r)
}

/// The error of one relation `(i, j)` (Kümmerle et al. 2009): the pose `δ_ref⁻¹ δ_est` with
/// `δ = x_i⁻¹ x_j`, as its translation length (m) and its wrapped angle (rad, signed).
pub fn relation_error(
    reference_i: &Pose2,
    reference_j: &Pose2,
    estimate_i: &Pose2,
    estimate_j: &Pose2,
) -> (f64, f64) {
    let e = (reference_i.inverse() * *reference_j).inverse() * (estimate_i.inverse() * *estimate_j);
    (e.translation().norm(), wrap_angle(e.theta()))
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

    #[test]
    fn read_laser_log_keeps_the_scans_of_the_front_laser_source() {
        use raypath_io::carmen::CarmenConfig;
        use raypath_io::sequence::{CarmenScans, LaserChoice};
        let robot =
            "ROBOTLASER1 0 -1.5 3.1 0.01 81.9 0.01 0 2 1 2 2 5 6 0 0 0 0 0 0 0 0 0 0 0 1 h 1";
        let flaser = [
            "FLASER 3 1 2 3 0 0 0 0 0 0 2.0 h 2.0",
            "FLASER 3 2 2 3 1 0 0 1 0 0 4.0 h 4.0",
        ];
        let rear = "RLASER 3 4 5 6 0 0 0 0 0 0 3.0 h 3.0";
        let dir = tempfile::tempdir().unwrap();
        let logs = [
            (
                format!("{robot}\n{}\n{rear}\n{}\n", flaser[0], flaser[1]),
                2,
                LaserKind::Front,
            ),
            (
                format!("{robot}\n{rear}\n{robot}\n"),
                2,
                LaserKind::RobotLaser1,
            ),
        ];
        for (k, (text, count, kind)) in logs.iter().enumerate() {
            let path = dir.path().join(format!("{k}.log"));
            std::fs::write(&path, text).unwrap();
            let scans = read_laser_log(&path).unwrap();
            let frames: Vec<PlanarFrame> =
                CarmenScans::open(&path, LaserChoice::Front, CarmenConfig::default())
                    .unwrap()
                    .collect::<raypath_io::Result<_>>()
                    .unwrap();
            assert_eq!((scans.len(), frames.len()), (*count, *count));
            for (s, f) in scans.iter().zip(&frames) {
                assert_eq!(s.kind, *kind);
                assert_eq!((&s.scan, s.world_from_laser), (&f.scan, f.world_from_laser));
                assert_eq!(s.logger_timestamp_secs, f.stamp_secs);
                assert_eq!(raypath_io::sequence::Origin::Line(s.line), f.origin);
            }
            // The matcher reads both alike.
            let config = MatcherConfig::default();
            let (_, a) = run_matcher(&scans, config, &PointFilter::default(), None, true).unwrap();
            let (_, b) = run_matcher(&frames, config, &PointFilter::default(), None, true).unwrap();
            let poses =
                |r: &[MatchResult]| r.iter().map(|m| m.world_from_sensor).collect::<Vec<_>>();
            assert_eq!(poses(&a), poses(&b));
        }
    }
}
