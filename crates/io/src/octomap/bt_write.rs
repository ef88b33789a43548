//! Writing OctoMap binary occupancy trees (`.bt`), in the layout described in
//! [`super::BtReader`], with the header OctoMap itself writes.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use super::bt::{BINARY_HEADER, OcTree, OctreeLeaf, TREE_DEPTH};
use crate::{Error, Location, Result};

/// A child slot of an inner node while the tree is rebuilt from its leaves.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    Empty,
    Free,
    Occupied,
    Inner(usize),
}

impl Slot {
    fn code(self) -> u16 {
        match self {
            Slot::Empty => 0,
            Slot::Free => 1,
            Slot::Occupied => 2,
            Slot::Inner(_) => 3,
        }
    }
}

/// Writes `tree` to a file (uncompressed).
pub fn write_bt_file(path: &Path, tree: &OcTree) -> Result<()> {
    let file = File::create(path).map_err(|e| Error::io(path, Location::File, e))?;
    let mut writer = BufWriter::new(file);
    write_bt(&mut writer, tree, path)?;
    writer
        .flush()
        .map_err(|e| Error::io(path, Location::File, e))
}

/// Writes `tree` to `writer`; `name` is used in errors.
///
/// The tree is rebuilt from each leaf's `depth` and `key_min` (centres and sizes are not
/// consulted). Fails when leaves overlap, a key is not aligned to its depth, the depth is
/// outside 1..=16 or the resolution is not positive. `nodes_in_file` and `inner_nodes` are
/// recomputed, not copied. A tree read by [`super::read_bt`] writes back byte for byte.
pub fn write_bt<W: Write>(mut writer: W, tree: &OcTree, name: &Path) -> Result<()> {
    let unwritable = |reason: String| Error::Unwritable {
        path: name.to_path_buf(),
        reason,
    };
    if !(tree.resolution_m.is_finite() && tree.resolution_m > 0.0) {
        return Err(unwritable(format!(
            "resolution must be positive, not {}",
            tree.resolution_m
        )));
    }
    if tree.id.is_empty() || tree.id.contains(char::is_whitespace) {
        return Err(unwritable(format!("tree id {:?} is not one word", tree.id)));
    }
    let mut inner: Vec<[Slot; 8]> = Vec::new();
    if !tree.leaves.is_empty() {
        inner.push([Slot::Empty; 8]);
    }
    for (i, leaf) in tree.leaves.iter().enumerate() {
        insert(&mut inner, leaf).map_err(|reason| unwritable(format!("leaf {i}: {reason}")))?;
    }
    // The root plus every child of every inner node.
    let children = inner
        .iter()
        .flatten()
        .filter(|s| **s != Slot::Empty)
        .count();
    let size = if inner.is_empty() { 0 } else { 1 + children };
    let header = format!(
        "{BINARY_HEADER}\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n\
         id {}\nsize {size}\nres {}\ndata\n",
        tree.id, tree.resolution_m
    );
    let mut data = Vec::with_capacity(inner.len() * 2);
    if !inner.is_empty() {
        write_node(&inner, 0, &mut data);
    }
    writer
        .write_all(header.as_bytes())
        .and_then(|()| writer.write_all(&data))
        .map_err(|e| Error::io(name, Location::File, e))
}

/// Inserts a leaf below the root (index 0), creating inner nodes on the way.
fn insert(inner: &mut Vec<[Slot; 8]>, leaf: &OctreeLeaf) -> Result<(), String> {
    if leaf.depth == 0 || leaf.depth > TREE_DEPTH {
        return Err(format!("depth {} is outside 1..={TREE_DEPTH}", leaf.depth));
    }
    let span = 1u32 << (TREE_DEPTH - leaf.depth);
    if leaf.key_min.iter().any(|&k| u32::from(k) % span != 0) {
        return Err(format!(
            "key {:?} is not aligned to the {span}-key cells of depth {}",
            leaf.key_min, leaf.depth
        ));
    }
    let mut node = 0;
    for depth in 0..leaf.depth {
        let bit = TREE_DEPTH - 1 - depth;
        let child = (0..3).fold(0usize, |idx, axis| {
            idx | (usize::from(leaf.key_min[axis] >> bit & 1) << axis)
        });
        let last = depth + 1 == leaf.depth;
        let slot = inner[node][child];
        match (slot, last) {
            (Slot::Empty, true) => {
                inner[node][child] = if leaf.occupied {
                    Slot::Occupied
                } else {
                    Slot::Free
                };
            }
            (Slot::Empty, false) => {
                inner.push([Slot::Empty; 8]);
                let new = inner.len() - 1;
                inner[node][child] = Slot::Inner(new);
                node = new;
            }
            (Slot::Inner(next), false) => node = next,
            _ => return Err("overlaps another leaf".into()),
        }
    }
    Ok(())
}

/// Appends the two bytes of inner node `node`, then its inner children's subtrees.
fn write_node(inner: &[[Slot; 8]], node: usize, out: &mut Vec<u8>) {
    let slots = inner[node];
    let codes = slots
        .iter()
        .enumerate()
        .fold(0u16, |acc, (i, s)| acc | (s.code() << (2 * i)));
    out.extend_from_slice(&codes.to_le_bytes());
    for slot in slots {
        if let Slot::Inner(child) = slot {
            write_node(inner, child, out);
        }
    }
}
