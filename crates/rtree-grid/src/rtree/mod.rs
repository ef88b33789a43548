//! An R-tree of order (d, M) over [`KeyBox`]es (Guttman 1984; Khan 2017, §2.4).
//!
//! Height-balanced: every leaf node sits at level 0, an inner node at level `l` holds the
//! minimum bounding boxes (MBRC) of its children at level `l − 1`. Every node but the root
//! holds between `d` and `M` entries; an inner root holds at least two. Insertion descends by
//! least enlargement (ties: smaller volume) and splits overflowing nodes with Guttman's
//! quadratic split; deletion removes the entry, tightens the boxes on the path to the root and
//! re-inserts the entries of nodes that fall below `d` at their own level (CondenseTree).
//!
//! Nodes live in one arena: node `n` owns the `M + 1` entry slots `n·(M+1) ..` of the flat
//! `boxes`/`ids` vectors (one spare slot takes the overflowing entry before a split), so no
//! node is a separate heap allocation and a leaf entry is 16 bytes (a 12-byte box and a
//! 4-byte item id). Freed nodes are recycled. Item ids are opaque `u32`s chosen by the caller;
//! the tree never looks inside them.
//!
//! Complexity (n items, h = log_d n levels): insertion `O(h·M)` plus `O(M²)` per split;
//! deletion a FindLeaf search (`O(h·M)` without overlaps) plus `O(h·M)` tightening; box and
//! point queries visit only the subtrees whose boxes meet the query.

mod split;
#[cfg(test)]
mod tests;

use crate::key::{Key, KeyBox};

/// Marks "no node".
const NONE: u32 = u32::MAX;
/// Largest supported M (counts are bytes).
pub const MAX_ORDER: usize = 128;

/// Errors of [`RTree::new`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OrderError {
    /// M outside `2 ..= 128` or d outside `1 ..= M/2`.
    #[error(
        "invalid R-tree order (d = {min_entries}, M = {max_entries}): need 2 <= M <= 128 and 1 <= d <= M/2"
    )]
    Invalid {
        /// The requested d.
        min_entries: usize,
        /// The requested M.
        max_entries: usize,
    },
}

/// An arena-allocated R-tree of order (d, M) whose leaf entries are `(KeyBox, item id)`.
#[derive(Clone, Debug)]
pub struct RTree {
    max_entries: usize,
    min_entries: usize,
    cap: usize,
    boxes: Vec<KeyBox>,
    ids: Vec<u32>,
    count: Vec<u8>,
    parent: Vec<u32>,
    level: Vec<u8>,
    free_nodes: Vec<u32>,
    root: u32,
    len: usize,
    scratch: Vec<(KeyBox, u32)>,
    orphans: Vec<(KeyBox, u32, u8)>,
}

impl RTree {
    /// An empty tree of order (`min_entries` = d, `max_entries` = M).
    pub fn new(min_entries: usize, max_entries: usize) -> Result<Self, OrderError> {
        if !(2..=MAX_ORDER).contains(&max_entries)
            || min_entries == 0
            || min_entries > max_entries / 2
        {
            return Err(OrderError::Invalid {
                min_entries,
                max_entries,
            });
        }
        let mut tree = Self {
            max_entries,
            min_entries,
            cap: max_entries + 1,
            boxes: Vec::new(),
            ids: Vec::new(),
            count: Vec::new(),
            parent: Vec::new(),
            level: Vec::new(),
            free_nodes: Vec::new(),
            root: 0,
            len: 0,
            scratch: Vec::new(),
            orphans: Vec::new(),
        };
        tree.root = tree.alloc_node(0);
        Ok(tree)
    }

    /// M, the largest number of entries per node.
    pub fn max_entries(&self) -> usize {
        self.max_entries
    }

    /// d, the smallest number of entries per non-root node.
    pub fn min_entries(&self) -> usize {
        self.min_entries
    }

