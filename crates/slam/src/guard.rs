//! Guards of the front-end (ours; none of this is in the theses): an odometry increment that
//! the robot cannot have driven is not trusted, and a scan match is judged before it is
//! believed.
//!
//! * **Odometry outliers.** An increment moving faster than
//!   [`TrackingGuardConfig::max_speed_mps`] or turning faster than
//!   [`TrackingGuardConfig::max_turn_rate_rad_s`] over the time between the two scans (plus a
//!   fixed allowance for time-stamp jitter) is treated as unknown: the guess is the last pose
//!   (no motion), searched in rotation as any guess is, and the logged increment is only a
//!   second candidate, taken when it scores clearly better (the reverse of the front-end's
//!   handling of a large but plausible increment).
//! * **Match failure.** A match fails when the mean occupancy probability of its points on the
//!   finest level is below [`TrackingGuardConfig::min_score`], when its information is singular,
//!   or when it moved further from the guess than [`TrackingGuardConfig::max_correction_m`] /
//!   [`TrackingGuardConfig::max_correction_rad`]. The front-end then keeps the odometry guess
//!   and does not insert the scan into any submap (no submap is built across a jump); the
//!   sequential edges into and out of such a node get the odometry's uncertainty
//!   [`TrackingGuardConfig::fallback_sigma`] instead of the matcher's. The next scan is
//!   matched against the same submap from the odometry guess; when matching keeps failing for
//!   [`TrackingGuardConfig::max_failed_travel_m`], the active submaps are finished and a new
//!   one starts at the odometry's pose.
//! * **Degenerate match.** A match whose translational covariance is elongated (ratio of its
//!   eigenvalues below [`TrackingGuardConfig::degenerate_ratio`]: a corridor without features
//!   along it) keeps the match across the corridor and the guess along it.

use nalgebra::{Matrix2, Matrix3, Vector2};
use raypath_geometry::Pose2;
use raypath_reflectivity::{GridLevel, ScanPoints};
use serde::{Deserialize, Serialize};

use crate::config::Sigmas;
use crate::error::{Result, SlamError, require_positive};

/// Parameters of the front-end's guards (see the module docs). Defaults are ours, chosen on
/// the raw Intel and MIT CSAIL logs (`slam_log` example) so that the guards stay silent on
/// scans the front-end matches well there and catch the injected faults of the simulated
/// tests (`tests/robustness.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackingGuardConfig {
    /// A match fails when the mean occupancy probability (finest level, bilinear) at its points
    /// is below this (`None`: no score test). Unobserved cells count 0.5, free space less.
    /// Default 0.35 (ours): in our runs on the raw Intel and MIT CSAIL logs no match scored
    /// below 0.56 and 0.44; a scan placed in free space scores well below 0.35.
    pub min_score: Option<f64>,
    /// A match fails when it moved further than this from its guess, metres. Default 0.5 m
    /// (ours: ten finest cells; on the raw Intel and MIT CSAIL logs no match moved more than
    /// 0.27 m from its guess).
    pub max_correction_m: f64,
    /// … or turned further than this from its guess (after the rotation search), radians.
    /// Default 0.35 rad (20°, ours; there, no match turned more than 0.16 rad).
    pub max_correction_rad: f64,
    /// A match is degenerate when the smaller eigenvalue of its translational covariance is
    /// larger than the larger one times `1 / degenerate_ratio`, i.e. when
    /// `σ²_min / σ²_max < degenerate_ratio` (`None`: no test). Default 0.01 (ours): the
    /// smallest ratio of a match on the raw Intel and MIT CSAIL logs was 0.07 and 0.03, so the
    /// test keeps silent there and acts on a corridor with no feature in range.
    pub degenerate_ratio: Option<f64>,
    /// An odometry increment faster than this over the time between two scans is an outlier,
    /// m/s (`None`: no test). Default 2 m/s (ours): with the allowance it flags no increment of
    /// the raw Intel and MIT CSAIL logs (whose jumps the second, standing guess of the
    /// front-end already handles), and a 1 m jump between scans 0.05 s apart. Without the
    /// allowance it also decides when that standing guess is tried for a translation: only
    /// for a step of more than two coarsest cells faster than this (never for a plain step: in
    /// a corridor without features along it the last pose fits the scan as well, and with
    /// scans far apart the robot stood still; `tests/corridor.rs`).
    pub max_speed_mps: Option<f64>,
    /// The speed bound grows with the speed the odometry has shown lately: it is the larger
    /// of [`max_speed_mps`](Self::max_speed_mps) and this factor times the recent speed (an
    /// average of the plausible increments over the last [`SPEED_WINDOW_S`]). Default 2
    /// (ours): an outdoor vehicle at 3–5 m/s (the raw UAL campus log) is not an outlier
    /// throughout, and a jump of a metre between scans still is.
    pub recent_speed_factor: f64,
    /// … or turning faster than this, rad/s. Default 3 rad/s (ours, as above).
    pub max_turn_rate_rad_s: f64,
    /// Allowance added to both bounds, for time-stamp jitter: `(metres, radians)`. Default
    /// (0.2 m, 0.2 rad) (ours).
    pub allowance: [f64; 2],
    /// After this much path on odometry alone (consecutive failed matches), the active
    /// submaps are finished and a new one starts at the odometry's pose, metres. Shorter
    /// failures leave the submaps as they are (failed scans are never inserted) and the next
    /// scan is matched against the same submap from the odometry guess. Default 2 m (ours:
    /// the odometry of the benchmark logs drifts by a few centimetres over 2 m, well within the
    /// matcher's basin).
    pub max_failed_travel_m: f64,
    /// σ of the sequential edge into a node after a failed match: the odometry's uncertainty
    /// over one step. Default (0.25 m, 0.25 m, 5°) (ours).
    pub fallback_sigma: Sigmas,
}

