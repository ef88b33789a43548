//! `cargo xtask eval octomap`: the Rtree variable-resolution grid (Khan 2017, ch. 2) beside
//! OctoMap, measured in the same run on the same scans.
//!
//! * Data: real scans first — the OctoMap sample `octomap/scan.dat.bz2` (sensor at the
//!   origin), the 10 real KITTI frames of `kitti/sequences/{00,01,04,07}` and the posed real
//!   Ouster frames, at r = 0.2 m and M = 8 (the headline table) — then a simulated urban
//!   drive (raypath-sim `urban-kitti`, HDL-64E) and scans simulated inside the real building
//!   map `octomap/geb079.bt`. Every data set is written as an OctoMap `.graph` (raypath-io)
//!   and read by both sides.
//! * OctoMap 1.9 (the installed liboctomap) through `xtask/octomap/driver.cpp`, built with
//!   `g++ -O2` into `target/octomap-driver`: `insertPointCloud` (beam-based) or the
//!   de-duplicated end points (beam-end-point), then `prune()`, `memoryUsage()`, the leaf
//!   iterator for the occupied-cell access time and `search()` for the classification of
//!   sampled points. Without OctoMap the report covers our side only.
//! * Ours: [`RtreeGrid`] with the same parameters (P_occ 0.7, P_free 0.4, clamping
//!   0.12/0.97), for r ∈ {0.1, 0.2, 0.4, 0.8} m and M ∈ {4, 8, 16, 32} (quick: r = 0.2,
//!   M = 8, fewer points), both inverse models. Both sides run single-threaded, one after
//!   the other, on a machine shared with other jobs: compare ratios, not absolute times.

mod data;
mod geb079;
mod peer;
mod plot;
mod real;

use std::fmt::Write;
use std::time::Instant;

use anyhow::Result;
use raypath_rtree_grid::{FusionRule, GridConfig, Occupancy, RtreeGrid, Selection, SensorModel};
use serde_json::json;

use super::{EvalContext, EvalReport, comparable};
use crate::table::{Table, fmt_num};
use data::Dataset;
use peer::PeerRun;

const NAME: &str = "octomap";

/// Variant label of the equal-value rule with the thesis' selection.
const EQUAL_LABEL: &str = "equal-value fusion + split-on-update (ours, beam samples)";
/// Variant label of the equal-value rule seeded from every updated cell.
const EQUAL_UPDATED_LABEL: &str = "equal-value fusion + split-on-update (ours, every updated cell)";

/// Variant label of the equal-value rule fusing every 10 scans and after the last one.
const EQUAL_BATCH_LABEL: &str = "equal-value fusion + split-on-update (ours, beam samples, fused every 10 scans and at the end)";

/// Sums for the equal-value rule over the summary's data sets (as for the thesis' rule).
#[derive(Default)]
struct EqualSums {
    ours_insert: f64,
    peer_insert: f64,
    ours_bytes: usize,
    peer_bytes: usize,
    reduction: Option<(String, f64)>,
    geb079: Option<(f64, f64, f64)>,
}

impl EqualSums {
    fn insertion_ratio(&self) -> Option<f64> {
        (self.peer_insert > 0.0).then(|| self.ours_insert / self.peer_insert)
    }

    fn bytes_ratio(&self) -> Option<f64> {
        (self.peer_bytes > 0).then(|| self.ours_bytes as f64 / self.peer_bytes as f64)
    }

    fn json(&self) -> serde_json::Value {
        json!({
            "leaf_reduction_vs_pruned_octomap_0_2m": self.reduction.as_ref().map(|r| r.1),
            "leaf_reduction_data": self.reduction.as_ref().map(|r| r.0.clone()),
            "insertion_time_ratio_vs_octomap": self.insertion_ratio(),
            "bytes_ratio_vs_octomap": self.bytes_ratio(),
            "geb079": self.geb079.map(|(red, ins, b)| json!({
                "leaf_reduction_vs_pruned_octomap_0_2m": red,
                "insertion_time_ratio_vs_octomap": ins,
                "bytes_ratio_vs_octomap": b,
            })),
        })
    }
}

