//! Plane extraction shared by `eval synpeb` and `eval segcomp`: the three extractors of
//! Table 11.1 of Schaefer (2020) with their parameters ([`Method`]), the parameter grids the
//! evaluations search ([`ppe_grid`], [`peac_grid`], [`msac_grid`]) and the per-scan scores
//! of the Hoover et al. (1996) protocol with T = 0.8 ([`hoover_score`]).

use std::time::Instant;

use anyhow::{Context, Result};
use nalgebra::Vector3;
use raypath_geometry::PointCloud;
use raypath_planes::angle_deviation;
use raypath_planes::{
    HooverParams, MsacParams, PeacParams, PpeParams, Segmentation, compare, extract,
};

/// An extractor with its parameters (serde: the results of staged evaluations carry it).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Method {
    /// PPE, `raypath_planes::extract`.
    Ppe(PpeParams),
    /// The PEAC-style baseline.
    Peac(PeacParams),
    /// Iterative MSAC.
    Msac(MsacParams),
}

impl Method {
    /// The name in the tables.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Ppe(_) => "PPE",
            Method::Peac(_) => "PEAC-style",
            Method::Msac(_) => "MSAC",
        }
    }

    /// Segments the organized `cloud` (`what` names it in errors) and returns the
    /// segmentation and the extraction time (the conversion to the extractor's input
    /// included).
    pub fn run(&self, cloud: &PointCloud, what: &str) -> Result<(Segmentation, f64)> {
        let started = Instant::now();
        let points = || -> Vec<Vector3<f64>> {
            cloud
                .points
                .iter()
                .map(|p| p.coords.cast::<f64>())
                .collect()
        };
        let seg = match self {
            Method::Ppe(p) => extract(cloud, p),
            Method::Peac(p) => raypath_planes::peac(&points(), cloud.width, cloud.height, p),
            Method::Msac(p) => raypath_planes::msac(&points(), cloud.width, cloud.height, p),
        }
        .with_context(|| format!("{} on {what}", self.name()))?;
        Ok((seg, started.elapsed().as_secs_f64()))
    }
}

/// The PPE grid: `√e` × `d = l_max` × minimum plane size (metres, m, rays) with
/// `refine_rounds` post-processing rounds.
pub fn ppe_grid(
    sqrt_e: &[f64],
    l_max: &[f64],
    min_points: &[usize],
    refine_rounds: usize,
) -> Vec<(Method, String)> {
    let mut out = Vec::new();
    for &e in sqrt_e {
        for &d in l_max {
            for &m in min_points {
                let params = PpeParams {
                    max_increment_m2: e * e,
                    l_max_m: d,
                    min_points: m,
                    refine_rounds,
                    max_planes: None,
                };
                out.push((Method::Ppe(params), format!("√e {e:.2}, d {d:.1}, min {m}")));
            }
        }
    }
    out
}

/// The PEAC-style grid: block size × constant tolerance (merge = 1.5 × init) ×
/// discontinuity × minimum plane size.
pub fn peac_grid(
    blocks: &[usize],
    tol: &[f64],
    disc: &[f64],
    min_points: &[usize],
) -> Vec<(Method, String)> {
    let mut out = Vec::new();
    for &b in blocks {
        for &t in tol {
            for &j in disc {
                for &m in min_points {
                    let params = PeacParams {
                        block_size: b,
                        init_tol_m: t,
                        merge_tol_m: 1.5 * t,
                        discontinuity_rel: j,
                        min_points: m,
                        ..PeacParams::synpeb()
                    };
                    out.push((
                        Method::Peac(params),
                        format!("block {b}, tol {t:.2}, disc {j:.2}, min {m}"),
                    ));
                }
            }
        }
    }
    out
}

/// The MSAC grid: inlier distance × remaining fraction × minimum plane size.
pub fn msac_grid(dist: &[f64], remaining: &[f64], min_points: &[usize]) -> Vec<(Method, String)> {
    let mut out = Vec::new();
    for &d in dist {
        for &r in remaining {
            for &m in min_points {
                let params = MsacParams {
                    max_distance_m: d,
                    remaining_fraction: r,
                    min_points: m,
                    ..MsacParams::synpeb()
                };
                out.push((
                    Method::Msac(params),
                    format!("dist {d:.2}, remaining {r:.2}, min {m}"),
                ));
            }
        }
    }
    out
}

