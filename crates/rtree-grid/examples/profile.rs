//! Times scan insertion on a `.graph` file and prints the map's sizes and a digest of its
//! leaves (development aid).
#![allow(missing_docs, clippy::unwrap_used)]
use std::time::Instant;

use raypath_rtree_grid::{FusionRule, GridConfig, RtreeGrid, Selection, SensorModel};

/// An order-independent digest of the leaf set (boxes and probabilities): equal digests
/// mean equal maps.
fn leaf_digest(grid: &RtreeGrid) -> u64 {
    let mut leaves: Vec<([u16; 6], u64)> = grid
        .cuboids()
        .iter()
        .map(|c| {
            let (lo, hi) = (c.keys.lo, c.keys.hi);
            (
                [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]],
                c.probability.to_bits(),
            )
        })
        .collect();
    leaves.sort_unstable();
    leaves.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, (k, p)| {
        let mut h = h;
        for v in k.iter().map(|&v| u64::from(v)).chain([*p]) {
            h = (h ^ v).wrapping_mul(0x0100_0000_01b3);
        }
        h
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!(
            "usage: profile <scans.graph> [resolution_m] [label filter] [max scans] [fusion interval] [batch]"
        );
        std::process::exit(2);
    };
    let graph = match raypath_io::octomap::read_graph(std::path::Path::new(path)) {
        Ok(graph) => graph,
        Err(error) => {
            eprintln!("error: {error}");
            std::process::exit(2);
        }
    };
    let r: f64 = args.get(2).map_or(0.2, |s| s.parse().unwrap());
    let only: Option<&str> = args.get(3).map(String::as_str);
    let max_scans: usize = args.get(4).map_or(usize::MAX, |s| s.parse().unwrap());
    let interval: u32 = args.get(5).map_or(1, |s| s.parse().unwrap());
    let batch = args.get(6).is_some_and(|s| s == "batch");
    for (label, fusion, model, rule, selection) in [
        (
            "beam, clamped",
            true,
            SensorModel::BeamBased,
            FusionRule::Clamped,
            None,
        ),
        (
            "beam, no fusion",
            false,
            SensorModel::BeamBased,
            FusionRule::Clamped,
            None,
        ),
        (
            "beam, equal",
            true,
            SensorModel::BeamBased,
            FusionRule::EqualValue,
            None,
        ),
        (
            "beam, equal, updated",
            true,
            SensorModel::BeamBased,
            FusionRule::EqualValue,
            Some(Selection::UpdatedCells),
        ),
        (
            "endpoint, clamped",
            true,
            SensorModel::BeamEndPoint,
            FusionRule::Clamped,
            None,
        ),
        (
            "endpoint, equal",
            true,
            SensorModel::BeamEndPoint,
            FusionRule::EqualValue,
            None,
        ),
    ] {
        let skip = |o: &str| match o.strip_prefix('=') {
            Some(exact) => label != exact,
            None => !label.contains(o),
        };
        if only.is_some_and(skip) {
            continue;
        }
        let mut config = GridConfig::with(r, 8, model);
        config.fusion = fusion;
        config.fusion_rule = rule;
        config.fusion_interval_scans = interval;
        if let Some(selection) = selection {
            config.selection = selection;
        }
        let mut grid = RtreeGrid::new(config).unwrap();
        let t = Instant::now();
        let mut keys = 0;
        let mut splits = 0;
        if batch {
            let scans = graph.nodes.iter().take(max_scans);
            let u = grid.insert_clouds(scans.map(|n| (&n.world_from_sensor, &n.points)));
            keys += u.free_keys + u.occupied_keys;
            splits += u.splits;
        } else {
            for n in graph.nodes.iter().take(max_scans) {
                let u = grid.insert_cloud(&n.world_from_sensor, &n.points);
                keys += u.free_keys + u.occupied_keys;
                splits += u.splits;
            }
            grid.fuse_pending();
        }
        let secs = t.elapsed().as_secs_f64();
        let working_bytes = grid.memory_bytes();
        grid.shrink_to_fit();
        let s = grid.stats();
        println!(
            "{label}: {secs:.3} s, {keys} key updates, {} leaves, {} fused, {splits} splits, {} nodes, {} bytes ({working_bytes} before shrink_to_fit), {} base cubes, leaf digest {:016x}",
            s.leaves,
            s.fused_leaves,
            s.nodes,
            s.bytes,
            s.base_cubes,
            leaf_digest(&grid)
        );
    }
}
