//! Statistics of plane-labelled organized scans, for simulated and real SynPEB clouds alike.

use std::collections::HashMap;

use raypath_geometry::PointCloud;
use serde::Serialize;

/// Label threshold of planes (SynPEB and SegComp: labels ≥ 10 are planes).
pub const MIN_PLANE_LABEL: u32 = 10;

/// Statistics of one labelled scan (sensor at the origin of the cloud's frame).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScanStats {
    /// Pixels (points including no-returns).
    pub pixels: usize,
    /// Distinct plane labels (≥ 10) among the returns — how `synpebstat.m` of the PPE code
    /// counts planes per scan.
    pub planes: usize,
    /// Distinct plane labels with at least 10 returns.
    pub planes_min_10_pixels: usize,
    /// Fraction of all pixels that are returns on a plane.
    pub plane_pixel_fraction: f64,
    /// Fraction of pixels without a return.
    pub no_return_fraction: f64,
    /// Smallest range of a return, metres (NaN without returns).
    pub range_min_m: f64,
    /// Median range of the returns, metres.
    pub range_median_m: f64,
    /// Largest range of a return, metres.
    pub range_max_m: f64,
}

/// The statistics of `cloud`. Labels come from the label channel, or else from the intensity
/// channel (the SynPEB convention; rounded); without either, every return counts as unlabelled.
pub fn scan_stats(cloud: &PointCloud) -> ScanStats {
    let label_of = |i: usize| -> u32 {
        if let Some(labels) = &cloud.label {
            labels.get(i).copied().unwrap_or(0)
        } else if let Some(intensity) = &cloud.intensity {
            intensity
                .get(i)
                .filter(|v| v.is_finite() && **v >= 0.0)
                .map_or(0, |v| v.round() as u32)
        } else {
            0
        }
    };
    let mut counts: HashMap<u32, usize> = HashMap::new();
    let mut ranges = Vec::with_capacity(cloud.len());
    let mut plane_pixels = 0;
    for (i, p) in cloud.points.iter().enumerate() {
        if !p.iter().all(|v| v.is_finite()) {
            continue;
        }
        ranges.push(f64::from(p.coords.norm()));
        let label = label_of(i);
        if label >= MIN_PLANE_LABEL {
            plane_pixels += 1;
            *counts.entry(label).or_default() += 1;
        }
    }
    ranges.sort_by(f64::total_cmp);
    let pixels = cloud.len();
    let fraction = |n: usize| {
        if pixels == 0 {
            0.0
        } else {
            n as f64 / pixels as f64
        }
    };
    ScanStats {
        pixels,
        planes: counts.len(),
        planes_min_10_pixels: counts.values().filter(|&&n| n >= 10).count(),
        plane_pixel_fraction: fraction(plane_pixels),
        no_return_fraction: fraction(pixels - ranges.len()),
        range_min_m: ranges.first().copied().unwrap_or(f64::NAN),
        range_median_m: ranges.get(ranges.len() / 2).copied().unwrap_or(f64::NAN),
        range_max_m: ranges.last().copied().unwrap_or(f64::NAN),
    }
}

/// The `rows × cols` window of an organized cloud starting at pixel `(row0, col0)` (clipped
/// to the cloud).
pub fn crop(cloud: &PointCloud, row0: usize, col0: usize, rows: usize, cols: usize) -> PointCloud {
    let row_end = (row0 + rows).min(cloud.height);
    let col_end = (col0 + cols).min(cloud.width);
    let (height, width) = (row_end.saturating_sub(row0), col_end.saturating_sub(col0));
    let indices: Vec<usize> = (row0..row_end)
        .flat_map(|r| (col0..col_end).map(move |c| r * cloud.width + c))
        .filter(|&i| i < cloud.len())
        .collect();
    let pick = |v: &Vec<f32>| indices.iter().filter_map(|&i| v.get(i).copied()).collect();
    PointCloud {
        points: indices
            .iter()
            .filter_map(|&i| cloud.points.get(i).copied())
            .collect(),
        intensity: cloud.intensity.as_ref().map(pick),
        label: cloud
            .label
            .as_ref()
            .map(|v| indices.iter().filter_map(|&i| v.get(i).copied()).collect()),
        rgb: None,
        width,
        height,
    }
}

/// Mean, minimum and maximum of `values` as JSON (`null`s when empty).
pub(super) fn summary(values: &[f64]) -> serde_json::Value {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let min = values.iter().copied().fold(f64::INFINITY, f64::min);
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let finite = |v: f64| {
        if v.is_finite() {
            serde_json::json!(v)
        } else {
            serde_json::Value::Null
        }
    };
    serde_json::json!({ "mean": finite(mean), "min": finite(min), "max": finite(max) })
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    #[test]
    fn counts_planes_fractions_and_ranges() {
        let nan = Point3::new(f32::NAN, f32::NAN, f32::NAN);
        let cloud = PointCloud {
            points: vec![
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(0.0, 2.0, 0.0),
                Point3::new(0.0, 0.0, 3.0),
                nan,
            ],
            intensity: Some(vec![10.0, 12.0, 3.0, 0.0]),
            label: None,
            rgb: None,
            width: 2,
            height: 2,
        };
        let s = scan_stats(&cloud);
        assert_eq!((s.planes, s.planes_min_10_pixels), (2, 0));
        assert_eq!((s.plane_pixel_fraction, s.no_return_fraction), (0.5, 0.25));
        assert_eq!(
            (s.range_min_m, s.range_median_m, s.range_max_m),
            (1.0, 2.0, 3.0)
        );
        let c = crop(&cloud, 1, 0, 5, 1);
        assert_eq!((c.width, c.height), (1, 1));
        assert_eq!(c.intensity, Some(vec![3.0]));
    }
}
