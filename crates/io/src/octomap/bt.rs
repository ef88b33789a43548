//! Reading OctoMap binary occupancy trees (`.bt`).
//!
//! A `.bt` file is a text header followed by the tree, depth first:
//!
//! ```text
//! # Octomap OcTree binary file        (first line, verbatim)
//! # any comment lines
//! id OcTree                           (tree type; ColorOcTree etc. store the same bits)
//! size 532566                         (number of tree nodes, root included)
//! res 0.08                            (edge length of the smallest voxel, metres)
//! data
//! <tree>
//! ```
//!
//! Every inner node is stored as two bytes: byte 0 describes children 0–3, byte 1 children
//! 4–7, two bits per child starting at the least significant bit (child `i` of byte `b` is
//! `(b >> 2·(i mod 4)) & 3`): `0` = no child (unknown space), `1` = free leaf, `2` = occupied
//! leaf, `3` = inner node. After its two bytes come the subtrees of its inner children, in
//! child order (OctoMap `OccupancyOcTreeBase::readBinaryNode`). The root is always stored as
//! an inner node; leaves can sit at any depth from 1 to [`TREE_DEPTH`] (pruned subtrees).
//!
//! Keys and coordinates follow `OcTreeKey.h`: a voxel of the finest level has the integer key
//! `floor(coord / res) + 32768` per axis, and bit `15 − d` of the key selects the child at
//! depth `d` — x is bit 0 of the child index, y bit 1, z bit 2. A node at depth `d` spans
//! `2^(16−d)` keys, so its edge is `res · 2^(16−d)` metres.

use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};

use nalgebra::Point3;
use raypath_geometry::Aabb3;

use crate::source::{self, ByteReader};
use crate::{Error, Location, Result};

/// Depth of OctoMap trees: leaves of the finest resolution are at depth 16.
pub const TREE_DEPTH: u8 = 16;
/// The key of coordinate 0 (OctoMap's `tree_max_val`): `key = floor(coord / res) + 32768`.
pub const KEY_OFFSET: u32 = 32768;
/// First line of a `.bt` file.
pub(super) const BINARY_HEADER: &str = "# Octomap OcTree binary file";
/// Longest header line accepted.
const MAX_HEADER_LINE: u64 = 4096;

/// The text header of a `.bt` file.
#[derive(Clone, Debug, PartialEq)]
pub struct BtHeader {
    /// The tree type (`OcTree`, `ColorOcTree`, …; the deprecated id `1` reads as `OcTree`).
    pub id: String,
    /// Number of tree nodes stored (root, inner nodes and leaves).
    pub size: u64,
    /// Edge length of the finest voxels, metres.
    pub resolution_m: f64,
    /// Byte offset of the first byte of the tree data.
    pub data_offset: u64,
}

/// A leaf of an occupancy tree: a cube of known occupancy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OctreeLeaf {
    /// Centre of the cube in the map frame, metres.
    pub center: Point3<f64>,
    /// Edge length of the cube, metres (`resolution · 2^(16 − depth)`).
    pub size_m: f64,
    /// True for an occupied leaf, false for a free one.
    pub occupied: bool,
    /// Depth in the tree, 1 (children of the root) to [`TREE_DEPTH`].
    pub depth: u8,
    /// Smallest OctoMap key (per axis) inside the cube; its extent in keys is
    /// `2^(16 − depth)`.
    pub key_min: [u16; 3],
}

impl OctreeLeaf {
    /// The lower and upper corners of the cube.
    pub fn corners(&self) -> (Point3<f64>, Point3<f64>) {
        let h = self.size_m / 2.0;
        (self.center.map(|c| c - h), self.center.map(|c| c + h))
    }
}

/// A whole occupancy tree, as its leaves.
#[derive(Clone, Debug, PartialEq)]
pub struct OcTree {
    /// The tree type from the header (`OcTree` for plain occupancy trees).
    pub id: String,
    /// Edge length of the finest voxels, metres.
    pub resolution_m: f64,
    /// Number of nodes read (equal to the header's `size`).
    pub nodes_in_file: u64,
    /// Number of inner nodes (root included).
    pub inner_nodes: u64,
    /// The leaves in file order (depth first, children in index order).
    pub leaves: Vec<OctreeLeaf>,
}

impl OcTree {
    /// Number of occupied leaves.
    pub fn occupied_leaves(&self) -> usize {
        self.leaves.iter().filter(|l| l.occupied).count()
    }

    /// Number of free leaves.
    pub fn free_leaves(&self) -> usize {
        self.leaves.iter().filter(|l| !l.occupied).count()
    }

