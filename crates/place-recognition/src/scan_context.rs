//! Scan Context: an egocentric polar height descriptor of a 3-D scan with a yaw-invariant
//! distance (Kim & Kim, "Scan Context: Egocentric spatial descriptor for place recognition
//! within 3D point cloud map", IROS 2018). A baseline beside Khan 2017's SHOT bag of words
//! (§4.5.2); written from the paper.
//!
//! * **Descriptor.** The sensor-frame x–y plane is split into `N_r` = 20 rings of equal width
//!   up to `L_max` = 80 m and `N_s` = 60 sectors of 6° (counter-clockwise from +x). Each bin
//!   holds the **maximum point height** `z + h` of its points, `h` the sensor height
//!   ([`ScanContextConfig::sensor_height`]) so that ground points are positive; heights below
//!   `−h` are clamped to 0 and empty bins are 0 (a bin whose points all lie below `−h` thus
//!   counts as empty).
//! * **Distance.** With columns `c_j` (the ring profile of sector `j`),
//!   `d(I, I') = (1/N_s) Σ_j (1 − c_j·c'_j / (‖c_j‖‖c'_j‖))`, minimised over all `N_s`
//!   column shifts of `I'` (a yaw rotation of the sensor is a column shift). The paper leaves
//!   the empty-column case (`0/0`) open; **ours**: only column pairs where both columns are
//!   non-empty count, and the mean is over those pairs (`1/|J|` instead of `1/N_s`); with no
//!   such pair the distance is 1. The score of a candidate is `1 − d`.
//! * **Ring key.** `k_i = ‖r_i‖₀ / N_s`, the occupancy ratio of ring `i` (rotation
//!   invariant), kept in a 20-dimensional k-d tree (kiddo). A query takes the
//!   `num_candidates` (paper: 10) nearest ring keys and computes the full distance only for
//!   them; `None` compares with every frame. Only frames `< before` may be returned: the tree
//!   holds all frames, and **we** ask it for more neighbours (doubling) until enough frames
//!   `< before` are found. Identical ring keys share one tree entry (the tree cannot hold many
//!   identical points; tied frames are taken in index order), and a stored frame queried with
//!   [`PlaceRecognizer::query_stored`] is always among its own candidates.
//! * **Sector-key alignment (optional).** The sector key `s_j` = mean of column `j`; the
//!   shift minimising `Σ_j |s_j − s'_{j+n}|` is found first, and the full distance is only
//!   evaluated within `±w` shifts of it ([`ScanContextConfig::sector_key_window`]; default
//!   `None`: all shifts, which is exact and cheap at 60 sectors).

use kiddo::SquaredEuclidean;
use kiddo::float::kdtree::KdTree;
use rayon::prelude::*;
use raypath_geometry::PointCloud;

use crate::error::require_positive;
use crate::{Candidate, Frame, PlaceError, PlaceRecognizer, Result};

/// Number of rings `N_r` (Kim & Kim 2018); fixed because the ring-key tree is 20-dimensional.
pub const SCAN_CONTEXT_RINGS: usize = 20;

type RingKeyTree = KdTree<f64, u64, SCAN_CONTEXT_RINGS, 32, u32>;

/// Parameters of [`ScanContext`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ScanContextConfig {
    /// Number of sectors `N_s` over 360°. Default 60 (Kim & Kim 2018).
    pub num_sectors: usize,
    /// Maximum range `L_max`, metres; farther points are ignored. Default 80 m (Kim & Kim 2018).
    pub max_range: f64,
    /// Height added to `z` so bin values are non-negative, metres. Default 2 m (ours: above the
    /// mounting height of a car's lidar).
    pub sensor_height: f64,
    /// Ring-key nearest neighbours whose full distance is computed; `None` = every frame.
    /// Default `Some(10)` (Kim & Kim 2018).
    pub num_candidates: Option<usize>,
    /// Evaluate only shifts within `±w` of the sector-key alignment; `None` = all shifts.
    /// Default `None` (ours).
    pub sector_key_window: Option<usize>,
}

impl Default for ScanContextConfig {
    fn default() -> Self {
        Self {
            num_sectors: 60,
            max_range: 80.0,
            sensor_height: 2.0,
            num_candidates: Some(10),
            sector_key_window: None,
        }
    }
}

impl ScanContextConfig {
    fn validate(&self) -> Result<()> {
        if self.num_sectors == 0 {
            return Err(PlaceError::InvalidParameter {
                name: "num_sectors",
                reason: "must be at least 1".into(),
            });
        }
        if self.num_candidates == Some(0) {
            return Err(PlaceError::InvalidParameter {
                name: "num_candidates",
                reason: "must be at least 1 (or None for all frames)".into(),
            });
        }
        require_positive("max_range", self.max_range)?;
        if !self.sensor_height.is_finite() {
            return Err(PlaceError::InvalidParameter {
                name: "sensor_height",
                reason: format!("must be finite, got {}", self.sensor_height),
            });
        }
        Ok(())
    }
}

