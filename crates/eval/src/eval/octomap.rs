//! `cargo xtask eval octomap`: the Rtree variable-resolution grid (Khan 2017, ch. 2) beside
//! OctoMap, measured in the same run on the same scans.
//!
//! * Data: real scans first — the OctoMap sample `octomap/scan.dat.bz2` (sensor at the
//!   origin), the 10 real KITTI frames of `kitti/sequences/{00,01,04,07}` and the posed real
//!   Ouster frames, at r = 0.2 m and M = 8 (the headline table) — then a simulated urban
//!   drive (raypath-sim `urban-kitti`, HDL-64E) and scans simulated inside the real building
//!   map `octomap/geb079.bt`. Every data set is written as an OctoMap `.graph` (raypath-io)
//!   and read by both sides.
//! * OctoMap 1.9 (the installed liboctomap) through `crates/eval/octomap/driver.cpp`, built with
//!   `g++ -O2` into `target/octomap-driver`: `insertPointCloud` (beam-based) or the
//!   de-duplicated end points (beam-end-point), then `prune()`, `memoryUsage()`, the leaf
//!   iterator for the occupied-cell access time and `search()` for the classification of
//!   sampled points. Without OctoMap the report covers our side only.
//! * Ours: [`RtreeGrid`](raypath_rtree_grid::RtreeGrid) with the same parameters (P_occ 0.7,
//!   P_free 0.4, clamping 0.12/0.97), for r ∈ {0.1, 0.2, 0.4, 0.8} m and M ∈ {4, 8, 16, 32}
//!   (quick: r = 0.2, M = 8, fewer points), both inverse models. Both sides run
//!   single-threaded, one after the other, on a machine shared with other jobs: compare
//!   ratios, not absolute times.
//!
//! In stages: one unit per data set ([`measure`]), the page from their results.

mod data;
mod figures;
mod geb079;
mod measure;
mod peer;
mod plot;
mod real;
mod summary;
mod tables;

pub(super) use self::data::Dataset;
pub(super) use self::peer::{PeerRun, build as build_peer, run as run_peer};

use std::fmt::Write;

use anyhow::{Result, bail};
use serde_json::{Value, json};

use super::stages::{self, Staged, UnitResults};
use super::{EvalContext, EvalReport, comparable};
use measure::{SetInfo, SetResult};
use summary::Summary;

const NAME: &str = "octomap";

/// Variant label of the equal-value rule with the thesis' selection.
const EQUAL_LABEL: &str = "equal-value fusion + split-on-update (ours, beam samples)";
/// Variant label of the equal-value rule seeded from every updated cell.
const EQUAL_UPDATED_LABEL: &str = "equal-value fusion + split-on-update (ours, every updated cell)";

/// Variant label of the equal-value rule fusing every 10 scans and after the last one.
const EQUAL_BATCH_LABEL: &str = "equal-value fusion + split-on-update (ours, beam samples, fused every 10 scans and at the end)";
/// Variant label of the equal-value rule seeded from every updated cell, fusing every 10
/// scans and after the last one.
const EQUAL_UPDATED_BATCH_LABEL: &str = "equal-value fusion + split-on-update (ours, every updated cell, fused every 10 scans and at the end)";

/// The evaluation in stages: one unit per data set (`--shard i/n` and `eval merge`).
pub const STAGED: Staged = Staged {
    name: NAME,
    units,
    run_unit,
    report,
};

/// The KITTI sequences of the run.
fn kitti(ctx: &EvalContext) -> &'static [&'static str] {
    if ctx.quick {
        &["00"]
    } else {
        &["00", "01", "04", "07"]
    }
}

/// The resolutions and M of the full sweep.
fn sweep(ctx: &EvalContext) -> (&'static [f64], &'static [usize]) {
    if ctx.quick {
        (&[0.2], &[8])
    } else {
        (&[0.1, 0.2, 0.4, 0.8], &[4, 8, 16, 32])
    }
}

/// The data sets in report order: the real ones (the OctoMap sample scan once and inserted
/// five times, the KITTI sequences, the Ouster capture), then the simulated urban drive and
/// the scans simulated in geb079.
fn units(ctx: &EvalContext) -> Result<Vec<String>> {
    let mut units = vec!["scan.dat".to_owned(), "scan.dat-x5".to_owned()];
    units.extend(kitti(ctx).iter().map(|seq| format!("kitti-{seq}")));
    units.extend(["ouster-os1", "urban", "geb079"].map(str::to_owned));
    Ok(units)
}