/// Our side of one configuration.
struct OursRun {
    leaves: usize,
    fused: usize,
    nodes: usize,
    height: usize,
    bytes: usize,
    insert_secs: f64,
    access_secs: f64,
    occupied: usize,
    classes: Vec<Occupancy>,
}

fn run_ours(set: &Dataset, resolution_m: f64, m: usize, model: SensorModel) -> Result<OursRun> {
    run_config(set, GridConfig::with(resolution_m, m, model))
}

fn run_config(set: &Dataset, config: GridConfig) -> Result<OursRun> {
    let mut grid = RtreeGrid::new(config)?;
    let started = Instant::now();
    for node in &set.graph.nodes {
        grid.insert_cloud(&node.world_from_sensor, &node.points);
    }
    // Fusions still pending with a fusion interval > 1 scan (a no-op otherwise).
    grid.fuse_pending();
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

/// What the data of the summary's leaf-reduction row are (`set`: its name), for the
/// "comparable" cell.
fn summary_data(set: Option<&str>) -> String {
    match set {
        Some("urban") => "simulated HDL-64E urban drive, OctoMap in the same run".to_owned(),
        Some(name) => format!("`{name}`, OctoMap in the same run"),
        None => "no data set in this run".to_owned(),
    }
}

fn model_name(model: SensorModel) -> &'static str {
    match model {
        SensorModel::BeamBased => "beam",
        SensorModel::BeamEndPoint => "endpoint",
    }
}

/// One plotted configuration (M = 8).
struct PlotRow {
    data: String,
    resolution_m: f64,
    endpoint: bool,
    /// Leaves: ours, OctoMap's pruned (NaN without OctoMap).
    leaves: [f64; 2],
    /// Insertion µs per point: ours, OctoMap's.
    insert_us: [f64; 2],
}

