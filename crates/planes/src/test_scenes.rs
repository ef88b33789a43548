//! Synthetic organized scans of the unit tests of the extractors.

use nalgebra::Vector3;

/// A `width × height` organized scan from the origin of the wall x = 3 m and the floor
/// z = −1 m (row-major, row 0 on top): the ray of pixel (row, col) has the direction
/// `(1, (col − (width − 1)/2) · step, top − row · step)`, normalized.
pub(crate) fn wall_and_floor(
    width: usize,
    height: usize,
    step: f64,
    top: f64,
) -> Vec<Vector3<f64>> {
    let centre = (width as f64 - 1.0) / 2.0;
    let mut pts = Vec::with_capacity(width * height);
    for row in 0..height {
        for col in 0..width {
            let v = Vector3::new(1.0, (col as f64 - centre) * step, top - row as f64 * step)
                .normalize();
            let t_wall = 3.0 / v.x;
            let t_floor = if v.z < 0.0 { -1.0 / v.z } else { f64::INFINITY };
            pts.push(v * t_wall.min(t_floor));
        }
    }
    pts
}
