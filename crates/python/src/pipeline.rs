//! The Rust side of the bindings that is more than one library call, without Python types:
//! the Python functions and the overhead benchmark (`examples/overhead.rs`) both call it.

use raypath_geometry::{Grid2, Pose2};
use raypath_io::sequence::PlanarFrame;
use raypath_sensor_models::export::{MapKind, MapPicture, StoredStats, picture_values};
use raypath_slam::MapSettings;

/// Largest map [`rebuild_map`] allocates, cells.
pub const MAX_CELLS: usize = raypath_slam::map::MAX_MAP_CELLS;

/// The reflection map of `frames` at `poses` ([`raypath_slam::rebuild_map`], the map
/// `raypath slam` writes): a grid covering the poses and the returns below `max_range`,
/// no-returns not traced. Returns the grid and the reflection probability of every cell
/// (x fastest; `None`: no ray crossed it).
pub fn rebuild_map(
    frames: &[PlanarFrame],
    poses: &[Pose2],
    resolution: f64,
    max_range: f64,
) -> Result<(Grid2, Vec<Option<f64>>), String> {
    let settings = MapSettings {
        kind: MapKind::Reflection,
        resolution_m: resolution,
        max_range_m: max_range,
    };
    let file = raypath_slam::rebuild_map(frames, poses, &settings).map_err(|e| e.to_string())?;
    match &file.stats {
        StoredStats::Planar(stats) => {
            Ok((*stats.grid(), picture_values(stats, MapPicture::Reflection)))
        }
        StoredStats::Spatial(_) => Err("a 2-D map was expected".into()),
    }
}