/// The Scan Context of one cloud: bin values, column norms, ring key and sector key.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanContextDescriptor {
    /// Bin values, sector-major: ring `i` of sector `j` at `j * N_r + i`.
    values: Vec<f32>,
    /// `‖c_j‖` per sector.
    column_norms: Vec<f64>,
    /// Occupancy ratio per ring.
    ring_key: [f64; SCAN_CONTEXT_RINGS],
    /// Mean bin value per sector.
    sector_key: Vec<f32>,
}

impl ScanContextDescriptor {
    /// Computes the Scan Context of a sensor-frame cloud; non-finite points are skipped.
    pub fn new(cloud: &PointCloud, config: &ScanContextConfig) -> Result<Self> {
        config.validate()?;
        let ns = config.num_sectors;
        let nr = SCAN_CONTEXT_RINGS;
        let mut values = vec![0f32; ns * nr];
        let ring_width = config.max_range / nr as f64;
        let sector_width = std::f64::consts::TAU / ns as f64;
        for p in &cloud.points {
            let (x, y, z) = (f64::from(p.x), f64::from(p.y), f64::from(p.z));
            if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                continue;
            }
            let range = x.hypot(y);
            if range >= config.max_range {
                continue;
            }
            let ring = ((range / ring_width) as usize).min(nr - 1);
            let angle = y.atan2(x).rem_euclid(std::f64::consts::TAU);
            let sector = ((angle / sector_width) as usize).min(ns - 1);
            let v = &mut values[sector * nr + ring];
            *v = v.max((z + config.sensor_height).max(0.0) as f32);
        }
        Ok(Self::from_values(values, ns))
    }

    fn from_values(values: Vec<f32>, ns: usize) -> Self {
        let nr = SCAN_CONTEXT_RINGS;
        let mut ring_key = [0f64; SCAN_CONTEXT_RINGS];
        for column in values.chunks_exact(nr) {
            for (k, &v) in ring_key.iter_mut().zip(column) {
                *k += f64::from(u8::from(v > 0.0));
            }
        }
        ring_key.iter_mut().for_each(|k| *k /= ns as f64);
        let column_norms = values
            .chunks_exact(nr)
            .map(|c| {
                c.iter()
                    .map(|&v| f64::from(v) * f64::from(v))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let sector_key = values
            .chunks_exact(nr)
            .map(|c| c.iter().sum::<f32>() / nr as f32)
            .collect();
        Self {
            values,
            column_norms,
            ring_key,
            sector_key,
        }
    }

    /// Number of sectors `N_s`.
    pub fn num_sectors(&self) -> usize {
        self.column_norms.len()
    }

    /// The value of ring `ring` in sector `sector` (0 for an empty bin).
    pub fn value(&self, ring: usize, sector: usize) -> f32 {
        self.values[sector * SCAN_CONTEXT_RINGS + ring]
    }

    /// The ring key: occupancy ratio `‖r_i‖₀ / N_s` per ring.
    pub fn ring_key(&self) -> &[f64; SCAN_CONTEXT_RINGS] {
        &self.ring_key
    }

    /// The column distance `d(self, other shifted by n)`, with `other`'s column `(j + n) mod N_s`
    /// against column `j`; 1 when no column pair is non-empty on both sides.
    pub fn shifted_distance(&self, other: &Self, shift: usize) -> f64 {
        let ns = self.num_sectors();
        let nr = SCAN_CONTEXT_RINGS;
        let (mut sum, mut pairs) = (0f64, 0usize);
        for j in 0..ns {
            let k = (j + shift) % ns;
            let (na, nb) = (self.column_norms[j], other.column_norms[k]);
            if na <= 0.0 || nb <= 0.0 {
                continue;
            }
            let a = &self.values[j * nr..(j + 1) * nr];
            let b = &other.values[k * nr..(k + 1) * nr];
            let dot: f64 = a
                .iter()
                .zip(b)
                .map(|(&x, &y)| f64::from(x) * f64::from(y))
                .sum();
            sum += 1.0 - dot / (na * nb);
            pairs += 1;
        }
        if pairs == 0 {
            1.0
        } else {
            (sum / pairs as f64).max(0.0)
        }
    }

    /// The Scan Context distance minimised over all column shifts: `(d, best shift)`.
    /// Panics if the two descriptors have different numbers of sectors.
    pub fn distance(&self, other: &Self) -> (f64, usize) {
        assert_eq!(
            self.num_sectors(),
            other.num_sectors(),
            "sector counts differ"
        );
        self.best_of(0..self.num_sectors(), other)
    }

    /// The distance over shifts within `±window` of the sector-key alignment.
    fn distance_near(&self, other: &Self, window: usize) -> (f64, usize) {
        let ns = self.num_sectors();
        if 2 * window + 1 >= ns {
            return self.distance(other);
        }
        let coarse = (0..ns)
            .map(|n| {
                let cost: f32 = (0..ns)
                    .map(|j| (self.sector_key[j] - other.sector_key[(j + n) % ns]).abs())
                    .sum();
                (cost, n)
            })
            .fold(
                (f32::INFINITY, 0),
                |best, c| if c.0 < best.0 { c } else { best },
            );
        let shifts = (0..=2 * window).map(|o| (coarse.1 + ns + o - window) % ns);
        self.best_of(shifts, other)
    }

    fn best_of(&self, shifts: impl Iterator<Item = usize>, other: &Self) -> (f64, usize) {
        shifts
            .map(|n| (self.shifted_distance(other, n), n))
            .fold(
                (f64::INFINITY, 0),
                |best, c| if c.0 < best.0 { c } else { best },
            )
    }
}

/// Scan Context place recognition (name `scan-context`): ring-key k-d tree for candidates,
/// score `1 − d` with the yaw-invariant column distance. [`Frame::Cloud`] only.
#[derive(Debug)]
pub struct ScanContext {
    config: ScanContextConfig,
    frames: Vec<ScanContextDescriptor>,
    /// Frames per distinct ring key, in insertion order; the tree item is the group index.
    groups: Vec<Vec<usize>>,
    tree: RingKeyTree,
}

impl ScanContext {
    /// An empty database.
    pub fn new(config: ScanContextConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            config,
            frames: Vec::new(),
            groups: Vec::new(),
            tree: RingKeyTree::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ScanContextConfig {
        &self.config
    }

    /// The stored descriptor of frame `index`.
    pub fn descriptor(&self, index: usize) -> Option<&ScanContextDescriptor> {
        self.frames.get(index)
    }

    /// Candidate frames `< before` by ring-key distance (at most `num_candidates`; among
    /// equal ring keys the lower frame index first), or all of them. A stored frame `this`
    /// is always among its own candidates.
    fn candidates(
        &self,
        key: &[f64; SCAN_CONTEXT_RINGS],
        before: usize,
        this: Option<usize>,
    ) -> Vec<usize> {
        let before = before.min(self.frames.len());
        let wanted = match self.config.num_candidates {
            Some(n) if n < before => n,
            _ => return (0..before).collect(),
        };
        let this = this.filter(|&i| i < before);
        let mut qty = wanted;
        loop {
            let nearest = self.tree.nearest_n::<SquaredEuclidean>(key, qty);
            let mut found: Vec<usize> = this.into_iter().collect();
            let groups = nearest.iter().map(|nn| &self.groups[nn.item as usize]);
            let frames = groups
                .flatten()
                .copied()
                .filter(|&f| f < before && Some(f) != this);
            found.extend(frames.take(wanted - found.len()));
            if found.len() >= wanted || nearest.len() < qty {
                return found;
            }
            qty *= 2;
        }
    }

    fn score(&self, d: &ScanContextDescriptor, frames: Vec<usize>) -> Vec<Candidate> {
        frames
            .into_par_iter()
            .map(|f| {
                let other = &self.frames[f];
                let (dist, _) = match self.config.sector_key_window {
                    Some(w) => d.distance_near(other, w),
                    None => d.distance(other),
                };
                Candidate {
                    frame: f,
                    score: 1.0 - dist,
                }
            })
            .collect()
    }
}

impl PlaceRecognizer for ScanContext {
    type Description = ScanContextDescriptor;

    fn name(&self) -> &'static str {
        "scan-context"
    }

    fn describe(&mut self, frame: &Frame<'_>) -> Result<ScanContextDescriptor> {
        match frame {
            Frame::Cloud(cloud) => ScanContextDescriptor::new(cloud, &self.config),
            other => Err(PlaceError::UnsupportedFrame {
                method: self.name(),
                frame: other.kind(),
            }),
        }
    }

    fn query(&self, description: &ScanContextDescriptor, before: usize) -> Vec<Candidate> {
        if description.num_sectors() != self.config.num_sectors {
            return Vec::new();
        }
        let frames = self.candidates(&description.ring_key, before, None);
        self.score(description, frames)
    }

    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate> {
        match self.frames.get(index) {
            Some(d) => self.score(d, self.candidates(&d.ring_key, before, Some(index))),
            None => Vec::new(),
        }
    }

    /// Appends a descriptor. A descriptor with another sector count than the configuration
    /// is stored but never matched.
    fn insert(&mut self, description: ScanContextDescriptor) {
        let index = self.frames.len();
        let key = description.ring_key;
        let same = self
            .tree
            .nearest_n::<SquaredEuclidean>(&key, 1)
            .first()
            .filter(|nn| nn.distance == 0.0)
            .map(|nn| nn.item as usize);
        match same {
            Some(g) => self.groups[g].push(index),
            None => {
                self.tree.add(&key, self.groups.len() as u64);
                self.groups.push(vec![index]);
            }
        }
        self.frames.push(description);
    }

    fn len(&self) -> usize {
        self.frames.len()
    }
}

#[cfg(test)]
mod tests;
