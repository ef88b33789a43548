//! What one data set's unit measures: our grid and OctoMap at every resolution, inverse
//! sensor model and M of the sweep, and our variants at r = 0.2 m, M = 8, beam-based.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use raypath_rtree_grid::{FusionRule, GridConfig, Occupancy, RtreeGrid, Selection, SensorModel};
use serde::{Deserialize, Serialize};

use super::data::Dataset;
use super::peer::{self, PeerRun};
use super::{EQUAL_BATCH_LABEL, EQUAL_LABEL, EQUAL_UPDATED_BATCH_LABEL, EQUAL_UPDATED_LABEL};

/// One unit's result: the data set's measurements (`None`: its data are absent), whether
/// OctoMap could be built, and (for the simulated drive's unit) the note on how far
/// simulated scans are from real ones.
#[derive(Serialize, Deserialize)]
pub struct SetResult {
    /// The measurements, when the data are present.
    pub set: Option<SetInfo>,
    /// Why OctoMap is unavailable (`None`: it ran).
    pub octomap_unavailable: Option<String>,
    /// [`crate::eval::sim::gap_note`], measured in the `urban` unit.
    pub gap_note: Option<String>,
}

/// One data set and everything measured on it.
#[derive(Serialize, Deserialize)]
pub struct SetInfo {
    /// Short name.
    pub name: String,
    /// What it is.
    pub about: String,
    /// Points in all scans.
    pub points: usize,
    /// Query points of the classification agreement.
    pub queries: usize,
    /// Real data (the headline table) rather than simulated.
    pub real: bool,
    /// One per (resolution, model, M), in sweep order.
    pub runs: Vec<RunRecord>,
    /// Our variants at r = 0.2 m, M = 8, beam-based.
    pub variants: Vec<VariantRecord>,
}

/// Our side of one configuration (the query classes are not kept: the agreement is).
#[derive(Serialize, Deserialize)]
pub struct OursRun {
    /// Leaves (cells of the grid, fused or not).
    pub leaves: usize,
    /// Fused leaves.
    pub fused: usize,
    /// R-tree nodes.
    pub nodes: usize,
    /// R-tree height.
    pub height: usize,
    /// Allocated bytes.
    pub bytes: usize,
    /// Insertion of all scans, fusion included, seconds.
    pub insert_secs: f64,
    /// Visiting all leaves and testing occupancy, seconds.
    pub access_secs: f64,
    /// Occupied leaves.
    pub occupied: usize,
    /// The classes of the query points (not written to the unit result).
    #[serde(skip)]
    pub classes: Vec<Occupancy>,
}

/// Ours beside OctoMap's run at the same resolution and model.
#[derive(Serialize, Deserialize)]
pub struct Compared {
    /// Our grid.
    pub ours: OursRun,
    /// `None` without OctoMap.
    pub peer: Option<PeerRun>,
    /// Fraction of query points classified alike (all points; points known to both).
    pub agreement: Option<(f64, f64)>,
}

impl Compared {
    fn new(ours: OursRun, peer: Option<&PeerRun>) -> Self {
        let agreement = peer.map(|p| agreement(&ours.classes, &p.classes));
        Self {
            ours,
            peer: peer.cloned(),
            agreement,
        }
    }

    /// 1 − ours / pruned OctoMap leaves.
    pub fn reduction(&self) -> Option<f64> {
        let leaves = self.ours.leaves as f64;
        self.peer.as_ref().map(|p| 1.0 - leaves / p.leaves as f64)
    }

    /// Insertion time ours / OctoMap.
    pub fn insert_ratio(&self) -> Option<f64> {
        let secs = self.ours.insert_secs;
        self.peer.as_ref().map(|p| secs / p.insert_secs)
    }

    /// Bytes ours / OctoMap's `memoryUsage()`.
    pub fn bytes_ratio(&self) -> Option<f64> {
        let bytes = self.ours.bytes as f64;
        self.peer.as_ref().map(|p| bytes / p.memory_bytes as f64)
    }
}

