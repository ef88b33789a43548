//! Baseline: iterative MSAC plane detection (Torr and Zisserman 2000), as the thesis'
//! MATLAB baseline runs `pcfitplane` repeatedly (Schaefer 2020 § 11.4): detect the plane
//! with the least truncated-quadratic cost among random three-point hypotheses, remove its
//! inliers (orthogonal distance ≤ `max_distance_m`), repeat until at most
//! `remaining_fraction` of the returned rays are left or no plane with `min_points`
//! inliers is found. Hypotheses are scored on a fixed-size random subsample of the
//! remaining rays. Every detected plane is refitted on the exact radial residuals of its
//! inliers so that the RMSE is comparable with PPE's. Seeded: same input, same output.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::PlaneError;
use crate::fit::{PlaneFit, fit_members};
use crate::ppe::{Plane, Segmentation};

/// Parameters of [`msac`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MsacParams {
    /// Inlier threshold on the orthogonal point–plane distance (m).
    pub max_distance_m: f64,
    /// Stop when at most this fraction of the returned rays is left.
    pub remaining_fraction: f64,
    /// Hypotheses per detected plane.
    pub iterations: usize,
    /// Rays used to score a hypothesis.
    pub score_sample: usize,
    /// Smallest accepted plane (rays).
    pub min_points: usize,
    /// Random seed.
    pub seed: u64,
}

impl Default for MsacParams {
    fn default() -> Self {
        Self {
            max_distance_m: 0.04,
            remaining_fraction: 0.1,
            iterations: 300,
            score_sample: 2000,
            min_points: 10,
            seed: 0,
        }
    }
}

impl MsacParams {
    /// The parameters used on SynPEB-style scans: inlier distance 5 cm, stop at 10 %
    /// remaining rays (not grid-searched).
    pub fn synpeb() -> Self {
        Self {
            max_distance_m: 0.05,
            remaining_fraction: 0.1,
            ..Self::default()
        }
    }
}

/// Iterative MSAC on a row-major grid of endpoints (NaN = no return).
pub fn msac(
    points: &[Vector3<f64>],
    width: usize,
    height: usize,
    params: &MsacParams,
) -> Result<Segmentation, PlaneError> {
    PlaneError::check_organized(width, height, points.len())?;
    if params.max_distance_m.is_nan() || params.max_distance_m <= 0.0 {
        return Err(PlaneError::Parameter {
            name: "max_distance_m",
            reason: format!("must be positive, got {}", params.max_distance_m),
        });
    }
    if params.remaining_fraction.is_nan() || !(0.0..=1.0).contains(&params.remaining_fraction) {
        return Err(PlaneError::Parameter {
            name: "remaining_fraction",
            reason: format!("must lie in [0, 1], got {}", params.remaining_fraction),
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut remaining: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].iter().all(|x| x.is_finite()) && points[i].norm_squared() > 0.0)
        .collect();
    let total = remaining.len();
    let t2 = params.max_distance_m * params.max_distance_m;
    let mut planes = Vec::new();
    let mut sample = Vec::with_capacity(params.score_sample);
    while remaining.len() >= 3 && remaining.len() as f64 > params.remaining_fraction * total as f64
    {
        sample.clear();
        for _ in 0..params.score_sample.min(remaining.len()) {
            sample.push(points[remaining[rng.random_range(0..remaining.len())]]);
        }
        let mut best: Option<(f64, Vector3<f64>, f64)> = None; // (cost, unit normal, offset)
        for _ in 0..params.iterations {
            let a = points[remaining[rng.random_range(0..remaining.len())]];
            let b = points[remaining[rng.random_range(0..remaining.len())]];
            let c = points[remaining[rng.random_range(0..remaining.len())]];
            let Some(n) = (b - a).cross(&(c - a)).try_normalize(1e-12) else {
                continue;
            };
            let d = n.dot(&a);
            let cost: f64 = sample.iter().map(|p| (n.dot(p) - d).powi(2).min(t2)).sum();
            if best.is_none_or(|(bc, _, _)| cost < bc) {
                best = Some((cost, n, d));
            }
        }
        let Some((_, n, d)) = best else { break };
        let (inliers, rest): (Vec<usize>, Vec<usize>) = remaining
            .iter()
            .partition(|&&i| (n.dot(&points[i]) - d).powi(2) <= t2);
        if inliers.len() < params.min_points.max(4) {
            break;
        }
        remaining = rest;
        let members: Vec<Vector3<f64>> = inliers.iter().map(|&i| points[i]).collect();
        let fit = fit_members(&members).unwrap_or(PlaneFit {
            w: if d.abs() > 0.0 { n / d } else { n },
            sse: f64::INFINITY,
            n: members.len(),
        });
        planes.push(Plane {
            index: inliers,
            fit,
        });
    }
    let steps = planes.len();
    Ok(Segmentation::from_planes(
        width,
        height,
        points.len(),
        planes,
        steps,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes::wall_and_floor;

    #[test]
    fn finds_two_planes_and_partitions() {
        let (w, h) = (40, 30);
        let pts = wall_and_floor(w, h, 0.03, 0.1);
        let params = MsacParams {
            max_distance_m: 0.01,
            remaining_fraction: 0.02,
            ..MsacParams::default()
        };
        let seg = msac(&pts, w, h, &params).expect("msac");
        assert_eq!(seg.planes.len(), 2);
        let labelled = seg.labels.iter().filter(|l| l.is_some()).count();
        assert_eq!(
            labelled,
            seg.planes.iter().map(|p| p.index.len()).sum::<usize>()
        );
        assert!(seg.rmse_m() < 0.01);
        // Same seed, same answer.
        assert_eq!(msac(&pts, w, h, &params).expect("msac").labels, seg.labels);
        assert!(msac(&pts, w + 1, h, &params).is_err());
    }
}
