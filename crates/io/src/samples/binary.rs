//! Binary formats: KITTI scans and labels, NCLT scans and packet streams, OctoMap trees and
//! scan graphs, PCD, Unix `compress` streams and SegComp images.

use std::path::Path;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3};

use super::Sample;
use crate::octomap::{self, OcTree, OctreeLeaf, ScanEdge, ScanGraph, ScanNode, TREE_DEPTH};
use crate::pcd::{self, DataEncoding, WriteOptions};
use crate::{Error, Location, Result, kitti, lzw, nclt};

/// A small cloud with intensities.
fn cloud(n: usize) -> PointCloud {
    let mut cloud = PointCloud::from_points(
        (0..n)
            .map(|i| Point3::new(i as f32 * 0.75 - 3.0, 2.0 - 0.5 * i as f32, 0.25 * i as f32))
            .collect(),
    );
    cloud.intensity = Some((0..n).map(|i| (i % 5) as f32 * 0.2).collect());
    cloud
}

/// KITTI `velodyne/*.bin` scans (12 points with reflectance, and a single point).
pub fn kitti_velodyne() -> Result<Vec<Sample>> {
    let name = Path::new("000000.bin");
    Ok(vec![
        Sample::new("000000.bin", kitti::encode_velodyne(&cloud(12), name)?),
        Sample::new("000000.bin", kitti::encode_velodyne(&cloud(1), name)?),
    ])
}

/// A SemanticKITTI `.label` file: classes with and without instance ids, an unknown class.
pub fn kitti_labels() -> Vec<Sample> {
    let labels: Vec<u8> = [
        0u32,
        1,
        10,
        40,
        44 | 3 << 16,
        252 | 7 << 16,
        99,
        0xffff_ffff,
    ]
    .iter()
    .flat_map(|v| v.to_le_bytes())
    .collect();
    vec![Sample::new("000000.label", labels)]
}

/// An NCLT `velodyne_sync/*.bin` scan with intensities and laser ids.
pub fn nclt_sync() -> Result<Vec<Sample>> {
    let mut c = cloud(10);
    c.label = Some((0..10).map(|i| i * 3).collect());
    c.intensity = Some((0..10).map(|i| (i * 25) as f32).collect());
    Ok(vec![Sample::new(
        "1326030975726043.bin",
        nclt::encode_velodyne_sync(&c, Path::new("1326030975726043.bin"))?,
    )])
}

/// A `velodyne_hits.bin` packet stream: packets of `counts[i]` hits.
pub fn nclt_hits() -> Vec<Sample> {
    let stream = |counts: &[u16]| {
        let mut bytes = Vec::new();
        for (i, &n) in counts.iter().enumerate() {
            bytes.extend_from_slice(&nclt::HITS_MAGIC.to_le_bytes());
            bytes.extend_from_slice(&u32::from(n).to_le_bytes());
            bytes.extend_from_slice(&(1_326_030_975_726_043 + i as u64).to_le_bytes());
            bytes.extend_from_slice(&[0xee; 4]);
            for k in 0..n {
                for v in [20000 + k, 20000, 20000 - k] {
                    bytes.extend_from_slice(&v.to_le_bytes());
                }
                bytes.extend_from_slice(&[k as u8, (k % 32) as u8]);
            }
        }
        bytes
    };
    vec![
        Sample::new("velodyne_hits.bin", stream(&[3, 0, 5])),
        Sample::new("velodyne_hits.bin", stream(&[1])),
    ]
}

