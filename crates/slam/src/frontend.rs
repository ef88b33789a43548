//! The front-end ("local SLAM"): Hector-style Gauss–Newton matching of each scan against the
//! older active submap (Khan 2017 §3.4.2; Kohlbrecher et al. 2011), with the odometry increment
//! as the initial guess (and, with [`MatcherConfig::odometry_sigma`], as a prior), and the
//! node and submap bookkeeping of Hess et al. (2016, §IV).
//!
//! Poses here are in the front-end's **local** frame: the frame of the first scan, never
//! corrected by the pose graph. Submaps live in it, so matching never has to be redone after
//! an optimisation; the pipeline maps local poses to the optimised world frame.
//!
//! [`MatcherConfig::odometry_sigma`]: raypath_reflectivity::MatcherConfig::odometry_sigma

use std::collections::VecDeque;

use nalgebra::Matrix3;
use raypath_geometry::Pose2;
use raypath_reflectivity::{GridLevel, MatcherConfig, Prior, ScanPoints, match_levels};

use crate::config::{SlamConfig, information};
use crate::error::Result;
use crate::guard::{
    MatchStatus, TrackingGuardConfig, TrackingStats, judge, match_score, update_recent_speed,
};
use crate::submap::{ActiveSubmap, Submap};

/// The front-end state.
#[derive(Debug)]
pub(crate) struct FrontEnd {
    matcher: MatcherConfig,
    active: VecDeque<ActiveSubmap>,
    local: Pose2,
    last_odometry: Option<Pose2>,
    last_node: Option<Pose2>,
    travel_m: f64,
    rotation_window_rad: f64,
    rotation_step_rad: f64,
    rotation_min_gain: f64,
    rotation_window_growth: f64,
    guard: TrackingGuardConfig,
    last_stamp: Option<f64>,
    /// The odometry's recent speed, m/s ([`TrackingGuardConfig::recent_speed_factor`]).
    recent_speed_mps: f64,
    /// Matches have failed for too long: the next insertion finishes the active submaps and
    /// starts a new one.
    break_pending: bool,
    /// The last scan's match failed.
    last_failed: bool,
    /// Path since the last match that did not fail, metres.
    failed_travel_m: f64,
    /// A match failed since the last node.
    failed_since_node: bool,
    pub stats: TrackingStats,
}

impl FrontEnd {
    pub fn new(config: &SlamConfig) -> Self {
        Self {
            matcher: MatcherConfig {
                map: config.submap_map(),
                ..config.matcher
            },
            active: VecDeque::with_capacity(3),
            local: Pose2::identity(),
            last_odometry: None,
            last_node: None,
            travel_m: 0.0,
            rotation_window_rad: config.submaps.rotation_window_rad,
            rotation_step_rad: config.submaps.rotation_step_rad,
            rotation_min_gain: config.submaps.rotation_min_gain,
            rotation_window_growth: config.submaps.rotation_window_growth,
            guard: config.tracking,
            last_stamp: None,
            recent_speed_mps: 0.0,
            break_pending: false,
            last_failed: false,
            failed_travel_m: 0.0,
            failed_since_node: false,
            stats: TrackingStats::default(),
        }
    }

    /// Path length of the local trajectory so far, metres.
    pub fn travel_m(&self) -> f64 {
        self.travel_m
    }

    /// Whether a match failed since the last node (its sequential edge then carries the
    /// odometry's uncertainty, [`TrackingGuardConfig::fallback_sigma`]).
    pub fn failed_since_node(&self) -> bool {
        self.failed_since_node
    }