    /// Bounding box of the leaves' cubes, occupied ones only or all.
    pub fn bounding_box(&self, occupied_only: bool) -> Aabb3 {
        let mut bbox = Aabb3::empty();
        for leaf in self.leaves.iter().filter(|l| l.occupied || !occupied_only) {
            let (lo, hi) = leaf.corners();
            bbox.extend(&lo);
            bbox.extend(&hi);
        }
        bbox
    }
}

/// Reads a whole `.bt` file.
pub fn read_bt(path: &Path) -> Result<OcTree> {
    BtReader::open(path)?.read_all()
}

/// Parses a `.bt` file held in memory; `name` is used in errors.
pub fn parse_bt(bytes: &[u8], name: impl Into<PathBuf>) -> Result<OcTree> {
    BtReader::new(bytes, name)?.read_all()
}

/// One inner node whose children are being visited.
#[derive(Clone, Copy, Debug)]
struct Frame {
    key_min: [u32; 3],
    depth: u8,
    codes: u16,
    next_child: u8,
}

/// Streams the leaves of a `.bt` file in file order without holding the tree.
///
/// The iterator ends after the last leaf once the node count has been checked against the
/// header and the end of the file reached; any inconsistency is returned as an error.
pub struct BtReader<R> {
    header: BtHeader,
    bytes: ByteReader<R>,
    stack: Vec<Frame>,
    nodes: u64,
    inner_nodes: u64,
    finished: bool,
}

impl BtReader<Box<dyn BufRead + Send>> {
    /// Opens a `.bt` file (plain or compressed) and reads its header.
    pub fn open(path: &Path) -> Result<Self> {
        Self::new(source::open(path)?, path)
    }
}

impl<R: BufRead> BtReader<R> {
    /// Reads the header from `reader`; `name` is used in errors.
    pub fn new(mut reader: R, name: impl Into<PathBuf>) -> Result<Self> {
        let name = name.into();
        let header = read_header(&mut reader, &name)?;
        let mut bytes = ByteReader::new(reader, name, header.data_offset);
        let mut stack = Vec::with_capacity(usize::from(TREE_DEPTH));
        let (mut nodes, mut inner_nodes) = (0, 0);
        if header.size > 0 {
            let codes = bytes.read_u16_le("root node")?;
            stack.push(Frame {
                key_min: [0; 3],
                depth: 0,
                codes,
                next_child: 0,
            });
            nodes = 1;
            inner_nodes = 1;
        }
        Ok(Self {
            header,
            bytes,
            stack,
            nodes,
            inner_nodes,
            finished: false,
        })
    }

    /// The file's header.
    pub fn header(&self) -> &BtHeader {
        &self.header
    }

    /// Nodes read so far (all of them once the iterator has ended).
    pub fn nodes_read(&self) -> u64 {
        self.nodes
    }

    /// Inner nodes read so far (root included).
    pub fn inner_nodes(&self) -> u64 {
        self.inner_nodes
    }

    /// Reads all (remaining) leaves into an [`OcTree`].
    pub fn read_all(mut self) -> Result<OcTree> {
        let mut leaves = Vec::new();
        for leaf in &mut self {
            leaves.push(leaf?);
        }
        Ok(OcTree {
            id: self.header.id.clone(),
            resolution_m: self.header.resolution_m,
            nodes_in_file: self.nodes,
            inner_nodes: self.inner_nodes,
            leaves,
        })
    }

    fn step(&mut self) -> Result<Option<OctreeLeaf>> {
        loop {
            let Some(frame) = self.stack.last_mut() else {
                return self.finish().map(|()| None);
            };
            if frame.next_child == 8 {
                self.stack.pop();
                continue;
            }
            let child = frame.next_child;
            frame.next_child += 1;
            let code = (frame.codes >> (2 * child)) & 3;
            if code == 0 {
                continue;
            }
            let (parent_key, parent_depth) = (frame.key_min, frame.depth);
            self.nodes += 1;
            if self.nodes > self.header.size {
                return Err(self.bytes.error(format!(
                    "the tree has more nodes than the {} announced in the header",
                    self.header.size
                )));
            }
            let depth = parent_depth + 1;
            let span = 1u32 << (TREE_DEPTH - depth);
            let mut key_min = parent_key;
            for (axis, key) in key_min.iter_mut().enumerate() {
                if child >> axis & 1 == 1 {
                    *key += span;
                }
            }
            if code == 3 {
                if depth >= TREE_DEPTH {
                    return Err(self.bytes.error(format!(
                        "inner node at depth {depth}; OctoMap trees end at depth {TREE_DEPTH}"
                    )));
                }
                let codes = self.bytes.read_u16_le("inner node")?;
                self.inner_nodes += 1;
                self.stack.push(Frame {
                    key_min,
                    depth,
                    codes,
                    next_child: 0,
                });
                continue;
            }
            return Ok(Some(self.leaf(key_min, depth, code == 2)));
        }
    }

