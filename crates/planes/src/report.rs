//! A typed report of one segmentation: the JSON document of `raypath planes --json` (the keys
//! are a contract).

use serde::Serialize;

use crate::{HooverResult, Segmentation};

/// One plane.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PlaneReport {
    /// The plane's label (1-based; 0 is "no plane" in the label file).
    pub label: usize,
    /// Unit normal.
    pub normal: [f64; 3],
    /// Distance of the plane from the origin, metres.
    pub distance: f64,
    /// Points of the plane.
    pub points: usize,
    /// RMS distance of its points from the plane, metres.
    pub rmse: f64,
}

/// The planes of one scan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlanesReport {
    /// The scan's name.
    pub scan: String,
    /// Columns of the organized scan.
    pub width: usize,
    /// Rows of the organized scan.
    pub height: usize,
    /// The method's name.
    pub method: String,
    /// The preset's name.
    pub preset: String,
    /// The planes, by label.
    pub planes: Vec<PlaneReport>,
    /// RMS distance over all plane points, metres.
    pub rmse: f64,
    /// Time of the segmentation, seconds.
    pub seconds: f64,
}

impl PlaneReport {
    /// The planes of `seg`, labelled from 1 in order.
    pub fn all(seg: &Segmentation) -> Vec<Self> {
        seg.planes
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let n = p.fit.normal();
                Self {
                    label: i + 1,
                    normal: [n.x, n.y, n.z],
                    distance: p.fit.distance_m(),
                    points: p.index.len(),
                    rmse: p.fit.rmse_m(),
                }
            })
            .collect()
    }
}

/// A segmentation scored against the ground truth by Hoover et al. (1996)
/// ([`crate::compare`]): the JSON document of `raypath segcomp-eval --json`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HooverReport {
    /// Share of correctly detected ground-truth regions ([`HooverResult::fraction_correct`]).
    pub f: f64,
    /// [`HooverResult::k_value`].
    pub k: f64,
    /// Over-segmented regions.
    pub n_o: usize,
    /// Under-segmented regions.
    pub n_u: usize,
    /// Missed regions.
    pub n_m: usize,
    /// Noise regions.
    pub n_s: usize,
    /// Correct detections.
    pub correct: usize,
    /// Ground-truth regions.
    pub gt_planes: usize,
    /// Segments of the segmentation.
    pub segments: usize,
    /// The compare tolerance T.
    pub tolerance: f64,
}

impl HooverReport {
    /// The report of `r`, compared at `tolerance`.
    pub fn new(r: &HooverResult, tolerance: f64) -> Self {
        Self {
            f: r.fraction_correct(),
            k: r.k_value(),
            n_o: r.over,
            n_u: r.under,
            n_m: r.missed,
            n_s: r.noise,
            correct: r.correct.len(),
            gt_planes: r.gt_regions,
            segments: r.ms_regions,
            tolerance,
        }
    }
}
