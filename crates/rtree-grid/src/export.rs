//! Export: occupied cuboids as a PLY mesh, the whole map as an OctoMap tree (`.bt`).

use std::io::Write;

use nalgebra::Point3;
use raypath_io::octomap::{OcTree, OctreeLeaf, TREE_DEPTH};

use crate::RtreeGrid;
use crate::key::KeyBox;

impl RtreeGrid {
    /// Writes the occupied cuboids as an ASCII PLY mesh (8 vertices and 6 quads per
    /// cuboid, metres, world frame).
    pub fn write_occupied_ply<W: Write>(&self, mut out: W) -> std::io::Result<()> {
        let boxes: Vec<_> = self.cuboids().into_iter().filter(|c| c.occupied).collect();
        writeln!(
            out,
            "ply\nformat ascii 1.0\ncomment raypath-rtree-grid occupied cuboids"
        )?;
        writeln!(out, "element vertex {}", boxes.len() * 8)?;
        writeln!(out, "property float x\nproperty float y\nproperty float z")?;
        writeln!(out, "element face {}", boxes.len() * 6)?;
        writeln!(out, "property list uchar int vertex_indices\nend_header")?;
        for c in &boxes {
            for i in 0..8 {
                let x = if i & 1 == 0 { c.min_m[0] } else { c.max_m[0] };
                let y = if i & 2 == 0 { c.min_m[1] } else { c.max_m[1] };
                let z = if i & 4 == 0 { c.min_m[2] } else { c.max_m[2] };
                writeln!(out, "{x} {y} {z}")?;
            }
        }
        const FACES: [[usize; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        for b in 0..boxes.len() {
            for f in FACES {
                let v = f.map(|i| b * 8 + i);
                writeln!(out, "4 {} {} {} {}", v[0], v[1], v[2], v[3])?;
            }
        }
        Ok(())
    }

    /// The map as an OctoMap occupancy tree at the base resolution: every cuboid is cut into
    /// the largest octree-aligned cubes it contains (same keys as OctoMap, so the result
    /// can be written with [`raypath_io::octomap::write_bt`] and read by OctoMap).
    pub fn to_octree(&self) -> OcTree {
        let r = self.config().resolution_m;
        let mut leaves = Vec::new();
        self.for_each_cuboid(|c| decompose(&c.keys, c.occupied, r, [0; 3], 0, &mut leaves));
        OcTree {
            id: "OcTree".into(),
            resolution_m: r,
            nodes_in_file: 0,
            inner_nodes: 0,
            leaves,
        }
    }
}

/// Emits the octree cubes (node at `depth` with smallest key `key_min`) inside `bx`.
fn decompose(
    bx: &KeyBox,
    occupied: bool,
    resolution_m: f64,
    key_min: [u16; 3],
    depth: u8,
    out: &mut Vec<OctreeLeaf>,
) {
    let span = 1u32 << (TREE_DEPTH - depth);
    let node = KeyBox {
        lo: key_min,
        hi: key_min.map(|k| (u32::from(k) + span - 1) as u16),
    };
    if !node.intersects(bx) {
        return;
    }
    if depth > 0 && bx.contains_box(&node) {
        let lo = node.min_m(resolution_m);
        let size_m = resolution_m * f64::from(span);
        out.push(OctreeLeaf {
            center: Point3::new(
                lo[0] + size_m / 2.0,
                lo[1] + size_m / 2.0,
                lo[2] + size_m / 2.0,
            ),
            size_m,
            occupied,
            depth,
            key_min,
        });
        return;
    }
    let half = (span / 2) as u16;
    for child in 0..8u16 {
        let k = [
            key_min[0] + if child & 1 != 0 { half } else { 0 },
            key_min[1] + if child & 2 != 0 { half } else { 0 },
            key_min[2] + if child & 4 != 0 { half } else { 0 },
        ];
        decompose(bx, occupied, resolution_m, k, depth + 1, out);
    }
}
