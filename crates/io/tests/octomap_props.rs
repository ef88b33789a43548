//! OctoMap `.graph` and `.bt`: round trips, error places, and no panic on any input.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use nalgebra::{Point3, Vector3};
use proptest::prelude::*;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::octomap::{
    self, OcTree, OctreeLeaf, ScanEdge, ScanGraph, ScanGraphReader, ScanNode, TREE_DEPTH,
};
use raypath_io::{Error, Location};

fn sample_graph() -> ScanGraph {
    let nodes = (0..3u32)
        .map(|id| {
            let points = (0..5 + id)
                .map(|i| Point3::new(i as f32 * 0.5, -(id as f32), 1.25 + i as f32))
                .collect();
            ScanNode {
                id,
                world_from_sensor: Pose3::from_xyz_rpy(
                    f64::from(id),
                    2.0,
                    0.5,
                    0.1,
                    -0.2,
                    0.3 * f64::from(id),
                ),
                points: PointCloud::from_points(points),
            }
        })
        .collect::<Vec<_>>();
    let edges = vec![ScanEdge {
        first_id: 0,
        second_id: 2,
        first_from_second: nodes[0].world_from_sensor.inverse() * nodes[2].world_from_sensor,
        weight: 1.0,
    }];
    ScanGraph { nodes, edges }
}

fn graph_bytes(graph: &ScanGraph) -> Vec<u8> {
    let mut bytes = Vec::new();
    octomap::write_graph(&mut bytes, graph, "g.graph".as_ref()).unwrap();
    bytes
}

#[test]
fn graph_round_trips() {
    let graph = sample_graph();
    let bytes = graph_bytes(&graph);
    // n + 3 nodes (points, two poses, id) + m + one edge.
    let points: u64 = graph.nodes.iter().map(|n| n.points.len() as u64).sum();
    assert_eq!(
        bytes.len() as u64,
        4 + points * 28 + 3 * (4 + 64 + 4) + 4 + 80
    );
    let read = octomap::parse_graph(&bytes, "g.graph").unwrap();
    assert_eq!(read.nodes.len(), 3);
    for (a, b) in read.nodes.iter().zip(&graph.nodes) {
        assert_eq!(a.id, b.id);
        assert_eq!(a.points, b.points);
        let d = a.world_from_sensor.inverse() * b.world_from_sensor;
        assert!(d.translation().norm() < 1e-12 && d.rotation().angle() < 1e-12);
    }
    assert_eq!(read.edges.len(), 1);
    assert_eq!((read.edges[0].first_id, read.edges[0].second_id), (0, 2));
    // Writing what was read gives the same bytes.
    assert_eq!(graph_bytes(&read), bytes);
}

#[test]
fn graph_streams_node_by_node() {
    let bytes = graph_bytes(&sample_graph());
    let mut reader = ScanGraphReader::new(&bytes[..], "g.graph", None).unwrap();
    assert_eq!(reader.num_nodes(), 3);
    let first = reader.next().unwrap().unwrap();
    assert_eq!(first.points.len(), 5);
    // Edges can be read without iterating the other nodes.
    let edges = reader.read_edges().unwrap();
    assert_eq!(edges.len(), 1);
}

