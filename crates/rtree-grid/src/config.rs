//! Parameters of the Rtree grid (Khan 2017, §2.5, with the values of the experiments, §2.6).

/// The inverse sensor model (Khan 2017, §2.5.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SensorModel {
    /// Beam-based: cells a beam traverses get `P_free`, the cell it ends in gets `P_occ`.
    #[default]
    BeamBased,
    /// Beam-end-point: only the end cell is updated (`P_occ`); free space is not modelled.
    BeamEndPoint,
}

/// Which cells start a fusion after a scan (Khan 2017, §2.5.2, Fig. 2.6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Selection {
    /// The thesis' selection: every end-point cell plus cells sampled at random along the
    /// beams — here each de-duplicated traversed cell with probability `1 / spacing`, i.e.
    /// `len / (spacing · r)` expected samples per beam (the thesis gives no number; the
    /// default spacing is 10 base cubes). The end-point model uses end points only.
    BeamSamples {
        /// Mean distance between samples, in base cubes (s ≥ 1).
        spacing_cells: f64,
    },
    /// Every cell updated by the scan (slower, fuses at least as much).
    UpdatedCells,
}

impl Default for Selection {
    fn default() -> Self {
        Selection::BeamSamples {
            spacing_cells: 10.0,
        }
    }
}

/// Which cells may fuse into one cuboid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FusionRule {
    /// The thesis' rule (Khan 2017, §2.5.2): only cells clamped at the same bound
    /// (`μ_min` or `μ_max`) fuse; the fused cell takes the mean of its cells. Updates of a
    /// fused cell apply to the whole cuboid unless [`GridConfig::split_on_unclamp`] is set.
    #[default]
    Clamped,
    /// Our extension beyond Khan 2017, in the spirit of OctoMap's pruning (which merges 8
    /// siblings with equal log-odds) but with cuboids: cells whose log-odds are bit-equal
    /// `f32`s fuse, clamped or not, with the same search-direction order. The map stays
    /// exact: an update that changes the value of only part of a fused cell splits it
    /// (the changed base cubes, plus the fewest halving cuboids covering the rest with the
    /// old value) before the per-cube updates apply, so every base cube carries the log-odds
    /// an unfused lattice would (`split_on_unclamp` is implied).
    EqualValue,
}

/// Configuration of an [`RtreeGrid`](crate::RtreeGrid).
///
/// Defaults are the thesis' (§2.6, "same as in OctoMap"): `P_occ = 0.7`, `P_free = 0.4`,
/// clamping at `μ_min = 0.12` and `μ_max = 0.97`, prior 0.5, occupancy threshold 0.5
/// (OctoMap's default; the thesis does not name one). M and d were lost with the figure
/// legends; M = 8 with d = ⌈0.4·M⌉ is our choice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridConfig {
    /// Edge of the base cubes, metres (the thesis quotes 0.2 m).
    pub resolution_m: f64,
    /// M: most entries per R-tree node.
    pub max_entries: usize,
    /// d: fewest entries per non-root node (≤ M/2).
    pub min_entries: usize,
    /// `P_occ`, the inverse sensor model of a hit.
    pub prob_hit: f64,
    /// `P_free`, the inverse sensor model of a traversed cell.
    pub prob_miss: f64,
    /// `μ_min`: lower clamping bound (probability).
    pub clamp_min: f64,
    /// `μ_max`: upper clamping bound (probability).
    pub clamp_max: f64,
    /// Probability above which a cell counts as occupied.
    pub occupancy_threshold: f64,
    /// The inverse sensor model.
    pub model: SensorModel,
    /// Beams longer than this (metres) are cut and their end is not marked occupied
    /// (OctoMap's `maxrange`); `None` keeps every beam whole.
    pub max_range_m: Option<f64>,
    /// Whether cells fuse after each scan (off: a plain hashed grid in an R-tree).
    pub fusion: bool,
    /// Which cells start fusions.
    pub selection: Selection,
    /// Seed of the beam sampling.
    pub seed: u64,
    /// Split a fused cell back into base cubes when an update would take it out of the
    /// clamped state (the thesis' future work for dynamic scenes, §2.7); off in the thesis.
    pub split_on_unclamp: bool,
    /// Which cells may fuse (the thesis' clamped rule by default).
    pub fusion_rule: FusionRule,
    /// Fuse after every this many scans (≥ 1; the thesis: 1). The cells selected by the
    /// scans in between are kept and all start fusions then;
    /// [`RtreeGrid::fuse_pending`](crate::RtreeGrid::fuse_pending) runs them at any time.
    /// With [`FusionRule::EqualValue`] the map's values do not depend on it, only how often
    /// fused cells are split and re-fused.
    pub fusion_interval_scans: u32,
}

impl Default for GridConfig {
    fn default() -> Self {
        Self {
            resolution_m: 0.2,
            max_entries: 8,
            min_entries: 4,
            prob_hit: 0.7,
            prob_miss: 0.4,
            clamp_min: 0.12,
            clamp_max: 0.97,
            occupancy_threshold: 0.5,
            model: SensorModel::BeamBased,
            max_range_m: None,
            fusion: true,
            selection: Selection::default(),
            seed: 7,
            split_on_unclamp: false,
            fusion_rule: FusionRule::Clamped,
            fusion_interval_scans: 1,
        }
    }
}

impl GridConfig {
    /// The default configuration with resolution `resolution_m`, M = `max_entries` and
    /// d = ⌈0.4·M⌉.
    pub fn with(resolution_m: f64, max_entries: usize, model: SensorModel) -> Self {
        Self {
            resolution_m,
            max_entries,
            min_entries: (max_entries * 2)
                .div_ceil(5)
                .clamp(1, (max_entries / 2).max(1)),
            model,
            ..Self::default()
        }
    }
}

/// `l(p) = ln(p / (1 − p))`, Eq. (2.7).
pub fn logit(p: f64) -> f64 {
    (p / (1.0 - p)).ln()
}

/// Inverse of [`logit`].
pub fn probability(log_odds: f64) -> f64 {
    1.0 / (1.0 + (-log_odds).exp())
}
