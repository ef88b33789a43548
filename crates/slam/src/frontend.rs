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
    max_speed_mps: f64,
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
            max_speed_mps: config.submaps.max_speed_mps,
        }
    }

    /// Path length of the local trajectory so far, metres.
    pub fn travel_m(&self) -> f64 {
        self.travel_m
    }

    /// Matches a scan: `odometry` is the logged `world_from_sensor` of the odometry (or `None`
    /// to predict no motion), `dt_secs` the time since the last scan (0 when unknown). Returns
    /// the local pose and the matcher's covariance.
    pub fn track(
        &mut self,
        points: &ScanPoints,
        odometry: Option<Pose2>,
        dt_secs: f64,
    ) -> (Pose2, Matrix3<f64>) {
        let delta = match (self.last_odometry, odometry) {
            (Some(a), Some(b)) => a.inverse() * b,
            _ => Pose2::identity(),
        };
        if odometry.is_some() {
            self.last_odometry = odometry;
        }
        let guess = self.local * delta;
        let (pose, covariance) = match self.active.front() {
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
                    let (from_odometry, score) = search(initial);
                    initial = from_odometry;
                    // A glitch in the odometry (a jump in the log, wheel slip) moves the guess
                    // out of every basin: when the increment turns beyond the search window,
                    // or moves more than two coarsest cells faster than the robot can drive,
                    // the pose of the last scan (no motion) is a second candidate, taken when
                    // it scores clearly better.
                    let coarsest = submap.map.levels().last().map_or(0.0, |l| l.resolution_m());
                    let step = delta.translation().norm();
                    if delta.theta().abs() > window
                        || (dt_secs > 0.0
                            && step > 2.0 * coarsest
                            && step > self.max_speed_mps * dt_secs)
                    {
                        let (standing, standing_score) = search(submap_from_local * self.local);
                        if standing_score > score + self.rotation_min_gain {
                            initial = standing;
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
                (submap.local_from_submap * p, c)
            }
            _ => (guess, Matrix3::from_diagonal_element(f64::INFINITY)),
        };
        self.travel_m += (self.local.inverse() * pose).translation().norm();
        self.local = pose;
        (pose, covariance)
    }

    /// Whether the last tracked pose has moved far enough from the last node to become one.
    pub fn wants_node(&self, config: &SlamConfig) -> bool {
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
        let mut finished = Vec::new();
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
