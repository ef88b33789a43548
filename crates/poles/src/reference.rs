//! Reference poles from labelled scans and detection quality per class.
//!
//! SemanticKITTI (Behley et al., "SemanticKITTI: A Dataset for Semantic Scene Understanding
//! of LiDAR Sequences", ICCV 2019) labels pole (80), trunk (71) and traffic-sign (81) points
//! but gives them no instance ids (instance 0), so reference poles are formed here by
//! clustering the labelled points of a local map in the world frame:
//!
//! 1. points of the classes 80 and 81 together (a sign plate joins the post it is mounted
//!    on), and points of class 71 apart, each linked in the ground plane when closer than
//!    [`ReferenceRule::link_m`] (single linkage: connected components);
//! 2. a component is a **pole** when its pole points number at least
//!    [`ReferenceRule::min_points`] and span at least [`ReferenceRule::min_extent_m`]
//!    vertically; otherwise a **traffic sign** when its sign points number at least
//!    `min_points` (a plate on a wall, or on a post not labelled or too short); a trunk
//!    component is a **trunk** under the pole rule; anything else is dropped;
//! 3. the centre is the mean ground-plane position of the shaft points (pole or trunk
//!    points; for signs all points of the component): the centroid of the visible surface,
//!    off the axis towards the sensor by up to `2r/π` for a radius `r`.

use std::collections::HashMap;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};
use serde::{Deserialize, Serialize};

use crate::error::{PoleError, Result};
use crate::mapping::find;
use crate::pipeline::DetectionQuality;
use crate::pole::Pole;

/// The pole-like SemanticKITTI classes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PoleClass {
    /// Poles: street-light masts, sign posts, traffic-light posts (class 80).
    Pole,
    /// Tree trunks (class 71).
    Trunk,
    /// Traffic signs without a labelled post of their own (class 81).
    TrafficSign,
}

impl PoleClass {
    /// All classes.
    pub const ALL: [PoleClass; 3] = [PoleClass::Pole, PoleClass::Trunk, PoleClass::TrafficSign];

    /// The SemanticKITTI class id (`semantic-kitti.yaml`).
    pub fn semantic_id(self) -> u16 {
        match self {
            PoleClass::Pole => 80,
            PoleClass::Trunk => 71,
            PoleClass::TrafficSign => 81,
        }
    }

    /// The SemanticKITTI class name.
    pub fn name(self) -> &'static str {
        match self {
            PoleClass::Pole => "pole",
            PoleClass::Trunk => "trunk",
            PoleClass::TrafficSign => "traffic-sign",
        }
    }
}

/// How labelled points become reference poles (module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceRule {
    /// Ground-plane linking distance of the connected components, metres (0.5: wider than
    /// the gap between a post and its plate, narrower than the spacing of neighbouring
    /// poles, 1–2 m at the closest in the KITTI pole maps).
    pub link_m: f64,
    /// Minimum labelled points of the class in a component over all scans of the local map
    /// (10: fewer are single rings or label noise).
    pub min_points: usize,
    /// Minimum vertical extent of the pole or trunk points, metres (1.0: the extractor's
    /// minimum pole height `h_min`, Schaefer 2020 §12.3, so that a reference pole is a pole
    /// by the extractor's own definition when seen).
    pub min_extent_m: f64,
}

impl Default for ReferenceRule {
    fn default() -> Self {
        Self {
            link_m: 0.5,
            min_points: 10,
            min_extent_m: 1.0,
        }
    }
}

/// A reference pole.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferencePole {
    /// Centre x (world frame), metres.
    pub x: f64,
    /// Centre y (world frame), metres.
    pub y: f64,
    /// The class.
    pub class: PoleClass,
    /// Points the centre is the mean of.
    pub points: usize,
    /// Lowest of those points, metres.
    pub z_min: f64,
    /// Highest of those points, metres.
    pub z_max: f64,
    /// Traffic-sign points in the component (plates on a pole).
    pub sign_points: usize,
}

/// The reference poles of a local map and what the rule dropped.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ReferenceSet {
    /// The references.
    pub poles: Vec<ReferencePole>,
    /// Components below the rule (too few points or too short).
    pub dropped: usize,
}

