//! `.bt` files we write, read by OctoMap itself: `bt2vrml` (octomap-tools) loads the tree with
//! `OcTree::readBinary` and writes one box per occupied leaf; the boxes must be our occupied
//! leaves (centre and size). Skips with a message when octomap-tools is not installed.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeSet;
use std::process::Command;

use nalgebra::Point3;
use raypath_io::octomap::{self, KEY_OFFSET, OcTree, OctreeLeaf, TREE_DEPTH};

/// A tree at 0.1 m: a block of finest leaves on both sides of the origin (occupied on a
/// diagonal pattern, free elsewhere) and coarse leaves (depth 13, 0.8 m) beside it.
fn tree() -> OcTree {
    let res = 0.1;
    let leaf = |key_min: [u16; 3], depth: u8, occupied: bool| {
        let span = f64::from(1u32 << (TREE_DEPTH - depth));
        OctreeLeaf {
            center: Point3::from(
                key_min.map(|k| (f64::from(k) - f64::from(KEY_OFFSET) + span / 2.0) * res),
            ),
            size_m: span * res,
            occupied,
            depth,
            key_min,
        }
    };
    let mut leaves = Vec::new();
    for i in -4i32..4 {
        for j in -4i32..4 {
            for k in 0i32..3 {
                let key = [i, j, k].map(|c| (c + KEY_OFFSET as i32) as u16);
                leaves.push(leaf(key, TREE_DEPTH, (i + j + k).rem_euclid(3) == 0));
            }
        }
    }
    for (n, occupied) in [(2u16, true), (3, false), (4, true)] {
        let key = [
            KEY_OFFSET as u16 + 8 * n,
            KEY_OFFSET as u16,
            KEY_OFFSET as u16,
        ];
        leaves.push(leaf(key, 13, occupied));
    }
    OcTree {
        id: "OcTree".into(),
        resolution_m: res,
        nodes_in_file: 0,
        inner_nodes: 0,
        leaves,
    }
}

/// Centre and size in millimetres, for exact comparison.
fn mm(center: [f64; 3], size: f64) -> [i64; 4] {
    let r = |v: f64| (v * 1000.0).round() as i64;
    [r(center[0]), r(center[1]), r(center[2]), r(size)]
}

/// The boxes of a `bt2vrml` file: `Transform { translation x y z` then `Box { size s s s}`.
fn vrml_boxes(text: &str) -> BTreeSet<[i64; 4]> {
    let mut boxes = BTreeSet::new();
    let mut center = None;
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        if let Some(i) = words.iter().position(|w| *w == "translation") {
            let v: Vec<f64> = words[i + 1..i + 4]
                .iter()
                .map(|w| w.parse().unwrap())
                .collect();
            center = Some([v[0], v[1], v[2]]);
        }
        if let Some(i) = words.iter().position(|w| *w == "size") {
            let size: f64 = words[i + 1].parse().unwrap();
            let c = center.take().expect("a Box follows its Transform");
            assert!(boxes.insert(mm(c, size)), "box {c:?} twice");
        }
    }
    boxes
}

#[test]
fn octomap_bt2vrml_reads_our_bt_files() {
    let tree = tree();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ours.bt");
    octomap::write_bt_file(&path, &tree).unwrap();

    // Our own reader first: same leaves.
    let read = octomap::read_bt(&path).unwrap();
    assert_eq!(read.leaves.len(), tree.leaves.len());
    let key = |l: &OctreeLeaf| (l.key_min, l.depth, l.occupied);
    let ours: BTreeSet<_> = tree.leaves.iter().map(key).collect();
    assert_eq!(read.leaves.iter().map(key).collect::<BTreeSet<_>>(), ours);

    let run = match Command::new("bt2vrml").arg(&path).output() {
        Ok(out) => out,
        Err(e) => {
            raypath_io::data::skip(format_args!("bt2vrml (octomap-tools) not runnable: {e}"));
            return;
        }
    };
    assert!(
        run.status.success(),
        "bt2vrml failed: {}{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let wrl = std::fs::read_to_string(dir.path().join("ours.bt.wrl")).unwrap();
    let theirs = vrml_boxes(&wrl);
    let want: BTreeSet<[i64; 4]> = read
        .leaves
        .iter()
        .filter(|l| l.occupied)
        .map(|l| mm(l.center.into(), l.size_m))
        .collect();
    assert_eq!(want.len(), tree.occupied_leaves());
    assert_eq!(theirs, want);
}
