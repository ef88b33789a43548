//! The map of a run: the scans at their optimised poses in a sensor-model map, built in memory
//! (what `raypath slam` writes as `map.*` and the Python package returns).

use nalgebra::Point2;
use raypath_geometry::{Aabb2, Grid2, Pose2, Scan2};
use raypath_io::sequence::PlanarFrame;
use raypath_sensor_models::export::{MapFile, MapKind, StoredStats};
use raypath_sensor_models::{DenseStats2, MappingConfig};

use crate::error::{Result, SlamError};

/// Largest map [`rebuild_map`] allocates, cells (16 bytes each).
pub const MAX_MAP_CELLS: usize = 200_000_000;

/// How [`rebuild_map`] builds the map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapSettings {
    /// The sensor model the map is for (recorded in the map file).
    pub kind: MapKind,
    /// Cell edge, metres.
    pub resolution_m: f64,
    /// Returns at or beyond this range are not mapped (no-returns are never traced), metres.
    pub max_range_m: f64,
}

/// The map of `frames` at `world_from_sensor` (index-aligned; the optimised poses of
/// [`crate::SlamOutput`]): a grid covering the poses and the returns below the maximum range
/// plus one cell, every beam inserted as a ray, no-returns not traced. Scans whose pose is
/// not finite are left out.
///
/// Each pose is taken as a corrected log states it (`x`, `y`, `θ`), so the map equals,
/// bit for bit, the one `raypath map` builds from the corrected log of
/// [`crate::SlamOutput::write_corrected_log`].
pub fn rebuild_map(
    frames: &[PlanarFrame],
    world_from_sensor: &[Pose2],
    settings: &MapSettings,
) -> Result<MapFile> {
    let max_range = settings.max_range_m;
    let mut mapping =
        MappingConfig::with_range(0.0, max_range).map_err(|e| SlamError::InvalidParameter {
            name: "max_range_m",
            reason: e.to_string(),
        })?;
    mapping.include_no_returns = false;
    let mut bounds = Aabb2::empty();
    let mut scans: Vec<(Pose2, &Scan2)> = Vec::with_capacity(frames.len());
    for (frame, pose) in frames.iter().zip(world_from_sensor) {
        if !pose.is_finite() {
            continue;
        }
        let pose = Pose2::new(pose.x(), pose.y(), pose.theta());
        bounds.extend(&Point2::new(pose.x(), pose.y()));
        for ray in frame.scan.rays(pose) {
            if let Some(t) = ray.range.hit().filter(|&t| t < max_range) {
                bounds.extend(&ray.at(t));
            }
        }
        scans.push((pose, &frame.scan));
    }
    let grid = Grid2::covering(&bounds, settings.resolution_m).map_err(|e| {
        SlamError::BadInput(format!(
            "cannot build a grid of {} m cells over the scans: {e}",
            settings.resolution_m
        ))
    })?;
    let [w, h] = grid.dims();
    if w.saturating_mul(h) > MAX_MAP_CELLS {
        return Err(SlamError::BadInput(format!(
            "the map would have {w} × {h} cells of {} m (at most {MAX_MAP_CELLS})",
            settings.resolution_m
        )));
    }
    let mut stats = DenseStats2::planar(grid);
    stats.insert_scans_par(&scans, &mapping);
    Ok(MapFile {
        kind: settings.kind,
        posterior: false,
        mapping,
        stats: StoredStats::Planar(stats),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(pose: Pose2) -> PlanarFrame {
        let scan = Scan2 {
            angle_min_rad: -1.0,
            angle_increment_rad: 0.5,
            max_range_m: 10.0,
            ranges: vec![2.0, 3.0, 10.0, 2.5, 1.0],
            intensities: None,
        };
        PlanarFrame {
            stamp_secs: 0.0,
            ipc_stamp_secs: None,
            scan,
            world_from_robot: pose,
            world_from_laser: pose,
            reference: None,
            origin: raypath_io::sequence::Origin::Line(1),
        }
    }

    #[test]
    fn covers_the_returns_and_skips_non_finite_poses() {
        let poses = [Pose2::new(0.0, 0.0, 0.3), Pose2::new(f64::NAN, 0.0, 0.0)];
        let frames: Vec<_> = poses.iter().map(|&p| frame(p)).collect();
        let settings = MapSettings {
            kind: MapKind::Reflection,
            resolution_m: 0.1,
            max_range_m: 5.0,
        };
        let file = rebuild_map(&frames, &poses, &settings).unwrap();
        let StoredStats::Planar(stats) = &file.stats else {
            panic!("a planar map")
        };
        // One scan: four returns below 5 m, the 10 m reading is a no-return (not traced).
        assert_eq!(stats.summary().hits, 4);
        assert_eq!(stats.summary().no_returns_skipped, 1);
        assert!(!file.mapping.include_no_returns);
    }
}
