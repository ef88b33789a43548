//! `raypath scan-match --record`: the scans at their estimated poses, the trajectory, and the
//! finest map level as occupancy and reflectivity Grids.

use raypath_geometry::Pose2;
use raypath_io::foxglove::{GridLayer, GridValues, frame, topic};
use raypath_io::sequence::PlanarFrame;
use raypath_reflectivity::{GridLevel, probability};

use crate::commands::Failure;
use crate::commands::record::Recording;

/// Cells kept around the observed part of the map.
const MARGIN: usize = 10;

/// Writes every scan at its estimate `world_from_laser` (`/tf` `map → base_link`, `/scan` in
/// `base_link` with the logged mounting), the robot's `/trajectory`, and, from `level`, the
/// occupancy probability as `/map` and the mean relative reflectivity as `/reflectivity`
/// (`FLOAT32`, NaN where unobserved), cropped to the observed cells plus a margin.
pub fn record(
    recording: &mut Recording,
    scans: &[PlanarFrame],
    poses: &[Pose2],
    level: Option<&GridLevel>,
) -> Result<(), Failure> {
    recording.planar_track(scans, poses)?;
    let end = recording.end_stamp();
    let Some(level) = level else {
        return Ok(());
    };
    let Some([i0, j0, i1, j1]) = raypath_reflectivity::export::observed_box(level, MARGIN) else {
        return Ok(());
    };
    let cells = || (j0..j1).flat_map(|j| (i0..i1).map(move |i| (i, j)));
    let occupancy: Vec<f32> = cells()
        .map(|(i, j)| match level.log_odds(i, j) {
            0.0 => f32::NAN,
            l => probability(l) as f32,
        })
        .collect();
    let resolution = level.resolution_m();
    let [x, y] = level.origin();
    let mut layer = GridLayer {
        frame_id: frame::MAP,
        origin: Pose2::new(x + i0 as f64 * resolution, y + j0 as f64 * resolution, 0.0).to_pose3(),
        cell_size_m: resolution,
        columns: i1 - i0,
        rows: j1 - j0,
        field: "occupancy",
        values: GridValues::F32(&occupancy),
    };
    recording.grid_layer(topic::MAP, end, &layer)?;
    if level.has_reflectivity() {
        let reflectivity: Vec<f32> = cells()
            .map(|(i, j)| level.cell_reflectivity(i, j).map_or(f32::NAN, |(m, _)| m))
            .collect();
        layer.field = "reflectivity";
        layer.values = GridValues::F32(&reflectivity);
        recording.grid_layer(topic::REFLECTIVITY, end, &layer)?;
    }
    Ok(())
}
