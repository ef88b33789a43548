//! A geometric check of a method's candidates on planar scans (ours, in the spirit of DBoW2's
//! geometric verification, Gálvez-López & Tardós 2012): the best [`GeometricCheckConfig::top_k`]
//! candidates of any [`PlaceRecognizer`] are aligned to the query by point-to-line ICP
//! ([`raypath_geometry::LineTarget`]) from [`GeometricCheckConfig::start_headings`] headings,
//! and each is re-scored by its **support**: the smaller of the two scans' shares of points
//! that lie within [`GeometricCheckConfig::support_m`] of the other scan after the alignment.
//! Candidates below [`GeometricCheckConfig::min_support`] are dropped.
//!
//! Why: appearance scores of rasterised 2-D scans cannot separate a true revisit from a
//! similar-looking place (the false positive that ends recall at 100 % precision scores as
//! high as the true ones); two scans of the same place align with most of their points, two
//! scans of different places do not — except where the places are alike in geometry too (a
//! long featureless corridor), which no check of two single scans can tell apart.
//!
//! The check needs the scans: [`GeometricCheck::describe`] takes [`Frame::Planar`] frames, or
//! [`GeometricCheck::attach`] joins a description made elsewhere (shared features) to its scan.

use raypath_geometry::{LineIcp, LineTarget, Pose2, Scan2};
use serde::{Deserialize, Serialize};

use crate::error::require_positive;
use crate::run::sort_candidates;
use crate::{Candidate, Frame, PlaceError, PlaceRecognizer, Result};

/// Settings of [`GeometricCheck`]; the defaults are ours.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeometricCheckConfig {
    /// Candidates of the inner method checked per query, its best first. Default 3.
    pub top_k: usize,
    /// Start headings of the alignment, evenly spaced over the full turn (the two scans'
    /// relative heading is unknown). Default 8 (every 45°).
    pub start_headings: usize,
    /// Correspondence gates of the ICP stages, metres, narrowing. Default 1.0, 0.3, 0.1.
    pub gates_m: Vec<f64>,
    /// Gauss–Newton iterations per gate at most. Default 10.
    pub iterations: usize,
    /// Scale of the Cauchy weights of the point-to-line residuals, metres. Default 0.05.
    pub kernel_m: f64,
    /// Neighbours within this radius fit a point's line, metres. Default 0.3.
    pub normal_radius_m: f64,
    /// A point is supported when it lies within this distance of the other scan after the
    /// alignment, metres. Default 0.1.
    pub support_m: f64,
    /// Candidates whose support is below this share are dropped. Default 0.3.
    pub min_support: f64,
    /// Points farther from the sensor are left out, metres. Default 15.
    pub max_range_m: f64,
    /// Points closer than this to the previous kept point along the scan are left out,
    /// metres (thins dense near walls). Default 0.05.
    pub min_spacing_m: f64,
    /// A match whose two sensors are farther apart than this is no place match (support 0),
    /// metres: the application's notion of "the same place". Default ∞.
    pub max_offset_m: f64,
    /// … or whose headings differ by more than this, radians. Default π (any).
    pub max_heading_rad: f64,
    /// [`PlaceRecognizer::query_stored`] neither checks nor proposes frames within this many
    /// of the queried frame (its own recent past, as the online exclusion window). Default 0.
    pub exclude_recent: usize,
}

impl Default for GeometricCheckConfig {
    fn default() -> Self {
        Self {
            top_k: 3,
            start_headings: 8,
            gates_m: vec![1.0, 0.3, 0.1],
            iterations: 10,
            kernel_m: 0.05,
            normal_radius_m: 0.3,
            support_m: 0.1,
            min_support: 0.3,
            max_range_m: 15.0,
            min_spacing_m: 0.05,
            max_offset_m: f64::INFINITY,
            max_heading_rad: std::f64::consts::PI,
            exclude_recent: 0,
        }
    }
}

