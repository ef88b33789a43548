//! A local map of labelled scans (real SemanticKITTI frames or simulated ones): extraction
//! on all its scans or on some of them, its reference poles ([`reference_poles`]) and the
//! region where detections are scored.

use std::ops::RangeInclusive;
use std::path::Path;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::kitti::KittiSequence;

use crate::drive::Drive;
use crate::error::{PoleError, Result};
use crate::extract::{ExtractionStats, extract_poles_from_sweeps};
use crate::params::PoleParams;
use crate::pole::Pole;
use crate::reference::{ReferenceRule, ReferenceSet, reference_poles};
use crate::sweep::{SweepMotion, SweepTiming};

/// Registered scans with raw SemanticKITTI labels in [`PointCloud::label`] (class in the low
/// 16 bits, instance in the high 16).
#[derive(Clone, Debug)]
pub struct LabelledLocalMap {
    /// `world_from_sensor` and the scan (points in the sensor frame, REP-103, metres).
    pub scans: Vec<(Pose3, PointCloud)>,
    /// The sensor's motion during each scan when the scans are de-skewed sweeps (rays are
    /// then traced from where the sensor was at each point), `None` for scans measured from
    /// one pose.
    pub motions: Option<Vec<SweepMotion>>,
}

/// Where detections and references are compared: within `radius_m` of a scan position of
/// the local map, and at least `margin_m` inside the footprint of its grid.
#[derive(Clone, Debug, PartialEq)]
pub struct ScoringRegion {
    positions: Vec<(f64, f64)>,
    radius_m: f64,
    min: (f64, f64),
    max: (f64, f64),
}

impl ScoringRegion {
    /// True when the ground-plane point `(x, y)` is in the region.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        x >= self.min.0
            && x <= self.max.0
            && y >= self.min.1
            && y <= self.max.1
            && self
                .positions
                .iter()
                .any(|p| (p.0 - x).hypot(p.1 - y) <= self.radius_m)
    }
}

impl LabelledLocalMap {
    /// A local map of `scans`; fails when there are none or one lacks a label per point.
    pub fn new(scans: Vec<(Pose3, PointCloud)>) -> Result<Self> {
        let invalid = |reason: String| PoleError::InvalidParameter {
            name: "scans",
            reason,
        };
        if scans.is_empty() {
            return Err(invalid("no scans".into()));
        }
        if let Some(k) = scans
            .iter()
            .position(|(_, c)| c.label.as_ref().is_none_or(|l| l.len() != c.len()))
        {
            return Err(invalid(format!("scan {k} has no label per point")));
        }
        Ok(Self {
            scans,
            motions: None,
        })
    }

    /// The same map with the sensor's motion during each scan (one per scan).
    pub fn with_motions(mut self, motions: Vec<SweepMotion>) -> Result<Self> {
        if motions.len() != self.scans.len() {
            return Err(PoleError::InvalidParameter {
                name: "motions",
                reason: format!("{} motions for {} scans", motions.len(), self.scans.len()),
            });
        }
        self.motions = Some(motions);
        Ok(self)
    }

    /// Reads the scans `range` of a KITTI sequence directory (`velodyne/`, `labels/`,
    /// `poses.txt`, `calib.txt`; poses as [`Drive::open`]: the velodyne frame of the first
    /// frame is the world frame) with their SemanticKITTI labels, as de-skewed sweeps
    /// ([`SweepTiming::kitti`], the motion from the poses of neighbouring scans).
    pub fn read_kitti(dir: &Path, range: std::ops::Range<usize>) -> Result<Self> {
        let drive = Drive::open(dir)?;
        let poses = drive.require_ground_truth()?;
        let sequence = KittiSequence::open(dir)?;
        let missing = |reason: String| PoleError::Sequence {
            path: dir.to_path_buf(),
            reason,
        };
        let all_motions =
            SweepMotion::from_poses(poses, &drive.sweeps.stamps_secs, SweepTiming::kitti());
        let mut scans = Vec::with_capacity(range.len());
        let mut motions = Vec::with_capacity(range.len());
        for i in range {
            let file = sequence
                .scan_files
                .get(i)
                .ok_or_else(|| missing(format!("no scan {i}")))?;
            let labels = sequence
                .labels(file.frame)?
                .ok_or_else(|| missing(format!("no labels for frame {}", file.frame)))?;
            let mut cloud = drive.sweeps.sweep(i)?;
            cloud.label = Some(labels.iter().map(|l| l.raw()).collect());
            let pose = poses
                .get(i)
                .ok_or_else(|| missing(format!("no pose for scan {i}")))?;
            scans.push((*pose, cloud));
            motions.extend(all_motions.get(i).copied());
        }
        Self::new(scans)?.with_motions(motions)
    }

    /// Number of scans.
    pub fn len(&self) -> usize {
        self.scans.len()
    }

    /// True when the map has no scans (never, by construction).
    pub fn is_empty(&self) -> bool {
        self.scans.is_empty()
    }

