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

/// An extractor with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
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
#[derive(Debug, Default, Clone)]
pub struct HooverScore {
    /// Fraction of correctly detected ground-truth planes, %.
    pub f: f64,
    /// Rays of the correctly detected planes over the rays of all ground-truth planes, %.
    pub k: f64,
    /// Per-ray radial RMSE of the extracted planes with an RMSE below 10 m, mm.
    pub rmse_mm: f64,
    /// Mean angle deviation over adjacent, correctly detected ground-truth pairs, degrees
    /// (NaN without ground-truth angles or without such a pair).
    pub alpha_deg: f64,
    /// Over-segmented ground-truth planes.
    pub n_o: f64,
    /// Under-segmentations.
    pub n_u: f64,
    /// Missed ground-truth planes.
    pub n_m: f64,
    /// Spurious (noise) planes.
    pub n_s: f64,
    /// Ground-truth planes.
    pub gt: f64,
    /// Extracted planes.
    pub planes: f64,
    /// Extraction time, s.
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