/// The scans of data set `unit`, written as a `.graph`; `None` when its data are absent.
pub(super) fn dataset(ctx: &EvalContext, unit: &str) -> Result<Option<Dataset>> {
    let q = ctx.quick;
    let stride = if q { 4 } else { 1 };
    match unit {
        "scan.dat" => data::scan_dat(ctx, stride, 1),
        "scan.dat-x5" => data::scan_dat(ctx, stride, 5),
        "ouster-os1" => data::real_sweeps(
            ctx,
            unit,
            "ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap",
            "Ouster OS-1-128 frames (vendor SLAM poses)",
            if q { 8 } else { 2 },
        ),
        "urban" if q => data::urban(ctx, 5, 1, 8),
        "urban" => data::urban(ctx, 30, 1, 4),
        // Scans simulated inside the real building map (360 × 32 beams each).
        "geb079" => geb079::geb079(ctx, if q { 2 } else { 10 }, 360, 32),
        _ => match unit.strip_prefix("kitti-") {
            Some(seq) => data::real_sweeps(
                ctx,
                unit,
                &format!("kitti/sequences/{seq}"),
                "KITTI HDL-64E frames 0–9 (SemanticKITTI poses)",
                if q { 16 } else { 4 },
            ),
            None => bail!("{NAME}: no data set {unit:?}"),
        },
    }
}

/// Measures one data set, ours beside OctoMap (when it builds).
fn run_unit(ctx: &EvalContext, unit: &str) -> Result<Value> {
    let driver = peer::build(&ctx.workspace_root);
    if let Err(why) = &driver {
        eprintln!("octomap: OctoMap unavailable: {why}; reporting our side only");
    }
    let set = match dataset(ctx, unit)? {
        Some(set) => Some(measure::measure(&set, driver.as_deref().ok(), sweep(ctx))?),
        None => None,
    };
    let gap_note = if unit == "urban" {
        Some(super::sim::gap_note(ctx)?)
    } else {
        None
    };
    Ok(serde_json::to_value(SetResult {
        set,
        octomap_unavailable: driver.err(),
        gap_note,
    })?)
}

/// The page from every data set's measurements.
fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let units: Vec<SetResult> = stages::decode(results)?;
    let sets: Vec<&SetInfo> = units.iter().filter_map(|u| u.set.as_ref()).collect();
    let unavailable = units.iter().find_map(|u| u.octomap_unavailable.clone());
    let gap_note = match units.iter().find_map(|u| u.gap_note.clone()) {
        Some(note) => note,
        None => super::sim::gap_note(ctx)?,
    };
    let summary = Summary::of(&sets);
    let (runs, run_rows) = tables::runs(&sets);
    let (variants, variant_rows) = tables::variants(&sets);
    let (real_table, real_rows) = real::table(&sets, &run_rows, &variant_rows);
    let mut md = intro(&sets, unavailable.as_deref())?;
    md.push_str(&real_table.to_markdown()?);
    md.push_str(&summary_section(&summary, &gap_note)?);
    md.push_str(&plots_section(&figures::write(ctx, &sets)?)?);
    md.push_str(&runs_section(&sets)?);
    md.push_str(&runs.to_markdown()?);
    md.push_str(VARIANTS_TEXT);
    md.push_str(&variants.to_markdown()?);
    md.push_str(NOTES);
    let json = json!({
        "summary": summary.json(unavailable.is_none(), &real_rows),
        "runs": run_rows,
        "variants": variant_rows,
    });
    let headline = real::headline(&real_rows, summary.thesis.reduction.as_ref());
    Ok(EvalReport {
        name: NAME,
        title: "Rtree variable-resolution grid beside OctoMap (Khan ch. 2)".into(),
        markdown: md,
        json,
        headline,
    })
}

/// The set-up, OctoMap's availability, the data sets and the real table's heading.
fn intro(sets: &[&SetInfo], unavailable: Option<&str>) -> Result<String> {
    let mut md = String::new();
    writeln!(
        md,
        "Khan (2017), ch. 2: the Rtree variable-resolution occupancy grid (`raypath-rtree-grid`) \
         beside OctoMap, both fed the same `.graph` scans in the same run with P_occ = 0.7, \
         P_free = 0.4, clamping 0.12 / 0.97, occupancy threshold 0.5.\n"
    )?;
    match unavailable {
        None => writeln!(
            md,
            "OctoMap: the installed liboctomap (Debian `liboctomap-dev`, 1.9.x) through \
             `crates/eval/octomap/driver.cpp`; leaves and inner nodes after `prune()`, bytes from \
             `memoryUsage()`. Both sides single-threaded, run one after the other on a machine \
             shared with other jobs (absolute times are under load; the ratios are the result).\n"
        )?,
        Some(why) => writeln!(md, "**OctoMap unavailable ({why}); our side only.**\n")?,
    }
    writeln!(md, "## Data\n")?;
    for set in sets {
        writeln!(md, "- `{}`: {}", set.name, set.about)?;
    }
    writeln!(
        md,
        "\n## Real scans (headline; beam-based, r = 0.2 m, M = 8)\n\nLeaf reduction = 1 − \
         ours / pruned OctoMap; ratios ours / OctoMap, same run (insertion includes fusion). \
         \"thesis rule\" fuses clamped cells (Khan 2017 §2.4); \"equal-value\" is our exact \
         extension (see below).\n"
    )?;
    Ok(md)
}