/// A tree of a few finest-level leaves and a few coarse ones (in separate octants), and a
/// coarse-only tree.
pub fn octomap_bt() -> Result<Vec<Sample>> {
    let mut leaves: Vec<OctreeLeaf> = Vec::new();
    let mut taken = std::collections::HashSet::new();
    let res = 0.1;
    for i in 0..24u16 {
        let depth = if i % 4 == 0 { 12 } else { TREE_DEPTH };
        let span = 1u16 << (TREE_DEPTH - depth);
        let base: u16 = if depth == TREE_DEPTH { 32768 } else { 0 };
        let key = [0u16, 1, 2].map(|axis| base + (i * 5 + axis * 3 + i / 8) % 8 * span);
        if !taken.insert((key, depth)) {
            continue;
        }
        let span_f = f64::from(span);
        let center = key.map(|k| (f64::from(k) - 32768.0 + span_f / 2.0) * res);
        leaves.push(OctreeLeaf {
            center: Point3::from(center),
            size_m: span_f * res,
            occupied: i % 3 != 1,
            depth,
            key_min: key,
        });
    }
    let tree = |leaves: Vec<OctreeLeaf>| OcTree {
        id: "OcTree".into(),
        resolution_m: res,
        nodes_in_file: 0,
        inner_nodes: 0,
        leaves,
    };
    let mut fine = Vec::new();
    octomap::write_bt(&mut fine, &tree(leaves), Path::new("fuzz.bt"))?;
    // Root: child 0 free, child 1 occupied, child 7 inner with child 5 occupied.
    let mut coarse = b"# Octomap OcTree binary file\nid OcTree\nsize 5\nres 0.5\ndata\n".to_vec();
    coarse.extend_from_slice(&[0b0000_1001, 0b1100_0000, 0, 0b0000_1000]);
    Ok(vec![
        Sample::new("fuzz.bt", fine),
        Sample::new("fuzz.bt", coarse),
    ])
}

/// An OctoMap scan graph (`.graph`) of three nodes and one edge.
pub fn octomap_graph() -> Result<Vec<Sample>> {
    let nodes: Vec<ScanNode> = (0..3u32)
        .map(|id| ScanNode {
            id,
            world_from_sensor: Pose3::from_xyz_rpy(
                f64::from(id),
                2.0,
                0.5,
                0.1,
                -0.2,
                0.3 * f64::from(id),
            ),
            points: PointCloud::from_points(
                (0..2 + id)
                    .map(|i| Point3::new(i as f32 * 0.5, -(id as f32), 1.25 + i as f32))
                    .collect(),
            ),
        })
        .collect();
    let edges = vec![ScanEdge {
        first_id: 0,
        second_id: 2,
        first_from_second: nodes[0].world_from_sensor.inverse() * nodes[2].world_from_sensor,
        weight: 1.0,
    }];
    let mut bytes = Vec::new();
    octomap::write_graph(
        &mut bytes,
        &ScanGraph { nodes, edges },
        Path::new("fuzz.graph"),
    )?;
    Ok(vec![Sample::new("fuzz.graph", bytes)])
}

/// Every encoding of a small organized cloud with labels, colour and NaN points, and an
/// ASCII file with exotic fields.
pub fn pcd() -> Result<Vec<Sample>> {
    let n = 6;
    let cloud = PointCloud {
        points: (0..n)
            .map(|i| {
                if i % 5 == 3 {
                    Point3::new(f32::NAN, f32::NAN, f32::NAN)
                } else {
                    Point3::new(i as f32, -0.5 * i as f32, 2.0)
                }
            })
            .collect(),
        intensity: Some((0..n).map(|i| (i % 4) as f32 + 10.0).collect()),
        label: Some((0..n).map(|i| i as u32 * 3).collect()),
        rgb: Some((0..n).map(|i| i as u32 * 0x010203).collect()),
        width: 3,
        height: 2,
    };
    let mut seeds = Vec::new();
    for encoding in DataEncoding::ALL {
        let mut bytes = Vec::new();
        pcd::write_pcd_to(
            &mut bytes,
            &cloud,
            Path::new("fuzz.pcd"),
            &WriteOptions::new(encoding),
        )?;
        seeds.push(Sample::new("fuzz.pcd", bytes));
    }
    seeds.push(Sample::new(
        "fuzz.pcd",
        "VERSION .7\nFIELDS x y z w _ label\nSIZE 8 4 4 2 1 2\nTYPE F F F I U U\n\
         COUNT 1 1 1 2 3 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n\
         1.5 2 3 -1 4 0 0 0 7\nnan nan nan 0 0 1 1 1 8\n-2 1e3 0 5 5 2 2 2 9\n",
    ));
    Ok(seeds)
}

