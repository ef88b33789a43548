//! Pole extraction on the real KITTI frames (`RAYPATH_DATA/kitti/sequences/00`, frames 0–9,
//! SemanticKITTI labels) against the labelled poles: the recall and precision measured by
//! `cargo xtask eval poles-kitti` must not fall below floors a little under them. Skips with a
//! message when the data is not installed.

// Test setup panics on failures.
#![allow(clippy::unwrap_used)]

use raypath_io::data::require;
use raypath_poles::{
    DetectionQuality, LabelledLocalMap, PoleClass, PoleParams, ReferenceRule, class_quality,
};

/// Scoring as the evaluation: within 12 m of a scan, 1 m inside the grid, matches ≤ 1 m.
fn quality(
    map: &LabelledLocalMap,
    scans: &[usize],
    classes: &[PoleClass],
    params: &PoleParams,
) -> DetectionQuality {
    let references = map.references(params, &ReferenceRule::default()).unwrap();
    let region = map.region(scans, params, 12.0, 1.0);
    let (poles, _) = map.extract(scans, params).unwrap();
    let poles: Vec<_> = poles
        .into_iter()
        .filter(|p| region.contains(p.x, p.y))
        .collect();
    let refs: Vec<_> = references
        .poles
        .into_iter()
        .filter(|r| region.contains(r.x, r.y))
        .collect();
    class_quality(&poles, &refs, classes, 1.0)
}

#[test]
fn poles_of_real_kitti_00_are_found() {
    let Some(dir) = require("kitti/sequences/00/labels") else {
        return;
    };
    let dir = dir.parent().unwrap();
    let params = PoleParams::kitti();
    let map = LabelledLocalMap::read_kitti(dir, 0..10).unwrap();
    assert!(map.motions.is_some(), "KITTI frames are de-skewed sweeps");
    let all = [PoleClass::Pole, PoleClass::Trunk, PoleClass::TrafficSign];

    // Ten-scan local map (measured: 3 of 3 poles, 5 of 5 pole-like, no false pole).
    let poles = quality(&map, &map.all(), &[PoleClass::Pole], &params);
    assert_eq!(poles.truth, 3, "{poles:?}");
    assert!(poles.recall >= 0.66 && poles.precision >= 0.99, "{poles:?}");
    assert!(poles.mean_centre_error_m < 0.1, "{poles:?}");
    let any = quality(&map, &map.all(), &all, &params);
    assert!(any.recall >= 0.8 && any.precision >= 0.8, "{any:?}");

    // Every scan alone, pooled (measured: poles 25 of 27 with the rays traced from where the
    // sensor was; 21 of 27 from each scan's origin).
    let (mut matched, mut truth, mut detected) = (0, 0, 0);
    for i in map.all() {
        let q = quality(&map, &[i], &[PoleClass::Pole], &params);
        (matched, truth, detected) = (matched + q.matched, truth + q.truth, detected + q.detected);
    }
    assert_eq!(truth, 27);
    assert!(
        matched >= 24,
        "{matched} of {truth} poles found in single scans"
    );
    assert!(
        matched as f64 >= 0.95 * detected as f64,
        "{matched} of {detected} detections"
    );
}
