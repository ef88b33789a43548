//! Ground-truth revisits from positions (Khan 2017, §4.6.2: "less than 5 m") or planar poses
//! (distance and overlapping fields of view), with an exclusion window in frames and seconds.

use std::collections::HashMap;

use raypath_geometry::{Pose2, wrap_angle};
use serde::{Deserialize, Serialize};

use crate::error::require_positive;
use crate::{PlaceError, Result};

/// Which pairs of frames are close enough in time to be excluded from the evaluation (ours:
/// neighbouring frames trivially look alike and are no revisit).
///
/// A pair `(i, j)` is *evaluable* when it is outside **both** windows:
/// `|i − j| ≥ frames` **and** `|t_i − t_j| ≥ seconds` (the second test only when timestamps are
/// given).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Exclusion {
    /// Smallest index distance of an evaluable pair. Default 50 (ours).
    pub frames: usize,
    /// Smallest time distance of an evaluable pair, seconds. Default 30 (ours).
    pub seconds: f64,
}

impl Default for Exclusion {
    fn default() -> Self {
        Self {
            frames: 50,
            seconds: 30.0,
        }
    }
}

impl Exclusion {
    /// Only the diagonal is excluded (an unordered set of observations, kidnapped robot).
    pub fn none() -> Self {
        Self {
            frames: 1,
            seconds: 0.0,
        }
    }
}

/// The true revisits of a sequence of frames: for each frame, the evaluable frames at the same
/// place.
///
/// Frames whose position is not finite have no ground truth: every pair with them is
/// non-evaluable (neither a revisit nor a false match).
#[derive(Clone, Debug)]
pub struct GroundTruth {
    known: Vec<bool>,
    times: Option<Vec<f64>>,
    exclusion: Exclusion,
    /// Sorted evaluable revisits of each frame (both directions).
    partners: Vec<Vec<usize>>,
    pairs: usize,
}

impl GroundTruth {
    /// Two frames show the same place when their positions are less than `radius_m` apart
    /// (Khan 2017, §4.6.2, 5 m). `times` (seconds, one per frame) enables the time window of
    /// `exclusion`.
    pub fn from_positions(
        positions: &[[f64; 3]],
        times: Option<&[f64]>,
        radius_m: f64,
        exclusion: Exclusion,
    ) -> Result<Self> {
        Self::build(positions, times, radius_m, exclusion, |_, _| true)
    }