impl GeometricCheckConfig {
    /// Checks the settings (errors name the field).
    pub fn validate(&self) -> Result<()> {
        let positive_count = |name: &'static str, v: usize| {
            if v == 0 {
                Err(PlaceError::InvalidParameter {
                    name,
                    reason: "must be at least 1".into(),
                })
            } else {
                Ok(())
            }
        };
        positive_count("top_k", self.top_k)?;
        positive_count("start_headings", self.start_headings)?;
        positive_count("iterations", self.iterations)?;
        if self.gates_m.is_empty() {
            return Err(PlaceError::InvalidParameter {
                name: "gates_m",
                reason: "needs at least one gate".into(),
            });
        }
        for &g in &self.gates_m {
            require_positive("gates_m", g)?;
        }
        require_positive("kernel_m", self.kernel_m)?;
        require_positive("normal_radius_m", self.normal_radius_m)?;
        require_positive("support_m", self.support_m)?;
        require_positive("max_range_m", self.max_range_m)?;
        if self.max_offset_m.is_nan() || self.max_offset_m <= 0.0 {
            return Err(PlaceError::InvalidParameter {
                name: "max_offset_m",
                reason: format!("must be positive (∞ allowed), got {}", self.max_offset_m),
            });
        }
        require_positive("max_heading_rad", self.max_heading_rad)?;
        if !(0.0..=1.0).contains(&self.min_support) {
            return Err(PlaceError::InvalidParameter {
                name: "min_support",
                reason: format!("must lie in [0, 1], got {}", self.min_support),
            });
        }
        if !(self.min_spacing_m.is_finite() && self.min_spacing_m >= 0.0) {
            return Err(PlaceError::InvalidParameter {
                name: "min_spacing_m",
                reason: format!("must be finite and ≥ 0, got {}", self.min_spacing_m),
            });
        }
        Ok(())
    }
}

/// The best alignment of two scans found by the check.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanMatch {
    /// The smaller of the two scans' shares of supported points.
    pub support: f64,
    /// The pose of the second scan's sensor in the first's.
    pub a_from_b: Pose2,
}

/// A scan's points (sensor frame, thinned) indexed for alignment; `None` when too few.
struct CheckedScan(Option<LineTarget>);

/// A description of the inner method with its scan.
pub struct Checked<D> {
    /// The inner method's description.
    pub inner: D,
    scan: CheckedScan,
}

/// Any [`PlaceRecognizer`] whose candidates are re-scored by a geometric check (module docs).
/// Scores are supports in `[min_support, 1]`.
pub struct GeometricCheck<R: PlaceRecognizer> {
    inner: R,
    config: GeometricCheckConfig,
    scans: Vec<CheckedScan>,
}

impl<R: PlaceRecognizer> GeometricCheck<R> {
    /// Wraps `inner` (which must be empty).
    pub fn new(inner: R, config: GeometricCheckConfig) -> Result<Self> {
        config.validate()?;
        if !inner.is_empty() {
            return Err(PlaceError::BadInput(format!(
                "{}: the geometric check needs an empty database (it holds {} frames)",
                inner.name(),
                inner.len()
            )));
        }
        Ok(Self {
            inner,
            config,
            scans: Vec::new(),
        })
    }