/// A labelled world point.
#[derive(Clone, Copy)]
struct Labelled {
    p: Point3<f64>,
    class: u16,
}

/// The reference poles of registered scans (`world_from_sensor`, points in the sensor frame
/// with raw SemanticKITTI labels in [`PointCloud::label`]: class in the low 16 bits), using
/// only points whose world `z` lies in `z_band` (the height band of the local map).
///
/// Fails when a scan has no labels or not one per point.
pub fn reference_poles(
    scans: &[(Pose3, &PointCloud)],
    z_band: std::ops::RangeInclusive<f64>,
    rule: &ReferenceRule,
) -> Result<ReferenceSet> {
    let (mut posts, mut trunks) = (Vec::new(), Vec::new());
    for (k, (pose, cloud)) in scans.iter().enumerate() {
        let labels = cloud
            .label
            .as_deref()
            .filter(|l| l.len() == cloud.len())
            .ok_or_else(|| PoleError::InvalidParameter {
                name: "scans",
                reason: format!("scan {k} has no label per point"),
            })?;
        for (point, &raw) in cloud.points.iter().zip(labels) {
            let class = (raw & 0xffff) as u16;
            let list = match class {
                80 | 81 => &mut posts,
                71 => &mut trunks,
                _ => continue,
            };
            let p = pose.transform_point(&point.cast::<f64>());
            if p.iter().all(|v| v.is_finite()) && z_band.contains(&p.z) {
                list.push(Labelled { p, class });
            }
        }
    }
    let mut out = ReferenceSet::default();
    for points in [posts, trunks] {
        let ids = components(&points, rule.link_m);
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by_key(|&i| ids[i]);
        for group in order.chunk_by(|&a, &b| ids[a] == ids[b]) {
            match classify(group.iter().map(|&i| points[i]), rule) {
                Some(pole) => out.poles.push(pole),
                None => out.dropped += 1,
            }
        }
    }
    out.poles
        .sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    Ok(out)
}

/// Connected components of the points in the ground plane at linking distance `link`
/// (grid of `link`-sized cells, neighbours in the 3 × 3 cells around). A component id per
/// point.
fn components(points: &[Labelled], link: f64) -> Vec<usize> {
    let cell = |p: &Point3<f64>| ((p.x / link).floor() as i64, (p.y / link).floor() as i64);
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, l) in points.iter().enumerate() {
        cells.entry(cell(&l.p)).or_default().push(i);
    }
    let mut parent: Vec<usize> = (0..points.len()).collect();
    let link2 = link * link;
    for (&(cx, cy), members) in &cells {
        for (dx, dy) in [(0, 0), (1, -1), (1, 0), (1, 1), (0, 1)] {
            let Some(others) = cells.get(&(cx + dx, cy + dy)) else {
                continue;
            };
            for &i in members {
                for &j in others {
                    if (dx, dy) == (0, 0) && j <= i {
                        continue;
                    }
                    let (a, b) = (&points[i].p, &points[j].p);
                    if (a.x - b.x).powi(2) + (a.y - b.y).powi(2) <= link2 {
                        let (ra, rb) = (find(&mut parent, i), find(&mut parent, j));
                        if ra != rb {
                            parent[ra] = rb;
                        }
                    }
                }
            }
        }
    }
    (0..points.len()).map(|i| find(&mut parent, i)).collect()
}

/// Mean position and vertical span of points.
#[derive(Default)]
struct Part {
    n: usize,
    sx: f64,
    sy: f64,
    z_min: f64,
    z_max: f64,
}

impl Part {
    fn add(&mut self, p: &Point3<f64>) {
        if self.n == 0 {
            (self.z_min, self.z_max) = (p.z, p.z);
        }
        self.n += 1;
        self.sx += p.x;
        self.sy += p.y;
        self.z_min = self.z_min.min(p.z);
        self.z_max = self.z_max.max(p.z);
    }

    fn qualifies(&self, rule: &ReferenceRule) -> bool {
        self.n >= rule.min_points && self.z_max - self.z_min >= rule.min_extent_m
    }

