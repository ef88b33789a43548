//! Runs SLAM on a raw CARMEN log (or a rosbag2 bag) and, given the corrected log, prints the
//! relation errors of Kümmerle et al. (2009).
//!
//! ```text
//! cargo run --release -p raypath-slam --example slam_log -- RAW.clf [CORRECTED.log] [--no-loops]
//! ```

use std::path::PathBuf;
use std::time::Instant;

use raypath_geometry::Pose2;
use raypath_io::sequence::{PlanarOptions, pair_reference, read_planar};
use raypath_slam::benchmark::{
    RefineConfig, consecutive_relations, explicit_relation_errors, random_relations,
    refine_relations, relation_errors,
};
use raypath_slam::{Slam, SlamConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let no_loops = args.iter().any(|a| a == "--no-loops");
    let files: Vec<PathBuf> = args
        .iter()
        .filter(|a| !a.starts_with("--"))
        .map(PathBuf::from)
        .collect();
    let Some(raw) = files.first() else {
        eprintln!("usage: slam_log RAW [CORRECTED] [--no-loops]");
        return Ok(());
    };
    let options = PlanarOptions::default();
    let mut frames = read_planar(raw, &options)?;
    if let Some(corrected) = files.get(1) {
        let reference = read_planar(corrected, &options)?;
        let paired = pair_reference(&mut frames, &reference);
        eprintln!(
            "{paired} of {} scans paired with the reference",
            frames.len()
        );
    }
    let mut config = SlamConfig::default();
    if no_loops {
        config.loops = None;
    }
    // Quick knobs for experiments: SLAM_RES, SLAM_SEQ (σ_t of sequential edges), SLAM_LOOP
    // (σ_t of loop edges), SLAM_EVERY (loop search every n nodes), SLAM_NODES (per submap),
    // SLAM_ITER (finest-level iterations), SLAM_LEVELS, SLAM_FREE / SLAM_OCC (update factors),
    // SLAM_NODE_DIST (node spacing), SLAM_RANGE (max range); SLAM_WRITE_RELATIONS=FILE writes
    // the consecutive reference relations as a benchmark relation file; SLAM_AMBIG (rotation
    // ambiguity ratio, 0 = off), SLAM_AMBIG_DEG, SLAM_AMBIG_SHIFT (translation ambiguity, m).
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    if let Some(r) = env("SLAM_RES") {
        config.matcher.map.finest_resolution_m = r;
    }
    if let Some(s) = env("SLAM_SEQ") {
        config.sequential_sigma = [s, s, s / 2.0];
    }
    if let Some(s) = env("SLAM_LOOP") {
        config.loop_sigma = [s, s, s / 2.0];
    }
    if let (Some(e), Some(l)) = (env("SLAM_EVERY"), config.loops.as_mut()) {
        l.every_nodes = e as usize;
    }
    if let Some(g) = env("SLAM_GAIN") {
        config.submaps.rotation_min_gain = g;
    }
    if let Some(w) = env("SLAM_ROT") {
        config.submaps.rotation_window_rad = w;
    }
    if env("SLAM_NO_INTRA").is_some() {
        config.intra_submap_edges = false;
    }
    if let Some(w) = env("SLAM_REJECT") {
        config.reject_weight = w;
    }
    if let Some(s) = env("SLAM_ODO") {
        config.matcher.odometry_sigma = Some([s, s, env("SLAM_ODO_ROT").unwrap_or(s / 2.0)]);
    }
    if let Some(n) = env("SLAM_NODES") {
        config.submaps.nodes_per_submap = n as usize;
    }
    if let Some(n) = env("SLAM_ITER") {
        config.matcher.iterations_finest = n as usize;
    }
    if let Some(n) = env("SLAM_LEVELS") {
        config.matcher.map.levels = n as usize;
    }
    if let Some(f) = env("SLAM_FREE") {
        config.matcher.map.update_factor_free = f;
    }
    if let Some(f) = env("SLAM_OCC") {
        config.matcher.map.update_factor_occupied = f;
    }
    if let Some(d) = env("SLAM_NODE_DIST") {
        config.submaps.node_distance_m = d;
    }
    if let (Some(m), Some(l)) = (env("SLAM_MIN_SCORE"), config.loops.as_mut()) {
        l.correlative.min_score = m;
    }
    if let (Some(w), Some(l)) = (env("SLAM_WINDOW"), config.loops.as_mut()) {
        l.max_linear_window_m = w;
        l.linear_window_m = w.min(l.linear_window_m);
    }
    if let (Some(g), Some(l)) = (env("SLAM_GROWTH"), config.loops.as_mut()) {
        l.radius_growth = g;
    }
    if let Some(r) = env("SLAM_RANGE") {
        config.filter.max_range_m = r;
    }
    if let (Some(r), Some(l)) = (env("SLAM_AMBIG"), config.loops.as_mut()) {
        l.ambiguity_ratio = (r > 0.0).then_some(r);
        if let Some(d) = env("SLAM_AMBIG_DEG") {
            l.ambiguity_min_angle_rad = d.to_radians();
        }
    }
    if let (Some(d), Some(l)) = (env("SLAM_AMBIG_SHIFT"), config.loops.as_mut()) {
        l.ambiguity_min_shift_m = (d > 0.0).then_some(d);
    }
    let t0 = Instant::now();
    let mut slam = Slam::new(config)?;
    for f in &frames {
        slam.process(f)?;
    }
    let out = slam.finish()?;
    if let Ok(path) = std::env::var("SLAM_TRAJ") {
        let lines: Vec<String> = out
            .world_from_sensor
            .iter()
            .zip(&frames)
            .map(|(p, f)| {
                let o = f.world_from_laser;
                format!(
                    "{} {} {} {} {} {}",
                    p.x(),
                    p.y(),
                    p.theta(),
                    o.x(),
                    o.y(),
                    o.theta()
                )
            })
            .collect();
        std::fs::write(path, lines.join("\n"))?;
    }
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "{} scans, {} nodes, {} submaps, {} loop closures ({} rejected) in {secs:.2} s ({:.0} scans/s)",
        out.scans.len(),
        out.nodes.len(),
        out.submaps.len(),
        out.loop_closures.len(),
        out.rejected_loop_closures.len(),
        out.scans.len() as f64 / secs
    );
    println!("{:?}", out.stats);
    let reference: Vec<_> = frames.iter().map(|f| f.reference).collect();
    let referenced: Vec<usize> = (0..frames.len())
        .filter(|&i| reference[i].is_some())
        .collect();
    if let (Ok(path), false) = (std::env::var("SLAM_WRITE_RELATIONS"), referenced.is_empty()) {
        // The consecutive relations in the SLAM benchmark's file format.
        let stamps: Vec<_> = frames.iter().map(|f| f.ipc_stamp_secs).collect();
        let relations = raypath_slam::benchmark::relations_from_reference(
            &stamps,
            &reference,
            &consecutive_relations(&referenced),
        );
        raypath_io::relations::write_relations(std::path::Path::new(&path), &relations)?;
    }
    if !referenced.is_empty() {
        let c = relation_errors(
            &reference,
            &out.world_from_sensor,
            &consecutive_relations(&referenced),
        );
        let r = relation_errors(
            &reference,
            &out.world_from_sensor,
            &random_relations(&referenced, 1000, 1),
        );
        let odo: Vec<_> = frames.iter().map(|f| f.world_from_laser).collect();
        let o = relation_errors(&reference, &odo, &consecutive_relations(&referenced));
        println!("consecutive: {c:?}\nrandom: {r:?}\nodometry consecutive: {o:?}");
        {
            let scans: Vec<_> = frames.iter().map(|f| &f.scan).collect();
            let started = Instant::now();
            let refined = refine_relations(
                &scans,
                &reference,
                &consecutive_relations(&referenced),
                &RefineConfig::default(),
            )?;
            let (moved, _) = refined.correction_m();
            println!(
                "scan-refined: {:?} in {:.1} s; kept {}, reference moved {moved:.4} m on average, dropped {:?}",
                explicit_relation_errors(&out.world_from_sensor, &refined.relations),
                started.elapsed().as_secs_f64(),
                refined.relations.len(),
                refined.dropped
            );
            println!(
                "odometry scan-refined: {:?}",
                explicit_relation_errors(&odo, &refined.relations)
            );
        }
        {
            let (mut t, _) = raypath_reflectivity::benchmark::relation_error_lists(
                |i| reference.get(i).and_then(Option::as_ref),
                &out.world_from_sensor,
                &consecutive_relations(&referenced),
            );
            t.sort_by(f64::total_cmp);
            let q = |p: f64| t[((t.len() - 1) as f64 * p).round() as usize];
            println!(
                "consecutive translation quantiles: 10 % {:.4}, 25 % {:.4}, 50 % {:.4}, 75 % {:.4}, 90 % {:.4}, 99 % {:.4}",
                q(0.1),
                q(0.25),
                q(0.5),
                q(0.75),
                q(0.9),
                q(0.99)
            );
        }
        if std::env::var("SLAM_WORST").is_ok() {
            for (i, j) in consecutive_relations(&referenced) {
                let (gi, gj) = (
                    reference[i].unwrap_or_default(),
                    reference[j].unwrap_or_default(),
                );
                let (ei, ej) = (out.world_from_sensor[i], out.world_from_sensor[j]);
                let e = (gi.inverse() * gj).inverse() * (ei.inverse() * ej);
                if e.translation().norm() > 0.2 || e.theta().abs() > 0.05 {
                    let odo = (frames[i].world_from_laser.inverse() * frames[j].world_from_laser)
                        .inverse()
                        * (gi.inverse() * gj);
                    println!(
                        "relation {i}-{j}: error {:.3} m {:.1}°, odometry error {:.3} m {:.1}°, ref step {:.2} m {:.1}°",
                        e.translation().norm(),
                        e.theta().to_degrees(),
                        odo.translation().norm(),
                        odo.theta().to_degrees(),
                        (gi.inverse() * gj).translation().norm(),
                        (gi.inverse() * gj).theta().to_degrees()
                    );
                }
            }
        }
        let all_scans: Vec<_> = frames.iter().map(|f| &f.scan).collect();
        let (checked, wrong, checks) = raypath_slam::benchmark::check_loops(
            &out,
            &all_scans,
            &reference,
            50,
            raypath_slam::benchmark::LoopPairing::Overlap,
        );
        let (_, wrong_nearest, _) = raypath_slam::benchmark::check_loops(
            &out,
            &all_scans,
            &reference,
            50,
            raypath_slam::benchmark::LoopPairing::Nearest,
        );
        println!("loop closures against the nearest node: {wrong_nearest} wrong");
        println!("loop stats: {:?}", out.stats.loops);
        println!("loop closures: {wrong} of {checked} checked wrong");
        for cut in [0.3, 0.5, 0.7] {
            let low = |wrong: bool| {
                checks
                    .iter()
                    .filter(|k| k.is_wrong() == wrong)
                    .filter(|k| out.graph.edge_weight(out.loop_closures[k.closure].edge) < cut)
                    .count()
            };
            println!("weight < {cut}: {} right, {} wrong", low(false), low(true));
        }
        if std::env::var("SLAM_LOOPS").is_ok() {
            let scans: Vec<_> = frames.iter().map(|f| &f.scan).collect();
            for k in checks.iter().filter(|k| k.is_wrong()) {
                let c = &out.loop_closures[k.closure];
                let (a, b) = (scans[k.near_scan], scans[k.scan]);
                let share = |p| raypath_slam::benchmark::support_share(a, b, p).unwrap_or(0.0);
                println!(
                    "loop {}->{} {:?} score {:.3} error {:.3} m {:.2}° weight {:.3} chi2 {:.1} \
                     support measured {:.2} reference {:.2}, reference disputed: {}",
                    k.near_scan,
                    k.scan,
                    c.source,
                    c.score,
                    k.trans_m,
                    k.rot_rad.to_degrees(),
                    out.graph.edge_weight(c.edge),
                    out.graph.edge_chi2(c.edge),
                    share(&k.measured),
                    share(&k.reference()),
                    k.reference_disputed(&scans, &reference),
                );
                let support = |i: usize, pose: &Pose2| {
                    raypath_slam::benchmark::reference_support(&scans, &reference, i, pose)
                        .unwrap_or(f64::NAN)
                };
                let gap = |i: usize| {
                    (0..=50)
                        .find(|d| {
                            [i.saturating_sub(*d), i + d]
                                .iter()
                                .any(|&m| reference.get(m).copied().flatten().is_some())
                        })
                        .unwrap_or(99)
                };
                let loop_scan = k.reference_near * k.measured;
                let loop_near = k.reference_scan * k.measured.inverse();
                println!(
                    "    map support: near {} (gap {}) at reference {:.2}, at loop {:.2}; \
                     scan {} (gap {}) at reference {:.2}, at loop {:.2}",
                    k.near_scan,
                    gap(k.near_scan),
                    support(k.near_scan, &k.reference_near),
                    support(k.near_scan, &loop_near),
                    k.scan,
                    gap(k.scan),
                    support(k.scan, &k.reference_scan),
                    support(k.scan, &loop_scan),
                );
            }
        }
        let refs: Vec<_> = referenced.iter().filter_map(|&i| reference[i]).collect();
        let est: Vec<_> = referenced
            .iter()
            .map(|&i| out.world_from_sensor[i])
            .collect();
        let a = raypath_reflectivity::benchmark::aligned_errors(&refs, &est);
        println!("aligned: {a:?}");
    }
    Ok(())
}