/// The summary of the earlier sets with the notes on the equal-value rule and the JSON keys.
fn summary_section(summary: &Summary, gap_note: &str) -> Result<String> {
    let mut md = String::new();
    writeln!(
        md,
        "\n## Summary of the earlier sets (beam-based, r = 0.2 m, M = 8; urban and geb079 are \
         simulated)\n"
    )?;
    writeln!(md, "{gap_note}")?;
    md.push_str(&summary.table()?);
    writeln!(
        md,
        "\nThe equal-value rule is our extension beyond Khan 2017: cells whose log-odds are \
         bit-equal fuse, clamped or not (OctoMap's pruning rule — 8 siblings with equal \
         log-odds — but with cuboids grown in the thesis' search-direction order). The map \
         stays exact: a fused cell whose value a scan changes for only part of its base cubes \
         is split (the changed cubes, plus halving cuboids with the old value) before the \
         updates apply, so each base cube holds the log-odds of an unfused lattice. Rows in \
         the Variants table; figures under `summary.equal_value` (thesis selection), \
         `summary.equal_value_updated_cells`, `summary.equal_value_every_10_scans` and \
         `summary.equal_value_updated_cells_every_10_scans` (fusion every 10 scans and after \
         the last; the map's values do not depend on when fusion runs, only how often fused \
         cells are split and re-fused) in the JSON, which also lists every variant under \
         `variants`. Every variant inserts the scans of a data set as one batch \
         (`RtreeGrid::insert_clouds`): with a fusion interval above one scan, the cells of the \
         scans between two fusion passes enter the R-tree only after the pass.\n"
    )?;
    writeln!(
        md,
        "\nThe summary keys of `target/eval/octomap.json` keep their meaning: the leaf \
         reduction on the urban drive, the insertion-time and bytes ratios summed over \
         scan.dat, scan.dat-x5 and urban. The geb079 figures are under `summary.geb079`.\n"
    )?;
    Ok(md)
}

/// The plots (file, caption), when any were drawn.
fn plots_section(figures: &[(String, String)]) -> Result<String> {
    let mut md = String::new();
    if !figures.is_empty() {
        writeln!(md, "\n## Plots\n")?;
        for (file, caption) in figures {
            writeln!(md, "![{caption}](octomap/{file})\n\n*{caption}*\n")?;
        }
    }
    Ok(md)
}

/// The heading and legend of the table of all runs.
fn runs_section(sets: &[&SetInfo]) -> Result<String> {
    let mut md = String::new();
    writeln!(md, "\n## All runs\n")?;
    writeln!(
        md,
        "`nodes` = R-tree nodes (the MBRCs of the hierarchy, Fig. 2.9a counts these against \
         OctoMap's inner nodes); `bytes` = our allocated bytes (tree arena, 16-byte cells, \
         lattice index); insertion time includes fusion; access = visiting all leaves and \
         testing occupancy (both sides); agreement = share of {} sampled points (on beams, \
         t ∈ [0, 1.05] of the beam) classified alike as unknown/free/occupied, and among the \
         points both sides know.\n",
        sets.first().map_or(0, |s| s.queries)
    )?;
    writeln!(
        md,
        "Comparable, ours beside OctoMap in these tables: {}; the data set is real or \
         simulated as listed under Data.\n",
        comparable::yes(
            "both fed the same scans in the same run on the same machine, one thread each"
        )
    )?;
    Ok(md)
}

/// The heading and legend of the variants table.
const VARIANTS_TEXT: &str = "\n## Variants (beam-based, r = 0.2 m, M = 8)\n\nThe thesis fuses \
     only clamped cells, starting from end-point cells and cells sampled along the beams; the \
     variants show what the selection, the optional split-back (the thesis' future work) and \
     our equal-value rule (exact, with split-on-update) change.\n\n";