    /// Matches a scan taken at `stamp_secs`: `odometry` is the logged `world_from_sensor` of
    /// the odometry (or `None` to predict no motion). An implausible odometry increment is
    /// replaced by no motion, and a failed match by the odometry guess (see [`crate::guard`]).
    /// Returns the local pose.
    pub fn track(
        &mut self,
        points: &ScanPoints,
        odometry: Option<Pose2>,
        stamp_secs: f64,
    ) -> Pose2 {
        let mut delta = match (self.last_odometry, odometry) {
            (Some(a), Some(b)) => a.inverse() * b,
            _ => Pose2::identity(),
        };
        if odometry.is_some() {
            self.last_odometry = odometry;
        }
        let dt = self.last_stamp.map_or(f64::NAN, |t| stamp_secs - t);
        self.last_stamp = Some(stamp_secs);
        // An increment the robot cannot have driven is unknown: no motion is the guess, the
        // logged increment only a second candidate (below).
        let logged = delta;
        let outlier = !self.guard.plausible(&delta, dt, self.recent_speed_mps);
        if outlier {
            self.stats.odometry_outliers += 1;
            delta = Pose2::identity();
        } else {
            self.recent_speed_mps =
                update_recent_speed(self.recent_speed_mps, delta.translation().norm(), dt);
        }
        let guess = self.local * delta;
        let mut status = MatchStatus::Good;
        let (pose, _covariance) = match self.active.front() {
            Some(submap) if !points.is_empty() => {
                let submap_from_local = submap.local_from_submap.inverse();
                let mut initial = submap_from_local * guess;
                if self.rotation_window_rad > 0.0 {
                    let window = self.rotation_window_rad
                        + self.rotation_window_growth * delta.theta().abs();
                    let search = |start: Pose2| {
                        rotation_search(
                            submap.map.levels(),
                            points,
                            start,
                            window,
                            self.rotation_step_rad,
                            self.rotation_min_gain,
                        )
                    };
                    let (from_guess, score) = search(initial);
                    initial = from_guess;
                    // A glitch in the odometry (a jump in the log, wheel slip) moves the guess
                    // out of every basin: when the increment turns beyond the search window,
                    // or moves more than two coarsest cells faster than the robot can drive
                    // ([`TrackingGuardConfig::max_speed_mps`], no allowance), the pose of the
                    // last scan (no motion) is a second candidate, taken when it scores
                    // clearly better. A plain step is never second-guessed: in a corridor
                    // without features along it the last pose fits as well. For an implausible
                    // increment the roles swap.
                    let coarsest = submap.map.levels().last().map_or(0.0, |l| l.resolution_m());
                    let step = delta.translation().norm();
                    let too_fast = self
                        .guard
                        .speed_bound(self.recent_speed_mps)
                        .is_some_and(|v| dt > 0.0 && step > 2.0 * coarsest && step > v * dt);
                    let second = if outlier {
                        Some(self.local * logged)
                    } else if delta.theta().abs() > window || too_fast {
                        Some(self.local)
                    } else {
                        None
                    };
                    if let Some(second) = second {
                        let (alternative, alt_score) = search(submap_from_local * second);
                        if alt_score > score + self.rotation_min_gain {
                            initial = alternative;
                        }
                    }
                }
                let prior = self.matcher.odometry_sigma.map(|s| Prior {
                    pose: initial,
                    information: information(&s),
                });
                let (p, c) = match_levels(
                    submap.map.levels(),
                    &self.matcher,
                    points,
                    initial,
                    prior.as_ref(),
                );
                let score = submap
                    .map
                    .levels()
                    .first()
                    .map_or(0.0, |l| match_score(l, points, &p));
                let (kept, verdict) = judge(&self.guard, initial, p, &c, score);
                status = verdict;
                let kept = match verdict {
                    MatchStatus::Failed => submap_from_local * guess,
                    _ => kept,
                };
                (submap.local_from_submap * kept, c)
            }
            _ => (guess, Matrix3::from_diagonal_element(f64::INFINITY)),
        };
        let step = (self.local.inverse() * pose).translation().norm();
        self.last_failed = status == MatchStatus::Failed;
        match status {
            MatchStatus::Good => self.failed_travel_m = 0.0,
            MatchStatus::Degenerate => {
                self.stats.degenerate += 1;
                self.failed_travel_m = 0.0;
            }
            MatchStatus::Failed => {
                self.stats.failed += 1;
                self.failed_since_node = true;
                self.failed_travel_m += step;
                if self.failed_travel_m >= self.guard.max_failed_travel_m {
                    self.break_pending = true;
                }
            }
        }
        self.travel_m += step;
        self.local = pose;
        pose
    }

    /// Whether the last tracked pose has moved far enough from the last node to become one.
    pub fn wants_node(&self, config: &SlamConfig) -> bool {
        if self.break_pending {
            return true;
        }
        match self.last_node {
            None => true,
            Some(last) => {
                let d = last.inverse() * self.local;
                d.translation().norm() >= config.submaps.node_distance_m
                    || d.theta().abs() >= config.submaps.node_angle_rad
            }
        }
    }

