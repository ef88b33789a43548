//! Configuration of the model scoring (Table 7.3 / 8.2 / 8.3).

use serde::{Deserialize, Serialize};

use crate::SensorModelError;

/// How the scans of a log are split into a mapping set and a disjoint test set (the thesis
/// keeps them disjoint but does not say how, Sec. 7.6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Split {
    /// Even-indexed scans build the map, odd-indexed scans are scored (the default): both
    /// sets cover the whole trajectory, so every test scan sees mapped space.
    #[default]
    Alternate,
    /// The first half of the scans builds the map, the second half is scored (a harder
    /// test: parts of the second half may see space the map never saw).
    Halves,
}

impl Split {
    /// True when scan `index` of `count` belongs to the test set.
    pub fn is_test(self, index: usize, count: usize) -> bool {
        match self {
            Split::Alternate => index % 2 == 1,
            Split::Halves => index >= count / 2,
        }
    }

    /// The split's name (`alternate`, `halves`).
    pub fn name(self) -> &'static str {
        match self {
            Split::Alternate => "alternate",
            Split::Halves => "halves",
        }
    }

    /// The split named `name`, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "alternate" => Some(Split::Alternate),
            "halves" => Some(Split::Halves),
            _ => None,
        }
    }
}

/// Configuration of [`crate::scoring::score_planar`] and [`crate::scoring::score_spatial`].
///
/// Defaults ([`ScoringConfig::default`]) and why:
/// * `resolution_m = 0.1` — the 2-D cell edge. The thesis used 0.5 m voxels for a
///   Velodyne HDL-64E over 200–300 m scenes; the 2-D CARMEN logs are buildings of
///   30–100 m scanned by SICK lasers with centimetre range noise, and 0.1 m is the usual
///   resolution of their occupancy maps (rooms and corridors of 1–3 m stay resolved while
///   a wall is one or two cells thick). 3-D callers pass 0.5 m as the thesis did.
/// * `split = Alternate`, `max_range_m = None` (the smallest `max_range_m` of the scans,
///   i.e. the no-return threshold that `raypath-io` inferred for the log).
/// * `poses_per_scan = 50`, `disc_radius_m = 2.5` (Sec. 7.6.2), `ground_truth_sigma_m = 0.05`
///   (ch. 8's Applanix σ; Sec. 7.6.2 gives none); only the position is perturbed, heading (and
///   height and attitude in 3-D) stay at the truth; the true pose is **not** one of the samples
///   (the thesis samples uniformly in the disc; adding the truth would hand every model the exact
///   answer as a candidate).
/// * `seed = 0` — the samples of test scan `i` come from a generator seeded with
///   `(seed, i)`, the same samples for every model.
/// * `beam_step = 1`, `max_test_scans = None` — every beam of every test scan (the thesis's
///   sums over the whole data set); evaluations pass larger steps to stay fast.
/// * `endpoint_sigma_m = None` — σ of the endpoint model's Gaussian field:
///   `max(0.2 m, resolution)` (AMCL's 0.2 m, but never below one cell).
/// * `margin_m = 1.0`, `max_cells = 100_000_000` (a larger grid is refused as bad input).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScoringConfig {
    /// Cell (voxel) edge of the maps in metres.
    pub resolution_m: f64,
    /// Mapping / test split of the scans.
    pub split: Split,
    /// Maximum sensor range `r_max` in metres; `None` takes it from the scans.
    pub max_range_m: Option<f64>,
    /// Number of perturbed poses `M` per test scan (Eq. 7.29).
    pub poses_per_scan: usize,
    /// Radius of the disc the perturbed positions are drawn from, in metres.
    pub disc_radius_m: f64,
    /// σ of the Gaussian ground-truth pose distribution in metres (per axis).
    pub ground_truth_sigma_m: f64,
    /// Seed of the pose samples.
    pub seed: u64,
    /// Every `beam_step`-th beam (point) of a test scan is scored.
    pub beam_step: usize,
    /// At most this many test scans (evenly spaced over the test set); `None`: all.
    pub max_test_scans: Option<usize>,
    /// σ of the endpoint model's field in metres (`None`: `max(0.2, resolution_m)`).
    pub endpoint_sigma_m: Option<f64>,
    /// Free space around the mapped data and the test poses, in metres.
    pub margin_m: f64,
    /// Largest grid accepted, in cells.
    pub max_cells: usize,
}

impl Default for ScoringConfig {
    fn default() -> Self {
        Self {
            resolution_m: 0.1,
            split: Split::Alternate,
            max_range_m: None,
            poses_per_scan: 50,
            disc_radius_m: 2.5,
            ground_truth_sigma_m: 0.05,
            seed: 0,
            beam_step: 1,
            max_test_scans: None,
            endpoint_sigma_m: None,
            margin_m: 1.0,
            max_cells: 100_000_000,
        }
    }
}

impl ScoringConfig {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), SensorModelError> {
        let bad = |name: &'static str, reason: String| {
            Err(SensorModelError::InvalidParameter { name, reason })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.resolution_m) {
            return bad(
                "resolution_m",
                format!("must be positive, got {}", self.resolution_m),
            );
        }
        if let Some(r) = self.max_range_m
            && !positive(r)
        {
            return bad("max_range_m", format!("must be positive, got {r}"));
        }
        if self.poses_per_scan < 2 {
            return bad(
                "poses_per_scan",
                format!("need at least 2 poses, got {}", self.poses_per_scan),
            );
        }
        if !positive(self.disc_radius_m) {
            return bad(
                "disc_radius_m",
                format!("must be positive, got {}", self.disc_radius_m),
            );
        }
        if !positive(self.ground_truth_sigma_m) {
            return bad(
                "ground_truth_sigma_m",
                format!("must be positive, got {}", self.ground_truth_sigma_m),
            );
        }
        if self.beam_step == 0 {
            return bad("beam_step", "must be at least 1".into());
        }
        if self.max_test_scans == Some(0) {
            return bad("max_test_scans", "must be at least 1".into());
        }
        if let Some(s) = self.endpoint_sigma_m
            && !positive(s)
        {
            return bad("endpoint_sigma_m", format!("must be positive, got {s}"));
        }
        if !(self.margin_m.is_finite() && self.margin_m >= 0.0) {
            return bad(
                "margin_m",
                format!("must be non-negative, got {}", self.margin_m),
            );
        }
        Ok(())
    }

    /// σ of the endpoint model's field in metres.
    pub fn endpoint_sigma(&self) -> f64 {
        self.endpoint_sigma_m.unwrap_or(self.resolution_m.max(0.2))
    }
}