/// One configuration of the sweep.
#[derive(Serialize, Deserialize)]
pub struct RunRecord {
    /// Resolution r, metres.
    pub resolution_m: f64,
    /// Beam-end-point model (otherwise beam-based).
    pub endpoint: bool,
    /// Maximal entries per R-tree node.
    pub m: usize,
    /// Ours beside OctoMap.
    pub compared: Compared,
}

impl RunRecord {
    /// r = 0.2 m, M = 8, beam-based: the configuration of the summary.
    pub fn at_02(&self) -> bool {
        is_02(self.resolution_m) && self.m == 8 && !self.endpoint
    }
}

/// One variant of our grid (r = 0.2 m, M = 8, beam-based).
#[derive(Serialize, Deserialize)]
pub struct VariantRecord {
    /// The variant's label in the table.
    pub label: String,
    /// Whether cells fuse at all.
    pub fusion: bool,
    /// `clamped` or `equal`.
    pub fusion_rule: String,
    /// `beam-samples` or `updated-cells`.
    pub selection: String,
    /// Fused cells split when a value leaves the clamping bounds.
    pub split_on_unclamp: bool,
    /// Scans between fusions.
    pub fusion_interval_scans: u32,
    /// Ours beside OctoMap.
    pub compared: Compared,
}

/// Whether `r` is 0.2 m.
pub fn is_02(r: f64) -> bool {
    (r - 0.2).abs() < 1e-9
}

/// The name of an inverse sensor model in tables and JSON.
pub fn model_name(endpoint: bool) -> &'static str {
    if endpoint { "endpoint" } else { "beam" }
}

fn sensor_model(endpoint: bool) -> SensorModel {
    if endpoint {
        SensorModel::BeamEndPoint
    } else {
        SensorModel::BeamBased
    }
}

/// Measures `set` at every resolution and M of `sweep` (r = 0.2 m, M = 8 only for a set
/// without the full sweep), both models, beside OctoMap when `driver` is given.
pub fn measure(set: &Dataset, driver: Option<&Path>, sweep: (&[f64], &[usize])) -> Result<SetInfo> {
    let (resolutions, orders) = if set.full_sweep {
        sweep
    } else {
        (&[0.2][..], &[8][..])
    };
    let mut info = SetInfo {
        name: set.name.clone(),
        about: set.about.clone(),
        points: set.graph.num_points(),
        queries: set.queries.len(),
        real: set.real,
        runs: Vec::new(),
        variants: Vec::new(),
    };
    for &r in resolutions {
        for endpoint in [false, true] {
            let peer = driver.map(|d| run_peer(d, set, r, endpoint)).transpose()?;
            if is_02(r) && !endpoint {
                info.variants = variants(set, r, peer.as_ref())?;
            }
            for &m in orders {
                let ours = run_config(set, GridConfig::with(r, m, sensor_model(endpoint)))?;
                info.runs.push(RunRecord {
                    resolution_m: r,
                    endpoint,
                    m,
                    compared: Compared::new(ours, peer.as_ref()),
                });
            }
        }
    }
    Ok(info)
}

/// OctoMap on `set`, checked to have read every point.
fn run_peer(driver: &Path, set: &Dataset, r: f64, endpoint: bool) -> Result<PeerRun> {
    let p = peer::run(driver, &set.path, r, endpoint, Some(&set.queries_path))?;
    anyhow::ensure!(
        p.points == set.graph.num_points(),
        "OctoMap read {} points from {}, we wrote {}",
        p.points,
        set.path.display(),
        set.graph.num_points()
    );
    Ok(p)
}

