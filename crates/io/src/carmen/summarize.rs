//! `raypath info` for CARMEN logs.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::Point3;
use raypath_geometry::Aabb3;

use super::reader::CarmenReader;
use super::record::{LaserKind, Record};
use crate::error::Result;
use crate::summary::{BoundingBox, Summary, TimeSpan};

/// Summarizes a CARMEN log (format `carmen`), reading it with the default configuration.
///
/// * `scans`: laser messages (`FLASER`, `RLASER`, `ROBOTLASER1`); `beams` their most
///   common beam count (with `beams_min`/`beams_max` when counts differ);
/// * `poses`: laser messages with a pose (all of them: every laser line carries one);
/// * `odometry`: `ODOM` lines only (the odometry poses inside laser lines are not counted,
///   so a log like mit-csail, whose odometry lives only in its `FLASER` lines, reports 0);
/// * `time_span`: over the IPC timestamps of the laser messages (of the `ODOM` messages in a
///   log without laser messages). The `ODOM` lines of the corrected Radish logs carry
///   timestamps unrelated to the scans (zeros, UNIX times), so they are left out. The data
///   are what they are: freiburg-campus's scans are all stamped 0, and infinite-corridor's
///   last scans 4 294 967 296 s (2³², an overflow in the original conversion);
/// * `bbox`: of the world-frame hit points (laser poses, z = 0);
/// * extras: `no_return_range_m` (the no-return threshold of the last scan of the most
///   common laser kind),
///   `no_return_code_m` (the inferred code, when one was found), `messages` (lines per
///   message tag) and `params` (number of `PARAM` lines).
///
/// The first malformed line fails the summary with its error.
pub fn summarize(path: &Path) -> Result<Summary> {
    let reader = CarmenReader::open(path)?;
    let mut summary = Summary::new("carmen");
    let mut beams: BTreeMap<u64, u64> = BTreeMap::new();
    let mut kinds: BTreeMap<LaserKind, (u64, f64)> = BTreeMap::new();
    let mut messages: BTreeMap<String, u64> = BTreeMap::new();
    let mut bbox = Aabb3::empty();
    let (mut time_span, mut odometry_span) = (None, None);
    let (mut scans, mut odometry, mut params) = (0u64, 0u64, 0u64);
    let mut estimates = Vec::new();
    for kind in [LaserKind::Front, LaserKind::Rear, LaserKind::RobotLaser1] {
        estimates.push((kind, reader.no_return(kind)));
    }
    for record in reader {
        let tag = match record? {
            Record::Laser(laser) => {
                scans += 1;
                *beams.entry(laser.scan.len() as u64).or_insert(0) += 1;
                let kind = kinds.entry(laser.kind).or_insert((0, 0.0));
                *kind = (kind.0 + 1, laser.scan.max_range_m);
                TimeSpan::extend(&mut time_span, laser.ipc_timestamp_secs);
                for p in laser.scan.points(laser.world_from_laser) {
                    bbox.extend(&Point3::new(p.x, p.y, 0.0));
                }
                laser.kind.tag().to_owned()
            }
            Record::Odometry(odom) => {
                odometry += 1;
                TimeSpan::extend(&mut odometry_span, odom.ipc_timestamp_secs);
                "ODOM".to_owned()
            }
            Record::Param { .. } => {
                params += 1;
                "PARAM".to_owned()
            }
            Record::Other { tag, .. } => tag,
        };
        *messages.entry(tag).or_insert(0) += 1;
    }
    summary.scans = Some(scans);
    summary.set_beams_from_counts(&beams);
    summary.poses = Some(scans);
    summary.odometry = Some(odometry);
    summary.time_span = time_span.or(odometry_span);
    summary.bbox = BoundingBox::from_aabb(&bbox);
    // The most common laser kind speaks for the log.
    if let Some((&main_kind, &(_, range_m))) = kinds.iter().max_by_key(|&(_, (n, _))| *n) {
        summary = summary.with_extra("no_return_range_m", range_m);
        if let Some((_, Some(estimate))) = estimates.iter().find(|(k, _)| *k == main_kind) {
            summary = summary.with_extra("no_return_code_m", estimate.code_m);
        }
    }
    Ok(summary
        .with_extra(
            "messages",
            serde_json::to_value(&messages).unwrap_or_default(),
        )
        .with_extra("params", params))
}
