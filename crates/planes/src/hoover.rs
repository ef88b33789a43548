//! The segmentation-comparison protocol of Hoover et al. (1996, "An experimental
//! comparison of range image segmentation algorithms", IEEE TPAMI 18(7)) as used by
//! Schaefer (2020, § 11.4, Table 11.1) with tolerance `T = 0.8`.
//!
//! With overlap `O_gm` of ground-truth region `g` (`P_g` rays) and machine region `m`
//! (`P_m` rays): **correct** if `O ≥ T P_m` and `O ≥ T P_g`; **over-segmented** GT region
//! `g` into `m_1..m_x` (`x ≥ 2`) if `O_gm_i ≥ T P_m_i` for all `i` and `Σ O ≥ T P_g`;
//! **under-segmented** GT regions `g_1..g_x` in one `m` if `O_g_i m ≥ T P_g_i` for all
//! `i` and `Σ O ≥ T P_m`; GT regions in no class are **missed**, machine regions in none
//! are **noise** (the thesis' "spurious"). Classes are resolved in the order correct,
//! over, under (a region takes the first class it qualifies for; Hoover's tool resolves by
//! the largest average overlap, which agrees whenever the classes do not overlap).
//! Ground-truth labels below `min_gt_label` (SynPEB/SegComp: 10) are not planes.
//! `strict` reproduces the reference evaluator's `>` comparisons.
//!
//! Also: the k-value (fraction of GT plane rays in correctly detected regions; the reference
//! implementation divides by the rays of GT planes, Eq. (11.5) by all rays `K`) and the angle
//! deviation `α` over adjacent, correctly detected GT pairs.

use std::collections::HashMap;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::PlaneError;

/// Parameters of the comparison.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HooverParams {
    /// Tolerance `T` in `(0.5, 1]`.
    pub tolerance: f64,
    /// Use `>` instead of `≥` (the reference evaluator).
    pub strict: bool,
    /// Ground-truth labels below this value are not planes.
    pub min_gt_label: u32,
}

impl Default for HooverParams {
    fn default() -> Self {
        Self {
            tolerance: 0.8,
            strict: false,
            min_gt_label: 10,
        }
    }
}

/// The outcome of comparing one segmentation with its ground truth.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct HooverResult {
    /// Number of GT plane regions.
    pub gt_regions: usize,
    /// Number of machine-segmented regions.
    pub ms_regions: usize,
    /// Correct detections as (GT label, machine label).
    pub correct: Vec<(u32, u32)>,
    /// Over-segmented GT regions.
    pub over: usize,
    /// Under-segmentations (machine regions covering several GT regions).
    pub under: usize,
    /// Missed GT regions.
    pub missed: usize,
    /// Noise (spurious) machine regions.
    pub noise: usize,
    /// Rays of all GT plane regions.
    pub gt_points: usize,
    /// Rays of the correctly detected GT regions.
    pub correct_points: usize,
}

impl HooverResult {
    /// `f`: correct detections / GT regions (0 for no GT region).
    pub fn fraction_correct(&self) -> f64 {
        if self.gt_regions == 0 {
            0.0
        } else {
            self.correct.len() as f64 / self.gt_regions as f64
        }
    }

    /// `k`: rays of correctly detected GT regions / rays of all GT regions.
    pub fn k_value(&self) -> f64 {
        if self.gt_points == 0 {
            0.0
        } else {
            self.correct_points as f64 / self.gt_points as f64
        }
    }
}