    /// Number of items (leaf entries).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the tree holds no item.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of nodes (root, inner and leaf nodes): the MBRCs of the hierarchy.
    pub fn num_nodes(&self) -> usize {
        self.count.len() - self.free_nodes.len()
    }

    /// Number of levels (1 for a tree that is a single leaf node).
    pub fn height(&self) -> usize {
        usize::from(self.level[self.root as usize]) + 1
    }

    /// Bytes held by the arena (allocated capacity of every vector).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.boxes.capacity() * size_of::<KeyBox>()
            + self.ids.capacity() * 4
            + self.count.capacity()
            + self.parent.capacity() * 4
            + self.level.capacity()
            + self.free_nodes.capacity() * 4
            + self.scratch.capacity() * size_of::<(KeyBox, u32)>()
            + self.orphans.capacity() * size_of::<(KeyBox, u32, u8)>()
            + size_of::<Self>()
    }

    #[inline]
    fn slot(&self, node: u32, i: usize) -> usize {
        node as usize * self.cap + i
    }

    #[inline]
    fn entries(&self, node: u32) -> std::ops::Range<usize> {
        let start = node as usize * self.cap;
        start..start + usize::from(self.count[node as usize])
    }

    fn alloc_node(&mut self, level: u8) -> u32 {
        if let Some(n) = self.free_nodes.pop() {
            self.count[n as usize] = 0;
            self.parent[n as usize] = NONE;
            self.level[n as usize] = level;
            return n;
        }
        let n = self.count.len() as u32;
        let empty = KeyBox::cube([0; 3]);
        self.boxes.resize(self.boxes.len() + self.cap, empty);
        self.ids.resize(self.ids.len() + self.cap, NONE);
        self.count.push(0);
        self.parent.push(NONE);
        self.level.push(level);
        n
    }

    fn free_node(&mut self, node: u32) {
        self.count[node as usize] = 0;
        self.parent[node as usize] = NONE;
        self.free_nodes.push(node);
    }

    /// The tight bounding box of a node's entries (`None` when it is empty).
    fn node_box(&self, node: u32) -> Option<KeyBox> {
        let range = self.entries(node);
        let mut iter = self.boxes[range].iter();
        let first = *iter.next()?;
        Some(iter.fold(first, |acc, b| acc.union(b)))
    }

    fn push_entry(&mut self, node: u32, bx: KeyBox, id: u32) {
        let s = self.slot(node, usize::from(self.count[node as usize]));
        self.boxes[s] = bx;
        self.ids[s] = id;
        self.count[node as usize] += 1;
        if self.level[node as usize] > 0 {
            self.parent[id as usize] = node;
        }
    }

    fn remove_slot(&mut self, node: u32, i: usize) {
        let last = usize::from(self.count[node as usize]) - 1;
        let (a, b) = (self.slot(node, i), self.slot(node, last));
        self.boxes.swap(a, b);
        self.ids.swap(a, b);
        self.count[node as usize] -= 1;
    }

    fn slot_of_child(&self, parent: u32, child: u32) -> usize {
        let range = self.entries(parent);
        let start = range.start;
        self.ids[range]
            .iter()
            .position(|&c| c == child)
            .map_or(start, |i| start + i)
    }

    /// Inserts `item` with box `bx` (Guttman Insert: least enlargement, quadratic split).
    pub fn insert(&mut self, item: u32, bx: KeyBox) {
        self.insert_at_level(bx, item, 0);
        self.len += 1;
    }

    /// Inserts an entry into a node at `level` (0: an item into a leaf node).
    fn insert_at_level(&mut self, bx: KeyBox, id: u32, level: u8) {
        let mut node = self.root;
        while self.level[node as usize] > level {
            let mut best = self.slot(node, 0);
            let mut best_key = (u64::MAX, u64::MAX);
            for s in self.entries(node) {
                let b = &self.boxes[s];
                let key = (b.enlargement(&bx), b.volume());
                if key < best_key {
                    best_key = key;
                    best = s;
                }
            }
            node = self.ids[best];
        }
        self.push_entry(node, bx, id);
        self.adjust_upwards(node);
    }

    /// Splits overflowing nodes and tightens boxes from `node` up to the root.
    fn adjust_upwards(&mut self, mut node: u32) {
        loop {
            let sibling = if usize::from(self.count[node as usize]) > self.max_entries {
                Some(self.split(node))
            } else {
                None
            };
            if node == self.root {
                if let Some(sibling) = sibling {
                    let level = self.level[node as usize] + 1;
                    let root = self.alloc_node(level);
                    for child in [node, sibling] {
                        if let Some(b) = self.node_box(child) {
                            self.push_entry(root, b, child);
                        }
                    }
                    self.root = root;
                }
                return;
            }
            let parent = self.parent[node as usize];
            let s = self.slot_of_child(parent, node);
            let tight = self.node_box(node).unwrap_or(self.boxes[s]);
            let changed = tight != self.boxes[s];
            self.boxes[s] = tight;
            if let Some(sibling) = sibling {
                if let Some(b) = self.node_box(sibling) {
                    self.push_entry(parent, b, sibling);
                }
            } else if !changed {
                return;
            }
            node = parent;
        }
    }

    /// Removes `item` stored with box `bx`; returns whether it was found (Guttman Delete:
    /// FindLeaf, remove, CondenseTree, shorten the tree).
    pub fn remove(&mut self, item: u32, bx: &KeyBox) -> bool {
        let Some((leaf, slot)) = self.find_leaf(self.root, item, bx) else {
            return false;
        };
        let i = slot - self.slot(leaf, 0);
        self.remove_slot(leaf, i);
        self.len -= 1;
        self.condense(leaf);
        true
    }

    fn find_leaf(&self, node: u32, item: u32, bx: &KeyBox) -> Option<(u32, usize)> {
        let range = self.entries(node);
        if self.level[node as usize] == 0 {
            return range
                .into_iter()
                .find(|&s| self.ids[s] == item && self.boxes[s] == *bx)
                .map(|s| (node, s));
        }
        for s in range {
            if self.boxes[s].contains_box(bx) {
                if let Some(found) = self.find_leaf(self.ids[s], item, bx) {
                    return Some(found);
                }
            }
        }
        None
    }

    fn condense(&mut self, leaf: u32) {
        let mut orphans = std::mem::take(&mut self.orphans);
        orphans.clear();
        let mut node = leaf;
        while node != self.root {
            let parent = self.parent[node as usize];
            let s = self.slot_of_child(parent, node);
            if usize::from(self.count[node as usize]) < self.min_entries {
                self.remove_slot(parent, s - self.slot(parent, 0));
                let level = self.level[node as usize];
                for e in self.entries(node) {
                    orphans.push((self.boxes[e], self.ids[e], level));
                }
                self.free_node(node);
            } else if let Some(b) = self.node_box(node) {
                self.boxes[s] = b;
            }
            node = parent;
        }
        self.shorten();
        for &(bx, id, level) in &orphans {
            if level <= self.level[self.root as usize] {
                self.insert_at_level(bx, id, level);
                self.shorten();
            } else {
                self.reinsert_items_of(id, level - 1);
            }
        }
        orphans.clear();
        self.orphans = orphans;
    }

    /// Re-inserts every item below `node` (at `level`) as a leaf entry and frees the nodes.
    fn reinsert_items_of(&mut self, node: u32, level: u8) {
        let entries: Vec<(KeyBox, u32)> = self
            .entries(node)
            .map(|s| (self.boxes[s], self.ids[s]))
            .collect();
        self.free_node(node);
        for (bx, id) in entries {
            if level == 0 {
                self.insert_at_level(bx, id, 0);
            } else {
                self.reinsert_items_of(id, level - 1);
            }
        }
    }

    /// Makes the only child of an inner root the new root (repeatedly).
    fn shorten(&mut self) {
        while self.level[self.root as usize] > 0 && self.count[self.root as usize] <= 1 {
            let old = self.root;
            if self.count[old as usize] == 0 {
                self.level[old as usize] = 0;
                return;
            }
            self.root = self.ids[self.slot(old, 0)];
            self.parent[self.root as usize] = NONE;
            self.free_node(old);
        }
    }

    /// The item whose box contains the base cube `key` (the first found; leaves of an
    /// occupancy grid never overlap, so it is unique there).
    pub fn find_containing(&self, key: Key) -> Option<(u32, KeyBox)> {
        self.find_containing_in(self.root, key)
    }

    fn find_containing_in(&self, node: u32, key: Key) -> Option<(u32, KeyBox)> {
        let leaf = self.level[node as usize] == 0;
        for s in self.entries(node) {
            if self.boxes[s].contains_key(key) {
                if leaf {
                    return Some((self.ids[s], self.boxes[s]));
                }
                if let Some(found) = self.find_containing_in(self.ids[s], key) {
                    return Some(found);
                }
            }
        }
        None
    }

    /// Calls `visit(item, box)` for every item whose box shares a base cube with `query`.
    pub fn for_each_intersecting(&self, query: &KeyBox, visit: &mut impl FnMut(u32, &KeyBox)) {
        self.intersecting_in(self.root, query, visit);
    }

    fn intersecting_in(&self, node: u32, query: &KeyBox, visit: &mut impl FnMut(u32, &KeyBox)) {
        let leaf = self.level[node as usize] == 0;
        for s in self.entries(node) {
            if self.boxes[s].intersects(query) {
                if leaf {
                    visit(self.ids[s], &self.boxes[s]);
                } else {
                    self.intersecting_in(self.ids[s], query, visit);
                }
            }
        }
    }

    /// Calls `visit(item, box)` for every item, in tree order.
    pub fn for_each_item(&self, visit: &mut impl FnMut(u32, &KeyBox)) {
        self.items_in(self.root, visit);
    }

    fn items_in(&self, node: u32, visit: &mut impl FnMut(u32, &KeyBox)) {
        let leaf = self.level[node as usize] == 0;
        for s in self.entries(node) {
            if leaf {
                visit(self.ids[s], &self.boxes[s]);
            } else {
                self.items_in(self.ids[s], visit);
            }
        }
    }

    /// Checks the R-tree invariants: fill in `[d, M]` except at the root (an inner root holds
    /// at least two entries), every inner entry's box is the tight bounding box of its child,
    /// all leaf nodes at level 0 (equal depth), parent links and the item count.
    pub fn check_invariants(&self) -> Result<(), String> {
        let root = self.root;
        if self.parent[root as usize] != NONE {
            return Err("root has a parent".into());
        }
        if self.level[root as usize] > 0 && self.count[root as usize] < 2 {
            return Err("inner root with fewer than two entries".into());
        }
        let mut items = 0usize;
        self.check_node(root, &mut items)?;
        if items != self.len {
            return Err(format!("{items} items reachable, len says {}", self.len));
        }
        Ok(())
    }

    fn check_node(&self, node: u32, items: &mut usize) -> Result<(), String> {
        let count = usize::from(self.count[node as usize]);
        if count > self.max_entries {
            return Err(format!("node {node} holds {count} > M entries"));
        }
        if node != self.root && count < self.min_entries {
            return Err(format!("node {node} holds {count} < d entries"));
        }
        let level = self.level[node as usize];
        for s in self.entries(node) {
            if level == 0 {
                *items += 1;
                continue;
            }
            let child = self.ids[s];
            if self.parent[child as usize] != node {
                return Err(format!("child {child} does not point back to {node}"));
            }
            if self.level[child as usize] + 1 != level {
                return Err(format!("child {child} is not one level below {node}"));
            }
            if self.node_box(child) != Some(self.boxes[s]) {
                return Err(format!("box of child {child} in node {node} is not tight"));
            }
            self.check_node(child, items)?;
        }
        Ok(())
    }
}