    fn pole(&self, class: PoleClass, sign_points: usize) -> ReferencePole {
        let n = self.n.max(1) as f64;
        ReferencePole {
            x: self.sx / n,
            y: self.sy / n,
            class,
            points: self.n,
            z_min: self.z_min,
            z_max: self.z_max,
            sign_points,
        }
    }
}

/// The reference of one component, `None` when the rule drops it.
fn classify(points: impl Iterator<Item = Labelled>, rule: &ReferenceRule) -> Option<ReferencePole> {
    let (mut pole, mut trunk, mut sign, mut all) = (
        Part::default(),
        Part::default(),
        Part::default(),
        Part::default(),
    );
    for l in points {
        let part: &mut Part = match l.class {
            80 => &mut pole,
            71 => &mut trunk,
            _ => &mut sign,
        };
        part.add(&l.p);
        all.add(&l.p);
    }
    if pole.qualifies(rule) {
        Some(pole.pole(PoleClass::Pole, sign.n))
    } else if trunk.qualifies(rule) {
        Some(trunk.pole(PoleClass::Trunk, 0))
    } else if sign.n >= rule.min_points {
        Some(all.pole(PoleClass::TrafficSign, sign.n))
    } else {
        None
    }
}

/// Greedy one-to-one matching of detections to references, closest pairs first, within
/// `radius_m`: `(detection, reference, distance)` per match.
pub fn greedy_matches(
    detected: &[(f64, f64)],
    truth: &[(f64, f64)],
    radius_m: f64,
) -> Vec<(usize, usize, f64)> {
    let mut pairs = Vec::new();
    for (i, d) in detected.iter().enumerate() {
        for (j, t) in truth.iter().enumerate() {
            let dist = (d.0 - t.0).hypot(d.1 - t.1);
            if dist <= radius_m {
                pairs.push((i, j, dist));
            }
        }
    }
    pairs.sort_by(|a, b| a.2.total_cmp(&b.2));
    let (mut used_d, mut used_t) = (vec![false; detected.len()], vec![false; truth.len()]);
    pairs.retain(|&(i, j, _)| {
        let free = !used_d[i] && !used_t[j];
        if free {
            (used_d[i], used_t[j]) = (true, true);
        }
        free
    });
    pairs
}