#[test]
fn graph_errors_name_the_byte() {
    let bytes = graph_bytes(&sample_graph());
    // Every truncation is an error.
    for len in 0..bytes.len() {
        assert!(
            octomap::parse_graph(&bytes[..len], "g.graph").is_err(),
            "prefix {len}"
        );
    }
    // A point count larger than the file: refused before allocating.
    let mut huge = bytes.clone();
    huge[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
    let err = octomap::parse_graph(&huge, "g.graph").unwrap_err();
    assert_eq!(err.location(), Location::Byte(4));
    assert!(err.to_string().contains("point count"), "{err}");
    // A wrong dimension marker of the first point.
    let mut marker = bytes.clone();
    marker[8] = 4;
    let err = octomap::parse_graph(&marker, "g.graph").unwrap_err();
    assert_eq!(err.location(), Location::Byte(8));
    assert!(
        err.to_string()
            .starts_with("g.graph: byte 8: point: dimension marker is 4"),
        "{err}"
    );
    // Trailing garbage.
    let mut trailing = bytes.clone();
    trailing.push(0);
    assert!(octomap::parse_graph(&trailing, "g.graph").is_err());
    // An edge to a node that does not exist.
    let mut graph = sample_graph();
    graph.edges[0].second_id = 7;
    assert!(matches!(
        octomap::write_graph(Vec::new(), &graph, "g.graph".as_ref()),
        Err(Error::Unwritable { .. })
    ));
    let mut dangling = bytes.clone();
    let edge_at = bytes.len() - 80;
    dangling[edge_at + 4..edge_at + 8].copy_from_slice(&7u32.to_le_bytes());
    let err = octomap::parse_graph(&dangling, "g.graph").unwrap_err();
    assert_eq!(err.location(), Location::Byte(edge_at as u64));
}

#[test]
fn graph_writer_refuses_missing_points() {
    let mut graph = sample_graph();
    graph.nodes[1].points.points[2].x = f32::NAN;
    assert!(matches!(
        octomap::write_graph(Vec::new(), &graph, "g.graph".as_ref()),
        Err(Error::Unwritable { .. })
    ));
}

/// A tree of `n` random finest-level leaves plus a few coarse ones, via the writer.
fn sample_tree(seed: u64) -> OcTree {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut leaves: Vec<OctreeLeaf> = Vec::new();
    let mut taken = std::collections::HashSet::new();
    let res = 0.1;
    for i in 0..400 {
        // Coarse leaves in one octant, fine leaves in another, so they never overlap.
        let depth = if i % 10 == 0 { 12 } else { TREE_DEPTH };
        let span = 1u16 << (TREE_DEPTH - depth);
        let base: u16 = if depth == TREE_DEPTH { 32768 } else { 0 };
        let key = [0; 3].map(|_: u16| base + rng.random_range(0..64u16) * span);
        if !taken.insert((key, depth)) {
            continue;
        }
        let span_f = f64::from(span);
        let center = key.map(|k| (f64::from(k) - 32768.0 + span_f / 2.0) * res);
        leaves.push(OctreeLeaf {
            center: Point3::from(center),
            size_m: span_f * res,
            occupied: rng.random_bool(0.5),
            depth,
            key_min: key,
        });
    }
    OcTree {
        id: "OcTree".into(),
        resolution_m: res,
        nodes_in_file: 0,
        inner_nodes: 0,
        leaves,
    }
}

fn tree_bytes(tree: &OcTree) -> Vec<u8> {
    let mut bytes = Vec::new();
    octomap::write_bt(&mut bytes, tree, "t.bt".as_ref()).unwrap();
    bytes
}

fn sorted(mut leaves: Vec<OctreeLeaf>) -> Vec<OctreeLeaf> {
    leaves.sort_by_key(|l| (l.depth, l.key_min));
    leaves
}

#[test]
fn tree_round_trips() {
    let tree = sample_tree(7);
    let bytes = tree_bytes(&tree);
    let read = octomap::parse_bt(&bytes, "t.bt").unwrap();
    assert_eq!(read.resolution_m, 0.1);
    assert_eq!(
        read.inner_nodes + read.leaves.len() as u64,
        read.nodes_in_file
    );
    assert_eq!(sorted(read.leaves.clone()), sorted(tree.leaves.clone()));
    assert_eq!(tree_bytes(&read), bytes);
    // A leaf's key decides where it goes: key 32768 at depth 16 is the cell [0, res).
    let leaf = read.leaves.iter().find(|l| l.depth == TREE_DEPTH).unwrap();
    let lo = leaf.center - Vector3::repeat(leaf.size_m / 2.0);
    for axis in 0..3 {
        assert!((lo[axis] / 0.1 - (f64::from(leaf.key_min[axis]) - 32768.0)).abs() < 1e-9);
    }
}

#[test]
fn tree_bit_layout_matches_octomap() {
    // Root with child 0 free (bits 01), child 1 occupied (10), child 7 inner (11), whose
    // child 5 is occupied: 0b0000_1001 0b1100_0000, then 0b0000_0000 0b0000_1000.
    let mut bytes = b"# Octomap OcTree binary file\nid OcTree\nsize 5\nres 0.5\ndata\n".to_vec();
    bytes.extend_from_slice(&[0b0000_1001, 0b1100_0000, 0, 0b0000_1000]);
    let tree = octomap::parse_bt(&bytes, "t.bt").unwrap();
    assert_eq!(tree.inner_nodes, 2);
    let half = 0.5 * 32768.0;
    let l = &tree.leaves;
    assert_eq!(l.len(), 3);
    assert!(!l[0].occupied && l[0].depth == 1);
    assert_eq!(
        l[0].center,
        Point3::new(-half / 2.0, -half / 2.0, -half / 2.0)
    );
    assert!(l[1].occupied);
    assert_eq!(
        l[1].center,
        Point3::new(half / 2.0, -half / 2.0, -half / 2.0)
    );
    // Child 5 (x and z set) of child 7 (all set): the +x, −y, +z quarter of the + octant.
    assert!(l[2].occupied && l[2].depth == 2);
    assert_eq!(l[2].size_m, half / 2.0);
    assert_eq!(
        l[2].center,
        Point3::new(half * 0.75, half * 0.25, half * 0.75)
    );
    assert_eq!(tree_bytes(&tree), {
        let mut canonical = tree_bytes(&tree);
        canonical.truncate(canonical.len() - 4);
        canonical.extend_from_slice(&[0b0000_1001, 0b1100_0000, 0, 0b0000_1000]);
        canonical
    });
}

#[test]
fn tree_errors_name_the_place() {
    let head = "# Octomap OcTree binary file\nid OcTree\nsize 1\nres 0.5\ndata\n";
    let err = octomap::parse_bt(b"# Octomap OcTree file\nid OcTree\n", "t.ot").unwrap_err();
    assert!(err.to_string().contains(".ot"), "{err}");
    let err = octomap::parse_bt(
        b"# Octomap OcTree binary file\nid OcTree\nsize x\nres 0.5\ndata\n",
        "t.bt",
    )
    .unwrap_err();
    assert_eq!(err.location(), Location::Line(3));
    let err = octomap::parse_bt(
        b"# Octomap OcTree binary file\nid OcTree\nsize 1\nres -1\ndata\n\0\0",
        "t.bt",
    )
    .unwrap_err();
    assert_eq!(err.location(), Location::Line(4));
    // Header says 1 node, the root has a child.
    let mut bytes = head.as_bytes().to_vec();
    bytes.extend_from_slice(&[1, 0]);
    let err = octomap::parse_bt(&bytes, "t.bt").unwrap_err();
    assert!(err.to_string().contains("more nodes"), "{err}");
    // Trailing bytes after a complete tree.
    let mut bytes = head.as_bytes().to_vec();
    bytes.extend_from_slice(&[0, 0, 9]);
    let err = octomap::parse_bt(&bytes, "t.bt").unwrap_err();
    assert_eq!(err.location(), Location::Byte(head.len() as u64 + 2));
    // An inner node below depth 16: a chain of 16 "child 0 is inner" nodes.
    let mut bytes = b"# Octomap OcTree binary file\nid OcTree\nsize 100\nres 0.5\ndata\n".to_vec();
    for _ in 0..17 {
        bytes.extend_from_slice(&[3, 0]);
    }
    let err = octomap::parse_bt(&bytes, "t.bt").unwrap_err();
    assert!(err.to_string().contains("depth 16"), "{err}");
    // Truncated data.
    let full = tree_bytes(&sample_tree(3));
    for len in (0..full.len()).step_by(7) {
        assert!(
            octomap::parse_bt(&full[..len], "t.bt").is_err(),
            "prefix {len}"
        );
    }
}

/// Truncates `bytes` to `cut` (as a fraction) and overwrites a few bytes.
fn mutate(bytes: &[u8], cut: f64, edits: &[(usize, u8)]) -> Vec<u8> {
    let len = ((bytes.len() as f64) * cut) as usize;
    let mut out = bytes[..len.min(bytes.len())].to_vec();
    for &(at, value) in edits {
        if !out.is_empty() {
            let i = at % out.len();
            out[i] = value;
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn graph_reader_never_panics(
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<usize>(), any::<u8>()), 0..6),
    ) {
        let bytes = mutate(&graph_bytes(&sample_graph()), cut, &edits);
        let _ = octomap::parse_graph(&bytes, "g.graph");
        if let Ok(reader) = ScanGraphReader::new(&bytes[..], "g.graph", None) {
            for node in reader.take(10) {
                let _ = node;
            }
        }
    }

    #[test]
    fn tree_reader_never_panics(
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<usize>(), any::<u8>()), 0..6),
    ) {
        let bytes = mutate(&tree_bytes(&sample_tree(11)), cut, &edits);
        match octomap::parse_bt(&bytes, "t.bt") {
            Ok(tree) => prop_assert_eq!(tree.inner_nodes + tree.leaves.len() as u64, tree.nodes_in_file),
            Err(e) => prop_assert_eq!(e.path(), std::path::Path::new("t.bt")),
        }
    }
}