/// The scores of one segmented scan under the Hoover et al. protocol (T = 0.8).
#[derive(Debug, Default, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HooverScore {
    /// Fraction of correctly detected ground-truth planes, %.
    #[serde(with = "super::stages::float")]
    pub f: f64,
    /// Rays of the correctly detected planes over the rays of all ground-truth planes, %.
    #[serde(with = "super::stages::float")]
    pub k: f64,
    /// Per-ray radial RMSE of the extracted planes with an RMSE below 10 m, mm.
    #[serde(with = "super::stages::float")]
    pub rmse_mm: f64,
    /// Mean angle deviation over adjacent, correctly detected ground-truth pairs, degrees
    /// (NaN without ground-truth angles or without such a pair).
    #[serde(with = "super::stages::float")]
    pub alpha_deg: f64,
    /// Over-segmented ground-truth planes.
    #[serde(with = "super::stages::float")]
    pub n_o: f64,
    /// Under-segmentations.
    #[serde(with = "super::stages::float")]
    pub n_u: f64,
    /// Missed ground-truth planes.
    #[serde(with = "super::stages::float")]
    pub n_m: f64,
    /// Spurious (noise) planes.
    #[serde(with = "super::stages::float")]
    pub n_s: f64,
    /// Ground-truth planes.
    #[serde(with = "super::stages::float")]
    pub gt: f64,
    /// Extracted planes.
    #[serde(with = "super::stages::float")]
    pub planes: f64,
    /// Extraction time, s.
    #[serde(with = "super::stages::float")]
    pub secs: f64,
}

/// Scores `seg` against the ground-truth labels `gt` (one per ray, `None` = unlabelled;
/// labels below 10 are not planes). `angles`: the ground-truth angles `(label, label,
/// degrees)` between adjacent planes, for α.
pub fn hoover_score(
    gt: &[Option<u32>],
    seg: &Segmentation,
    secs: f64,
    angles: Option<&[(u32, u32, f64)]>,
) -> Result<HooverScore> {
    let h = compare(gt, &seg.labels, &HooverParams::default())?;
    let (mut sse, mut n) = (0.0, 0usize);
    for p in &seg.planes {
        if p.fit.rmse_m() < 10.0 {
            sse += p.fit.sse;
            n += p.fit.n;
        }
    }
    let alpha_deg = match angles {
        Some(pairs) => {
            let (sum, count) = angle_deviation(&h, pairs, |m| {
                seg.planes.get(m as usize).map(|p| p.fit.normal())
            });
            if count == 0 {
                f64::NAN
            } else {
                sum / count as f64
            }
        }
        None => f64::NAN,
    };
    Ok(HooverScore {
        f: 100.0 * h.fraction_correct(),
        k: 100.0 * h.k_value(),
        rmse_mm: if n == 0 {
            f64::NAN
        } else {
            1000.0 * (sse / n as f64).sqrt()
        },
        alpha_deg,
        n_o: h.over as f64,
        n_u: h.under as f64,
        n_m: h.missed as f64,
        n_s: h.noise as f64,
        gt: h.gt_regions as f64,
        planes: seg.planes.len() as f64,
        secs,
    })
}

