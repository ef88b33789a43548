//! Reading OctoMap ScanGraph files (`.graph`).
//!
//! Layout (all little-endian; OctoMap `ScanGraph::readBinary`):
//!
//! ```text
//! u32 n_nodes
//! n_nodes × node:   Pointcloud { u32 n_points; n_points × vec3 }   (sensor frame, metres)
//!                   Pose6D     { vec3 translation; quat rotation }  (world_from_sensor)
//!                   u32 id
//! u32 n_edges
//! n_edges × edge:   u32 first_id, u32 second_id, Pose6D constraint (first_from_second),
//!                   f64 weight
//! vec3 = i32 3, then 3 × f64 x y z          (28 bytes)
//! quat = i32 4, then 4 × f64 w x y z        (36 bytes)
//! ```
//!
//! OctoMap keeps points and translations in `f32` (`point3d`) and widens them to `f64` in the
//! file; raypath keeps points in `f32` ([`PointCloud`]) and poses in `f64`, so files written by
//! OctoMap read and write back bit for bit.

use std::collections::HashSet;
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};

use nalgebra::{Point3, Quaternion, UnitQuaternion, Vector3};
use raypath_geometry::{PointCloud, Pose3};

use crate::Result;
use crate::source::{self, ByteReader};

/// Bytes of one point in the file (`i32` dimension + 3 × `f64`).
pub(super) const POINT_BYTES: u64 = 28;
/// Bytes of one edge in the file (2 × `u32`, a pose of 28 + 36 bytes, `f64` weight).
pub(super) const EDGE_BYTES: u64 = 80;
/// Largest deviation of a stored quaternion's norm from 1 that is accepted (OctoMap stores
/// unit quaternions, rounded to `f32` by some versions).
const QUATERNION_NORM_TOLERANCE: f64 = 1e-2;

/// One scan of a [`ScanGraph`].
#[derive(Clone, Debug, PartialEq)]
pub struct ScanNode {
    /// The node id (OctoMap numbers nodes 0, 1, … in insertion order).
    pub id: u32,
    /// Pose of the sensor in the world (map) frame when the scan was taken.
    pub world_from_sensor: Pose3,
    /// The scan's points in the sensor frame, metres (unorganized, no attributes).
    pub points: PointCloud,
}

/// An edge between two nodes of a [`ScanGraph`] (OctoMap `ScanEdge`).
#[derive(Clone, Debug, PartialEq)]
pub struct ScanEdge {
    /// Id of the first node.
    pub first_id: u32,
    /// Id of the second node.
    pub second_id: u32,
    /// The constraint: pose of the second node in the first node's frame
    /// (OctoMap computes it as `first.pose.inv() * second.pose`).
    pub first_from_second: Pose3,
    /// The edge weight (OctoMap's default is 1).
    pub weight: f64,
}

/// An OctoMap scan graph: scans with poses and edges between them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScanGraph {
    /// The scans, in file order.
    pub nodes: Vec<ScanNode>,
    /// The edges, in file order.
    pub edges: Vec<ScanEdge>,
}

impl ScanGraph {
    /// Total number of points over all scans.
    pub fn num_points(&self) -> usize {
        self.nodes.iter().map(|n| n.points.len()).sum()
    }
}

/// Reads a whole `.graph` file (plain or gzip/bzip2-compressed).
pub fn read_graph(path: &Path) -> Result<ScanGraph> {
    ScanGraphReader::open(path)?.read_all()
}

/// Parses a `.graph` file held in memory; `name` is used in errors.
pub fn parse_graph(bytes: &[u8], name: impl Into<PathBuf>) -> Result<ScanGraph> {
    ScanGraphReader::new(bytes, name, Some(bytes.len() as u64))?.read_all()
}