    fn leaf(&self, key_min: [u32; 3], depth: u8, occupied: bool) -> OctreeLeaf {
        let res = self.header.resolution_m;
        let span = f64::from(1u32 << (TREE_DEPTH - depth));
        let center = key_min.map(|k| (f64::from(k) - f64::from(KEY_OFFSET) + span / 2.0) * res);
        OctreeLeaf {
            center: Point3::from(center),
            size_m: span * res,
            occupied,
            depth,
            // Keys of nodes below the root are < 2^16 (the root spans [0, 2^16)).
            key_min: key_min.map(|k| k.min(u32::from(u16::MAX)) as u16),
        }
    }

    fn finish(&mut self) -> Result<()> {
        if self.nodes != self.header.size {
            return Err(self.bytes.error(format!(
                "the tree has {} nodes but the header announces {}",
                self.nodes, self.header.size
            )));
        }
        if !self.bytes.at_end()? {
            return Err(self
                .bytes
                .error("unexpected bytes after the end of the tree"));
        }
        Ok(())
    }
}

impl<R: BufRead> Iterator for BtReader<R> {
    type Item = Result<OctreeLeaf>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.finished {
            return None;
        }
        match self.step() {
            Ok(Some(leaf)) => Some(Ok(leaf)),
            Ok(None) => {
                self.finished = true;
                None
            }
            Err(e) => {
                self.finished = true;
                Some(Err(e))
            }
        }
    }
}

/// Reads the header lines up to and including `data`, leaving `reader` at the tree data.
fn read_header<R: BufRead>(reader: &mut R, name: &Path) -> Result<BtHeader> {
    let (mut offset, mut line_no) = (0u64, 0u64);
    let mut line = Vec::with_capacity(128);
    let (mut id, mut size, mut resolution_m) = (None, None, None);
    loop {
        line.clear();
        let n = reader
            .by_ref()
            .take(MAX_HEADER_LINE)
            .read_until(b'\n', &mut line)
            .map_err(|e| Error::io(name, Location::Line(line_no + 1), e))?;
        line_no += 1;
        offset += n as u64;
        let malformed = |reason: String| Error::malformed(name, Location::Line(line_no), reason);
        if n == 0 {
            return Err(Error::truncated(
                name,
                Location::Line(line_no),
                "the OcTree header (no `data` line)",
            ));
        }
        if line.last() != Some(&b'\n') && n as u64 == MAX_HEADER_LINE {
            return Err(malformed(format!(
                "header line longer than {MAX_HEADER_LINE} bytes"
            )));
        }
        let text = String::from_utf8_lossy(&line);
        let text = text.trim();
        if line_no == 1 {
            if !text.starts_with(BINARY_HEADER) {
                let reason = if text.starts_with("# Octomap OcTree file") {
                    "this is a full OcTree (.ot) file; only binary trees (.bt) are supported"
                        .to_owned()
                } else {
                    format!(
                        "first line must be {BINARY_HEADER:?} (legacy headerless .bt files are not supported)"
                    )
                };
                return Err(malformed(reason));
            }
            continue;
        }
        let mut fields = text.split_whitespace();
        let Some(keyword) = fields.next() else {
            continue;
        };
        let value = fields.next();
        match keyword {
            k if k.starts_with('#') => {}
            "data" => break,
            "id" => {
                let v = value.ok_or_else(|| malformed("`id` without a value".into()))?;
                id = Some(if v == "1" { "OcTree" } else { v }.to_owned());
            }
            "size" => {
                let v = value.ok_or_else(|| malformed("`size` without a value".into()))?;
                size = Some(
                    v.parse::<u64>()
                        .map_err(|_| malformed(format!("size: cannot parse {v:?}")))?,
                );
            }
            "res" => {
                let v = value.ok_or_else(|| malformed("`res` without a value".into()))?;
                let res = v
                    .parse::<f64>()
                    .map_err(|_| malformed(format!("res: cannot parse {v:?}")))?;
                if !(res.is_finite() && res > 0.0) {
                    return Err(malformed(format!("resolution must be positive, not {res}")));
                }
                resolution_m = Some(res);
            }
            // OctoMap skips unknown keywords (with a warning); so do we.
            _ => {}
        }
    }
    let missing = |what: &str| {
        Error::malformed(
            name,
            Location::Line(line_no),
            format!("the header has no `{what}` line before `data`"),
        )
    };
    Ok(BtHeader {
        id: id.ok_or_else(|| missing("id"))?,
        size: size.ok_or_else(|| missing("size"))?,
        resolution_m: resolution_m.ok_or_else(|| missing("res"))?,
        data_offset: offset,
    })
}