    /// The wrapped method (to describe with its own entry points).
    pub fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }

    /// Joins a description of the inner method to the scan it describes.
    pub fn attach(&self, inner: R::Description, scan: &Scan2) -> Checked<R::Description> {
        Checked {
            inner,
            scan: self.index(scan),
        }
    }

    /// The scan's thinned end points within range, indexed.
    fn index(&self, scan: &Scan2) -> CheckedScan {
        let c = &self.config;
        let mut points: Vec<[f64; 2]> = Vec::with_capacity(scan.len());
        for p in scan.points(Pose2::identity()) {
            if !(p.x.is_finite() && p.y.is_finite()) || p.coords.norm() > c.max_range_m {
                continue;
            }
            let far_enough = points.last().is_none_or(|q| {
                (q[0] - p.x).powi(2) + (q[1] - p.y).powi(2) >= c.min_spacing_m * c.min_spacing_m
            });
            if far_enough {
                points.push([p.x, p.y]);
            }
        }
        CheckedScan(LineTarget::new(&points, c.normal_radius_m))
    }

    /// The best alignment of scan `b` onto scan `a` (module docs): every start heading runs
    /// the coarse gates on every second point of `b`; the start whose result `b` supports most
    /// runs the last gate on all points and is scored both ways. Support 0 when either scan is
    /// too sparse or no alignment succeeds.
    fn best_alignment(&self, a: &CheckedScan, b: &CheckedScan) -> ScanMatch {
        let none = ScanMatch {
            support: 0.0,
            a_from_b: Pose2::identity(),
        };
        let (Some(a), Some(b)) = (&a.0, &b.0) else {
            return none;
        };
        let c = &self.config;
        let (coarse, fine) = c.gates_m.split_at(c.gates_m.len() - 1);
        let icp = |gates_m| LineIcp {
            gates_m,
            iterations: c.iterations,
            kernel_m: c.kernel_m,
        };
        let thinned: Vec<[f64; 2]> = b.points().iter().step_by(2).copied().collect();
        let (ca, cb) = (centroid(a.points()), centroid(b.points()));
        let mut best: Option<(f64, Pose2)> = None;
        for k in 0..c.start_headings {
            let heading = std::f64::consts::TAU * k as f64 / c.start_headings as f64;
            // The start puts the centroids of the two point sets on each other.
            let (cos, sin) = (heading.cos(), heading.sin());
            let start = Pose2::new(
                ca[0] - (cos * cb[0] - sin * cb[1]),
                ca[1] - (sin * cb[0] + cos * cb[1]),
                heading,
            );
            let pose = match coarse.is_empty() {
                true => Some(start),
                false => a
                    .align(&thinned, start, &icp(coarse))
                    .map(|m| m.target_from_source),
            };
            let Some(pose) = pose else {
                continue;
            };
            let support = a.support(&thinned, &pose, c.support_m);
            if best.is_none_or(|(s, _)| support > s) {
                best = Some((support, pose));
            }
        }
        let Some((_, start)) = best else {
            return none;
        };
        let Some(found) = a.align(b.points(), start, &icp(fine)) else {
            return none;
        };
        let pose = found.target_from_source;
        let b_on_a = a.support(b.points(), &pose, c.support_m);
        let a_on_b = b.support(a.points(), &pose.inverse(), c.support_m);
        ScanMatch {
            support: b_on_a.min(a_on_b),
            a_from_b: pose,
        }
    }

    /// The support of the best alignment (0 when it is no place match, see
    /// [`GeometricCheckConfig::max_offset_m`]).
    fn support(&self, a: &CheckedScan, b: &CheckedScan) -> f64 {
        let m = self.best_alignment(a, b);
        let c = &self.config;
        let near = m.a_from_b.translation().norm() <= c.max_offset_m
            && m.a_from_b.theta().abs() <= c.max_heading_rad;
        if near { m.support } else { 0.0 }
    }

    /// Aligns two scans as the check does (from every start heading) and returns the best
    /// match, whatever its offset.
    pub fn match_scans(&self, a: &Scan2, b: &Scan2) -> ScanMatch {
        self.best_alignment(&self.index(a), &self.index(b))
    }

    /// The inner candidates (any order) checked against `scan`, best support first.
    fn check(&self, scan: &CheckedScan, mut candidates: Vec<Candidate>) -> Vec<Candidate> {
        sort_candidates(&mut candidates);
        candidates.truncate(self.config.top_k);
        let mut checked: Vec<Candidate> = candidates
            .into_iter()
            .filter_map(|c| {
                let score = self.support(self.scans.get(c.frame)?, scan);
                (score >= self.config.min_support).then_some(Candidate {
                    frame: c.frame,
                    score,
                })
            })
            .collect();
        sort_candidates(&mut checked);
        checked
    }
}

/// The mean of some points (the origin for none).
fn centroid(points: &[[f64; 2]]) -> [f64; 2] {
    let n = points.len().max(1) as f64;
    let sum = points
        .iter()
        .fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
    [sum[0] / n, sum[1] / n]
}

impl<R: PlaceRecognizer> PlaceRecognizer for GeometricCheck<R> {
    type Description = Checked<R::Description>;

    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn describe(&mut self, frame: &Frame<'_>) -> Result<Self::Description> {
        let Frame::Planar(scan) = frame else {
            return Err(PlaceError::UnsupportedFrame {
                method: "geometric check",
                frame: frame.kind(),
            });
        };
        let inner = self.inner.describe(frame)?;
        Ok(self.attach(inner, scan))
    }

    fn query(&self, description: &Self::Description, before: usize) -> Vec<Candidate> {
        let candidates = self.inner.query(&description.inner, before);
        self.check(&description.scan, candidates)
    }

    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate> {
        let gap = self.config.exclude_recent;
        let candidates = self
            .inner
            .query_stored(index, before)
            .into_iter()
            .filter(|c| c.frame != index && c.frame.abs_diff(index) >= gap)
            .collect();
        match self.scans.get(index) {
            Some(scan) => self.check(scan, candidates),
            None => Vec::new(),
        }
    }

    fn insert(&mut self, description: Self::Description) {
        self.inner.insert(description.inner);
        self.scans.push(description.scan);
    }

    fn len(&self) -> usize {
        self.inner.len()
    }

    fn start_sequence(&mut self) {
        self.inner.start_sequence();
    }
}

#[cfg(test)]
mod tests;
