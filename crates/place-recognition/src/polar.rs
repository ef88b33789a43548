//! A Scan-Context-like global descriptor for planar scans, the 2-D geometric baseline.
//!
//! Scan Context (Kim & Kim, IROS 2018) bins a 3-D scan into rings × sectors around the sensor,
//! retrieves candidates with a rotation-invariant ring key in a k-d tree, and scores them by a
//! column-wise cosine distance minimised over column shifts (the unknown heading). We adapt the
//! idea to planar scans (written from the paper; this baseline is not in Khan 2017):
//!
//! * **Bins**: [`PolarConfig::rings`] rings of equal width up to [`PolarConfig::max_range_m`]
//!   × [`PolarConfig::sectors`] sectors over 360° (sector 0 starts at the sensor's x axis,
//!   counter-clockwise, REP-103). A planar scan has no height, so a bin holds the **number of
//!   end points** in it (occupancy weighted by count). With
//!   [`PolarConfig::soft_rings`] each end point is split linearly between the two nearest ring
//!   centres (ours), which keeps the descriptor from jumping when a wall crosses a ring border.
//!   No-returns, end points beyond `max_range_m` and non-finite readings are skipped.
//! * **Distance** (Kim & Kim, eq. (5)–(6)): for a column shift `n`,
//!   `d_n(q, c) = (1/N_s) Σ_j (1 − q_j · c_{j+n} / (‖q_j‖ ‖c_{j+n}‖))` over sectors `j`; two
//!   empty columns contribute 0 and one empty column 1 (ours: the paper does not say). The
//!   distance is `min_n d_n`, and the score `1 − min_n d_n ∈ [0, 1]`. A cosine per column is
//!   blind to the count scale, so "count" and "share of the sector's beams" give equal
//!   distances.
//! * **Ring key**: the share of occupied sectors per ring, invariant to heading. The k-d tree
//!   needs a fixed dimension, so the key always has [`KEY_DIM`] = 20 components: with 20 rings
//!   (the default) component `j` is ring `j`; with more rings it is the mean over the rings
//!   that fall in range band `j`; with fewer, ring `⌊j · rings / 20⌋` (ours).
//! * **Retrieval**: with `candidates = Some(k)` the `k` frames whose keys are nearest (kiddo
//!   k-d tree, squared Euclidean; identical keys share one tree entry) among frames `< before`
//!   are scored exactly; `None` scores every frame `< before`.
//!
//! Defaults (20 rings up to 20 m, 60 sectors, 10 candidates) follow Scan Context's paper setup
//! (20 × 60 bins, a few candidates) with an indoor-laser range of 20 m (ours; the paper uses
//! 80 m for Velodyne scans).

use std::collections::HashMap;

use kiddo::{KdTree, SquaredEuclidean};
use raypath_geometry::Scan2;

use crate::{Candidate, Frame, PlaceError, PlaceRecognizer, Result};

/// Dimension of the ring key in the k-d tree.
pub const KEY_DIM: usize = 20;

/// Parameters of [`PolarContext`].
#[derive(Clone, Debug, PartialEq)]
pub struct PolarConfig {
    /// Number of rings (default 20, Scan Context's N_r).
    pub rings: usize,
    /// Number of sectors over 360° (default 60, Scan Context's N_s: 6° each).
    pub sectors: usize,
    /// Outer radius of the last ring in metres (default 20 m; ours, indoor 2-D lasers).
    pub max_range_m: f64,
    /// Frames retrieved by the ring-key tree and scored exactly; `None` scores every frame
    /// (default `Some(10)`, Scan Context's candidate count).
    pub candidates: Option<usize>,
    /// Split each end point linearly between the two nearest ring centres (default true; ours).
    pub soft_rings: bool,
}

impl Default for PolarConfig {
    fn default() -> Self {
        Self {
            rings: 20,
            sectors: 60,
            max_range_m: 20.0,
            candidates: Some(10),
            soft_rings: true,
        }
    }
}