/// Compares machine labels `ms` (`None` = unsegmented) with ground truth `gt` (`None` =
/// unlabelled), both one entry per ray of the same cloud.
pub fn compare(
    gt: &[Option<u32>],
    ms: &[Option<u32>],
    params: &HooverParams,
) -> Result<HooverResult, PlaneError> {
    if gt.len() != ms.len() {
        return Err(PlaneError::LengthMismatch {
            ground_truth: gt.len(),
            segmentation: ms.len(),
        });
    }
    if params.tolerance.is_nan() || params.tolerance <= 0.5 || params.tolerance > 1.0 {
        return Err(PlaneError::Parameter {
            name: "tolerance",
            reason: format!("must lie in (0.5, 1], got {}", params.tolerance),
        });
    }
    let mut gt_size: HashMap<u32, usize> = HashMap::new();
    let mut ms_size: HashMap<u32, usize> = HashMap::new();
    let mut overlap: HashMap<(u32, u32), usize> = HashMap::new();
    for (g, m) in gt.iter().zip(ms) {
        let g = g.filter(|&g| g >= params.min_gt_label);
        if let Some(g) = g {
            *gt_size.entry(g).or_default() += 1;
        }
        if let Some(m) = m {
            *ms_size.entry(*m).or_default() += 1;
            if let Some(g) = g {
                *overlap.entry((g, *m)).or_default() += 1;
            }
        }
    }
    let t = params.tolerance;
    let at_least = |o: usize, p: usize| {
        if params.strict {
            o as f64 > t * p as f64
        } else {
            o as f64 >= t * p as f64
        }
    };
    let mut gt_done: HashMap<u32, bool> = gt_size.keys().map(|&g| (g, false)).collect();
    let mut ms_done: HashMap<u32, bool> = ms_size.keys().map(|&m| (m, false)).collect();
    let mut result = HooverResult {
        gt_regions: gt_size.len(),
        ms_regions: ms_size.len(),
        gt_points: gt_size.values().sum(),
        ..HooverResult::default()
    };
    let mut pairs: Vec<((u32, u32), usize)> = overlap.into_iter().collect();
    pairs.sort_unstable();
    for &((g, m), o) in &pairs {
        if at_least(o, gt_size[&g]) && at_least(o, ms_size[&m]) && !gt_done[&g] && !ms_done[&m] {
            result.correct.push((g, m));
            result.correct_points += gt_size[&g];
            gt_done.insert(g, true);
            ms_done.insert(m, true);
        }
    }
    // Over-segmentation: per GT region, the machine regions mostly inside it.
    let mut by_gt: HashMap<u32, Vec<(u32, usize)>> = HashMap::new();
    let mut by_ms: HashMap<u32, Vec<(u32, usize)>> = HashMap::new();
    for &((g, m), o) in &pairs {
        by_gt.entry(g).or_default().push((m, o));
        by_ms.entry(m).or_default().push((g, o));
    }
    let mut gts: Vec<u32> = by_gt.keys().copied().collect();
    gts.sort_unstable();
    for g in gts {
        if gt_done[&g] {
            continue;
        }
        let parts: Vec<(u32, usize)> = by_gt[&g]
            .iter()
            .copied()
            .filter(|&(m, o)| !ms_done[&m] && at_least(o, ms_size[&m]))
            .collect();
        let sum: usize = parts.iter().map(|p| p.1).sum();
        if parts.len() >= 2 && at_least(sum, gt_size[&g]) {
            result.over += 1;
            gt_done.insert(g, true);
            for (m, _) in parts {
                ms_done.insert(m, true);
            }
        }
    }
    let mut mss: Vec<u32> = by_ms.keys().copied().collect();
    mss.sort_unstable();
    for m in mss {
        if ms_done[&m] {
            continue;
        }
        let parts: Vec<(u32, usize)> = by_ms[&m]
            .iter()
            .copied()
            .filter(|&(g, o)| !gt_done[&g] && at_least(o, gt_size[&g]))
            .collect();
        let sum: usize = parts.iter().map(|p| p.1).sum();
        if parts.len() >= 2 && at_least(sum, ms_size[&m]) {
            result.under += 1;
            ms_done.insert(m, true);
            for (g, _) in parts {
                gt_done.insert(g, true);
            }
        }
    }
    result.missed = gt_done.values().filter(|&&d| !d).count();
    result.noise = ms_done.values().filter(|&&d| !d).count();
    result.correct.sort_unstable();
    Ok(result)
}

/// Angle between two plane normals folded into `[0°, 90°]`.
pub fn folded_angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let c = (a.dot(b) / (a.norm() * b.norm())).clamp(-1.0, 1.0);
    let deg = c.acos().to_degrees();
    if deg > 90.0 { 180.0 - deg } else { deg }
}