impl Default for TrackingGuardConfig {
    fn default() -> Self {
        Self {
            min_score: Some(0.35),
            max_correction_m: 0.5,
            max_correction_rad: 0.35,
            degenerate_ratio: Some(0.01),
            max_speed_mps: Some(2.0),
            recent_speed_factor: 2.0,
            max_turn_rate_rad_s: 3.0,
            allowance: [0.2, 0.2],
            max_failed_travel_m: 2.0,
            fallback_sigma: [0.25, 0.25, 5f64.to_radians()],
        }
    }
}

impl TrackingGuardConfig {
    /// Checks the parameters (errors name the field).
    pub fn validate(&self) -> Result<()> {
        if let Some(s) = self.min_score {
            if !(0.0..1.0).contains(&s) {
                return Err(SlamError::InvalidParameter {
                    name: "tracking.min_score",
                    reason: format!("must lie in [0, 1), got {s}"),
                });
            }
        }
        if let Some(r) = self.degenerate_ratio {
            if !(r > 0.0 && r < 1.0) {
                return Err(SlamError::InvalidParameter {
                    name: "tracking.degenerate_ratio",
                    reason: format!("must lie in (0, 1), got {r}"),
                });
            }
        }
        require_positive("tracking.max_correction_m", self.max_correction_m)?;
        require_positive("tracking.max_correction_rad", self.max_correction_rad)?;
        if let Some(v) = self.max_speed_mps {
            require_positive("tracking.max_speed_mps", v)?;
        }
        require_positive("tracking.recent_speed_factor", self.recent_speed_factor)?;
        require_positive("tracking.max_turn_rate_rad_s", self.max_turn_rate_rad_s)?;
        require_positive("tracking.max_failed_travel_m", self.max_failed_travel_m)?;
        for v in self.allowance {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(SlamError::InvalidParameter {
                    name: "tracking.allowance",
                    reason: format!("must be finite and ≥ 0, got {v}"),
                });
            }
        }
        for v in self.fallback_sigma {
            require_positive("tracking.fallback_sigma", v)?;
        }
        Ok(())
    }

    /// The speed bound, m/s, given the recent speed (`None`: no speed test).
    pub fn speed_bound(&self, recent_speed_mps: f64) -> Option<f64> {
        self.max_speed_mps
            .map(|v| v.max(self.recent_speed_factor * recent_speed_mps))
    }

    /// Whether the odometry increment `delta` over `dt` seconds is one the robot can have
    /// driven, after driving at `recent_speed_mps` lately (always true without a speed bound
    /// or a usable `dt`).
    pub fn plausible(&self, delta: &Pose2, dt: f64, recent_speed_mps: f64) -> bool {
        let Some(v) = self.speed_bound(recent_speed_mps) else {
            return true;
        };
        if !(dt.is_finite() && dt >= 0.0) {
            return true;
        }
        delta.translation().norm() <= v * dt + self.allowance[0]
            && delta.theta().abs() <= self.max_turn_rate_rad_s * dt + self.allowance[1]
    }
}