impl PolarConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let zero = |name| PlaceError::InvalidParameter {
            name,
            reason: "must be at least 1".into(),
        };
        if self.rings == 0 {
            return Err(zero("rings"));
        }
        if self.sectors == 0 {
            return Err(zero("sectors"));
        }
        if self.candidates == Some(0) {
            return Err(zero("candidates"));
        }
        crate::error::require_positive("max_range_m", self.max_range_m)
    }
}

/// The polar descriptor of one planar scan.
#[derive(Clone, Debug, PartialEq)]
pub struct PolarDescription {
    rings: usize,
    sectors: usize,
    /// Bin values, sector-major: `bins[s · rings + r]`.
    bins: Vec<f32>,
    /// Euclidean norm of each sector's column.
    norms: Vec<f32>,
    key: [f64; KEY_DIM],
}

impl PolarDescription {
    /// The value of ring `r`, sector `s` (end-point count, split between rings when soft).
    pub fn bin(&self, ring: usize, sector: usize) -> f32 {
        self.bins[sector * self.rings + ring]
    }

    /// The rotation-invariant ring key (share of occupied sectors per range band).
    pub fn ring_key(&self) -> &[f64; KEY_DIM] {
        &self.key
    }

    /// The heading-free distance `min_n d_n` to `other` and the minimising column shift `n`
    /// (sector `j` of `self` against sector `j + n` of `other`; the smallest `n` on ties).
    /// Descriptions of different shapes are at distance 1.
    pub fn distance(&self, other: &Self) -> (f64, usize) {
        if self.rings != other.rings || self.sectors != other.sectors {
            return (1.0, 0);
        }
        let (ns, nr) = (self.sectors, self.rings);
        let mut best = (f64::INFINITY, 0);
        for shift in 0..ns {
            let mut sum = 0.0f64;
            for j in 0..ns {
                let k = (j + shift) % ns;
                let (na, nb) = (self.norms[j], other.norms[k]);
                sum += match (na > 0.0, nb > 0.0) {
                    (false, false) => 0.0,
                    (true, true) => {
                        let a = &self.bins[j * nr..(j + 1) * nr];
                        let b = &other.bins[k * nr..(k + 1) * nr];
                        let dot: f32 = a.iter().zip(b).map(|(x, y)| x * y).sum();
                        (1.0 - dot / (na * nb)).max(0.0) as f64
                    }
                    _ => 1.0,
                };
            }
            let d = sum / ns as f64;
            if d < best.0 {
                best = (d, shift);
            }
        }
        best
    }
}

/// The planar Scan-Context-like place recognizer (see the module docs).
#[derive(Debug)]
pub struct PolarContext {
    config: PolarConfig,
    descriptions: Vec<PolarDescription>,
    tree: KdTree<f64, KEY_DIM>,
    /// Frames per distinct ring key, ascending; the tree's item is the group's index.
    groups: Vec<Vec<usize>>,
    group_of_key: HashMap<[u64; KEY_DIM], usize>,
}

impl Default for PolarContext {
    fn default() -> Self {
        Self::with_valid_config(PolarConfig::default())
    }
}

