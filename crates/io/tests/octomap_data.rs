//! OctoMap readers and writers on the real sample files (RAYPATH_DATA/octomap).

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use raypath_io::data::require;
use raypath_io::octomap::{self, KEY_OFFSET, TREE_DEPTH};

#[test]
fn spherical_scan_graph_has_one_node_of_10201_points() {
    let Some(path) = require("octomap/spherical_scan.graph") else {
        return;
    };
    assert_eq!(std::fs::metadata(&path).unwrap().len(), 285_708);
    let graph = octomap::read_graph(&path).unwrap();
    assert_eq!(graph.nodes.len(), 1);
    assert_eq!(graph.edges.len(), 0);
    let node = &graph.nodes[0];
    assert_eq!(node.id, 0);
    assert_eq!(node.points.len(), 10201);
    // A spherical scan: all points at (nearly) the same distance from the sensor, which sits
    // at the pose's translation.
    let ranges: Vec<f64> = node
        .points
        .points
        .iter()
        .map(|p| p.cast::<f64>().coords.norm())
        .collect();
    let (lo, hi) = ranges.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| {
        (lo.min(r), hi.max(r))
    });
    assert!(lo > 0.0 && hi.is_finite(), "ranges {lo}..{hi}");

    // Writing it back gives the identical file.
    let original = std::fs::read(&path).unwrap();
    let mut written = Vec::new();
    octomap::write_graph(&mut written, &graph, "copy.graph".as_ref()).unwrap();
    assert_eq!(written.len(), original.len());
    assert!(
        written == original,
        "write(read(file)) differs from the file"
    );

    let summary = raypath_io::summarize(&path).unwrap();
    assert_eq!(summary.format, "octomap-graph");
    assert_eq!(summary.scans, Some(1));
    assert_eq!(summary.nodes, Some(1));
    assert_eq!(summary.poses, Some(1));
    assert_eq!(summary.points, Some(10201));
    assert_eq!(summary.extra["edges"], 0);
    assert!(summary.bbox.is_some());
}

#[test]
fn geb079_tree_matches_its_header_and_lattice() {
    let Some(path) = require("octomap/geb079.bt") else {
        return;
    };
    let tree = octomap::read_bt(&path).unwrap();
    assert_eq!(tree.id, "OcTree");
    assert_eq!(tree.resolution_m, 0.08);
    assert_eq!(tree.nodes_in_file, 532_566);
    // Every node is the root, an inner node or a leaf.
    assert_eq!(
        tree.inner_nodes + tree.leaves.len() as u64,
        tree.nodes_in_file
    );
    let occupied = tree.occupied_leaves();
    let free = tree.free_leaves();
    assert!(
        occupied > 10_000 && free > 10_000,
        "{occupied} occupied, {free} free"
    );

    let res = tree.resolution_m;
    for leaf in &tree.leaves {
        assert!((1..=TREE_DEPTH).contains(&leaf.depth));
        let span_keys = f64::from(1u32 << (TREE_DEPTH - leaf.depth));
        assert_eq!(leaf.size_m, res * span_keys);
        for axis in 0..3 {
            // The centre lies on the lattice of its depth: (key_min − 32768 + span/2) · res.
            let key = f64::from(leaf.key_min[axis]);
            let expected = (key - f64::from(KEY_OFFSET) + span_keys / 2.0) * res;
            assert!((leaf.center[axis] - expected).abs() < 1e-9);
            assert_eq!(key % span_keys, 0.0, "key not aligned to its depth");
            let cells = leaf.center[axis] / res - span_keys / 2.0;
            assert!((cells - cells.round()).abs() < 1e-6);
        }
    }
    // Leaves never overlap: their volumes add up to at most the bounding box volume, and the
    // occupied part is a building of plausible size (tens of metres, a few floors high).
    let bbox = tree.bounding_box(true);
    let extent = bbox.extents();
    assert!(extent.x > 10.0 && extent.x < 200.0, "{extent:?}");
    assert!(extent.y > 10.0 && extent.y < 200.0, "{extent:?}");
    assert!(extent.z > 2.0 && extent.z < 30.0, "{extent:?}");
    let all = tree.bounding_box(false);
    let volume: f64 = tree.leaves.iter().map(|l| l.size_m.powi(3)).sum();
    let e = all.extents();
    assert!(volume <= e.x * e.y * e.z + 1e-6);

    // Writing the tree back reproduces the file byte for byte (OctoMap's own header).
    let original = std::fs::read(&path).unwrap();
    let mut written = Vec::new();
    octomap::write_bt(&mut written, &tree, "copy.bt".as_ref()).unwrap();
    let first_diff = written.iter().zip(&original).position(|(a, b)| a != b);
    assert!(
        written == original,
        "write(read(geb079.bt)) differs from the file: lengths {} vs {}, first difference at {first_diff:?}",
        written.len(),
        original.len()
    );

    let summary = raypath_io::summarize(&path).unwrap();
    assert_eq!(summary.format, "octomap-bt");
    assert_eq!(summary.nodes, Some(532_566));
    assert_eq!(summary.extra["resolution"], 0.08);
    assert_eq!(summary.extra["leaves"], tree.leaves.len() as u64);
    assert_eq!(summary.extra["occupied_leaves"], occupied as u64);
    assert_eq!(summary.extra["free_leaves"], free as u64);
    let b = summary.bbox.unwrap();
    assert_eq!(b.min, [bbox.min.x, bbox.min.y, bbox.min.z]);
    eprintln!(
        "geb079: {} inner, {occupied} occupied, {free} free leaves; occupied bbox {:?}..{:?}",
        tree.inner_nodes, b.min, b.max
    );
}