    /// Two planar poses show the same place when they are less than `radius_m` apart and their
    /// fields of view overlap: the headings differ by at most `fov_rad / 2`, so that each
    /// sensor's optical axis lies inside the other's field of view and the two views share at
    /// least half their angular extent (ours; for a 180° laser, headings within ±90°).
    /// `fov_rad ≥ 2π` (a 360° sensor) ignores the headings.
    pub fn from_planar_poses(
        poses: &[Pose2],
        times: Option<&[f64]>,
        radius_m: f64,
        fov_rad: f64,
        exclusion: Exclusion,
    ) -> Result<Self> {
        require_positive("fov_rad", fov_rad)?;
        let positions: Vec<[f64; 3]> = poses
            .iter()
            .map(|p| {
                if p.is_finite() {
                    [p.x(), p.y(), 0.0]
                } else {
                    [f64::NAN; 3]
                }
            })
            .collect();
        let half = fov_rad / 2.0;
        let omni = fov_rad >= std::f64::consts::TAU;
        Self::build(&positions, times, radius_m, exclusion, |i, j| {
            omni || wrap_angle(poses[i].theta() - poses[j].theta()).abs() <= half
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.known.len()
    }

    /// True when there are no frames.
    pub fn is_empty(&self) -> bool {
        self.known.is_empty()
    }

    /// The exclusion window.
    pub fn exclusion(&self) -> Exclusion {
        self.exclusion
    }

    /// True when the pair is evaluated: both frames have ground truth, `i ≠ j`, and the pair
    /// is outside the exclusion window. False for indices out of range.
    pub fn is_evaluable(&self, i: usize, j: usize) -> bool {
        if i == j || i >= self.len() || j >= self.len() || !self.known[i] || !self.known[j] {
            return false;
        }
        if i.abs_diff(j) < self.exclusion.frames {
            return false;
        }
        match &self.times {
            Some(t) => (t[i] - t[j]).abs() >= self.exclusion.seconds,
            None => true,
        }
    }

    /// True when `(i, j)` is an evaluable pair at the same place.
    pub fn is_revisit(&self, i: usize, j: usize) -> bool {
        self.partners
            .get(i)
            .is_some_and(|p| p.binary_search(&j).is_ok())
    }

    /// The evaluable frames at the same place as frame `i`, ascending (empty out of range).
    pub fn revisits(&self, i: usize) -> &[usize] {
        self.partners.get(i).map_or(&[], Vec::as_slice)
    }

    /// True when frame `t` revisits an earlier frame (an evaluable revisit `j < t`).
    pub fn has_earlier_revisit(&self, t: usize) -> bool {
        self.revisits(t).first().is_some_and(|&j| j < t)
    }

    /// Number of unordered evaluable revisit pairs.
    pub fn true_pairs(&self) -> usize {
        self.pairs
    }

    fn build(
        positions: &[[f64; 3]],
        times: Option<&[f64]>,
        radius_m: f64,
        exclusion: Exclusion,
        same_view: impl Fn(usize, usize) -> bool,
    ) -> Result<Self> {
        require_positive("radius_m", radius_m)?;
        if !(exclusion.seconds.is_finite() && exclusion.seconds >= 0.0) {
            return Err(PlaceError::InvalidParameter {
                name: "exclusion.seconds",
                reason: format!("must be finite and non-negative, got {}", exclusion.seconds),
            });
        }
        if let Some(t) = times {
            if t.len() != positions.len() {
                return Err(PlaceError::BadInput(format!(
                    "{} timestamps for {} frames",
                    t.len(),
                    positions.len()
                )));
            }
            if let Some(k) = t.iter().position(|x| !x.is_finite()) {
                return Err(PlaceError::BadInput(format!(
                    "timestamp of frame {k} is not finite"
                )));
            }
        }
        let known: Vec<bool> = positions
            .iter()
            .map(|p| p.iter().all(|c| c.is_finite()))
            .collect();
        let mut truth = Self {
            known,
            times: times.map(<[f64]>::to_vec),
            exclusion,
            partners: vec![Vec::new(); positions.len()],
            pairs: 0,
        };
        // A uniform grid of cells of side `radius_m`: the neighbours of a point lie in its
        // cell and the 26 around it.
        let cell = |p: &[f64; 3]| p.map(|c| (c / radius_m).floor() as i64);
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (i, p) in positions.iter().enumerate() {
            if truth.known[i] {
                grid.entry(cell(p)).or_default().push(i);
            }
        }
        let r2 = radius_m * radius_m;
        for (i, p) in positions.iter().enumerate() {
            if !truth.known[i] {
                continue;
            }
            let c = cell(p);
            for offset in NEIGHBOURS {
                let key = [c[0] + offset[0], c[1] + offset[1], c[2] + offset[2]];
                let Some(members) = grid.get(&key) else {
                    continue;
                };
                for &j in members {
                    if j <= i || !truth.is_evaluable(i, j) {
                        continue;
                    }
                    let q = &positions[j];
                    let d2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                    if d2 < r2 && same_view(i, j) {
                        truth.partners[i].push(j);
                        truth.partners[j].push(i);
                        truth.pairs += 1;
                    }
                }
            }
        }
        for p in &mut truth.partners {
            p.sort_unstable();
        }
        Ok(truth)
    }
}

/// The 27 cell offsets of a 3×3×3 neighbourhood.
const NEIGHBOURS: [[i64; 3]; 27] = {
    let mut out = [[0i64; 3]; 27];
    let mut k = 0;
    while k < 27 {
        out[k] = [
            (k % 3) as i64 - 1,
            ((k / 3) % 3) as i64 - 1,
            (k / 9) as i64 - 1,
        ];
        k += 1;
    }
    out
};

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: all pairs by brute force.
    fn brute(positions: &[[f64; 3]], radius: f64, frames: usize) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for i in 0..positions.len() {
            for j in i + 1..positions.len() {
                let d: f64 = (0..3)
                    .map(|k| (positions[i][k] - positions[j][k]).powi(2))
                    .sum();
                if j - i >= frames && d.sqrt() < radius {
                    out.push((i, j));
                }
            }
        }
        out
    }

    #[test]
    fn square_loop_trajectory_matches_brute_force() {
        // Two laps of a 20 m square, 1 m steps: frames k and k + 80 are at the same place.
        let lap: Vec<[f64; 3]> = (0..80)
            .map(|k| {
                let s = k as f64;
                match k / 20 {
                    0 => [s, 0.0, 0.0],
                    1 => [20.0, s - 20.0, 0.0],
                    2 => [60.0 - s, 20.0, 0.0],
                    _ => [0.0, 80.0 - s, 0.0],
                }
            })
            .collect();
        let positions: Vec<[f64; 3]> = lap.iter().chain(&lap).copied().collect();
        let exclusion = Exclusion {
            frames: 10,
            seconds: 0.0,
        };
        let gt = GroundTruth::from_positions(&positions, None, 2.5, exclusion).unwrap();
        let expected = brute(&positions, 2.5, 10);
        let mut got = Vec::new();
        for i in 0..positions.len() {
            got.extend(gt.revisits(i).iter().filter(|&&j| j > i).map(|&j| (i, j)));
        }
        assert_eq!(got, expected);
        assert_eq!(gt.true_pairs(), expected.len());
        assert!(gt.is_revisit(85, 5) && gt.is_revisit(5, 85));
        assert!(!gt.is_revisit(5, 7), "inside the 10-frame window");
        assert!(gt.has_earlier_revisit(85) && !gt.has_earlier_revisit(5));
    }

