//! OctoMap files: binary occupancy trees (`.bt`) and scan graphs (`.graph`).
//!
//! Both formats come from the OctoMap library (Hornung et al., "OctoMap: an efficient
//! probabilistic 3D mapping framework based on octrees", Autonomous Robots 2013;
//! <https://github.com/OctoMap/octomap>, BSD licence). The layouts below follow its sources:
//! `ScanGraph.cpp`, `Pointcloud.cpp`, `math/{Vector3,Quaternion,Pose6D}.cpp` for `.graph` and
//! `AbstractOcTree.cpp`, `AbstractOccupancyOcTree.cpp`, `OccupancyOcTreeBase.hxx`
//! (`readBinaryNode`/`writeBinaryNode`) and `OcTreeKey.h` for `.bt`.
//!
//! * [`ScanGraph`] (read and write): 3-D scans in their sensor frame, each with the pose
//!   `world_from_sensor` it was taken from, and optional edges between scans. Read all at once
//!   with [`read_graph`] or node by node with [`ScanGraphReader`]; write with [`write_graph`].
//! * [`OcTree`] (read and write): the maximum-likelihood occupancy of every leaf of the tree
//!   (occupied or free; unknown space has no leaf), with the leaf's centre and edge length.
//!   Read all leaves with [`read_bt`] or stream them with [`BtReader`]; write with
//!   [`write_bt`].
//!
//! Frames and units are OctoMap's: metres, the map frame of whoever built the map (OctoMap
//! data sets use x forward, y left, z up as REP-103 does).

mod bt;
mod bt_write;
mod graph;
mod graph_write;

use std::path::Path;

use raypath_geometry::Aabb3;

use crate::summary::{BoundingBox, Summary};
use crate::{Format, Result};

pub use bt::{BtHeader, BtReader, KEY_OFFSET, OcTree, OctreeLeaf, TREE_DEPTH, parse_bt, read_bt};
pub use bt_write::{write_bt, write_bt_file};
pub use graph::{ScanEdge, ScanGraph, ScanGraphReader, ScanNode, parse_graph, read_graph};
pub use graph_write::{write_graph, write_graph_file};

/// Summarizes a `.bt` file: `nodes` (tree nodes, as in the header), `bbox` of the occupied
/// leaves, and extra `resolution` (metres), `tree_type`, `inner_nodes`, `leaves`,
/// `occupied_leaves`, `free_leaves`, `known_bbox` (all leaves, free or occupied).
pub fn summarize_bt(path: &Path) -> Result<Summary> {
    let mut reader = BtReader::open(path)?;
    let (mut occupied, mut free) = (0u64, 0u64);
    let (mut occupied_box, mut known_box) = (Aabb3::empty(), Aabb3::empty());
    for leaf in &mut reader {
        let leaf = leaf?;
        let (lo, hi) = leaf.corners();
        known_box.extend(&lo);
        known_box.extend(&hi);
        if leaf.occupied {
            occupied += 1;
            occupied_box.extend(&lo);
            occupied_box.extend(&hi);
        } else {
            free += 1;
        }
    }
    let header = reader.header().clone();
    let mut summary = Summary::new(Format::OctomapBt.name())
        .with_extra("resolution", header.resolution_m)
        .with_extra("tree_type", header.id.clone())
        .with_extra("inner_nodes", reader.inner_nodes())
        .with_extra("leaves", occupied + free)
        .with_extra("occupied_leaves", occupied)
        .with_extra("free_leaves", free);
    if let Some(known) = BoundingBox::from_aabb(&known_box) {
        summary = summary.with_extra(
            "known_bbox",
            serde_json::json!({ "min": known.min, "max": known.max }),
        );
    }
    summary.nodes = Some(header.size);
    summary.bbox = BoundingBox::from_aabb(&occupied_box);
    Ok(summary)
}

/// Summarizes a `.graph` file: `scans` and `nodes` (graph nodes), `poses` (one per node),
/// `points` (all scans), `bbox` of all points in the world frame, and extra `edges`.
pub fn summarize_graph(path: &Path) -> Result<Summary> {
    let mut reader = ScanGraphReader::open(path)?;
    let (mut nodes, mut points) = (0u64, 0u64);
    let mut bbox = Aabb3::empty();
    for node in &mut reader {
        let node = node?;
        nodes += 1;
        points += node.points.len() as u64;
        for p in &node.points.points {
            bbox.extend(&node.world_from_sensor.transform_point(&p.cast::<f64>()));
        }
    }
    let edges = reader.read_edges()?;
    let mut summary =
        Summary::new(Format::OctomapGraph.name()).with_extra("edges", edges.len() as u64);
    summary.scans = Some(nodes);
    summary.nodes = Some(nodes);
    summary.poses = Some(nodes);
    summary.points = Some(points);
    summary.bbox = BoundingBox::from_aabb(&bbox);
    Ok(summary)
}