/// The Unix `compress` reference streams of the `.Z` decoder's tests (ncompress 4.2.4.6:
/// 9-bit codes with clear codes, 12-bit and 16-bit codes), and the SegComp test images.
pub const LZW_STREAMS: [(&str, &[u8]); 5] = [
    ("tobe.Z", include_bytes!("../../tests/data/lzw/tobe.Z")),
    (
        "mixed-b12.Z",
        include_bytes!("../../tests/data/lzw/mixed-b12.Z"),
    ),
    (
        "text-b16.Z",
        include_bytes!("../../tests/data/lzw/text-b16.Z"),
    ),
    (
        "synth.test.1.Z",
        include_bytes!("../../tests/data/segcomp/synth.test.1.Z"),
    ),
    (
        "synth.test.1.gt-seg.Z",
        include_bytes!("../../tests/data/segcomp/synth.test.1.gt-seg.Z"),
    ),
];

/// The Unix `compress` (`.Z`) reference streams of [`LZW_STREAMS`].
pub fn lzw() -> Vec<Sample> {
    LZW_STREAMS
        .iter()
        .map(|(name, bytes)| Sample::new(*name, *bytes))
        .collect()
}

fn unpack(name: &str) -> Result<Vec<u8>> {
    let (_, packed) = LZW_STREAMS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| Error::malformed(name, Location::File, "no such sample stream"))?;
    lzw::decompress(packed, 1 << 20)
        .map_err(|e| Error::malformed(name, Location::Byte(e.offset), e.reason))
}

/// SegComp range images: a hand-made 3 × 2 raster and the packed test image.
pub fn segcomp_range() -> Result<Vec<Sample>> {
    let mut bytes = b"3 rows\n2 columns\n".to_vec();
    bytes.extend(b"header line\n".repeat(8));
    bytes.extend(b"\n");
    for i in 0..6u32 {
        bytes.extend((0x5000_0000 | (i * 500)).to_be_bytes());
    }
    Ok(vec![
        Sample::new("perc.test.1", bytes),
        Sample::new("synth.test.1", unpack("synth.test.1.Z")?),
    ])
}

/// SegComp ground-truth segmentations in every raster layout the reader knows (Sun raster
/// with and without run-length encoding, binary and ASCII PGM, raw), and the packed test one.
pub fn segcomp_gt_seg() -> Result<Vec<Sample>> {
    let mut sun = Vec::new();
    for w in [0x59a6_6a95u32, 3, 2, 8, 12, 2, 1, 3] {
        sun.extend(w.to_be_bytes());
    }
    sun.extend([1, 2, 3]);
    sun.extend([0x80, 2, 10, 0, 0x80, 0, 11, 12, 0]);
    let mut plain = Vec::new();
    for w in [0x59a6_6a95u32, 3, 2, 8, 8, 1, 0, 0] {
        plain.extend(w.to_be_bytes());
    }
    plain.extend([10, 10, 11, 0, 12, 12, 13, 0]);
    let mut pgm = b"P5\n# c\n3 2\n300\n".to_vec();
    pgm.extend([0, 10, 0, 11, 1, 44, 0, 12, 0, 13, 0, 14]);
    let mut raw = b"2 rows\n3 columns\n".to_vec();
    raw.extend(b"x\n".repeat(9));
    raw.extend([10, 11, 12, 13, 14, 15]);
    Ok(vec![
        Sample::new("fuzz.gt-seg", sun),
        Sample::new("fuzz.gt-seg", plain),
        Sample::new("fuzz.gt-seg", pgm),
        Sample::new("fuzz.gt-seg", "P2 2 2 20\n1 2\n3 20\n"),
        Sample::new("fuzz.gt-seg", raw),
        Sample::new("synth.test.1.gt-seg", unpack("synth.test.1.gt-seg.Z")?),
    ])
}

/// SegComp ground-truth angle lists.
pub fn segcomp_gt_ang() -> Vec<Sample> {
    vec![
        Sample::new("fuzz.gt-ang", "3\n10 11 90\n11 12 45\n\n10 12 135\n"),
        Sample::new(
            "synth.test.1.gt-ang",
            &include_bytes!("../../tests/data/segcomp/synth.test.1.gt-ang")[..],
        ),
    ]
}
