//! Deletion: Guttman's Delete (FindLeaf, remove the entry, CondenseTree, shorten the tree;
//! Guttman 1984, §3.3; Khan 2017, §2.4), for one item or a batch.
//!
//! A batch takes every entry out of its leaf node first and then condenses the nodes that
//! lost entries level by level, bottom-up: each node is tightened or dissolved once, and the
//! entries re-inserted from dissolved nodes are live ones only (removing items one at a time
//! re-inserts entries that are about to be removed too).

use std::cmp::Reverse;

use super::{NONE, RTree};
use crate::key::{KeyBox, pack};

impl RTree {
    /// Removes `item`; returns its box, `None` when it is not in the tree (Guttman Delete:
    /// FindLeaf, remove, CondenseTree, shorten the tree).
    pub fn remove(&mut self, item: u32) -> Option<KeyBox> {
        let bx = self.item_box(item)?;
        let (leaf, i) = self.locate(item, &bx)?;
        self.remove_slot(leaf, i);
        self.len -= 1;
        let mut nodes = std::mem::take(&mut self.touched);
        nodes.clear();
        nodes.push(leaf);
        self.condense(&mut nodes);
        self.touched = nodes;
        Some(bx)
    }

    /// Removes every item of `items` that is in the tree (each at most once): the entries
    /// leave their leaf nodes, then one CondenseTree pass runs over the nodes that lost
    /// entries.
    pub fn remove_many(&mut self, items: &[u32]) {
        let mut nodes = std::mem::take(&mut self.touched);
        nodes.clear();
        for &item in items {
            let Some(bx) = self.item_box(item) else {
                continue;
            };
            let Some((leaf, i)) = self.locate(item, &bx) else {
                continue;
            };
            self.remove_slot(leaf, i);
            self.len -= 1;
            nodes.push(leaf);
        }
        self.condense(&mut nodes);
        self.touched = nodes;
    }

    /// The leaf node and slot holding `item`: the leaf remembered for it (kept by
    /// `push_entry`), else Guttman's FindLeaf search.
    fn locate(&self, item: u32, bx: &KeyBox) -> Option<(u32, usize)> {
        let remembered = self.item_leaf.get(item as usize).and_then(|&leaf| {
            (leaf != NONE && (leaf as usize) < self.count.len() && self.level[leaf as usize] == 0)
                .then(|| (0..self.len_of(leaf)).find(|&i| self.id_at(leaf, i) == item))
                .flatten()
                .map(|i| (leaf, i))
        });
        remembered.or_else(|| self.find_leaf(self.root, item, bx))
    }

    fn find_leaf(&self, node: u32, item: u32, bx: &KeyBox) -> Option<(u32, usize)> {
        let n = self.len_of(node);
        if self.level[node as usize] == 0 {
            return (0..n)
                .find(|&i| self.id_at(node, i) == item)
                .map(|i| (node, i));
        }
        for i in 0..n {
            if self.entry_box(node, i).contains_box(bx) {
                if let Some(found) = self.find_leaf(self.id_at(node, i), item, bx) {
                    return Some(found);
                }
            }
        }
        None
    }

    /// CondenseTree over the leaf nodes `nodes` that lost entries, one level per round:
    /// a node below d entries leaves its parent and its entries wait for re-insertion, any
    /// other node's box is tightened in its parent; parents that changed go on to the next
    /// round. Then the tree is shortened and the waiting entries are re-inserted at their
    /// level.
    fn condense(&mut self, nodes: &mut Vec<u32>) {
        let mut orphans = std::mem::take(&mut self.orphans);
        orphans.clear();
        let mut next = Vec::new();
        while !nodes.is_empty() {
            nodes.sort_unstable();
            nodes.dedup();
            for &node in nodes.iter() {
                if node == self.root {
                    continue;
                }
                let parent = self.parent[node as usize];
                let i = self.index_of_child(parent, node);
                if self.len_of(node) < self.min_entries {
                    self.remove_slot(parent, i);
                    let level = self.level[node as usize];
                    for e in 0..self.len_of(node) {
                        orphans.push((self.entry_box(node, e), self.id_at(node, e), level));
                    }
                    self.free_node(node);
                    next.push(parent);
                } else if let Some(b) = self.node_box(node) {
                    // An unchanged box leaves everything above as it is.
                    if self.entry_box(parent, i) != b {
                        self.set_entry_box(parent, i, b);
                        next.push(parent);
                    }
                }
            }
            std::mem::swap(nodes, &mut next);
            next.clear();
        }
        self.shorten();
        // Higher levels first, each in lattice order (z, y, x of the lower corner): neighbours
        // descend the same paths.
        orphans.sort_unstable_by_key(|&(bx, id, level)| (Reverse(level), pack(bx.lo), id));
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
        let entries: Vec<(KeyBox, u32)> = (0..self.len_of(node))
            .map(|i| (self.entry_box(node, i), self.id_at(node, i)))
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
        while self.level[self.root as usize] > 0 && self.len_of(self.root) <= 1 {
            let old = self.root;
            if self.len_of(old) == 0 {
                // An empty inner root becomes an empty leaf node.
                self.level[old as usize] = 0;
                let block = std::mem::replace(&mut self.box_block[old as usize], NONE);
                if block != NONE {
                    self.free_blocks.push(block);
                }
                return;
            }
            self.root = self.id_at(old, 0);
            self.parent[self.root as usize] = NONE;
            self.free_node(old);
        }
    }
}