/// Sum and count of the angle deviations `|θ_ms − θ_gt|` (degrees) over adjacent GT pairs
/// `(g1, g2, θ_gt)` whose regions are both correctly detected; `normal_of(m)` gives the
/// normal of machine region `m`. `α = sum / count`.
pub fn angle_deviation(
    result: &HooverResult,
    gt_pairs: &[(u32, u32, f64)],
    normal_of: impl Fn(u32) -> Option<Vector3<f64>>,
) -> (f64, usize) {
    let partner: HashMap<u32, u32> = result.correct.iter().copied().collect();
    let mut sum = 0.0;
    let mut count = 0;
    for &(g1, g2, theta_gt) in gt_pairs {
        let (Some(m1), Some(m2)) = (partner.get(&g1), partner.get(&g2)) else {
            continue;
        };
        let (Some(n1), Some(n2)) = (normal_of(*m1), normal_of(*m2)) else {
            continue;
        };
        let folded_gt = if theta_gt > 90.0 {
            180.0 - theta_gt
        } else {
            theta_gt
        };
        sum += (folded_angle_deg(&n1, &n2) - folded_gt).abs();
        count += 1;
    }
    (sum, count)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(v: &[i64]) -> Vec<Option<u32>> {
        v.iter().map(|&x| (x >= 0).then_some(x as u32)).collect()
    }

    #[test]
    fn classes_of_a_hand_made_case() {
        // GT: region 10 (10 rays), 11 (10 rays), 12 (10 rays), 13 (5 rays), label 3 (not a plane).
        let mut gt = vec![10; 10];
        gt.extend([11; 10]);
        gt.extend([12; 10]);
        gt.extend([13; 5]);
        gt.extend([3; 5]);
        // MS: 10 → region 0 except one ray (correct, 90 %); 11 → split 1/2 (over);
        // 12 + 13 → one region 3 (under); label-3 rays → region 4 (noise).
        let mut ms = vec![0; 9];
        ms.push(-1);
        ms.extend([1; 5]);
        ms.extend([2; 5]);
        ms.extend([3; 15]);
        ms.extend([4; 5]);
        let gt: Vec<Option<u32>> = gt.into_iter().map(Some).collect();
        let r = compare(&gt, &labels(&ms), &HooverParams::default()).expect("compare");
        assert_eq!(r.gt_regions, 4);
        assert_eq!(r.ms_regions, 5);
        assert_eq!(r.correct, vec![(10, 0)]);
        assert_eq!((r.over, r.under, r.missed, r.noise), (1, 1, 0, 1));
        assert_eq!((r.correct_points, r.gt_points), (10, 35));
        assert!((r.fraction_correct() - 0.25).abs() < 1e-12);
        // Strict comparison: 9 of 10 is still > 0.8; an 8-of-10 region is not.
        let mut ms2 = labels(&ms);
        ms2[8] = None;
        let strict = HooverParams {
            strict: true,
            ..HooverParams::default()
        };
        let r2 = compare(&gt, &ms2, &strict).expect("compare");
        assert!(r2.correct.is_empty());
        assert_eq!(r2.missed, 1);
        let r3 = compare(&gt, &ms2, &HooverParams::default()).expect("compare");
        assert_eq!(r3.correct, vec![(10, 0)]);
    }

    #[test]
    fn identical_labels_are_all_correct_and_errors_are_reported() {
        let gt: Vec<Option<u32>> = (0..100).map(|i| Some(10 + i / 10)).collect();
        let r = compare(&gt, &gt, &HooverParams::default()).expect("compare");
        assert_eq!(r.correct.len(), 10);
        assert_eq!((r.over, r.under, r.missed, r.noise), (0, 0, 0, 0));
        assert!((r.k_value() - 1.0).abs() < 1e-12);
        assert!(compare(&gt, &gt[1..], &HooverParams::default()).is_err());
        let bad = HooverParams {
            tolerance: 0.4,
            ..HooverParams::default()
        };
        assert!(compare(&gt, &gt, &bad).is_err());
    }

    #[test]
    fn angles_fold_and_average() {
        let x = Vector3::x();
        let tilted = Vector3::new(-(0.5f64).cos(), (0.5f64).sin(), 0.0);
        assert!((folded_angle_deg(&x, &tilted) - 0.5f64.to_degrees()).abs() < 1e-9);
        let r = HooverResult {
            correct: vec![(10, 0), (11, 1)],
            ..HooverResult::default()
        };
        let normals = [x, Vector3::y()];
        let (sum, count) = angle_deviation(&r, &[(10, 11, 88.0), (10, 12, 30.0)], |m| {
            normals.get(m as usize).copied()
        });
        assert_eq!(count, 1);
        assert!((sum - 2.0).abs() < 1e-9);
    }
}