    #[test]
    fn fov_rule_and_time_window() {
        use std::f64::consts::PI;
        let poses = [
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(0.5, 0.0, 0.4 * PI), // 72°: within ±90° → same view
            Pose2::new(0.0, 0.5, PI),       // reversed → different view
            Pose2::new(1.0, 0.0, -0.5 * PI), // exactly 90°: overlapping
            Pose2::new(f64::NAN, 0.0, 0.0), // no ground truth
            Pose2::new(0.0, 0.0, 0.0),      // same pose but 1 s after frame 0
        ];
        let times = [0.0, 100.0, 200.0, 300.0, 400.0, 1.0];
        let ex = Exclusion {
            frames: 1,
            seconds: 30.0,
        };
        let gt = GroundTruth::from_planar_poses(&poses, Some(&times), 2.0, PI, ex).unwrap();
        assert!(gt.is_revisit(0, 1));
        assert!(!gt.is_revisit(0, 2) && !gt.is_revisit(1, 2));
        assert!(gt.is_revisit(0, 3));
        assert!(!gt.is_revisit(1, 3), "162° apart");
        assert!(!gt.is_evaluable(0, 4) && !gt.is_revisit(0, 4));
        assert!(!gt.is_evaluable(0, 5), "1 s apart, inside the 30 s window");
        assert!(gt.is_revisit(1, 5));
        // A 360° sensor ignores headings.
        let omni = GroundTruth::from_planar_poses(&poses, Some(&times), 2.0, 2.0 * PI, ex).unwrap();
        assert!(omni.is_revisit(0, 2) && omni.is_revisit(1, 3));
    }

    #[test]
    fn both_windows_must_be_passed() {
        let positions = [[0.0; 3]; 4];
        let times = [0.0, 100.0, 101.0, 120.0];
        let ex = Exclusion {
            frames: 2,
            seconds: 50.0,
        };
        let gt = GroundTruth::from_positions(&positions, Some(&times), 1.0, ex).unwrap();
        assert!(!gt.is_evaluable(0, 1), "1 frame apart");
        assert!(!gt.is_evaluable(1, 3), "2 frames but only 20 s apart");
        assert!(gt.is_revisit(0, 2) && gt.is_revisit(0, 3));
        assert_eq!(gt.true_pairs(), 2);
    }

    #[test]
    fn ten_thousand_frames_three_laps() {
        // Three laps of a circle of circumference 1000 m, 0.3 m steps (10 002 frames).
        let n = 10_002;
        let lap = n / 3;
        let radius = 1000.0 / std::f64::consts::TAU;
        let positions: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let a = (k % lap) as f64 / lap as f64 * std::f64::consts::TAU;
                [radius * a.cos(), radius * a.sin(), 0.0]
            })
            .collect();
        let ex = Exclusion {
            frames: 50,
            seconds: 0.0,
        };
        let gt = GroundTruth::from_positions(&positions, None, 5.0, ex).unwrap();
        // Less than 5 m: 16 steps of 0.3 m either way, on each other lap; the frame's own
        // neighbours are inside the 50-frame window.
        assert!(gt.is_revisit(lap + 10, 10) && gt.is_revisit(2 * lap + 10, 10));
        assert!((0..lap - 20).all(|t| !gt.has_earlier_revisit(t)));
        assert!((lap..n).all(|t| gt.has_earlier_revisit(t)));
        assert_eq!(gt.revisits(lap + 500).len(), 2 * 33);
    }

    #[test]
    fn bad_parameters_are_errors() {
        let p = [[0.0; 3]; 2];
        assert!(GroundTruth::from_positions(&p, None, 0.0, Exclusion::none()).is_err());
        assert!(GroundTruth::from_positions(&p, Some(&[0.0]), 1.0, Exclusion::none()).is_err());
        let ex = Exclusion {
            frames: 1,
            seconds: f64::NAN,
        };
        assert!(GroundTruth::from_positions(&p, None, 1.0, ex).is_err());
    }
}