/// The window of the recent speed ([`TrackingGuardConfig::recent_speed_factor`]), seconds.
pub const SPEED_WINDOW_S: f64 = 2.0;

/// The recent speed after a plausible increment of `step` metres over `dt` seconds: an
/// exponential average with the time constant [`SPEED_WINDOW_S`].
pub(crate) fn update_recent_speed(recent: f64, step: f64, dt: f64) -> f64 {
    if !(dt.is_finite() && dt > 0.0 && step.is_finite()) {
        return recent;
    }
    let alpha = (dt / SPEED_WINDOW_S).min(1.0);
    recent + alpha * (step / dt - recent)
}

/// Counters of the front-end's guards.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TrackingStats {
    /// Odometry increments treated as unknown (implausibly fast).
    pub odometry_outliers: usize,
    /// Matches that failed (pose kept from the guess).
    pub failed: usize,
    /// Matches kept from the guess along a degenerate direction.
    pub degenerate: usize,
    /// Times the active submaps were finished early after a failed match.
    pub submap_breaks: usize,
}

/// How the front-end's match of one scan went.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MatchStatus {
    /// Believed as matched (or nothing to match against yet).
    #[default]
    Good,
    /// Good, but translation along one direction was kept from the guess.
    Degenerate,
    /// Not believed: the pose is the guess.
    Failed,
}

/// Mean occupancy probability of `points` placed at `pose` on `level` (points outside the grid
/// count as unobserved, 0.5); 0 without points.
pub(crate) fn match_score(level: &GridLevel, points: &ScanPoints, pose: &Pose2) -> f64 {
    let (c, s) = (pose.theta().cos(), pose.theta().sin());
    let mut sum = 0.0;
    let pts = points.points();
    for p in pts {
        let x = c * p[0] - s * p[1] + pose.x();
        let y = s * p[0] + c * p[1] + pose.y();
        sum += level.occupancy(x, y).map_or(0.5, |m| m.value);
    }
    if pts.is_empty() {
        0.0
    } else {
        sum / pts.len() as f64
    }
}

/// The translational covariance's eigenvalue ratio `σ²_min / σ²_max` and the unit direction of
/// `σ²_max` (the weakly constrained one); `None` when the covariance is not finite.
pub(crate) fn conditioning(covariance: &Matrix3<f64>) -> Option<(f64, Vector2<f64>)> {
    let c: Matrix2<f64> = covariance.fixed_view::<2, 2>(0, 0).into_owned();
    if !c.iter().all(|v| v.is_finite()) {
        return None;
    }
    let sym = (c + c.transpose()) * 0.5;
    let eig = sym.symmetric_eigen();
    let (i_max, i_min) = if eig.eigenvalues[0] >= eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    let (max, min) = (eig.eigenvalues[i_max], eig.eigenvalues[i_min]);
    if max <= 0.0 {
        return None;
    }
    let dir = eig.eigenvectors.column(i_max).into_owned();
    Some((min.max(0.0) / max, dir))
}

