//! Voxel-grid down-sampling (Khan 2017, §4.5.2, voxel size ψ) and uniform keypoint sampling
//! on a coarser grid (ours: the thesis names no detector).

use nalgebra::Point3;
use raypath_geometry::PointCloud;

use crate::error::require_positive;
use crate::{PlaceError, Result};

/// Largest voxel index magnitude accepted (keeps the integer keys exact).
const MAX_CELL: f64 = (1u64 << 40) as f64;

/// Integer voxel keys of the finite points of `points` (and finite intensity, when given),
/// sorted with the point index as tie-break: deterministic whatever the input order.
fn sorted_keys(
    points: &[Point3<f32>],
    intensity: Option<&[f32]>,
    size: f64,
) -> Result<Vec<([i64; 3], u32)>> {
    let inv = 1.0 / size;
    let mut keys = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let finite_i = intensity.is_none_or(|v| v[i].is_finite());
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite() && finite_i) {
            continue;
        }
        let cell = [p.x, p.y, p.z].map(|c| (f64::from(c) * inv).floor());
        if cell.iter().any(|c| c.abs() > MAX_CELL) {
            return Err(PlaceError::BadInput(format!(
                "point {i} at ({}, {}, {}) is too far from the origin for a {size} m grid",
                p.x, p.y, p.z
            )));
        }
        let index = u32::try_from(i)
            .map_err(|_| PlaceError::BadInput("cloud has more than 2^32 points".into()))?;
        keys.push((cell.map(|c| c as i64), index));
    }
    keys.sort_unstable();
    Ok(keys)
}

/// Down-samples a cloud on a voxel grid of edge `voxel_size` (ψ, metres): one point per
/// occupied voxel at the centroid of its points, with their mean intensity when the cloud has
/// intensities. Voxels come in lexicographic order of their integer coordinates.
/// Non-finite points (and points with a non-finite intensity) are skipped.
pub fn voxel_downsample(cloud: &PointCloud, voxel_size: f64) -> Result<PointCloud> {
    require_positive("voxel_size", voxel_size)?;
    let intensity = cloud.intensity.as_deref();
    if intensity.is_some_and(|v| v.len() != cloud.points.len()) {
        return Err(PlaceError::BadInput(
            "intensity and point counts differ".into(),
        ));
    }
    let keys = sorted_keys(&cloud.points, intensity, voxel_size)?;
    let mut points = Vec::new();
    let mut out_intensity = intensity.map(|_| Vec::new());
    let mut start = 0;
    while start < keys.len() {
        let key = keys[start].0;
        let end = start + keys[start..].iter().take_while(|k| k.0 == key).count();
        let (mut sum, mut sum_i) = ([0f64; 3], 0f64);
        for &(_, i) in &keys[start..end] {
            let p = &cloud.points[i as usize];
            sum[0] += f64::from(p.x);
            sum[1] += f64::from(p.y);
            sum[2] += f64::from(p.z);
            if let Some(v) = intensity {
                sum_i += f64::from(v[i as usize]);
            }
        }
        let n = (end - start) as f64;
        points.push(Point3::new(
            (sum[0] / n) as f32,
            (sum[1] / n) as f32,
            (sum[2] / n) as f32,
        ));
        if let Some(out) = out_intensity.as_mut() {
            out.push((sum_i / n) as f32);
        }
        start = end;
    }
    let mut down = PointCloud::from_points(points);
    down.intensity = out_intensity;
    Ok(down)
}

/// Uniform keypoints (ours): on a grid of edge `spacing` metres, the point of `cloud` nearest
/// the centroid of each occupied cell (ties → lower index); with more than `max_keypoints`
/// cells, those nearest the origin (the sensor: the cloud is densest there and nearby frames
/// overlap most; ties → lower index). Indices ascend.
pub fn uniform_keypoints(
    cloud: &PointCloud,
    spacing: f64,
    max_keypoints: usize,
) -> Result<Vec<usize>> {
    require_positive("keypoint_spacing", spacing)?;
    let keys = sorted_keys(&cloud.points, None, spacing)?;
    let mut picked = Vec::new();
    let mut start = 0;
    while start < keys.len() {
        let key = keys[start].0;
        let end = start + keys[start..].iter().take_while(|k| k.0 == key).count();
        let group = &keys[start..end];
        let mut c = nalgebra::Vector3::<f64>::zeros();
        for &(_, i) in group {
            c += cloud.point_f64(i as usize).coords;
        }
        c /= group.len() as f64;
        let best = group
            .iter()
            .map(|&(_, i)| ((cloud.point_f64(i as usize).coords - c).norm_squared(), i))
            .fold(
                (f64::INFINITY, u32::MAX),
                |b, x| if x.0 < b.0 { x } else { b },
            );
        picked.push(best.1 as usize);
        start = end;
    }
    if picked.len() > max_keypoints {
        let range_2 = |i: usize| cloud.point_f64(i).coords.norm_squared();
        picked.sort_by(|&a, &b| range_2(a).total_cmp(&range_2(b)).then(a.cmp(&b)));
        picked.truncate(max_keypoints);
    }
    picked.sort_unstable();
    Ok(picked)
}