/// The mean of `f` over `scans` (NaN for none).
pub fn mean(scans: &[HooverScore], f: impl Fn(&HooverScore) -> f64) -> f64 {
    if scans.is_empty() {
        f64::NAN
    } else {
        scans.iter().map(f).sum::<f64>() / scans.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use raypath_planes::{Plane, PlaneFit};

    use super::*;

    /// A plane of `n` rays with a per-ray RMSE of `rmse_m`, at 1/‖w‖ m along `w`'s direction.
    fn plane(w: [f64; 3], n: usize, rmse_m: f64) -> Plane {
        Plane {
            index: Vec::new(),
            fit: PlaneFit {
                w: Vector3::from(w),
                sse: n as f64 * rmse_m * rmse_m,
                n,
            },
        }
    }

    /// Ground truth and machine labels built group by group: `(gt, machine, rays)`.
    fn labels(
        groups: &[(Option<u32>, Option<u32>, usize)],
    ) -> (Vec<Option<u32>>, Vec<Option<u32>>) {
        let mut gt = Vec::new();
        let mut ms = Vec::new();
        for &(g, m, rays) in groups {
            gt.extend(std::iter::repeat_n(g, rays));
            ms.extend(std::iter::repeat_n(m, rays));
        }
        (gt, ms)
    }

    /// Six ground-truth planes (40 rays) against six machine planes, counted by hand at
    /// T = 0.8:
    /// * GT 10 (10 rays) ← machine 0 (9 of them, nothing else): correct;
    /// * GT 11 (10 rays) split into machines 1 and 2 (5 rays each): over-segmented;
    /// * GT 12 and GT 13 (5 rays each) both in machine 3 (10 rays): one under-segmentation;
    /// * GT 14 (4 rays) unsegmented: missed;
    /// * machine 4 (4 rays) on unlabelled rays and label 1 (below 10, not a plane): noise;
    /// * GT 15 (6 rays) ← machine 5 (the same 6 rays): correct.
    ///
    /// f = 2/6, k = (10 + 6)/40; every plane fits to 10 mm except the noise plane (11 m,
    /// left out of the RMSE); α over the one pair of correct detections: normals 90° apart
    /// against a ground-truth 100° (folded: 80°) gives 10°.
    #[test]
    fn hoover_score_counts_a_known_segmentation() {
        let (gt, ms) = labels(&[
            (Some(10), Some(0), 9),
            (Some(10), None, 1),
            (Some(11), Some(1), 5),
            (Some(11), Some(2), 5),
            (Some(12), Some(3), 5),
            (Some(13), Some(3), 5),
            (Some(14), None, 4),
            (None, Some(4), 2),
            (Some(1), Some(4), 2),
            (Some(15), Some(5), 6),
        ]);
        let seg = Segmentation {
            width: gt.len(),
            height: 1,
            labels: ms,
            planes: vec![
                plane([0.5, 0.0, 0.0], 9, 0.01),
                plane([0.0, 0.0, 1.0], 5, 0.01),
                plane([0.0, 0.0, 1.0], 5, 0.01),
                plane([0.0, 0.0, 1.0], 10, 0.01),
                plane([0.0, 0.0, 1.0], 4, 11.0),
                plane([0.0, 0.25, 0.0], 6, 0.01),
            ],
            steps: 0,
        };
        let angles = [(10, 11, 90.0), (10, 15, 100.0), (12, 13, 45.0)];
        let s = hoover_score(&gt, &seg, 0.125, Some(&angles)).unwrap();
        assert!((s.f - 100.0 / 3.0).abs() < 1e-9, "f {}", s.f);
        assert!((s.k - 40.0).abs() < 1e-9, "k {}", s.k);
        assert_eq!(
            (s.n_o, s.n_u, s.n_m, s.n_s),
            (1.0, 1.0, 1.0, 1.0),
            "over, under, missed, noise"
        );
        assert_eq!((s.gt, s.planes, s.secs), (6.0, 6.0, 0.125));
        assert!((s.rmse_mm - 10.0).abs() < 1e-9, "rmse {}", s.rmse_mm);
        assert!((s.alpha_deg - 10.0).abs() < 1e-9, "alpha {}", s.alpha_deg);

        // Without angles, or without a pair of correct detections, α is not defined.
        assert!(
            hoover_score(&gt, &seg, 0.0, None)
                .unwrap()
                .alpha_deg
                .is_nan()
        );
        let only_misses = [(11, 12, 90.0)];
        let s = hoover_score(&gt, &seg, 0.0, Some(&only_misses)).unwrap();
        assert!(s.alpha_deg.is_nan());
        assert!(hoover_score(&gt[1..], &seg, 0.0, None).is_err());
    }

    /// A perfect segmentation scores 100 % on both counts; a plane-free one has no RMSE.
    #[test]
    fn hoover_score_of_perfect_and_empty_segmentations() {
        let (gt, ms) = labels(&[(Some(20), Some(0), 8), (Some(21), Some(1), 8)]);
        let perfect = Segmentation {
            width: 16,
            height: 1,
            labels: ms,
            planes: vec![
                plane([1.0, 0.0, 0.0], 8, 0.0),
                plane([0.0, 1.0, 0.0], 8, 0.0),
            ],
            steps: 0,
        };
        let s = hoover_score(&gt, &perfect, 1.0, None).unwrap();
        assert_eq!((s.f, s.k, s.rmse_mm), (100.0, 100.0, 0.0));
        assert_eq!((s.n_o, s.n_u, s.n_m, s.n_s), (0.0, 0.0, 0.0, 0.0));
        let empty = Segmentation {
            labels: vec![None; 16],
            planes: Vec::new(),
            ..perfect
        };
        let s = hoover_score(&gt, &empty, 1.0, None).unwrap();
        assert_eq!((s.f, s.k, s.n_m, s.planes), (0.0, 0.0, 2.0, 0.0));
        assert!(s.rmse_mm.is_nan());
    }

    #[test]
    fn mean_over_scans() {
        let scans = [
            HooverScore {
                f: 50.0,
                ..HooverScore::default()
            },
            HooverScore {
                f: 100.0,
                ..HooverScore::default()
            },
        ];
        assert_eq!(mean(&scans, |s| s.f), 75.0);
        assert!(mean(&[], |s| s.f).is_nan());
    }

    /// The grids' sizes and the parameter labels their tables show.
    #[test]
    fn grids_and_their_labels() {
        let ppe = ppe_grid(&[0.1, 0.2], &[0.5], &[30, 60], 2);
        assert_eq!(ppe.len(), 4);
        assert_eq!(ppe[1].1, "√e 0.10, d 0.5, min 60");
        let Method::Ppe(p) = ppe[3].0 else {
            panic!("not PPE")
        };
        assert!((p.max_increment_m2 - 0.04).abs() < 1e-12);
        assert_eq!((p.l_max_m, p.min_points, p.refine_rounds), (0.5, 60, 2));
        assert_eq!(ppe[0].0.name(), "PPE");

        let peac = peac_grid(&[4, 8], &[0.02], &[0.05, 0.1], &[40]);
        assert_eq!(peac.len(), 4);
        assert_eq!(peac[3].1, "block 8, tol 0.02, disc 0.10, min 40");
        let Method::Peac(p) = peac[0].0 else {
            panic!("not PEAC")
        };
        assert!((p.merge_tol_m - 0.03).abs() < 1e-12);
        assert_eq!(peac[0].0.name(), "PEAC-style");

        let msac = msac_grid(&[0.05], &[0.1, 0.2], &[50]);
        assert_eq!(msac.len(), 2);
        assert_eq!(msac[1].1, "dist 0.05, remaining 0.20, min 50");
        assert_eq!(msac[0].0.name(), "MSAC");
    }
}
