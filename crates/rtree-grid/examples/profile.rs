//! Times the phases of scan insertion on a `.graph` file (development aid).
#![allow(missing_docs, clippy::unwrap_used)]
use std::time::Instant;

use raypath_rtree_grid::{GridConfig, RtreeGrid, SensorModel};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: profile <scans.graph> [resolution_m]");
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
    for (label, fusion, model) in [
        ("beam, fusion", true, SensorModel::BeamBased),
        ("beam, no fusion", false, SensorModel::BeamBased),
        ("endpoint, fusion", true, SensorModel::BeamEndPoint),
    ] {
        let mut config = GridConfig::with(r, 8, model);
        config.fusion = fusion;
        let mut grid = RtreeGrid::new(config).unwrap();
        let t = Instant::now();
        let mut keys = 0;
        for n in &graph.nodes {
            let u = grid.insert_cloud(&n.world_from_sensor, &n.points);
            keys += u.free_keys + u.occupied_keys;
        }
        let s = grid.stats();
        println!(
            "{label}: {:.3} s, {keys} key updates, {} leaves, {} fused",
            t.elapsed().as_secs_f64(),
            s.leaves,
            s.fused_leaves
        );
    }
}