/// Reads a `.graph` file node by node, so graphs of hundreds of megabytes never sit in memory
/// whole. Iterate to get the nodes, then call [`ScanGraphReader::read_edges`].
///
/// ```no_run
/// use raypath_io::octomap::ScanGraphReader;
/// let mut reader = ScanGraphReader::open("fr_campus.graph".as_ref())?;
/// for node in &mut reader {
///     let node = node?;
///     println!("scan {}: {} points", node.id, node.points.len());
/// }
/// let edges = reader.read_edges()?;
/// # Ok::<(), raypath_io::Error>(())
/// ```
pub struct ScanGraphReader<R> {
    bytes: ByteReader<R>,
    /// Length of the (decompressed) input when known, to check counts before allocating.
    len: Option<u64>,
    num_nodes: u32,
    nodes_read: u32,
    ids: HashSet<u32>,
    failed: bool,
}

impl ScanGraphReader<Box<dyn BufRead + Send>> {
    /// Opens a `.graph` file (plain or compressed) and reads its node count.
    pub fn open(path: &Path) -> Result<Self> {
        let len = source::plain_len(path)?;
        Self::new(source::open(path)?, path, len)
    }
}

impl<R: BufRead> ScanGraphReader<R> {
    /// Reads from `reader`; `name` is used in errors and `len`, the number of bytes of the
    /// input when known, guards counts read from the file before anything is allocated.
    pub fn new(reader: R, name: impl Into<PathBuf>, len: Option<u64>) -> Result<Self> {
        let mut bytes = ByteReader::new(reader, name, 0);
        let num_nodes = bytes.read_u32_le("node count")?;
        // Each node holds at least a point count, a pose and an id.
        let min_node = 4 + 28 + 36 + 4;
        if let Some(len) = len
            && u64::from(num_nodes) * min_node > len
        {
            return Err(bytes.error_at(
                0,
                format!("node count {num_nodes} cannot fit in a file of {len} bytes"),
            ));
        }
        Ok(Self {
            bytes,
            len,
            num_nodes,
            nodes_read: 0,
            ids: HashSet::new(),
            failed: false,
        })
    }

    /// The number of nodes the file announces.
    pub fn num_nodes(&self) -> u32 {
        self.num_nodes
    }

    /// Reads the remaining nodes and the edges.
    pub fn read_all(mut self) -> Result<ScanGraph> {
        let mut nodes = Vec::new();
        for node in &mut self {
            nodes.push(node?);
        }
        let edges = self.read_edges()?;
        Ok(ScanGraph { nodes, edges })
    }

    /// Reads the edges. Nodes not yet read are read and dropped first. Fails when an edge
    /// names a node id that is not in the graph, or when bytes follow the last edge.
    pub fn read_edges(mut self) -> Result<Vec<ScanEdge>> {
        while self.nodes_read < self.num_nodes {
            self.read_node()?;
        }
        let start = self.bytes.offset();
        let n = self.bytes.read_u32_le("edge count")?;
        self.check_fits(start, u64::from(n), EDGE_BYTES, "edge count")?;
        let mut edges = Vec::with_capacity((n as usize).min(1 << 16));
        for _ in 0..n {
            let at = self.bytes.offset();
            let first_id = self.bytes.read_u32_le("edge first id")?;
            let second_id = self.bytes.read_u32_le("edge second id")?;
            for id in [first_id, second_id] {
                if !self.ids.contains(&id) {
                    return Err(self.bytes.error_at(
                        at,
                        format!("edge refers to node id {id}, which is not in the graph"),
                    ));
                }
            }
            let first_from_second = read_pose(&mut self.bytes, "edge constraint")?;
            let weight_at = self.bytes.offset();
            let weight = self.bytes.read_f64_le("edge weight")?;
            if !weight.is_finite() {
                return Err(self
                    .bytes
                    .error_at(weight_at, format!("edge weight is {weight}")));
            }
            edges.push(ScanEdge {
                first_id,
                second_id,
                first_from_second,
                weight,
            });
        }
        if !self.bytes.at_end()? {
            return Err(self
                .bytes
                .error("unexpected bytes after the last edge of the scan graph"));
        }
        Ok(edges)
    }

    fn check_fits(&self, start: u64, count: u64, bytes_each: u64, what: &str) -> Result<()> {
        if let Some(len) = self.len {
            let remaining = len.saturating_sub(self.bytes.offset());
            if count.saturating_mul(bytes_each) > remaining {
                return Err(self.bytes.error_at(
                    start,
                    format!(
                        "{what} {count} needs {} bytes but only {remaining} remain",
                        count.saturating_mul(bytes_each)
                    ),
                ));
            }
        }
        Ok(())
    }

