//! The Rust side of the bindings that is more than one library call, without Python types:
//! the Python functions and the overhead benchmark (`examples/overhead.rs`) both call it.

use raypath_geometry::{Aabb2, Grid2, Pose2, Scan2};
use raypath_io::sequence::PlanarFrame;
use raypath_sensor_models::export::{MapPicture, picture_values};
use raypath_sensor_models::{DenseStats2, MappingConfig};

/// Largest map [`rebuild_map`] allocates, cells.
pub const MAX_CELLS: usize = 200_000_000;

/// The reflection map of `frames` at `poses`: a grid covering the poses and the returns
/// below `max_range`, no-returns not traced (as `raypath slam` rebuilds its map). Returns the
/// grid and the reflection probability of every cell (x fastest; `None`: no ray crossed it).
pub fn rebuild_map(
    frames: &[PlanarFrame],
    poses: &[Pose2],
    resolution: f64,
    max_range: f64,
) -> Result<(Grid2, Vec<Option<f64>>), String> {
    let mut bounds = Aabb2::empty();
    let mut scans: Vec<(Pose2, &Scan2)> = Vec::with_capacity(frames.len());
    for (frame, pose) in frames.iter().zip(poses) {
        if !pose.is_finite() {
            continue;
        }
        bounds.extend(&nalgebra::Point2::new(pose.x(), pose.y()));
        for ray in frame.scan.rays(*pose) {
            if let Some(t) = ray.range.hit().filter(|&t| t < max_range) {
                bounds.extend(&ray.at(t));
            }
        }
        scans.push((*pose, &frame.scan));
    }
    let grid = Grid2::covering(&bounds, resolution).map_err(|e| e.to_string())?;
    let [w, h] = grid.dims();
    if w.saturating_mul(h) > MAX_CELLS {
        return Err(format!(
            "the map would have {w} × {h} cells of {resolution} m (at most {MAX_CELLS})"
        ));
    }
    let mut config = MappingConfig::with_range(0.0, max_range).map_err(|e| e.to_string())?;
    config.include_no_returns = false;
    let mut stats = DenseStats2::planar(grid);
    stats.insert_scans_par(&scans, &config);
    let values = picture_values(&stats, MapPicture::Reflection);
    Ok((grid, values))
}