impl PolarContext {
    /// A recognizer with an empty database.
    pub fn new(config: PolarConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self::with_valid_config(config))
    }

    fn with_valid_config(config: PolarConfig) -> Self {
        Self {
            config,
            descriptions: Vec::new(),
            tree: KdTree::new(),
            groups: Vec::new(),
            group_of_key: HashMap::new(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &PolarConfig {
        &self.config
    }

    /// The stored description of frame `index`.
    pub fn description(&self, index: usize) -> Option<&PolarDescription> {
        self.descriptions.get(index)
    }

    /// Describes a planar scan (sensor frame).
    pub fn describe_scan(&self, scan: &Scan2) -> Result<PolarDescription> {
        let PolarConfig {
            rings,
            sectors,
            max_range_m,
            soft_rings,
            ..
        } = self.config;
        let mut bins = vec![0.0f32; rings * sectors];
        let ring_width = max_range_m / rings as f64;
        let sector_width = std::f64::consts::TAU / sectors as f64;
        for i in 0..scan.len() {
            let Some(r) = scan.range(i).hit() else {
                continue;
            };
            let angle = scan.angle(i);
            if r > max_range_m || !angle.is_finite() {
                continue;
            }
            let s = ((angle.rem_euclid(std::f64::consts::TAU) / sector_width) as usize)
                .min(sectors - 1);
            let column = &mut bins[s * rings..(s + 1) * rings];
            let rr = r / ring_width;
            if soft_rings {
                // Ring centres sit at (k + ½) · ring width.
                let t = (rr - 0.5).clamp(0.0, (rings - 1) as f64);
                let k0 = t.floor() as usize;
                let f = (t - k0 as f64) as f32;
                column[k0] += 1.0 - f;
                if f > 0.0 {
                    column[k0 + 1] += f;
                }
            } else {
                column[(rr as usize).min(rings - 1)] += 1.0;
            }
        }
        Ok(Self::finish(rings, sectors, bins))
    }

    /// Column norms and the ring key of a filled bin matrix.
    fn finish(rings: usize, sectors: usize, bins: Vec<f32>) -> PolarDescription {
        let norms = bins
            .chunks_exact(rings)
            .map(|c| c.iter().map(|v| v * v).sum::<f32>().sqrt())
            .collect();
        let share = |r: usize| {
            let occupied = (0..sectors).filter(|&s| bins[s * rings + r] > 0.0).count();
            occupied as f64 / sectors as f64
        };
        let mut key = [0.0; KEY_DIM];
        for (j, k) in key.iter_mut().enumerate() {
            let lo = j * rings / KEY_DIM;
            let hi = ((j + 1) * rings / KEY_DIM).max(lo + 1);
            *k = (lo..hi).map(share).sum::<f64>() / (hi - lo) as f64;
        }
        PolarDescription {
            rings,
            sectors,
            bins,
            norms,
            key,
        }
    }

    /// Frames `< before` to score for a ring key, ascending; `include` (the query's own
    /// index) is always among them when it is `< before`.
    fn candidate_frames(
        &self,
        key: &[f64; KEY_DIM],
        before: usize,
        include: Option<usize>,
    ) -> Vec<usize> {
        let before = before.min(self.descriptions.len());
        let Some(k) = self.config.candidates else {
            return (0..before).collect();
        };
        if k >= before {
            return (0..before).collect();
        }
        let include = include.filter(|&i| i < before);
        let total = self.groups.len();
        let mut n = k.min(total);
        loop {
            let mut frames: Vec<usize> = include.into_iter().collect();
            for nn in self.tree.nearest_n::<SquaredEuclidean>(key, n) {
                let group = &self.groups[nn.item as usize];
                let room = k - frames.len();
                let fits = |&f: &usize| f < before && Some(f) != include;
                frames.extend(group.iter().copied().filter(fits).take(room));
                if frames.len() == k {
                    break;
                }
            }
            if frames.len() == k || n == total {
                frames.sort_unstable();
                return frames;
            }
            n = (2 * n).min(total);
        }
    }

    /// Scores the candidates of `description`, best first (ties: lower frame index first,
    /// `first` — the query's own index — before all).
    fn score(
        &self,
        description: &PolarDescription,
        before: usize,
        first: Option<usize>,
    ) -> Vec<Candidate> {
        let mut out: Vec<Candidate> = self
            .candidate_frames(&description.key, before, first)
            .into_iter()
            .map(|frame| Candidate {
                frame,
                score: 1.0 - description.distance(&self.descriptions[frame]).0,
            })
            .collect();
        out.sort_by(|a, b| {
            b.score
                .total_cmp(&a.score)
                .then((Some(b.frame) == first).cmp(&(Some(a.frame) == first)))
                .then(a.frame.cmp(&b.frame))
        });
        out
    }
}

impl PlaceRecognizer for PolarContext {
    type Description = PolarDescription;

    fn name(&self) -> &'static str {
        "polar-context"
    }

    fn describe(&mut self, frame: &Frame<'_>) -> Result<PolarDescription> {
        match frame {
            Frame::Planar(scan) => self.describe_scan(scan),
            other => Err(PlaceError::UnsupportedFrame {
                method: "polar-context",
                frame: other.kind(),
            }),
        }
    }

    fn query(&self, description: &PolarDescription, before: usize) -> Vec<Candidate> {
        self.score(description, before, None)
    }

    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate> {
        match self.descriptions.get(index) {
            Some(d) => self.score(d, before, Some(index)),
            None => Vec::new(),
        }
    }

    fn insert(&mut self, description: PolarDescription) {
        let frame = self.descriptions.len();
        let bits = description.key.map(f64::to_bits);
        let group = *self.group_of_key.entry(bits).or_insert_with(|| {
            self.groups.push(Vec::new());
            self.tree
                .add(&description.key, (self.groups.len() - 1) as u64);
            self.groups.len() - 1
        });
        self.groups[group].push(frame);
        self.descriptions.push(description);
    }

    fn len(&self) -> usize {
        self.descriptions.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wall segments `(x0, y0, x1, y1)` of a 12 m × 8 m room with two boxes, world frame.
    const WALLS: [[f64; 4]; 12] = [
        [-6.0, -4.0, 6.0, -4.0],
        [6.0, -4.0, 6.0, 4.0],
        [6.0, 4.0, -6.0, 4.0],
        [-6.0, 4.0, -6.0, -4.0],
        [1.0, 1.0, 2.0, 1.0],
        [2.0, 1.0, 2.0, 2.5],
        [2.0, 2.5, 1.0, 2.5],
        [1.0, 2.5, 1.0, 1.0],
        [-3.0, -2.0, -2.0, -2.0],
        [-2.0, -2.0, -2.0, -1.5],
        [-2.0, -1.5, -3.0, -1.5],
        [-3.0, -1.5, -3.0, -2.0],
    ];

    /// A 360-beam scan from `(x, y, heading)`, beams at half-degree offsets (never on a
    /// 6° sector border), ranges scaled by `1 + noise · sin(7 i)`.
    fn scan_at(x: f64, y: f64, heading: f64, noise: f64) -> Scan2 {
        let angle_min_rad = 0.5f64.to_radians();
        let inc = 1f64.to_radians();
        let ranges = (0..360)
            .map(|i| {
                let a = heading + angle_min_rad + i as f64 * inc;
                let (dx, dy) = (a.cos(), a.sin());
                let mut best = 30.0;
                for w in WALLS {
                    let (ex, ey) = (w[2] - w[0], w[3] - w[1]);
                    let den = dx * ey - dy * ex;
                    if den.abs() < 1e-12 {
                        continue;
                    }
                    let (wx, wy) = (w[0] - x, w[1] - y);
                    let t = (wx * ey - wy * ex) / den;
                    let u = (wx * dy - wy * dx) / den;
                    if t > 0.0 && (0.0..=1.0).contains(&u) && t < best {
                        best = t;
                    }
                }
                best * (1.0 + noise * (7.0 * i as f64).sin())
            })
            .collect();
        Scan2 {
            angle_min_rad,
            angle_increment_rad: inc,
            max_range_m: 30.0,
            ranges,
            intensities: None,
        }
    }

    fn database(config: PolarConfig, poses: &[(f64, f64, f64)]) -> PolarContext {
        let mut pc = PolarContext::new(config).unwrap();
        for &(x, y, h) in poses {
            let d = pc.describe(&Frame::Planar(&scan_at(x, y, h, 0.0))).unwrap();
            pc.insert(d);
        }
        pc
    }

    fn grid_poses() -> Vec<(f64, f64, f64)> {
        (0..40)
            .map(|i| {
                let (ix, iy) = (i % 8, i / 8);
                (
                    -4.5 + 1.3 * ix as f64,
                    -3.0 + 1.4 * iy as f64,
                    0.3 * i as f64,
                )
            })
            .collect()
    }

    #[test]
    fn whole_sector_rotation_has_distance_zero() {
        let pc = PolarContext::default();
        let a = pc.describe_scan(&scan_at(0.5, -1.0, 0.0, 0.0)).unwrap();
        for k in [1, 7, 31] {
            let mut rotated = scan_at(0.5, -1.0, 0.0, 0.0);
            rotated.angle_min_rad += k as f64 * std::f64::consts::TAU / 60.0;
            let b = pc.describe_scan(&rotated).unwrap();
            assert_eq!(a.ring_key(), b.ring_key());
            let (d, shift) = a.distance(&b);
            assert!(d < 1e-6, "k = {k}: distance {d}");
            assert_eq!(shift, k);
        }
        // A different place is far.
        let c = pc.describe_scan(&scan_at(-4.0, 3.0, 0.0, 0.0)).unwrap();
        assert!(a.distance(&c).0 > 0.2);
    }

    #[test]
    fn stored_frames_retrieve_themselves_first() {
        let poses = grid_poses();
        for candidates in [Some(10), None] {
            let config = PolarConfig {
                candidates,
                ..PolarConfig::default()
            };
            let pc = database(config, &poses);
            for i in 0..poses.len() {
                let c = pc.query_stored(i, poses.len());
                assert_eq!(c[0].frame, i);
                assert!((c[0].score - 1.0).abs() < 1e-6);
                assert!(c.len() <= candidates.unwrap_or(poses.len()));
            }
            assert!(pc.query_stored(5, 3).iter().all(|c| c.frame < 3));
            assert!(pc.query_stored(99, 3).is_empty());
        }
    }

    #[test]
    fn tree_and_exhaustive_agree_on_an_easy_query() {
        let poses = grid_poses();
        let tree = database(PolarConfig::default(), &poses);
        let all = database(
            PolarConfig {
                candidates: None,
                ..PolarConfig::default()
            },
            &poses,
        );
        // Re-visit of place 13 with range noise and a turned heading.
        let (x, y, h) = poses[13];
        let scan = scan_at(x + 0.05, y - 0.05, h + 1.0, 0.01);
        let d = tree.describe_scan(&scan).unwrap();
        let a = tree.query(&d, poses.len());
        let b = all.query(&d, poses.len());
        assert_eq!(a[0].frame, 13);
        assert_eq!(b[0].frame, 13);
        assert!(a[0].score > 0.8, "{}", a[0].score);
        // Only frames before the limit are proposed.
        assert!(tree.query(&d, 10).iter().all(|c| c.frame < 10));
    }

    #[test]
    fn many_identical_scans_share_a_tree_entry() {
        // More identical keys than a kiddo leaf holds (32).
        let poses = vec![(0.0, 0.0, 0.0); 100];
        let pc = database(PolarConfig::default(), &poses);
        assert_eq!(pc.groups.len(), 1);
        let c = pc.query_stored(70, 100);
        assert_eq!(c[0].frame, 70);
        assert_eq!(c.len(), 10);
    }

    #[test]
    fn bad_frames_configs_and_empty_scans() {
        let mut pc = PolarContext::default();
        let img = image::GrayImage::new(4, 4);
        assert!(matches!(
            pc.describe(&Frame::Image(&img)),
            Err(PlaceError::UnsupportedFrame { .. })
        ));
        for bad in [
            PolarConfig {
                rings: 0,
                ..PolarConfig::default()
            },
            PolarConfig {
                candidates: Some(0),
                ..PolarConfig::default()
            },
            PolarConfig {
                max_range_m: -1.0,
                ..PolarConfig::default()
            },
        ] {
            assert!(PolarContext::new(bad).is_err());
        }
        let mut empty = scan_at(0.0, 0.0, 0.0, 0.0);
        empty.ranges.iter_mut().for_each(|r| *r = f64::NAN);
        let d = pc.describe_scan(&empty).unwrap();
        assert!(d.ring_key().iter().all(|&k| k == 0.0));
        assert_eq!(d.distance(&d).0, 0.0);
    }
}