    fn read_node(&mut self) -> Result<ScanNode> {
        let start = self.bytes.offset();
        let n = self.bytes.read_u32_le("point count")?;
        self.check_fits(start, u64::from(n), POINT_BYTES, "point count")?;
        // Grows with what is actually read, so a corrupt count in a compressed file (whose
        // length is unknown) fails at the end of the data instead of allocating up front.
        let mut points = Vec::with_capacity((n as usize).min(1 << 16));
        for _ in 0..n {
            let p = read_vec3(&mut self.bytes, "point")?;
            let p32 = p.cast::<f32>();
            if !p32.iter().all(|v| v.is_finite()) {
                let at = self.bytes.offset() - POINT_BYTES;
                return Err(self
                    .bytes
                    .error_at(at, format!("point {p:?} does not fit in 32-bit floats")));
            }
            points.push(Point3::from(p32));
        }
        let world_from_sensor = read_pose(&mut self.bytes, "scan pose")?;
        let id_at = self.bytes.offset();
        let id = self.bytes.read_u32_le("node id")?;
        if !self.ids.insert(id) {
            return Err(self
                .bytes
                .error_at(id_at, format!("node id {id} appears twice")));
        }
        self.nodes_read += 1;
        Ok(ScanNode {
            id,
            world_from_sensor,
            points: PointCloud::from_points(points),
        })
    }
}

impl<R: BufRead> Iterator for ScanGraphReader<R> {
    type Item = Result<ScanNode>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed || self.nodes_read >= self.num_nodes {
            return None;
        }
        let node = self.read_node();
        self.failed = node.is_err();
        Some(node)
    }
}

/// Reads the dimension marker `expected` (an `i32`) of a vector or quaternion.
fn read_marker<R: Read>(bytes: &mut ByteReader<R>, expected: i32, what: &str) -> Result<()> {
    let at = bytes.offset();
    let marker = bytes.read_i32_le(what)?;
    if marker != expected {
        return Err(bytes.error_at(
            at,
            format!("{what}: dimension marker is {marker}, expected {expected}"),
        ));
    }
    Ok(())
}

/// Reads `n` finite `f64` values after a dimension marker.
fn read_values<R: Read, const N: usize>(bytes: &mut ByteReader<R>, what: &str) -> Result<[f64; N]> {
    let start = bytes.offset();
    read_marker(bytes, N as i32, what)?;
    let mut buf = [0u8; 32];
    let raw = &mut buf[..N * 8];
    bytes.read_exact(raw, what)?;
    let mut values = [0.0; N];
    for (value, chunk) in values.iter_mut().zip(raw.chunks_exact(8)) {
        let mut b = [0u8; 8];
        b.copy_from_slice(chunk);
        *value = f64::from_le_bytes(b);
    }
    if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
        return Err(bytes.error_at(start, format!("{what}: non-finite value {bad}")));
    }
    Ok(values)
}

fn read_vec3<R: Read>(bytes: &mut ByteReader<R>, what: &str) -> Result<Vector3<f64>> {
    let [x, y, z] = read_values::<R, 3>(bytes, what)?;
    Ok(Vector3::new(x, y, z))
}

fn read_pose<R: Read>(bytes: &mut ByteReader<R>, what: &str) -> Result<Pose3> {
    let translation = read_vec3(bytes, what)?;
    let at = bytes.offset();
    let [w, x, y, z] = read_values::<R, 4>(bytes, what)?;
    let q = Quaternion::new(w, x, y, z);
    let norm = q.norm();
    if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(bytes.error_at(
            at,
            format!("{what}: rotation quaternion has norm {norm}, expected 1"),
        ));
    }
    // Keep quaternions that are unit to rounding as they are, so files read and write back bit
    // for bit; renormalize the others (OctoMap versions that round to f32).
    let rotation = if (norm - 1.0).abs() <= 1e-12 {
        UnitQuaternion::new_unchecked(q)
    } else {
        UnitQuaternion::from_quaternion(q)
    };
    Ok(Pose3::from_parts(translation, rotation))
}