/// The closing notes.
const NOTES: &str = "\n## Notes\n\n\
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
     - OctoMap's leaf counts are after `prune()`; OctoMap prunes during updates as well.\n\n";

#[cfg(test)]
mod tests {
    use super::*;
    use measure::{Compared, OursRun, RunRecord, VariantRecord};
    use peer::PeerRun;

    /// Ours with `leaves` beside OctoMap's 100 pruned leaves; half OctoMap's time and bytes.
    fn compared(leaves: usize) -> Compared {
        Compared {
            ours: OursRun {
                leaves,
                fused: 1,
                nodes: 3,
                height: 2,
                bytes: 1000,
                insert_secs: 0.25,
                access_secs: 0.001,
                occupied: 5,
                classes: Vec::new(),
            },
            peer: Some(PeerRun {
                points: 10,
                insert_secs: 0.5,
                nodes: 120,
                leaves: 100,
                inner_nodes: 20,
                leaves_built: 110,
                memory_bytes: 2000,
                occupied_leaves: 7,
                access_secs: 0.002,
                peak_rss_kib: Some(4096),
                classes: String::new(),
            }),
            agreement: Some((0.9, 0.95)),
        }
    }

    /// A data set with one run at r = 0.2 m, M = 8, beam-based, and the equal-value variant.
    fn set(name: &str, real: bool, leaves: usize, equal_leaves: usize) -> Value {
        let info = SetInfo {
            name: name.to_owned(),
            about: format!("about {name}"),
            points: 10,
            queries: 4,
            real,
            runs: vec![RunRecord {
                resolution_m: 0.2,
                endpoint: false,
                m: 8,
                compared: compared(leaves),
            }],
            variants: vec![VariantRecord {
                label: EQUAL_LABEL.to_owned(),
                fusion: true,
                fusion_rule: "equal".to_owned(),
                selection: "beam-samples".to_owned(),
                split_on_unclamp: false,
                fusion_interval_scans: 1,
                compared: compared(equal_leaves),
            }],
        };
        serde_json::to_value(SetResult {
            set: Some(info),
            octomap_unavailable: None,
            gap_note: (name == "urban").then(|| "GAP NOTE".to_owned()),
        })
        .unwrap()
    }

    /// The page from known measurements: an absent set left out, the real row in the
    /// headline table, the urban drive in the summary, the sums over scan.dat and urban.
    #[test]
    fn report_from_known_measurements() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = EvalContext::scratch(dir.path());
        let absent = serde_json::to_value(SetResult {
            set: None,
            octomap_unavailable: None,
            gap_note: None,
        })
        .unwrap();
        let results = vec![
            ("scan.dat".to_owned(), set("scan.dat", true, 70, 40)),
            ("kitti-00".to_owned(), absent),
            ("urban".to_owned(), set("urban", false, 90, 60)),
        ];
        let page = report(&ctx, &results).unwrap();
        let summary = &page.json["summary"];
        assert_eq!(summary["leaf_reduction_data"], "urban");
        let reduction = summary["leaf_reduction_vs_pruned_octomap_0_2m"].as_f64();
        assert!((reduction.unwrap() - 0.1).abs() < 1e-12, "{summary}");
        assert_eq!(summary["insertion_time_ratio_vs_octomap"], 0.5);
        assert_eq!(summary["bytes_ratio_vs_octomap"], 0.5);
        assert_eq!(summary["octomap_available"], true);
        let equal = summary["equal_value"]["leaf_reduction_vs_pruned_octomap_0_2m"].as_f64();
        assert!((equal.unwrap() - 0.4).abs() < 1e-12, "{summary}");
        assert_eq!(summary["real"].as_array().map(Vec::len), Some(1));
        assert_eq!(page.json["runs"].as_array().map(Vec::len), Some(2));
        let md = &page.markdown;
        assert!(md.contains("- `scan.dat`: about scan.dat\n- `urban`: about urban\n"));
        assert!(md.contains("GAP NOTE"), "{md}");
        let real = md.lines().find(|l| l.starts_with("| scan.dat ")).unwrap();
        assert!(real.contains("30.0 % / 60.0 %"), "{real}");
        let summary_row = md
            .lines()
            .find(|l| l.starts_with("| leaf reduction vs pruned OctoMap (urban)"))
            .unwrap();
        assert!(summary_row.contains("| 10.00 %"), "{summary_row}");
        let headline = page.headline.unwrap();
        assert!(headline.starts_with("Real scans (scan.dat;"), "{headline}");
    }
}
