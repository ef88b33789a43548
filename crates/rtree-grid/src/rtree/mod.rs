//! An R-tree of order (d, M) over [`KeyBox`]es (Guttman 1984; Khan 2017, §2.4).
//!
//! Height-balanced: every leaf node sits at level 0, an inner node at level `l` holds the
//! minimum bounding boxes (MBRC) of its children at level `l − 1`. Every node but the root
//! holds between `d` and `M` entries; an inner root holds at least two. Insertion descends by
//! least enlargement (ties: smaller volume) and splits overflowing nodes with Guttman's
//! quadratic split; deletion removes the entry, tightens the boxes on the path to the root and
//! re-inserts the entries of nodes that fall below `d` at their own level (CondenseTree).
//!
//! Nodes live in one arena: node `n` owns the `M` child-id slots `n·M ..` of the flat `ids`
//! vector (the overflowing `M + 1`-th entry waits in `spill` for the split that follows at
//! once); inner nodes also own a block of `M` boxes in `inner_boxes`. Item boxes are stored
//! once, indexed by item id (`items`), each with a 4-byte value of the caller's beside it (one
//! memory access reads both), so a leaf entry costs a 4-byte slot plus the item's 16-byte
//! record, and no node is a separate heap allocation. Freed nodes and box blocks are
//! recycled. Item ids are small `u32`s chosen by the caller (dense ids keep `items` compact).
//! Items may be removed one by one or in a batch (one CondenseTree pass, `delete`).
//!
//! Complexity (n items, h = log_d n levels): insertion `O(h·M)` plus `O(M²)` per split;
//! deletion a FindLeaf search (`O(h·M)` without overlaps) plus `O(h·M)` tightening; box and
//! point queries visit only the subtrees whose boxes meet the query.

mod delete;
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

/// An item's box and the caller's 4-byte value (16 bytes: read together).
#[derive(Clone, Copy, Debug)]
struct Item {
    bx: KeyBox,
    value: u32,
}

impl Item {
    const EMPTY: Self = Self {
        bx: KeyBox {
            lo: [0; 3],
            hi: [0; 3],
        },
        value: 0,
    };
}