/// The variants of our grid, by label, from the thesis' configuration `base`.
fn variant_configs(base: GridConfig) -> [(&'static str, GridConfig); 8] {
    let equal = GridConfig {
        fusion_rule: FusionRule::EqualValue,
        ..base
    };
    [
        (
            "no fusion (plain grid in the R-tree)",
            GridConfig {
                fusion: false,
                ..base
            },
        ),
        ("thesis selection (default)", base),
        (
            "fuse from every updated cell",
            GridConfig {
                selection: Selection::UpdatedCells,
                ..base
            },
        ),
        (
            "split fused cells on unclamp",
            GridConfig {
                split_on_unclamp: true,
                ..base
            },
        ),
        (EQUAL_LABEL, equal),
        (
            EQUAL_UPDATED_LABEL,
            GridConfig {
                selection: Selection::UpdatedCells,
                ..equal
            },
        ),
        (
            EQUAL_BATCH_LABEL,
            GridConfig {
                fusion_interval_scans: 10,
                ..equal
            },
        ),
        (
            EQUAL_UPDATED_BATCH_LABEL,
            GridConfig {
                selection: Selection::UpdatedCells,
                fusion_interval_scans: 10,
                ..equal
            },
        ),
    ]
}

/// Every variant on `set` at resolution `r`, M = 8, beam-based.
fn variants(set: &Dataset, r: f64, peer: Option<&PeerRun>) -> Result<Vec<VariantRecord>> {
    let base = GridConfig::with(r, 8, SensorModel::BeamBased);
    let mut records = Vec::new();
    for (label, config) in variant_configs(base) {
        let ours = run_config(set, config)?;
        records.push(VariantRecord {
            label: label.to_owned(),
            fusion: config.fusion,
            fusion_rule: match config.fusion_rule {
                FusionRule::Clamped => "clamped",
                FusionRule::EqualValue => "equal",
            }
            .to_owned(),
            selection: match config.selection {
                Selection::BeamSamples { .. } => "beam-samples",
                Selection::UpdatedCells => "updated-cells",
            }
            .to_owned(),
            split_on_unclamp: config.split_on_unclamp,
            fusion_interval_scans: config.fusion_interval_scans,
            compared: Compared::new(ours, peer),
        });
    }
    Ok(records)
}

/// Our grid with `config` on every scan of `set`: insertion (fusion included), access to
/// the occupied cells, statistics and the classes of the query points.
fn run_config(set: &Dataset, config: GridConfig) -> Result<OursRun> {
    let mut grid = RtreeGrid::new(config)?;
    let started = Instant::now();
    // One batch: fusions at the interval and after the last scan (the same leaves as
    // `insert_cloud` per scan and `fuse_pending`).
    let scans = set.graph.nodes.iter();
    grid.insert_clouds(scans.map(|n| (&n.world_from_sensor, &n.points)));
    let insert_secs = started.elapsed().as_secs_f64();
    grid.shrink_to_fit();
    let started = Instant::now();
    let occupied = grid.for_each_occupied(|b| {
        std::hint::black_box(b);
    });
    let access_secs = started.elapsed().as_secs_f64();
    let stats = grid.stats();
    let classes = set.queries.iter().map(|q| grid.classify(q)).collect();
    Ok(OursRun {
        leaves: stats.leaves,
        fused: stats.fused_leaves,
        nodes: stats.nodes,
        height: stats.height,
        bytes: stats.bytes,
        insert_secs,
        access_secs,
        occupied,
        classes,
    })
}

/// Fraction of query points classified alike (all points; points known to both).
fn agreement(ours: &[Occupancy], peer: &str) -> (f64, f64) {
    let (mut same, mut total, mut known_same, mut known) = (0usize, 0usize, 0usize, 0usize);
    for (o, p) in ours.iter().zip(peer.chars()) {
        let p = match p {
            'o' => Occupancy::Occupied,
            'f' => Occupancy::Free,
            _ => Occupancy::Unknown,
        };
        total += 1;
        same += usize::from(*o == p);
        if *o != Occupancy::Unknown && p != Occupancy::Unknown {
            known += 1;
            known_same += usize::from(*o == p);
        }
    }
    (
        same as f64 / total.max(1) as f64,
        known_same as f64 / known.max(1) as f64,
    )
}