/// The verdict on one match: `matched` from `guess` with `covariance`, `score` as
/// [`match_score`]. Returns the pose to keep and the status.
pub(crate) fn judge(
    config: &TrackingGuardConfig,
    guess: Pose2,
    matched: Pose2,
    covariance: &Matrix3<f64>,
    score: f64,
) -> (Pose2, MatchStatus) {
    let d = guess.inverse() * matched;
    let failed = !matched.is_finite()
        || config.min_score.is_some_and(|s| score < s)
        || d.translation().norm() > config.max_correction_m
        || d.theta().abs() > config.max_correction_rad;
    let Some((ratio, weak)) = conditioning(covariance) else {
        return (guess, MatchStatus::Failed);
    };
    if failed {
        return (guess, MatchStatus::Failed);
    }
    if config.degenerate_ratio.is_some_and(|r| ratio < r) {
        // Keep the guess along the weak direction, the match across it (frame of the levels).
        let shift = matched.translation() - guess.translation();
        let kept = shift - weak * weak.dot(&shift);
        let pose = Pose2::new(guess.x() + kept.x, guess.y() + kept.y, matched.theta());
        return (pose, MatchStatus::Degenerate);
    }
    (matched, MatchStatus::Good)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odometry_faster_than_the_robot_is_implausible() {
        let c = TrackingGuardConfig::default();
        assert!(c.plausible(&Pose2::new(0.1, 0.0, 0.05), 0.1, 0.0));
        assert!(!c.plausible(&Pose2::new(1.0, 0.0, 0.0), 0.1, 0.0));
        assert!(!c.plausible(&Pose2::new(0.0, 0.0, 20f64.to_radians()), 0.0, 0.0));
        // After a 5 s gap in the log, 2 m is possible.
        assert!(c.plausible(&Pose2::new(2.0, 0.0, 0.3), 5.0, 0.0));
    }

    #[test]
    fn a_fast_vehicle_raises_the_bound_and_a_jump_stays_implausible() {
        let c = TrackingGuardConfig::default();
        // 0.4 m every 0.05 s (8 m/s): implausible from rest, plausible at speed.
        let step = Pose2::new(0.4, 0.0, 0.0);
        assert!(!c.plausible(&step, 0.05, 0.0));
        let mut recent = 0.0;
        for _ in 0..1000 {
            recent = update_recent_speed(recent, 0.4, 0.05);
        }
        assert!((recent - 8.0).abs() < 1e-3);
        assert!(c.plausible(&step, 0.05, recent));
        // A 1 m jump on top of a step is still an outlier.
        assert!(!c.plausible(&Pose2::new(1.4, 0.0, 0.0), 0.05, recent));
        assert_eq!(c.speed_bound(recent), Some(2.0 * recent));
    }

    #[test]
    fn a_corridor_keeps_the_guess_along_it_and_a_far_match_fails() {
        let c = TrackingGuardConfig::default();
        // Covariance long along x (a corridor along x).
        let cov = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1e-4, 1e-5));
        let guess = Pose2::new(1.0, 2.0, 0.1);
        let matched = Pose2::new(1.3, 2.05, 0.12);
        let (p, status) = judge(&c, guess, matched, &cov, 0.8);
        assert_eq!(status, MatchStatus::Degenerate);
        assert!((p.x() - 1.0).abs() < 1e-9 && (p.y() - 2.05).abs() < 1e-9);
        assert!((p.theta() - 0.12).abs() < 1e-12);
        let round = Matrix3::from_diagonal_element(1e-4);
        assert_eq!(judge(&c, guess, matched, &round, 0.8).1, MatchStatus::Good);
        let far = Pose2::new(2.0, 2.0, 0.1);
        assert_eq!(
            judge(&c, guess, far, &round, 0.8),
            (guess, MatchStatus::Failed)
        );
        assert_eq!(
            judge(&c, guess, matched, &round, 0.1).1,
            MatchStatus::Failed
        );
        let singular = Matrix3::from_diagonal_element(f64::INFINITY);
        assert_eq!(
            judge(&c, guess, matched, &singular, 0.8).1,
            MatchStatus::Failed
        );
    }
}