/// Detection quality against the references of `classes`: detections and references are
/// matched once, jointly over all classes (greedy, within `radius_m`); detections matched
/// to a reference of another class are left out of the count of detections (a trunk found
/// is no false pole), so `precision = matched / (detected − matched to other classes)` and
/// `recall = matched / references of the classes`.
pub fn class_quality(
    detected: &[Pole],
    reference: &[ReferencePole],
    classes: &[PoleClass],
    radius_m: f64,
) -> DetectionQuality {
    let d: Vec<(f64, f64)> = detected.iter().map(|p| (p.x, p.y)).collect();
    let t: Vec<(f64, f64)> = reference.iter().map(|p| (p.x, p.y)).collect();
    let matches = greedy_matches(&d, &t, radius_m);
    let wanted = |j: usize| classes.contains(&reference[j].class);
    let other = matches.iter().filter(|m| !wanted(m.1)).count();
    let ours: Vec<f64> = matches
        .iter()
        .filter(|m| wanted(m.1))
        .map(|m| m.2)
        .collect();
    let truth = (0..reference.len()).filter(|&j| wanted(j)).count();
    DetectionQuality::from_counts(detected.len() - other, truth, &ours)
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    /// A vertical line of points of `class` at (x, y) from z0 to z1, 0.1 m apart.
    fn column(x: f64, y: f64, z0: f64, z1: f64, class: u32) -> Vec<(Point3<f32>, u32)> {
        let n = ((z1 - z0) / 0.1).round() as usize + 1;
        (0..n)
            .map(|k| {
                let p = Point3::new(x as f32, y as f32, (z0 + 0.1 * k as f64) as f32);
                (p, class)
            })
            .collect()
    }

    fn cloud(parts: &[Vec<(Point3<f32>, u32)>]) -> PointCloud {
        let all: Vec<_> = parts.iter().flatten().copied().collect();
        let mut c = PointCloud::from_points(all.iter().map(|a| a.0).collect());
        c.label = Some(all.iter().map(|a| a.1).collect());
        c
    }

    #[test]
    fn components_follow_the_rule() {
        let scan = cloud(&[
            // A sign post with its plate 0.3 m beside it: one pole with sign points.
            column(0.0, 0.0, -1.7, 0.3, 80),
            column(0.3, 0.0, 0.0, 0.5, 81 | (7 << 16)),
            // A trunk 0.4 m from the post: a trunk of its own (trunks cluster apart).
            column(0.0, 0.4, -1.7, -0.2, 71),
            // A short pole (0.5 m): dropped; a lone plate: a traffic sign.
            column(5.0, 0.0, -1.7, -1.2, 80),
            column(8.0, 3.0, 0.0, 1.0, 81),
            // Outside the height band: unseen.
            column(12.0, 0.0, 2.0, 4.0, 80),
        ]);
        let pose = Pose3::from_xyz_rpy(1.0, 2.0, 0.0, 0.0, 0.0, 0.0);
        let set = reference_poles(&[(pose, &scan)], -2.0..=1.0, &ReferenceRule::default()).unwrap();
        assert_eq!(set.dropped, 1);
        let classes: Vec<_> = set.poles.iter().map(|p| (p.class, p.x, p.y)).collect();
        assert_eq!(classes.len(), 3, "{classes:?}");
        let post = set
            .poles
            .iter()
            .find(|p| p.class == PoleClass::Pole)
            .unwrap();
        assert!((post.x - 1.0).abs() < 1e-6 && (post.y - 2.0).abs() < 1e-6);
        assert_eq!((post.points, post.sign_points), (21, 6));
        let trunk = set
            .poles
            .iter()
            .find(|p| p.class == PoleClass::Trunk)
            .unwrap();
        assert!((trunk.y - 2.4).abs() < 1e-6);
        let sign = set
            .poles
            .iter()
            .find(|p| p.class == PoleClass::TrafficSign)
            .unwrap();
        assert!((sign.x - 9.0).abs() < 1e-6 && (sign.y - 5.0).abs() < 1e-6);
        let unlabelled = PointCloud::from_points(vec![Point3::origin()]);
        let error = reference_poles(
            &[(pose, &unlabelled)],
            -2.0..=1.0,
            &ReferenceRule::default(),
        );
        assert!(error.is_err());
    }

    #[test]
    fn single_linkage_chains_points() {
        // Points 0.4 m apart in a row form one component, a point 0.6 m further another.
        let p = |x: f64| Labelled {
            p: Point3::new(x, 0.0, 0.0),
            class: 80,
        };
        let ids = components(&[p(0.0), p(0.4), p(0.8), p(1.2), p(1.8)], 0.5);
        assert!(ids[..4].iter().all(|&i| i == ids[0]));
        assert_ne!(ids[4], ids[0]);
    }

    #[test]
    fn class_quality_ignores_detections_of_other_classes() {
        let det = |x: f64| Pole {
            x,
            y: 0.0,
            z_start: 0.0,
            z_end: 2.0,
            width: 0.2,
            score: 0.8,
        };
        let reference = |x: f64, class| ReferencePole {
            x,
            y: 0.0,
            class,
            points: 50,
            z_min: 0.0,
            z_max: 2.0,
            sign_points: 0,
        };
        let refs = [
            reference(0.0, PoleClass::Pole),
            reference(10.0, PoleClass::Pole),
            reference(20.0, PoleClass::Trunk),
        ];
        // A pole 0.1 m off, a trunk found, one false detection; the second pole missed.
        let found = [det(0.1), det(20.0), det(30.0)];
        let poles = class_quality(&found, &refs, &[PoleClass::Pole], 1.0);
        assert_eq!((poles.detected, poles.truth, poles.matched), (2, 2, 1));
        assert!((poles.precision - 0.5).abs() < 1e-12 && (poles.recall - 0.5).abs() < 1e-12);
        assert!((poles.mean_centre_error_m - 0.1).abs() < 1e-9);
        let both = class_quality(&found, &refs, &[PoleClass::Pole, PoleClass::Trunk], 1.0);
        assert_eq!((both.detected, both.truth, both.matched), (3, 3, 2));
    }
}