/// Draws the plots into `docs/results/octomap/`; returns file names and captions.
fn write_figures(
    ctx: &EvalContext,
    sets: &[Dataset],
    rows: &[PlotRow],
) -> Result<Vec<(String, String)>> {
    if rows.is_empty() {
        return Ok(Vec::new());
    }
    let dir = ctx.figure_dir(NAME)?;
    let mut resolutions: Vec<f64> = rows.iter().map(|r| r.resolution_m).collect();
    resolutions.sort_by(f64::total_cmp);
    resolutions.dedup();
    let panels = |value: &dyn Fn(&PlotRow) -> [f64; 2]| -> Vec<plot::Panel> {
        sets.iter()
            .map(|set| plot::Panel {
                groups: resolutions
                    .iter()
                    .map(|&r| {
                        let mut bars = [None; 4];
                        for row in rows.iter().filter(|row| {
                            row.data == set.name && (row.resolution_m - r).abs() < 1e-9
                        }) {
                            let v = value(row);
                            let at = if row.endpoint { 2 } else { 0 };
                            bars[at] = Some(v[0]);
                            bars[at + 1] = Some(v[1]);
                        }
                        (format!("{r}"), bars)
                    })
                    .collect(),
            })
            .collect()
    };
    let names: Vec<&str> = sets.iter().map(|s| s.name.as_str()).collect();
    let legend = format!(
        "panels left to right: {}; groups: resolution r in m; bars: ours beam-based (dark blue), \
         OctoMap beam-based (dark orange), ours end-point (light blue), OctoMap end-point (light \
         orange); M = 8; log scale, labels are powers of ten",
        names.join(", ")
    );
    let mut out = Vec::new();
    let file = "leaves.png";
    plot::bar_chart(&dir.join(file), &panels(&|r| r.leaves))?;
    out.push((
        file.to_owned(),
        format!("Leaves, ours vs pruned OctoMap ({legend})."),
    ));
    let file = "insert_us_per_point.png";
    plot::bar_chart(&dir.join(file), &panels(&|r| r.insert_us))?;
    out.push((
        file.to_owned(),
        format!("Insertion time per point in µs, fusion included ({legend})."),
    ));
    Ok(out)
}

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let (resolutions, orders): (&[f64], &[usize]) = if ctx.quick {
        (&[0.2], &[8])
    } else {
        (&[0.1, 0.2, 0.4, 0.8], &[4, 8, 16, 32])
    };
    let mut sets = Vec::new();
    let stride = if ctx.quick { 4 } else { 1 };
    for repeat in [1, 5] {
        sets.extend(data::scan_dat(ctx, stride, repeat)?);
    }
    let kitti: &[&str] = if ctx.quick {
        &["00"]
    } else {
        &["00", "01", "04", "07"]
    };
    for seq in kitti {
        sets.extend(data::real_sweeps(
            ctx,
            &format!("kitti-{seq}"),
            &format!("kitti/sequences/{seq}"),
            "KITTI HDL-64E frames 0–9 (SemanticKITTI poses)",
            if ctx.quick { 16 } else { 4 },
        )?);
    }
    sets.extend(data::real_sweeps(
        ctx,
        "ouster-os1",
        "ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap",
        "Ouster OS-1-128 frames (vendor SLAM poses)",
        if ctx.quick { 8 } else { 2 },
    )?);
    let urban = if ctx.quick {
        data::urban(ctx, 5, 1, 8)?
    } else {
        data::urban(ctx, 30, 1, 4)?
    };
    sets.extend(urban);
    // Scans simulated inside the real building map (360 × 32 beams each).
    sets.extend(geb079::geb079(
        ctx,
        if ctx.quick { 2 } else { 10 },
        360,
        32,
    )?);
    let driver = peer::build(&ctx.workspace_root);
    if let Err(why) = &driver {
        eprintln!("octomap: OctoMap unavailable: {why}; reporting our side only");
    }
    let models = [SensorModel::BeamBased, SensorModel::BeamEndPoint];
    let sweep = |set: &Dataset| -> (&[f64], &[usize]) {
        if set.full_sweep {
            (resolutions, orders)
        } else {
            (&[0.2], &[8])
        }
    };
    let total: usize = sets
        .iter()
        .map(|s| sweep(s).0.len() * models.len() * (sweep(s).1.len() + 1))
        .sum();
    let bar = ctx.progress(total as u64, NAME);

    let mut table = Table::new([
        "data",
        "model",
        "r [m]",
        "M",
        "leaves",
        "fused",
        "nodes",
        "height",
        "bytes",
        "insert [µs/pt]",
        "access [ms]",
        "OctoMap leaves (pruned)",
        "OctoMap inner",
        "OctoMap bytes",
        "OctoMap insert [µs/pt]",
        "OctoMap access [ms]",
        "leaf reduction",
        "insert ratio",
        "bytes ratio",
        "agree (all / known)",
    ]);
    let mut rows = Vec::new();
    // Sums over the data sets at r = 0.2 m, M = 8, beam-based (the summary).
    let (mut ours_insert_02, mut peer_insert_02) = (0.0, 0.0);
    let (mut ours_bytes_02, mut peer_bytes_02) = (0usize, 0usize);
    let mut reduction_02: Option<(String, f64)> = None;
    // geb079 at r = 0.2 m, M = 8, beam-based (reported beside the summary, not in it).
    let mut geb079_02: Option<(f64, f64, f64)> = None;
    // Per data set, model and resolution at M = 8: leaves and µs/point, ours and OctoMap's.
    let mut plot_rows: Vec<PlotRow> = Vec::new();
    // The equal-value rule (beam samples; every updated cell) at r = 0.2 m, M = 8, beam.
    let mut equal_02: [EqualSums; 3] = Default::default();
    let mut variant_rows = Vec::new();
    let mut variants = Table::new([
        "data",
        "variant",
        "leaves",
        "fused",
        "bytes",
        "insert [µs/pt]",
        "leaf reduction",
        "insert ratio",
        "agree (all / known)",
    ]);
    for set in &sets {
        let points = set.graph.num_points().max(1) as f64;
        let (set_resolutions, set_orders) = sweep(set);
        // The summary's sums keep their meaning: scan.dat, scan.dat-x5 and urban only.
        let in_sums = ["scan.dat", "scan.dat-x5", "urban"].contains(&set.name.as_str());
        for &r in set_resolutions {
            for model in models {
                let endpoint = model == SensorModel::BeamEndPoint;
                let peer: Option<PeerRun> = match &driver {
                    Ok(d) => {
                        let p = peer::run(d, &set.path, r, endpoint, Some(&set.queries_path))?;
                        anyhow::ensure!(
                            p.points == set.graph.num_points(),
                            "OctoMap read {} points from {}, we wrote {}",
                            p.points,
                            set.path.display(),
                            set.graph.num_points()
                        );
                        Some(p)
                    }
                    Err(_) => None,
                };
                bar.inc(1);
                if (r - 0.2).abs() < 1e-9 && !endpoint {
                    let base = GridConfig::with(r, 8, model);
                    let cases = [
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
                        (
                            EQUAL_LABEL,
                            GridConfig {
                                fusion_rule: FusionRule::EqualValue,
                                ..base
                            },
                        ),
                        (
                            EQUAL_UPDATED_LABEL,
                            GridConfig {
                                fusion_rule: FusionRule::EqualValue,
                                selection: Selection::UpdatedCells,
                                ..base
                            },
                        ),
                        (
                            EQUAL_BATCH_LABEL,
                            GridConfig {
                                fusion_rule: FusionRule::EqualValue,
                                fusion_interval_scans: 10,
                                ..base
                            },
                        ),
                    ];
                    for (label, config) in cases {
                        let ours = run_config(set, config)?;
                        let rule = match config.fusion_rule {
                            FusionRule::Clamped => "clamped",
                            FusionRule::EqualValue => "equal",
                        };
                        let selection = match config.selection {
                            Selection::BeamSamples { .. } => "beam-samples",
                            Selection::UpdatedCells => "updated-cells",
                        };
                        variant_rows.push(json!({
                            "data": set.name, "variant": label, "fusion": config.fusion,
                            "fusion_rule": rule, "selection": selection,
                            "split_on_unclamp": config.split_on_unclamp,
                            "fusion_interval_scans": config.fusion_interval_scans,
                            "leaves": ours.leaves, "fused_leaves": ours.fused, "bytes": ours.bytes,
                            "insert_secs": ours.insert_secs,
                            "leaf_reduction": peer.as_ref().map(|p| 1.0 - ours.leaves as f64 / p.leaves as f64),
                            "insertion_time_ratio": peer.as_ref().map(|p| ours.insert_secs / p.insert_secs),
                            "bytes_ratio": peer.as_ref().map(|p| ours.bytes as f64 / p.memory_bytes as f64),
                        }));
                        if let (Some(p), Some(k)) = (
                            &peer,
                            [EQUAL_LABEL, EQUAL_UPDATED_LABEL, EQUAL_BATCH_LABEL]
                                .iter()
                                .position(|l| *l == label),
                        ) {
                            let e = &mut equal_02[k];
                            if set.name == "geb079" {
                                e.geb079 = Some((
                                    1.0 - ours.leaves as f64 / p.leaves as f64,
                                    ours.insert_secs / p.insert_secs,
                                    ours.bytes as f64 / p.memory_bytes as f64,
                                ));
                            } else if in_sums {
                                e.ours_insert += ours.insert_secs;
                                e.peer_insert += p.insert_secs;
                                e.ours_bytes += ours.bytes;
                                e.peer_bytes += p.memory_bytes;
                                if e.reduction.is_none() || set.name == "urban" {
                                    e.reduction = Some((
                                        set.name.clone(),
                                        1.0 - ours.leaves as f64 / p.leaves as f64,
                                    ));
                                }
                            }
                        }
                        variants.row([
                            set.name.clone(),
                            label.to_owned(),
                            ours.leaves.to_string(),
                            ours.fused.to_string(),
                            ours.bytes.to_string(),
                            fmt_num(ours.insert_secs / points * 1e6, 3),
                            peer.as_ref().map_or("—".into(), |p| {
                                format!(
                                    "{:.1} %",
                                    100.0 * (1.0 - ours.leaves as f64 / p.leaves as f64)
                                )
                            }),
                            peer.as_ref().map_or("—".into(), |p| {
                                fmt_num(ours.insert_secs / p.insert_secs, 2)
                            }),
                            peer.as_ref().map_or("—".into(), |p| {
                                let (a, k) = agreement(&ours.classes, &p.classes);
                                format!("{a:.3} / {k:.3}")
                            }),
                        ]);
                    }
                }
                for &m in set_orders {
                    let ours = run_ours(set, r, m, model)?;
                    bar.inc(1);
                    let reduction = peer
                        .as_ref()
                        .map(|p| 1.0 - ours.leaves as f64 / p.leaves as f64);
                    let ratio = peer.as_ref().map(|p| ours.insert_secs / p.insert_secs);
                    let bytes_ratio = peer
                        .as_ref()
                        .map(|p| ours.bytes as f64 / p.memory_bytes as f64);
                    let agree = peer.as_ref().map(|p| agreement(&ours.classes, &p.classes));
                    if m == 8 {
                        plot_rows.push(PlotRow {
                            data: set.name.clone(),
                            resolution_m: r,
                            endpoint,
                            leaves: [
                                ours.leaves as f64,
                                peer.as_ref().map_or(f64::NAN, |p| p.leaves as f64),
                            ],
                            insert_us: [
                                ours.insert_secs / points * 1e6,
                                peer.as_ref()
                                    .map_or(f64::NAN, |p| p.insert_secs / points * 1e6),
                            ],
                        });
                    }
                    let at_02 = (r - 0.2).abs() < 1e-9 && m == 8 && !endpoint;
                    if at_02 && set.name == "geb079" {
                        if let (Some(red), Some(ins), Some(b)) = (reduction, ratio, bytes_ratio) {
                            geb079_02 = Some((red, ins, b));
                        }
                    } else if at_02 && in_sums {
                        if let Some(p) = &peer {
                            ours_insert_02 += ours.insert_secs;
                            peer_insert_02 += p.insert_secs;
                            ours_bytes_02 += ours.bytes;
                            peer_bytes_02 += p.memory_bytes;
                            let take = reduction_02.as_ref().is_none_or(|_| set.name == "urban");
                            if take {
                                reduction_02 =
                                    Some((set.name.clone(), reduction.unwrap_or(f64::NAN)));
                            }
                        }
                    }
                    let opt =
                        |v: Option<f64>, d: usize| v.map_or("—".to_owned(), |v| fmt_num(v, d));
                    table.row([
                        set.name.clone(),
                        model_name(model).to_owned(),
                        format!("{r}"),
                        m.to_string(),
                        ours.leaves.to_string(),
                        ours.fused.to_string(),
                        ours.nodes.to_string(),
                        ours.height.to_string(),
                        ours.bytes.to_string(),
                        fmt_num(ours.insert_secs / points * 1e6, 3),
                        fmt_num(ours.access_secs * 1e3, 3),
                        peer.as_ref().map_or("—".into(), |p| p.leaves.to_string()),
                        peer.as_ref()
                            .map_or("—".into(), |p| p.inner_nodes.to_string()),
                        peer.as_ref()
                            .map_or("—".into(), |p| p.memory_bytes.to_string()),
                        opt(peer.as_ref().map(|p| p.insert_secs / points * 1e6), 3),
                        opt(peer.as_ref().map(|p| p.access_secs * 1e3), 3),
                        reduction.map_or("—".into(), |v| format!("{:.1} %", 100.0 * v)),
                        opt(ratio, 2),
                        opt(bytes_ratio, 2),
                        agree.map_or("—".into(), |(a, k)| format!("{:.3} / {:.3}", a, k)),
                    ]);
                    rows.push(json!({
                        "data": set.name, "model": model_name(model), "resolution_m": r, "m": m,
                        "points": set.graph.num_points(),
                        "ours": {"leaves": ours.leaves, "fused_leaves": ours.fused, "nodes": ours.nodes,
                            "height": ours.height, "bytes": ours.bytes, "insert_secs": ours.insert_secs,
                            "access_secs": ours.access_secs, "occupied_leaves": ours.occupied},
                        "octomap": peer.as_ref().map(|p| json!({"leaves_pruned": p.leaves,
                            "leaves_built": p.leaves_built, "inner_nodes": p.inner_nodes, "nodes": p.nodes,
                            "memory_bytes": p.memory_bytes, "insert_secs": p.insert_secs,
                            "access_secs": p.access_secs, "occupied_leaves": p.occupied_leaves})),
                        "leaf_reduction": reduction, "insertion_time_ratio": ratio, "bytes_ratio": bytes_ratio,
                        "agreement_all": agree.map(|a| a.0), "agreement_known": agree.map(|a| a.1),
                    }));
                }
            }
        }
    }
    bar.finish_and_clear();

    let insertion_ratio = (peer_insert_02 > 0.0).then(|| ours_insert_02 / peer_insert_02);
    let bytes_ratio = (peer_bytes_02 > 0).then(|| ours_bytes_02 as f64 / peer_bytes_02 as f64);
    let leaf_reduction = reduction_02.as_ref().map(|r| r.1);
    let mut md = String::new();
    writeln!(
        md,
        "Khan (2017), ch. 2: the Rtree variable-resolution occupancy grid (`raypath-rtree-grid`) \
         beside OctoMap, both fed the same `.graph` scans in the same run with P_occ = 0.7, \
         P_free = 0.4, clamping 0.12 / 0.97, occupancy threshold 0.5.\n"
    )?;
    match &driver {
        Ok(_) => writeln!(
            md,
            "OctoMap: the installed liboctomap (Debian `liboctomap-dev`, 1.9.x) through \
             `xtask/octomap/driver.cpp`; leaves and inner nodes after `prune()`, bytes from \
             `memoryUsage()`. Both sides single-threaded, run one after the other on a machine \
             shared with other jobs (absolute times are under load; the ratios are the result).\n"
        )?,
        Err(why) => writeln!(md, "**OctoMap unavailable ({why}); our side only.**\n")?,
    }
    writeln!(md, "## Data\n")?;
    for set in &sets {
        writeln!(md, "- `{}`: {}", set.name, set.about)?;
    }
    let (real_table, real_rows) = real::table(&sets, &rows, &variant_rows);
    writeln!(
        md,
        "\n## Real scans (headline; beam-based, r = 0.2 m, M = 8)\n\nLeaf reduction = 1 − \
         ours / pruned OctoMap; ratios ours / OctoMap, same run (insertion includes fusion). \
         \"thesis rule\" fuses clamped cells (Khan 2017 §2.4); \"equal-value\" is our exact \
         extension (see below).\n"
    )?;
    md.push_str(&real_table.to_markdown()?);
    writeln!(
        md,
        "\n## Summary of the earlier sets (beam-based, r = 0.2 m, M = 8; urban and geb079 are \
         simulated)\n"
    )?;
    writeln!(md, "{}", super::sim::gap_note(ctx)?)?;
    let mut summary = Table::new(["quantity", "measured", "thesis / aim", comparable::HEADER]);
    summary.row([
        format!(
            "leaf reduction vs pruned OctoMap ({})",
            reduction_02.as_ref().map_or("—", |r| r.0.as_str())
        ),
        leaf_reduction.map_or("—".into(), |v| format!("{:.2} %", 100.0 * v)),
        "28.51 % fewer leaves at 0.2 m (Freiburg campus, Fig. 2.9b); aim ≥ 28.5 %".into(),
        comparable::no(&format!(
            "{}; thesis: the real 81-scan Freiburg campus graph (not available here)",
            summary_data(reduction_02.as_ref().map(|r| r.0.as_str()))
        )),
    ]);
    summary.row([
        "insertion time ours / OctoMap (scan.dat, scan.dat-x5, urban)".to_owned(),
        insertion_ratio.map_or("—".into(), |v| fmt_num(v, 2)),
        "thesis: Rtree slower (> 1, Fig. 2.9c); aim ≤ 1".into(),
        comparable::no(
            "real OctoMap sample scan and simulated urban drive, ratio of one run on shared \
             cores; thesis: the real Freiburg campus graph on one Intel i5-2500K core",
        ),
    ]);
    summary.row([
        "bytes ours / OctoMap memoryUsage() (scan.dat, scan.dat-x5, urban)".to_owned(),
        bytes_ratio.map_or("—".into(), |v| fmt_num(v, 2)),
        "thesis: not reported; aim < 1".into(),
        comparable::no("the thesis reports no memory figure: the aim only"),
    ]);
    if let Some((red, ins, b)) = geb079_02 {
        summary.row([
            "geb079 (not in the rows above): leaf reduction / insertion ratio / bytes ratio"
                .to_owned(),
            format!(
                "{:.2} % / {} / {}",
                100.0 * red,
                fmt_num(ins, 2),
                fmt_num(b, 2)
            ),
            "thesis: 28.51 % / > 1 / —; aim ≥ 28.5 % / ≤ 1 / < 1".into(),
            comparable::no(
                "scans simulated in the real geb079 building map; thesis: the real Freiburg \
                 campus graph",
            ),
        ]);
    }
    for (sums, label) in equal_02.iter().zip([
        "beam samples",
        "every updated cell",
        "beam samples, fused every 10 scans",
    ]) {
        summary.row([
            format!(
                "equal-value rule (ours, {label}): leaf reduction ({}) / insertion ratio / bytes ratio",
                sums.reduction.as_ref().map_or("—", |r| r.0.as_str())
            ),
            format!(
                "{} / {} / {}",
                sums.reduction
                    .as_ref()
                    .map_or("—".into(), |r| format!("{:.2} %", 100.0 * r.1)),
                sums.insertion_ratio().map_or("—".into(), |v| fmt_num(v, 2)),
                sums.bytes_ratio().map_or("—".into(), |v| fmt_num(v, 2)),
            ),
            "not in the thesis (our extension); aim ≥ 28.5 % / ≤ 1 / < 1".into(),
            comparable::no("not in the thesis (our extension): the aim only"),
        ]);
    }
    md.push_str(&summary.to_markdown()?);
    writeln!(
        md,
        "\nThe equal-value rule is our extension beyond Khan 2017: cells whose log-odds are \
         bit-equal fuse, clamped or not (OctoMap's pruning rule — 8 siblings with equal \
         log-odds — but with cuboids grown in the thesis' search-direction order). The map \
         stays exact: a fused cell whose value a scan changes for only part of its base cubes \
         is split (the changed cubes, plus halving cuboids with the old value) before the \
         updates apply, so each base cube holds the log-odds of an unfused lattice. Rows in \
         the Variants table; figures under `summary.equal_value` (thesis selection) and \
         `summary.equal_value_updated_cells` and `summary.equal_value_every_10_scans` (fusion \
         every 10 scans and after the last; the map's values do not depend on when fusion \
         runs, only how often fused cells are split and re-fused) in the JSON, which also \
         lists every variant under `variants`.\n"
    )?;
    writeln!(
        md,
        "\nThe summary keys of `target/eval/octomap.json` keep their meaning: the leaf \
         reduction on the urban drive, the insertion-time and bytes ratios summed over \
         scan.dat, scan.dat-x5 and urban. The geb079 figures are under `summary.geb079`.\n"
    )?;
    let figures = write_figures(ctx, &sets, &plot_rows)?;
    if !figures.is_empty() {
        writeln!(md, "\n## Plots\n")?;
        for (file, caption) in &figures {
            writeln!(md, "![{caption}](octomap/{file})\n\n*{caption}*\n")?;
        }
    }
    writeln!(md, "\n## All runs\n")?;
    writeln!(
        md,
        "`nodes` = R-tree nodes (the MBRCs of the hierarchy, Fig. 2.9a counts these against \
         OctoMap's inner nodes); `bytes` = our allocated bytes (tree arena, 16-byte cells, \
         lattice index); insertion time includes fusion; access = visiting all leaves and \
         testing occupancy (both sides); agreement = share of {} sampled points (on beams, \
         t ∈ [0, 1.05] of the beam) classified alike as unknown/free/occupied, and among the \
         points both sides know.\n",
        sets.first().map_or(0, |s| s.queries.len())
    )?;
    writeln!(
        md,
        "Comparable, ours beside OctoMap in these tables: {}; the data set is real or \
         simulated as listed under Data.\n",
        comparable::yes(
            "both fed the same scans in the same run on the same machine, one thread each"
        )
    )?;
    md.push_str(&table.to_markdown()?);
    writeln!(
        md,
        "\n## Variants (beam-based, r = 0.2 m, M = 8)\n\nThe thesis fuses only clamped cells, \
         starting from end-point cells and cells sampled along the beams; the variants show \
         what the selection, the optional split-back (the thesis' future work) and our \
         equal-value rule (exact, with split-on-update) change.\n"
    )?;
    md.push_str(&variants.to_markdown()?);
    writeln!(
        md,
        "\n## Notes\n\n\
         - Thesis statements (§2.6): Rtree has fewer inner nodes and fewer leaves than pruned \
           OctoMap (28.51 % fewer at 0.2 m, beam-based), M does not change the leaves, Rtree \
           insertion is slower and access to occupied cells faster. The thesis used the 81-scan \
           Freiburg campus graph, which is not available here.\n\
         - Fusion selection is the thesis' (end-point cells plus cells drawn at random along \
           the beams: each traversed cell with probability 1/10, the spec's one sample per 10 \
           base cubes); fused cells are updated as a whole (no splitting).\n\
         - geb079: scans simulated in the real 0.08 m building map (see Data); a static \
           indoor scene seen from a few positions, so cells near the sensors are observed \
           several times.\n\
         - OctoMap's leaf counts are after `prune()`; OctoMap prunes during updates as well.\n"
    )?;
    let json = json!({
        "summary": {
            "leaf_reduction_vs_pruned_octomap_0_2m": leaf_reduction,
            "leaf_reduction_data": reduction_02.as_ref().map(|r| r.0.clone()),
            "insertion_time_ratio_vs_octomap": insertion_ratio,
            "bytes_ratio_vs_octomap": bytes_ratio,
            "octomap_available": driver.is_ok(),
            "equal_value": equal_02[0].json(),
            "equal_value_updated_cells": equal_02[1].json(),
            "equal_value_every_10_scans": equal_02[2].json(),
            "real": real_rows,
            "geb079": geb079_02.map(|(red, ins, b)| json!({
                "leaf_reduction_vs_pruned_octomap_0_2m": red,
                "insertion_time_ratio_vs_octomap": ins,
                "bytes_ratio_vs_octomap": b,
            })),
        },
        "runs": rows,
        "variants": variant_rows,
    });
    let headline = real::headline(&real_rows, reduction_02.as_ref());
    Ok(EvalReport {
        name: NAME,
        title: "Rtree variable-resolution grid beside OctoMap (Khan ch. 2)".into(),
        markdown: md,
        json,
        headline,
    })
}
