//! Real data: raw and corrected Intel scans (read through `raypath_io::sequence`) pair one to
//! one, and Hector with the odometry guess beats the odometry on the relative-motion error.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use raypath_geometry::Pose2;
use raypath_io::data::require;
use raypath_io::sequence::{LaserChoice, PlanarOptions, pair_reference, read_planar};
use raypath_reflectivity::MatcherConfig;
use raypath_reflectivity::PointFilter;
use raypath_reflectivity::benchmark::{
    consecutive_relations, pair_by_ranges, read_laser_log, relative_errors, run_matcher,
};

#[test]
fn intel_pairs_and_scan_matching_beats_odometry() {
    let (Some(raw), Some(corrected)) = (
        require("carmen/raw/intel.clf.bz2"),
        require("carmen/corrected/intel-corrected.log.gz"),
    ) else {
        return;
    };
    let options = PlanarOptions {
        laser: LaserChoice::Front,
        ..PlanarOptions::default()
    };
    let mut raw_frames = read_planar(&raw, &options).unwrap();
    let reference = read_planar(&corrected, &options).unwrap();
    assert_eq!((raw_frames.len(), reference.len()), (13631, 910));
    assert_eq!(pair_reference(&mut raw_frames, &reference), 910);
    let pairs: Vec<(usize, usize)> = raw_frames
        .iter()
        .enumerate()
        .filter(|(_, f)| f.reference.is_some())
        .map(|(i, _)| i)
        .zip(0..)
        .collect();
    // The corrected log's first scan is the raw scan with logger time 32.906827 s.
    let (i0, _) = pairs[0];
    assert!((raw_frames[i0].stamp_secs - 32.906827).abs() < 1e-6);
    // The CARMEN-specific reader of raypath-reflectivity reads and pairs the same scans.
    let (raw_log, reference_log) = (
        read_laser_log(&raw).unwrap(),
        read_laser_log(&corrected).unwrap(),
    );
    assert_eq!(pair_by_ranges(&raw_log, &reference_log), pairs);
    assert!(
        raw_log
            .iter()
            .zip(&raw_frames)
            .all(|(s, f)| s.scan == f.scan
                && s.world_from_laser == f.world_from_laser
                && s.logger_timestamp_secs == f.stamp_secs)
    );
    // The first 2000 raw scans with the odometry as the initial guess.
    let raw = &raw_frames[..2000];
    let (_, results) = run_matcher(
        raw,
        MatcherConfig::default(),
        &PointFilter::default(),
        None,
        true,
    )
    .unwrap();
    let used: Vec<(usize, usize)> = pairs.iter().copied().filter(|&(i, _)| i < 2000).collect();
    let truth: Vec<Pose2> = used
        .iter()
        .map(|&(i, _)| raw_frames[i].reference.unwrap())
        .collect();
    let est: Vec<Pose2> = used
        .iter()
        .map(|&(i, _)| results[i].world_from_sensor)
        .collect();
    let odo: Vec<Pose2> = used.iter().map(|&(i, _)| raw[i].world_from_laser).collect();
    let rel = consecutive_relations(truth.len());
    let matched = relative_errors(&truth, &est, &rel);
    let odometry = relative_errors(&truth, &odo, &rel);
    assert!(
        matched.rotation_rad.mean < 0.5 * odometry.rotation_rad.mean,
        "{matched:?} vs {odometry:?}"
    );
    assert!(matched.translation_m.mean < 0.05, "{matched:?}");
}