    /// Of the scans `indices`, the one at the middle of their arc length (the centre of
    /// their local map, as [`segments`](crate::segments)).
    pub fn center_scan(&self, indices: &[usize]) -> usize {
        let position = |i: usize| {
            self.scans
                .get(i)
                .map_or_else(nalgebra::Vector3::zeros, |s| s.0.translation())
        };
        let mut arc = vec![0.0];
        for w in indices.windows(2) {
            let step = (position(w[1]) - position(w[0])).norm();
            arc.push(arc.last().copied().unwrap_or(0.0) + step);
        }
        let mid = 0.5 * arc.last().copied().unwrap_or(0.0);
        (0..indices.len())
            .min_by(|&a, &b| (arc[a] - mid).abs().total_cmp(&(arc[b] - mid).abs()))
            .map_or(0, |k| indices[k])
    }

    fn center(&self, indices: &[usize]) -> Point3<f64> {
        let c = self.center_scan(indices);
        self.scans
            .get(c)
            .map_or_else(Point3::origin, |s| Point3::from(s.0.translation()))
    }

    /// Extracts poles from the scans `indices` in one local map centred at their
    /// [`center_scan`](Self::center_scan). Poles in the world frame.
    pub fn extract(
        &self,
        indices: &[usize],
        params: &PoleParams,
    ) -> Result<(Vec<Pole>, ExtractionStats)> {
        let scans: Vec<(Pose3, &PointCloud)> = indices
            .iter()
            .filter_map(|&i| self.scans.get(i).map(|(p, c)| (*p, c)))
            .collect();
        let motions: Option<Vec<SweepMotion>> = self
            .motions
            .as_ref()
            .map(|m| indices.iter().filter_map(|&i| m.get(i).copied()).collect());
        extract_poles_from_sweeps(&scans, motions.as_deref(), &self.center(indices), params)
    }

    /// All scan indices.
    pub fn all(&self) -> Vec<usize> {
        (0..self.scans.len()).collect()
    }

    /// The height band of the grid of the local map of all scans (world `z`).
    pub fn z_band(&self, params: &PoleParams) -> RangeInclusive<f64> {
        let bottom = self.center(&self.all()).z - params.sensor_in_grid_m[2];
        bottom..=bottom + params.extent_m[2]
    }

    /// The reference poles of all scans, from the points in the height band of their grid.
    pub fn references(&self, params: &PoleParams, rule: &ReferenceRule) -> Result<ReferenceSet> {
        let scans: Vec<(Pose3, &PointCloud)> = self.scans.iter().map(|(p, c)| (*p, c)).collect();
        reference_poles(&scans, self.z_band(params), rule)
    }

    /// The scoring region of the local map of the scans `indices`: within `radius_m` of one
    /// of their positions and at least `margin_m` inside their grid's footprint.
    pub fn region(
        &self,
        indices: &[usize],
        params: &PoleParams,
        radius_m: f64,
        margin_m: f64,
    ) -> ScoringRegion {
        let c = self.center(indices);
        let [ox, oy, _] = params.sensor_in_grid_m;
        let [ex, ey, _] = params.extent_m;
        ScoringRegion {
            positions: indices
                .iter()
                .filter_map(|&i| self.scans.get(i))
                .map(|(p, _)| (p.translation().x, p.translation().y))
                .collect(),
            radius_m,
            min: (c.x - ox + margin_m, c.y - oy + margin_m),
            max: (c.x - ox + ex - margin_m, c.y - oy + ey - margin_m),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labelled(n: usize) -> PointCloud {
        let mut c = PointCloud::from_points(vec![Point3::new(1.0, 0.0, 0.0); n]);
        c.label = Some(vec![80; n]);
        c
    }

    #[test]
    fn centre_and_region_follow_the_scans() {
        let scans: Vec<(Pose3, PointCloud)> = (0..5)
            .map(|i| {
                let pose = Pose3::from_xyz_rpy(2.0 * i as f64, 0.0, 0.5, 0.0, 0.0, 0.0);
                (pose, labelled(3))
            })
            .collect();
        let map = LabelledLocalMap::new(scans).unwrap();
        assert_eq!(map.center_scan(&map.all()), 2);
        assert_eq!(map.center_scan(&[3]), 3);
        let params = PoleParams::kitti();
        let band = map.z_band(&params);
        assert!((band.start() + 1.5).abs() < 1e-12 && (band.end() - 1.5).abs() < 1e-12);
        // Grid of the centre scan (4, 0): x in −11..19, y in −15..15; 1 m margin.
        let region = map.region(&map.all(), &params, 12.0, 1.0);
        assert!(region.contains(17.5, 0.0) && !region.contains(18.5, 0.0));
        assert!(region.contains(0.0, 11.9) && !region.contains(0.0, 12.1));
        assert!(!region.contains(-10.5, 0.0));
        let single = map.region(&[0], &params, 12.0, 1.0);
        assert!(!single.contains(12.5, 0.0) && single.contains(-11.5, 0.0));
    }

    #[test]
    fn scans_need_labels() {
        assert!(LabelledLocalMap::new(Vec::new()).is_err());
        let bare = PointCloud::from_points(vec![Point3::origin()]);
        assert!(LabelledLocalMap::new(vec![(Pose3::identity(), bare)]).is_err());
    }
}