    /// Makes the last tracked pose node `node`: starts a submap when due, inserts the scan into
    /// the active submaps (pushing `(anchor, submap_from_sensor)` of each onto `intra`, the
    /// intra-submap constraints of Hess et al. 2016) and returns the submaps that were
    /// finished.
    pub fn insert(
        &mut self,
        config: &SlamConfig,
        node: usize,
        points: &ScanPoints,
        intra: &mut Vec<(usize, Pose2)>,
    ) -> Result<Vec<ActiveSubmap>> {
        let s = &config.submaps;
        let mut finished = Vec::new();
        if std::mem::take(&mut self.break_pending) {
            // Matching has failed for too long: the active submaps end here and a new one
            // starts at the odometry's pose.
            finished.extend(self.active.drain(..));
            self.stats.submap_breaks += 1;
            self.failed_travel_m = 0.0;
        } else if self.last_failed {
            // No submap is built across a failed match: its scan is not inserted.
            self.last_node = Some(self.local);
            return Ok(finished);
        }
        // The edge into the next node is weak when this node's own match failed.
        self.failed_since_node = self.last_failed;
        let start = match self.active.back() {
            None => true,
            Some(newest) => {
                newest.nodes.len() >= s.nodes_per_submap
                    || s.max_distance_m
                        .is_some_and(|d| self.travel_m - newest.start_travel_m >= d)
            }
        };
        if start {
            self.active.push_back(ActiveSubmap::new(
                &self.matcher.map,
                node,
                self.local,
                self.travel_m,
            )?);
        }
        for submap in &mut self.active {
            let submap_from_sensor = submap.local_from_submap.inverse() * self.local;
            submap.map.update(&submap_from_sensor, points);
            submap.nodes.push(node);
            if submap.anchor != node {
                intra.push((submap.anchor, submap_from_sensor));
            }
        }
        self.last_node = Some(self.local);
        while self.active.len() > 2
            || self
                .active
                .front()
                .is_some_and(|f| self.active.len() > 1 && f.nodes.len() >= 2 * s.nodes_per_submap)
        {
            if let Some(f) = self.active.pop_front() {
                finished.push(f);
            }
        }
        Ok(finished)
    }

    /// Finishes every active submap (at the end of the log).
    pub fn finish(&mut self) -> Vec<ActiveSubmap> {
        self.active.drain(..).collect()
    }
}

/// The heading within `±window` (steps of `step`) around `initial` whose rotated points score
/// best on the coarsest level (mean bilinear occupancy of every 4th point; position kept), when
/// it beats the guess's score by at least `min_gain`: a correlative search over rotation only,
/// which brings large odometry heading errors into the Gauss–Newton basin (Olson 2009's idea,
/// restricted to one axis) and leaves good guesses alone. Returns the pose and its score.
fn rotation_search(
    levels: &[GridLevel],
    points: &ScanPoints,
    initial: Pose2,
    window: f64,
    step: f64,
    min_gain: f64,
) -> (Pose2, f64) {
    let Some(grid) = levels.last() else {
        return (initial, 0.0);
    };
    let score = |theta: f64| {
        let (c, s) = (theta.cos(), theta.sin());
        let (mut sum, mut n) = (0.0, 0usize);
        for p in points.points().iter().step_by(4) {
            let x = c * p[0] - s * p[1] + initial.x();
            let y = s * p[0] + c * p[1] + initial.y();
            if let Some(m) = grid.occupancy(x, y) {
                sum += m.value;
            }
            n += 1;
        }
        sum / n.max(1) as f64
    };
    let steps = (window / step).floor() as i64;
    let at_guess = score(initial.theta());
    let mut best = (at_guess + min_gain, initial.theta());
    for k in (-steps..=steps).filter(|&k| k != 0) {
        let theta = initial.theta() + k as f64 * step;
        let v = score(theta);
        if v > best.0 + 1e-9 {
            best = (v, theta);
        }
    }
    let score = if best.1 == initial.theta() {
        at_guess
    } else {
        best.0
    };
    (Pose2::new(initial.x(), initial.y(), best.1), score)
}

/// Freezes finished submaps with the branch-and-bound depth of `config`.
pub(crate) fn freeze_all(finished: Vec<ActiveSubmap>, depth: usize) -> Vec<Submap> {
    finished
        .into_iter()
        .filter_map(|s| s.freeze(depth))
        .collect()
}
