use proptest::prelude::*;

use super::*;

fn cube(x: u16, y: u16, z: u16) -> KeyBox {
    KeyBox::cube([x, y, z])
}

#[test]
fn rejects_bad_orders() {
    assert!(RTree::new(0, 8).is_err());
    assert!(RTree::new(5, 8).is_err());
    assert!(RTree::new(1, 1).is_err());
    assert!(RTree::new(2, 4).is_ok());
}

#[test]
fn thesis_example_m2_splits_and_grows() {
    // Fig. 2.3: with M = 2, inserting A..D makes the tree grow to height 2+.
    let mut tree = RTree::new(1, 2).unwrap();
    for (i, b) in [cube(0, 0, 0), cube(1, 0, 0), cube(5, 5, 0), cube(6, 5, 0)]
        .iter()
        .enumerate()
    {
        tree.insert(i as u32, *b);
        tree.check_invariants().unwrap();
    }
    assert!(tree.height() >= 2);
    assert_eq!(tree.find_containing([5, 5, 0]).map(|f| f.0), Some(2));
    assert_eq!(tree.find_containing([3, 3, 3]), None);
    // With M = 4 one node holds all four.
    let mut wide = RTree::new(2, 4).unwrap();
    for i in 0..4u16 {
        wide.insert(u32::from(i), cube(i, 0, 0));
    }
    assert_eq!((wide.height(), wide.num_nodes()), (1, 1));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn invariants_hold_under_inserts_and_removes(
        order in prop::sample::select(vec![(1usize, 2usize), (2, 4), (3, 8), (4, 16), (6, 16)]),
        cells in prop::collection::btree_set((0u16..12, 0u16..12, 0u16..4), 1..300),
        remove_mask in prop::collection::vec(any::<bool>(), 300),
    ) {
        let (d, m) = order;
        let mut tree = RTree::new(d, m).unwrap();
        let cells: Vec<_> = cells.into_iter().collect();
        for (i, &(x, y, z)) in cells.iter().enumerate() {
            tree.insert(i as u32, cube(x, y, z));
        }
        tree.check_invariants().map_err(TestCaseError::fail)?;
        prop_assert_eq!(tree.len(), cells.len());
        let mut kept = Vec::new();
        for (i, &(x, y, z)) in cells.iter().enumerate() {
            if remove_mask[i] {
                prop_assert_eq!(tree.remove(i as u32), Some(cube(x, y, z)));
                tree.check_invariants().map_err(TestCaseError::fail)?;
            } else {
                kept.push((i as u32, cube(x, y, z)));
            }
        }
        prop_assert_eq!(tree.len(), kept.len());
        if remove_mask[299] {
            let map = tree.compact();
            tree.check_invariants().map_err(TestCaseError::fail)?;
            prop_assert_eq!(tree.num_nodes(), tree.count.len());
            for k in &mut kept {
                k.0 = map[k.0 as usize];
                prop_assert!(k.0 < tree.len() as u32);
            }
            // Inserting and removing still work after compaction.
            let extra = cube(40, 40, 40);
            tree.insert(tree.len() as u32, extra);
            prop_assert_eq!(tree.remove(tree.len() as u32 - 1), Some(extra));
            tree.check_invariants().map_err(TestCaseError::fail)?;
        }
        for &(id, b) in &kept {
            prop_assert_eq!(tree.find_containing(b.lo), Some((id, b)));
        }
        let query = KeyBox { lo: [2, 3, 0], hi: [7, 9, 2] };
        let mut found = Vec::new();
        tree.for_each_intersecting(&query, &mut |id, _| found.push(id));
        found.sort_unstable();
        let mut expected: Vec<u32> =
            kept.iter().filter(|(_, b)| b.intersects(&query)).map(|&(id, _)| id).collect();
        expected.sort_unstable();
        prop_assert_eq!(found, expected);
        let mut all = 0;
        tree.for_each_item(&mut |_, _| all += 1);
        prop_assert_eq!(all, kept.len());
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// A batch removal (with ids not in the tree and repeats) leaves a valid tree holding
    /// exactly the other items; item values follow their items through splits, removals
    /// and compaction.
    #[test]
    fn batch_removal_keeps_the_rest(
        order in prop::sample::select(vec![(1usize, 2usize), (2, 4), (3, 8), (4, 16)]),
        cells in prop::collection::btree_set((0u16..12, 0u16..12, 0u16..4), 1..300),
        remove_mask in prop::collection::vec(any::<bool>(), 300),
    ) {
        let (d, m) = order;
        let mut tree = RTree::new(d, m).unwrap();
        let cells: Vec<_> = cells.into_iter().collect();
        for (i, &(x, y, z)) in cells.iter().enumerate() {
            tree.store_item(i as u32, cube(x, y, z), 1000 + i as u32);
            tree.insert(i as u32, cube(x, y, z));
        }
        let mut gone: Vec<u32> = (0..cells.len() as u32).filter(|&i| remove_mask[i as usize]).collect();
        let kept: Vec<u32> = (0..cells.len() as u32).filter(|&i| !remove_mask[i as usize]).collect();
        gone.extend(gone.clone()); // repeats are skipped
        gone.push(cells.len() as u32 + 7); // so are ids never stored
        tree.remove_many(&gone);
        tree.check_invariants().map_err(TestCaseError::fail)?;
        prop_assert_eq!(tree.len(), kept.len());
        let mut left = Vec::new();
        tree.for_each_item(&mut |id, b| left.push((id, *b)));
        left.sort_unstable_by_key(|e| e.0);
        let expected: Vec<_> = kept.iter().map(|&i| {
            let (x, y, z) = cells[i as usize];
            (i, cube(x, y, z))
        }).collect();
        prop_assert_eq!(&left, &expected);
        for &i in &kept {
            prop_assert_eq!(tree.item_value(i), Some(1000 + i));
        }
        let map = tree.compact();
        for &i in &kept {
            prop_assert_eq!(tree.item_value(map[i as usize]), Some(1000 + i));
        }
    }
}
