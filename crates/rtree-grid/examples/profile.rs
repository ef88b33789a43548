//! Times the phases of scan insertion on a `.graph` file (development aid).
#![allow(missing_docs, clippy::unwrap_used)]
use std::time::Instant;

use raypath_rtree_grid::{FusionRule, GridConfig, RtreeGrid, Selection, SensorModel};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: profile <scans.graph> [resolution_m] [label filter]");
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
        for n in graph.nodes.iter().take(max_scans) {
            let u = grid.insert_cloud(&n.world_from_sensor, &n.points);
            keys += u.free_keys + u.occupied_keys;
            splits += u.splits;
        }
        grid.fuse_pending();
        let secs = t.elapsed().as_secs_f64();
        grid.shrink_to_fit();
        let s = grid.stats();
        println!(
            "{label}: {secs:.3} s, {keys} key updates, {} leaves, {} fused, {splits} splits, {} bytes",
            s.leaves, s.fused_leaves, s.bytes
        );
    }
}
