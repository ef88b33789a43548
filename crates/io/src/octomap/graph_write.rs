//! Writing OctoMap ScanGraph files (`.graph`), in the layout described in the reader
//! ([`super::ScanGraphReader`]), readable by OctoMap's `ScanGraph::readBinary`.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use raypath_geometry::Pose3;

use super::graph::ScanGraph;
use crate::{Error, Location, Result};

/// Writes `graph` to a file (uncompressed).
pub fn write_graph_file(path: &Path, graph: &ScanGraph) -> Result<()> {
    let file = File::create(path).map_err(|e| Error::io(path, Location::File, e))?;
    let mut writer = BufWriter::new(file);
    write_graph(&mut writer, graph, path)?;
    writer
        .flush()
        .map_err(|e| Error::io(path, Location::File, e))
}

/// Writes `graph` to `writer`; `name` is used in errors.
///
/// Fails (before writing anything) when a count does not fit in the format's `u32`, a point or
/// pose is not finite, node ids repeat, or an edge names a node that is not in the graph, so
/// everything written reads back with [`super::read_graph`].
pub fn write_graph<W: Write>(writer: W, graph: &ScanGraph, name: &Path) -> Result<()> {
    check(graph, name)?;
    let mut out = Out {
        writer,
        name,
        offset: 0,
    };
    out.u32(graph.nodes.len() as u32)?;
    for node in &graph.nodes {
        out.u32(node.points.len() as u32)?;
        for p in &node.points.points {
            out.vec3([f64::from(p.x), f64::from(p.y), f64::from(p.z)])?;
        }
        out.pose(&node.world_from_sensor)?;
        out.u32(node.id)?;
    }
    out.u32(graph.edges.len() as u32)?;
    for edge in &graph.edges {
        out.u32(edge.first_id)?;
        out.u32(edge.second_id)?;
        out.pose(&edge.first_from_second)?;
        out.bytes(&edge.weight.to_le_bytes())?;
    }
    Ok(())
}

fn check(graph: &ScanGraph, name: &Path) -> Result<()> {
    let unwritable = |reason: String| Error::Unwritable {
        path: name.to_path_buf(),
        reason,
    };
    if u32::try_from(graph.nodes.len()).is_err() || u32::try_from(graph.edges.len()).is_err() {
        return Err(unwritable("more than 2^32 − 1 nodes or edges".into()));
    }
    let mut ids = std::collections::HashSet::new();
    for node in &graph.nodes {
        if !ids.insert(node.id) {
            return Err(unwritable(format!("node id {} appears twice", node.id)));
        }
        if u32::try_from(node.points.len()).is_err() {
            return Err(unwritable(format!("node {} has too many points", node.id)));
        }
        if let Some(i) = (0..node.points.len()).find(|&i| !node.points.is_valid(i)) {
            return Err(unwritable(format!(
                "node {}: point {i} is not finite (drop missing points of organized clouds first)",
                node.id
            )));
        }
        if !node.world_from_sensor.is_finite() {
            return Err(unwritable(format!("node {}: pose is not finite", node.id)));
        }
    }
    for (i, edge) in graph.edges.iter().enumerate() {
        if !ids.contains(&edge.first_id) || !ids.contains(&edge.second_id) {
            return Err(unwritable(format!(
                "edge {i} connects {} and {}, which are not both nodes of the graph",
                edge.first_id, edge.second_id
            )));
        }
        if !edge.first_from_second.is_finite() || !edge.weight.is_finite() {
            return Err(unwritable(format!(
                "edge {i}: constraint or weight not finite"
            )));
        }
    }
    Ok(())
}

struct Out<'a, W> {
    writer: W,
    name: &'a Path,
    offset: u64,
}

impl<W: Write> Out<'_, W> {
    fn bytes(&mut self, bytes: &[u8]) -> Result<()> {
        self.writer
            .write_all(bytes)
            .map_err(|e| Error::io(self.name, Location::Byte(self.offset), e))?;
        self.offset += bytes.len() as u64;
        Ok(())
    }

    fn u32(&mut self, value: u32) -> Result<()> {
        self.bytes(&value.to_le_bytes())
    }

    fn values<const N: usize>(&mut self, values: [f64; N]) -> Result<()> {
        let mut buf = [0u8; 36];
        buf[..4].copy_from_slice(&(N as i32).to_le_bytes());
        for (chunk, v) in buf[4..4 + 8 * N].chunks_exact_mut(8).zip(values) {
            chunk.copy_from_slice(&v.to_le_bytes());
        }
        self.bytes(&buf[..4 + 8 * N])
    }

    fn vec3(&mut self, v: [f64; 3]) -> Result<()> {
        self.values(v)
    }

    fn pose(&mut self, pose: &Pose3) -> Result<()> {
        let t = pose.translation();
        self.vec3([t.x, t.y, t.z])?;
        let q = pose.rotation();
        self.values([q.w, q.i, q.j, q.k])
    }
}
