//! Why references are missed and what false detections are: per missed reference its range,
//! points, height span, sign plates, the nearest detection and the labelled classes around
//! its centre; per unmatched detection its range, size, score and the classes around it.

use std::collections::BTreeMap;

use raypath_io::kitti::semantic_class_name;
use raypath_poles::{LabelledLocalMap, Pole, ReferencePole, ScoringRegion, greedy_matches};

use crate::table::fmt_num;

/// A reference the local map missed.
#[derive(Clone, Debug, serde::Serialize)]
pub(super) struct Miss {
    /// The reference.
    pub reference: ReferencePole,
    /// Distance to the nearest scan position, metres.
    pub range_m: f64,
    /// Distance to the nearest detection, metres (infinite without detections).
    pub nearest_detection_m: f64,
    /// Labelled points within 0.3 m of the centre (all scans, any height), by class name.
    pub classes_near: BTreeMap<String, usize>,
}

/// Columns of [`Miss::row`].
pub(super) const MISS_HEADERS: [&str; 10] = [
    "sequence",
    "variant",
    "class",
    "x, y [m]",
    "range [m]",
    "points",
    "span [m]",
    "sign points",
    "nearest detection [m]",
    "classes within 0.3 m",
];

impl Miss {
    /// A table row.
    pub fn row(&self, sequence: &str, variant: &str) -> Vec<String> {
        let r = &self.reference;
        vec![
            sequence.to_string(),
            variant.to_string(),
            r.class.name().to_string(),
            format!("{:.1}, {:.1}", r.x, r.y),
            fmt_num(self.range_m, 1),
            r.points.to_string(),
            fmt_num(r.z_max - r.z_min, 2),
            r.sign_points.to_string(),
            fmt_num(self.nearest_detection_m, 2),
            names(&self.classes_near),
        ]
    }
}

/// A detection matched to no reference.
#[derive(Clone, Debug, serde::Serialize)]
pub(super) struct FalsePositive {
    /// The detection.
    pub pole: Pole,
    /// Distance to the nearest scan position, metres.
    pub range_m: f64,
    /// Labelled points within 0.3 m of the centre (all scans, any height), by class name.
    pub classes_near: BTreeMap<String, usize>,
}

/// Columns of [`FalsePositive::row`].
pub(super) const FALSE_POSITIVE_HEADERS: [&str; 7] = [
    "sequence",
    "x, y [m]",
    "range [m]",
    "width [m]",
    "height [m]",
    "score",
    "classes within 0.3 m",
];

impl FalsePositive {
    /// A table row.
    pub fn row(&self, sequence: &str) -> Vec<String> {
        let p = &self.pole;
        vec![
            sequence.to_string(),
            format!("{:.1}, {:.1}", p.x, p.y),
            fmt_num(self.range_m, 1),
            fmt_num(p.width, 2),
            fmt_num(p.height(), 1),
            fmt_num(p.score, 2),
            names(&self.classes_near),
        ]
    }
}

/// The detections in `region` matched to no reference (matching as the scoring).
pub(super) fn false_positives(
    map: &LabelledLocalMap,
    detected: &[Pole],
    references: &[ReferencePole],
    region: &ScoringRegion,
    match_m: f64,
) -> Vec<FalsePositive> {
    let det: Vec<&Pole> = detected
        .iter()
        .filter(|p| region.contains(p.x, p.y))
        .collect();
    let xy: Vec<(f64, f64)> = det.iter().map(|p| (p.x, p.y)).collect();
    let refs: Vec<(f64, f64)> = references
        .iter()
        .filter(|p| region.contains(p.x, p.y))
        .map(|r| (r.x, r.y))
        .collect();
    let matched: Vec<usize> = greedy_matches(&xy, &refs, match_m)
        .iter()
        .map(|m| m.0)
        .collect();
    det.iter()
        .enumerate()
        .filter(|(i, _)| !matched.contains(i))
        .map(|(_, p)| FalsePositive {
            pole: **p,
            range_m: nearest_scan(map, p.x, p.y),
            classes_near: classes_near(map, p.x, p.y, 0.3),
        })
        .collect()
}

/// Distance from `(x, y)` to the nearest scan position, metres.
fn nearest_scan(map: &LabelledLocalMap, x: f64, y: f64) -> f64 {
    map.scans
        .iter()
        .map(|(p, _)| (p.translation().x - x).hypot(p.translation().y - y))
        .fold(f64::INFINITY, f64::min)
}

/// `class count, …` in descending count.
fn names(counts: &BTreeMap<String, usize>) -> String {
    let mut list: Vec<(&String, &usize)> = counts.iter().collect();
    list.sort_by(|a, b| b.1.cmp(a.1));
    list.iter()
        .map(|(name, n)| format!("{name} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The references in `region` left unmatched by `detected` (matching as the scoring).
pub(super) fn misses(
    map: &LabelledLocalMap,
    detected: &[Pole],
    references: &[ReferencePole],
    region: &ScoringRegion,
    match_m: f64,
) -> Vec<Miss> {
    let det: Vec<(f64, f64)> = detected
        .iter()
        .filter(|p| region.contains(p.x, p.y))
        .map(|p| (p.x, p.y))
        .collect();
    let refs: Vec<&ReferencePole> = references
        .iter()
        .filter(|p| region.contains(p.x, p.y))
        .collect();
    let xy: Vec<(f64, f64)> = refs.iter().map(|r| (r.x, r.y)).collect();
    let matched: Vec<usize> = greedy_matches(&det, &xy, match_m)
        .iter()
        .map(|m| m.1)
        .collect();
    refs.iter()
        .enumerate()
        .filter(|(j, _)| !matched.contains(j))
        .map(|(_, r)| Miss {
            reference: **r,
            range_m: nearest_scan(map, r.x, r.y),
            nearest_detection_m: detected
                .iter()
                .map(|d| (d.x - r.x).hypot(d.y - r.y))
                .fold(f64::INFINITY, f64::min),
            classes_near: classes_near(map, r.x, r.y, 0.3),
        })
        .collect()
}

/// Labelled points of all scans within `radius` of `(x, y)` in the ground plane, by class.
fn classes_near(map: &LabelledLocalMap, x: f64, y: f64, radius: f64) -> BTreeMap<String, usize> {
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for (pose, cloud) in &map.scans {
        let Some(labels) = cloud.label.as_deref() else {
            continue;
        };
        for (point, &raw) in cloud.points.iter().zip(labels) {
            let p = pose.transform_point(&point.cast::<f64>());
            if (p.x - x).hypot(p.y - y) <= radius {
                let class = (raw & 0xffff) as u16;
                let name =
                    semantic_class_name(class).map_or_else(|| class.to_string(), str::to_owned);
                *counts.entry(name).or_default() += 1;
            }
        }
    }
    counts
}
