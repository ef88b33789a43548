//! Running the three extractors on a real frame and scoring the planes against the
//! SemanticKITTI classes: planar recall, plane precision, class purity, RMSE, time.

use std::collections::{BTreeMap, HashMap};

use raypath_planes::Segmentation;

pub use crate::eval::planes::Method;

use super::data::Frame;

/// SemanticKITTI classes counted as planar (Behley et al. 2019, `semantic-kitti.yaml`):
/// road 40, parking 44, sidewalk 48, building 50, and lane-marking 60 (painted road, which
/// the benchmark's learning map folds into road).
pub const PLANAR: [u16; 5] = [40, 44, 48, 50, 60];
/// Classes that are often planar but not always (other-ground 49, fence 51, traffic-sign
/// 81): a plane on them is not counted against the lenient precision, and they are left
/// out of the recall.
pub const PLANAR_ISH: [u16; 3] = [49, 51, 81];

/// Counts of one segmented frame; sums over frames give pooled ratios.
#[derive(Clone, Debug, Default)]
pub struct FrameScore {
    /// Pixels with a return.
    pub valid: usize,
    /// Pixels on a plane.
    pub on_plane: usize,
    /// Pixels of a planar class.
    pub planar: usize,
    /// Pixels of a planar class on a plane.
    pub planar_on_plane: usize,
    /// Pixels on a plane that are of a planar or planar-ish class.
    pub on_plane_lenient: usize,
    /// Sum over planes of the size of the plane's majority class.
    pub majority: usize,
    /// Planes extracted.
    pub planes: usize,
    /// Squared radial residuals of the planes with RMSE < 10 m (m²) and their rays.
    pub sse_m2: f64,
    /// Rays of those planes.
    pub rmse_rays: usize,
    /// Extraction time (s).
    pub secs: f64,
    /// Pixels on a plane per SemanticKITTI class.
    pub on_plane_by_class: BTreeMap<u16, usize>,
}

/// Scores `seg` of `frame` (classes: `frame.classes`; without them the class counts are 0).
pub fn score(frame: &Frame, seg: &Segmentation, secs: f64) -> FrameScore {
    let is_planar = |c: u16| PLANAR.contains(&c);
    let is_lenient = |c: u16| is_planar(c) || PLANAR_ISH.contains(&c);
    let mut s = FrameScore {
        valid: frame.cloud.num_valid(),
        planes: seg.planes.len(),
        secs,
        ..FrameScore::default()
    };
    let classes = frame.classes.as_deref();
    if let Some(classes) = classes {
        s.planar = frame
            .cloud
            .points
            .iter()
            .zip(classes)
            .filter(|(p, c)| p.x.is_finite() && is_planar(**c))
            .count();
    }
    let mut counts: HashMap<u16, usize> = HashMap::new();
    for plane in &seg.planes {
        s.on_plane += plane.index.len();
        if plane.fit.rmse_m() < 10.0 {
            s.sse_m2 += plane.fit.sse;
            s.rmse_rays += plane.fit.n;
        }
        let Some(classes) = classes else { continue };
        counts.clear();
        for &i in &plane.index {
            let c = classes[i];
            s.planar_on_plane += usize::from(is_planar(c));
            s.on_plane_lenient += usize::from(is_lenient(c));
            *counts.entry(if c == 60 { 40 } else { c }).or_default() += 1;
            *s.on_plane_by_class.entry(c).or_default() += 1;
        }
        s.majority += counts.values().copied().max().unwrap_or(0);
    }
    s
}

/// Pooled figures over a set of frames.
#[derive(Clone, Debug)]
pub struct Pooled {
    /// Frames.
    pub frames: usize,
    /// Share of planar-class pixels on a plane.
    pub recall: f64,
    /// Share of plane pixels of a planar class.
    pub precision: f64,
    /// Share of plane pixels of a planar or planar-ish class.
    pub precision_lenient: f64,
    /// Majority-class share of the planes, weighted by size.
    pub purity: f64,
    /// Share of the returns on a plane.
    pub on_plane: f64,
    /// Mean planes per frame.
    pub planes: f64,
    /// Per-ray radial RMSE over all planes of all frames (mm).
    pub rmse_mm: f64,
    /// Median extraction time per frame (s).
    pub median_secs: f64,
    /// Share of the plane pixels per SemanticKITTI class.
    pub by_class: BTreeMap<u16, f64>,
}

impl Pooled {
    /// Pools `scores`.
    pub fn of(scores: &[FrameScore]) -> Self {
        let sum = |f: fn(&FrameScore) -> usize| scores.iter().map(f).sum::<usize>() as f64;
        let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { f64::NAN };
        let on_plane = sum(|s| s.on_plane);
        let sse: f64 = scores.iter().map(|s| s.sse_m2).sum();
        let mut secs: Vec<f64> = scores.iter().map(|s| s.secs).collect();
        let mut by_class = BTreeMap::new();
        for s in scores {
            for (&c, &n) in &s.on_plane_by_class {
                *by_class.entry(c).or_insert(0.0) += n as f64 / on_plane;
            }
        }
        Self {
            frames: scores.len(),
            recall: ratio(sum(|s| s.planar_on_plane), sum(|s| s.planar)),
            precision: ratio(sum(|s| s.planar_on_plane), on_plane),
            precision_lenient: ratio(sum(|s| s.on_plane_lenient), on_plane),
            purity: ratio(sum(|s| s.majority), on_plane),
            on_plane: ratio(on_plane, sum(|s| s.valid)),
            planes: ratio(sum(|s| s.planes), scores.len() as f64),
            rmse_mm: 1000.0 * ratio(sse, sum(|s| s.rmse_rays)).sqrt(),
            median_secs: crate::eval::median(&mut secs),
            by_class,
        }
    }

    /// F1 of the planar recall and the lenient precision: the PPE tuning objective.
    pub fn f1(&self) -> f64 {
        2.0 * self.recall * self.precision_lenient / (self.recall + self.precision_lenient)
    }

    /// The figures as JSON.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "frames": self.frames, "planar_recall": self.recall,
            "plane_precision": self.precision, "plane_precision_lenient": self.precision_lenient, "f1": self.f1(),
            "class_purity": self.purity, "share_on_planes": self.on_plane,
            "planes_per_frame": self.planes, "rmse_mm": self.rmse_mm,
            "median_seconds": self.median_secs,
        })
    }
}