/// An arena-allocated R-tree of order (d, M) whose leaf entries are `(KeyBox, item id)`.
#[derive(Clone, Debug)]
pub struct RTree {
    max_entries: usize,
    min_entries: usize,
    cap: usize,
    items: Vec<Item>,
    item_leaf: Vec<u32>,
    inner_boxes: Vec<KeyBox>,
    box_block: Vec<u32>,
    free_blocks: Vec<u32>,
    ids: Vec<u32>,
    count: Vec<u8>,
    parent: Vec<u32>,
    level: Vec<u8>,
    free_nodes: Vec<u32>,
    root: u32,
    len: usize,
    scratch: Vec<(KeyBox, u32)>,
    orphans: Vec<(KeyBox, u32, u8)>,
    /// The `M + 1`-th entry of the node about to be split.
    spill: Option<(KeyBox, u32)>,
    /// Split scratch: which entries have a group.
    assigned: Vec<bool>,
    /// Deletion scratch: nodes that lost entries.
    touched: Vec<u32>,
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
            cap: max_entries,
            items: Vec::new(),
            item_leaf: Vec::new(),
            inner_boxes: Vec::new(),
            box_block: Vec::new(),
            free_blocks: Vec::new(),
            ids: Vec::new(),
            count: Vec::new(),
            parent: Vec::new(),
            level: Vec::new(),
            free_nodes: Vec::new(),
            root: 0,
            len: 0,
            scratch: Vec::new(),
            orphans: Vec::new(),
            spill: None,
            assigned: Vec::new(),
            touched: Vec::new(),
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
        self.items.capacity() * size_of::<Item>()
            + self.inner_boxes.capacity() * size_of::<KeyBox>()
            + self.item_leaf.capacity() * 4
            + (self.box_block.capacity() + self.free_blocks.capacity()) * 4
            + self.ids.capacity() * 4
            + self.count.capacity()
            + self.parent.capacity() * 4
            + self.level.capacity()
            + self.free_nodes.capacity() * 4
            + self.scratch.capacity() * size_of::<(KeyBox, u32)>()
            + self.orphans.capacity() * size_of::<(KeyBox, u32, u8)>()
            + self.assigned.capacity()
            + self.touched.capacity() * 4
            + size_of::<Self>()
    }

    /// Releases spare capacity of the arena and drops the item → leaf map that speeds up
    /// removals (4 bytes per item; refilled as items are inserted or move).
    pub fn shrink_to_fit(&mut self) {
        self.items.shrink_to_fit();
        // The item → leaf map only speeds up removals; it is rebuilt as items move.
        self.item_leaf = Vec::new();
        self.inner_boxes.shrink_to_fit();
        self.box_block.shrink_to_fit();
        self.free_blocks.shrink_to_fit();
        self.ids.shrink_to_fit();
        self.count.shrink_to_fit();
        self.parent.shrink_to_fit();
        self.level.shrink_to_fit();
        self.free_nodes.shrink_to_fit();
        self.scratch = Vec::new();
        self.orphans = Vec::new();
        self.assigned = Vec::new();
        self.touched = Vec::new();
    }

    #[inline]
    fn slot(&self, node: u32, i: usize) -> usize {
        node as usize * self.cap + i
    }

    fn alloc_node(&mut self, level: u8) -> u32 {
        let n = if let Some(n) = self.free_nodes.pop() {
            self.count[n as usize] = 0;
            self.parent[n as usize] = NONE;
            self.level[n as usize] = level;
            n
        } else {
            let n = self.count.len() as u32;
            self.ids.resize(self.ids.len() + self.cap, NONE);
            self.count.push(0);
            self.parent.push(NONE);
            self.level.push(level);
            self.box_block.push(NONE);
            n
        };
        if level > 0 {
            self.give_block(n);
        }
        n
    }

    /// Gives an inner node its block of entry boxes.
    fn give_block(&mut self, node: u32) {
        let block = if let Some(b) = self.free_blocks.pop() {
            b
        } else {
            let b = (self.inner_boxes.len() / self.cap) as u32;
            let empty = KeyBox::cube([0; 3]);
            self.inner_boxes
                .resize(self.inner_boxes.len() + self.cap, empty);
            b
        };
        self.box_block[node as usize] = block;
    }

    fn free_node(&mut self, node: u32) {
        self.count[node as usize] = 0;
        self.parent[node as usize] = NONE;
        let block = std::mem::replace(&mut self.box_block[node as usize], NONE);
        if block != NONE {
            self.free_blocks.push(block);
        }
        self.free_nodes.push(node);
    }

    /// The box of entry `i` of `node`.
    #[inline]
    fn entry_box(&self, node: u32, i: usize) -> KeyBox {
        let block = self.box_block[node as usize];
        if block == NONE {
            self.items[self.ids[self.slot(node, i)] as usize].bx
        } else {
            self.inner_boxes[block as usize * self.cap + i]
        }
    }

    /// The child ids of `node`.
    #[inline]
    fn child_ids(&self, node: u32) -> &[u32] {
        let start = node as usize * self.cap;
        &self.ids[start..start + self.len_of(node)]
    }

    /// The entry boxes of an inner node.
    #[inline]
    fn inner_entry_boxes(&self, node: u32) -> &[KeyBox] {
        let start = self.box_block[node as usize] as usize * self.cap;
        &self.inner_boxes[start..start + self.len_of(node)]
    }

    /// Sets the box of entry `i` of an inner node.
    #[inline]
    fn set_entry_box(&mut self, node: u32, i: usize, bx: KeyBox) {
        let block = self.box_block[node as usize];
        if block != NONE {
            self.inner_boxes[block as usize * self.cap + i] = bx;
        }
    }

    /// The box stored for `item` (meaningful while the item is in the tree or after
    /// [`store_item`](Self::store_item)).
    #[inline]
    pub fn item_box(&self, item: u32) -> Option<KeyBox> {
        self.items.get(item as usize).map(|i| i.bx)
    }

    /// The box and the value stored for `item`.
    #[inline]
    pub fn item(&self, item: u32) -> Option<(KeyBox, u32)> {
        self.items.get(item as usize).map(|i| (i.bx, i.value))
    }

    /// The caller's 4-byte value stored beside `item`'s box (0 until set).
    #[inline]
    pub fn item_value(&self, item: u32) -> Option<u32> {
        self.items.get(item as usize).map(|i| i.value)
    }

    /// Sets the value of `item` (an item the table holds: in the tree or stored).
    #[inline]
    pub fn set_item_value(&mut self, item: u32, value: u32) {
        if let Some(i) = self.items.get_mut(item as usize) {
            i.value = value;
        }
    }

    /// Number of item ids the table has room for (one past the largest stored id).
    pub fn item_slots(&self) -> usize {
        self.items.len()
    }

    /// Stores the box and value of an item that is not in the tree (yet):
    /// [`item_box`](Self::item_box) returns the box, queries do not see it until
    /// [`insert`](Self::insert). The item must not be in the tree (its entries would read
    /// the new box).
    pub fn store_item(&mut self, item: u32, bx: KeyBox, value: u32) {
        let id = item as usize;
        if id >= self.items.len() {
            self.items.resize(id + 1, Item::EMPTY);
        }
        self.items[id] = Item { bx, value };
    }

    #[inline]
    fn len_of(&self, node: u32) -> usize {
        usize::from(self.count[node as usize])
    }

    #[inline]
    fn id_at(&self, node: u32, i: usize) -> u32 {
        self.ids[self.slot(node, i)]
    }

    /// The tight bounding box of a node's entries (`None` when it is empty).
    fn node_box(&self, node: u32) -> Option<KeyBox> {
        let n = self.len_of(node);
        if n == 0 {
            return None;
        }
        let mut acc = self.entry_box(node, 0);
        for i in 1..n {
            acc = acc.union(&self.entry_box(node, i));
        }
        Some(acc)
    }

    /// Appends an entry; into a full node it goes to `spill`, and the caller splits the
    /// node before anything else reads it.
    fn push_entry(&mut self, node: u32, bx: KeyBox, id: u32) {
        let i = self.len_of(node);
        self.count[node as usize] += 1;
        if i == self.cap {
            debug_assert!(self.spill.is_none());
            self.spill = Some((bx, id));
        } else {
            let s = self.slot(node, i);
            self.ids[s] = id;
            if self.level[node as usize] > 0 {
                self.set_entry_box(node, i, bx);
            }
        }
        if self.level[node as usize] > 0 {
            self.parent[id as usize] = node;
        } else {
            let id = id as usize;
            if id >= self.items.len() {
                self.items.resize(id + 1, Item::EMPTY);
            }
            self.items[id].bx = bx;
            if id >= self.item_leaf.len() {
                self.item_leaf.resize(self.items.len(), NONE);
            }
            self.item_leaf[id] = node;
        }
    }

    fn remove_slot(&mut self, node: u32, i: usize) {
        let last = self.len_of(node) - 1;
        let (a, b) = (self.slot(node, i), self.slot(node, last));
        self.ids.swap(a, b);
        let block = self.box_block[node as usize];
        if block != NONE {
            let base = block as usize * self.cap;
            self.inner_boxes.swap(base + i, base + last);
        }
        self.count[node as usize] -= 1;
    }

    fn index_of_child(&self, parent: u32, child: u32) -> usize {
        (0..self.len_of(parent))
            .find(|&i| self.id_at(parent, i) == child)
            .unwrap_or(0)
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
            // ChooseSubtree: least enlargement, ties to the smaller volume.
            let best = choose_subtree(self.inner_entry_boxes(node), &bx);
            node = self.id_at(node, best);
        }
        self.push_entry(node, bx, id);
        self.adjust_upwards(node, bx);
    }

    /// Splits overflowing nodes and enlarges the boxes from `node` up to the root after
    /// `added` was put into `node`'s subtree.
    fn adjust_upwards(&mut self, mut node: u32, added: KeyBox) {
        loop {
            let sibling = if self.len_of(node) > self.max_entries {
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
            let i = self.index_of_child(parent, node);
            let old = self.entry_box(parent, i);
            if let Some(sibling) = sibling {
                let tight = self.node_box(node).unwrap_or(old);
                self.set_entry_box(parent, i, tight);
                if let Some(b) = self.node_box(sibling) {
                    self.push_entry(parent, b, sibling);
                }
            } else {
                // Without a split the node's box only grows by the added box.
                let grown = old.union(&added);
                if grown == old {
                    return;
                }
                self.set_entry_box(parent, i, grown);
            }
            node = parent;
        }
    }

    /// The item whose box contains the base cube `key` (the first found; leaves of an
    /// occupancy grid never overlap, so it is unique there).
    pub fn find_containing(&self, key: Key) -> Option<(u32, KeyBox)> {
        self.find_containing_in(self.root, key)
    }

    fn find_containing_in(&self, node: u32, key: Key) -> Option<(u32, KeyBox)> {
        let ids = self.child_ids(node);
        if self.level[node as usize] == 0 {
            return ids.iter().find_map(|&id| {
                let b = self.items[id as usize].bx;
                b.contains_key(key).then_some((id, b))
            });
        }
        let boxes = self.inner_entry_boxes(node);
        for (b, &child) in boxes.iter().zip(ids) {
            if b.contains_key(key) {
                if let Some(found) = self.find_containing_in(child, key) {
                    return Some(found);
                }
            }
        }
        None
    }

    /// Calls `visit(item, box)` for every item whose box shares a base cube with `query`.
    pub fn for_each_intersecting(&self, query: &KeyBox, visit: &mut impl FnMut(u32, &KeyBox)) {
        self.intersecting_in(self.root, query, &mut |id, b| {
            visit(id, b);
            true
        });
    }

    /// Like [`for_each_intersecting`](Self::for_each_intersecting), but stops as soon as
    /// `visit` returns `false`; returns whether the walk ran to the end.
    pub fn for_each_intersecting_while(
        &self,
        query: &KeyBox,
        visit: &mut impl FnMut(u32, &KeyBox) -> bool,
    ) -> bool {
        self.intersecting_in(self.root, query, visit)
    }

    fn intersecting_in(
        &self,
        node: u32,
        query: &KeyBox,
        visit: &mut impl FnMut(u32, &KeyBox) -> bool,
    ) -> bool {
        let ids = self.child_ids(node);
        if self.level[node as usize] == 0 {
            for &id in ids {
                let b = &self.items[id as usize].bx;
                if b.intersects(query) && !visit(id, b) {
                    return false;
                }
            }
            return true;
        }
        let boxes = self.inner_entry_boxes(node);
        for (b, &child) in boxes.iter().zip(ids) {
            if b.intersects(query) && !self.intersecting_in(child, query, visit) {
                return false;
            }
        }
        true
    }

    /// Calls `visit(item, box)` for every item, in tree order.
    pub fn for_each_item(&self, visit: &mut impl FnMut(u32, &KeyBox)) {
        self.items_in(self.root, visit);
    }

    fn items_in(&self, node: u32, visit: &mut impl FnMut(u32, &KeyBox)) {
        let leaf = self.level[node as usize] == 0;
        for i in 0..self.len_of(node) {
            let id = self.id_at(node, i);
            if leaf {
                visit(id, &self.items[id as usize].bx);
            } else {
                self.items_in(id, visit);
            }
        }
    }

    /// Rebuilds the arena without holes: nodes renumbered depth first, items renumbered
    /// `0 .. len` in tree order (spatially coherent; values move with their items). The tree's shape is unchanged. Returns
    /// the map from old item id to new id (`u32::MAX` for ids not in the tree). `O(n)`.
    pub fn compact(&mut self) -> Vec<u32> {
        let mut out = Compacted {
            ids: Vec::with_capacity(self.num_nodes() * self.cap),
            count: Vec::with_capacity(self.num_nodes()),
            parent: Vec::with_capacity(self.num_nodes()),
            level: Vec::with_capacity(self.num_nodes()),
            box_block: Vec::with_capacity(self.num_nodes()),
            inner_boxes: Vec::new(),
            items: Vec::with_capacity(self.len),
            item_leaf: Vec::with_capacity(self.len),
        };
        let mut item_map = vec![NONE; self.items.len()];
        self.copy_node(self.root, NONE, &mut out, &mut item_map);
        self.ids = out.ids;
        self.count = out.count;
        self.parent = out.parent;
        self.level = out.level;
        self.box_block = out.box_block;
        self.inner_boxes = out.inner_boxes;
        self.items = out.items;
        self.item_leaf = out.item_leaf;
        self.free_nodes = Vec::new();
        self.free_blocks = Vec::new();
        self.root = 0;
        item_map
    }

    fn copy_node(&self, old: u32, parent: u32, out: &mut Compacted, item_map: &mut [u32]) -> u32 {
        let new = out.count.len() as u32;
        let n = self.len_of(old);
        let level = self.level[old as usize];
        out.count.push(self.count[old as usize]);
        out.parent.push(parent);
        out.level.push(level);
        out.ids.resize(out.ids.len() + self.cap, NONE);
        if level > 0 {
            let block = (out.inner_boxes.len() / self.cap) as u32;
            let start = self.box_block[old as usize] as usize * self.cap;
            out.inner_boxes
                .extend_from_slice(&self.inner_boxes[start..start + self.cap]);
            out.box_block.push(block);
        } else {
            out.box_block.push(NONE);
        }
        for i in 0..n {
            let child = self.id_at(old, i);
            let new_child = if level == 0 {
                let id = out.items.len() as u32;
                out.items.push(self.items[child as usize]);
                out.item_leaf.push(new);
                item_map[child as usize] = id;
                id
            } else {
                self.copy_node(child, new, out, item_map)
            };
            out.ids[new as usize * self.cap + i] = new_child;
        }
        new
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
        let count = self.len_of(node);
        if count > self.max_entries {
            return Err(format!("node {node} holds {count} > M entries"));
        }
        if node != self.root && count < self.min_entries {
            return Err(format!("node {node} holds {count} < d entries"));
        }
        let level = self.level[node as usize];
        if (level > 0) != (self.box_block[node as usize] != NONE) {
            return Err(format!(
                "node {node} at level {level} has the wrong box storage"
            ));
        }
        for i in 0..count {
            if level == 0 {
                *items += 1;
                continue;
            }
            let child = self.id_at(node, i);
            if self.parent[child as usize] != node {
                return Err(format!("child {child} does not point back to {node}"));
            }
            if self.level[child as usize] + 1 != level {
                return Err(format!("child {child} is not one level below {node}"));
            }
            if self.node_box(child) != Some(self.entry_box(node, i)) {
                return Err(format!("box of child {child} in node {node} is not tight"));
            }
            self.check_node(child, items)?;
        }
        Ok(())
    }
}

/// Guttman's ChooseSubtree: the entry whose box needs the least enlargement to hold `bx`,
/// ties to the smaller volume, then the first.
#[inline]
fn choose_subtree(boxes: &[KeyBox], bx: &KeyBox) -> usize {
    let mut best = 0;
    let mut best_key = u128::MAX;
    for (i, b) in boxes.iter().enumerate() {
        let (mut volume, mut grown) = (1u64, 1u64);
        for a in 0..3 {
            volume *= u64::from(b.hi[a] - b.lo[a]) + 1;
            grown *= u64::from(b.hi[a].max(bx.hi[a]) - b.lo[a].min(bx.lo[a])) + 1;
        }
        // (enlargement, volume), compared at once.
        let key = (u128::from(grown - volume) << 64) | u128::from(volume);
        if key < best_key {
            best_key = key;
            best = i;
        }
    }
    best
}

/// The arrays of a compacted tree under construction.
struct Compacted {
    ids: Vec<u32>,
    count: Vec<u8>,
    parent: Vec<u32>,
    level: Vec<u8>,
    box_block: Vec<u32>,
    inner_boxes: Vec<KeyBox>,
    items: Vec<Item>,
    item_leaf: Vec<u32>,
}
