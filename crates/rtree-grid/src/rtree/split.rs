//! Guttman's quadratic split (Khan 2017, §2.4; Guttman 1984, §3.5.2).

use super::RTree;

impl RTree {
    /// Splits the overflowing `node` (M entries and the spilled one) into itself and a new
    /// sibling at the same level; returns the sibling.
    ///
    /// PickSeeds takes the pair with the largest `J = vol(R_ij) − vol(R_i) − vol(R_j)`;
    /// PickNext repeatedly assigns the entry with the largest `|d1 − d2|` to the group that
    /// needs the smaller enlargement (ties: smaller volume, then fewer entries); when a group
    /// needs all remaining entries to reach d, it gets them.
    pub(super) fn split(&mut self, node: u32) -> u32 {
        let mut entries = std::mem::take(&mut self.scratch);
        entries.clear();
        for i in 0..self.len_of(node).min(self.cap) {
            entries.push((self.entry_box(node, i), self.id_at(node, i)));
        }
        entries.extend(self.spill.take());
        let n = entries.len();
        // PickSeeds.
        let (mut seed_a, mut seed_b, mut worst) = (0, 1, i64::MIN);
        for i in 0..n {
            for j in i + 1..n {
                let (a, b) = (&entries[i].0, &entries[j].0);
                let waste = a.union(b).volume() as i64 - a.volume() as i64 - b.volume() as i64;
                if waste > worst {
                    worst = waste;
                    (seed_a, seed_b) = (i, j);
                }
            }
        }
        let level = self.level[node as usize];
        let sibling = self.alloc_node(level);
        self.count[node as usize] = 0;
        let mut assigned = std::mem::take(&mut self.assigned);
        assigned.clear();
        assigned.resize(n, false);
        assigned[seed_a] = true;
        assigned[seed_b] = true;
        let (mut box_a, mut box_b) = (entries[seed_a].0, entries[seed_b].0);
        let (mut count_a, mut count_b) = (1usize, 1usize);
        self.push_entry(node, entries[seed_a].0, entries[seed_a].1);
        self.push_entry(sibling, entries[seed_b].0, entries[seed_b].1);
        let mut remaining = n - 2;
        while remaining > 0 {
            let to_a_all = count_a + remaining <= self.min_entries;
            let to_b_all = count_b + remaining <= self.min_entries;
            if to_a_all || to_b_all {
                for (i, e) in entries.iter().enumerate() {
                    if !assigned[i] {
                        let target = if to_a_all { node } else { sibling };
                        self.push_entry(target, e.0, e.1);
                    }
                }
                break;
            }
            // PickNext.
            let (mut next, mut best_diff) = (usize::MAX, -1i64);
            let (mut next_da, mut next_db) = (0u64, 0u64);
            for (i, e) in entries.iter().enumerate() {
                if assigned[i] {
                    continue;
                }
                let da = box_a.enlargement(&e.0);
                let db = box_b.enlargement(&e.0);
                let diff = (da as i64 - db as i64).abs();
                if diff > best_diff {
                    (next, best_diff, next_da, next_db) = (i, diff, da, db);
                }
            }
            assigned[next] = true;
            remaining -= 1;
            let to_a = (next_da, box_a.volume(), count_a) <= (next_db, box_b.volume(), count_b);
            let (bx, id) = entries[next];
            if to_a {
                box_a = box_a.union(&bx);
                count_a += 1;
                self.push_entry(node, bx, id);
            } else {
                box_b = box_b.union(&bx);
                count_b += 1;
                self.push_entry(sibling, bx, id);
            }
        }
        self.scratch = entries;
        self.assigned = assigned;
        sibling
    }
}
