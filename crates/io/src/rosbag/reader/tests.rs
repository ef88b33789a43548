//! The reader against the `mcap` crate's own: the same messages in the same order, for every
//! compression, whole or by their first bytes, and read again in and out of order.
#![allow(clippy::unwrap_used)]

use std::sync::Arc;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose3, Scan2};

use super::*;
use crate::rosbag::{BagCompression, BagWriteOptions, BagWriter, Stamp, Transform};

/// A bag of small chunks (so that many are decoded ahead) with scans, odometry, tf, clouds.
fn bag(path: &Path, compression: BagCompression) {
    let options = BagWriteOptions {
        compression,
        chunk_size_bytes: 3000,
    };
    let mut w = BagWriter::create(path, &options).unwrap();
    for k in 0..150 {
        let t = 10.0 + 0.1 * f64::from(k);
        let pose = Pose3::from_xyz_rpy(0.1 * f64::from(k), 0.0, 0.0, 0.0, 0.0, 0.01);
        w.write_odometry("/odom", t, "odom", "base_link", &pose)
            .unwrap();
        let tf = Transform {
            stamp: Stamp::from_secs(t).unwrap(),
            parent: "odom".into(),
            child: "base_link".into(),
            parent_from_child: pose,
        };
        w.write_tf("/tf", t, &[tf]).unwrap();
        let scan = Scan2 {
            angle_min_rad: -1.0,
            angle_increment_rad: 0.01,
            max_range_m: 20.0,
            ranges: (0..200).map(|i| f64::from((i * k) % 97) * 0.1).collect(),
            intensities: None,
        };
        w.write_scan("/scan", t, "laser", &scan).unwrap();
        if k % 3 == 0 {
            // Clouds larger than a chunk: each ends its chunk.
            let points = (0..400)
                .map(|i| Point3::new(i as f32, k as f32, (i % 7) as f32))
                .collect();
            w.write_cloud("/points", t, "laser", &PointCloud::from_points(points))
                .unwrap();
        }
    }
    w.finish().unwrap();
}

/// (topic, log time, message) of every message, by the `mcap` crate.
fn reference(path: &Path) -> Vec<(String, u64, Vec<u8>)> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            (m.channel.topic.clone(), m.log_time, m.data.to_vec())
        })
        .collect()
}

fn every_channel() -> Classify {
    Arc::new(|_| Some(1))
}

#[test]
fn messages_equal_the_mcap_crate() {
    let dir = tempfile::tempdir().unwrap();
    for compression in [
        BagCompression::None,
        BagCompression::Zstd,
        BagCompression::Lz4,
    ] {
        let path = dir.path().join(format!("{compression:?}.mcap"));
        bag(&path, compression);
        let want = reference(&path);
        assert_eq!(want.len(), 500);

        let mut reader = McapReader::open(&path, 0, every_channel()).unwrap();
        let mut got = Vec::new();
        let mut locs = Vec::new();
        while let Some(m) = reader.next_message().unwrap() {
            got.push((m.topic.to_string(), m.log_time, m.data.to_vec()));
            locs.push(m.loc);
        }
        assert_eq!(got, want, "{compression:?}");
        assert!(reader.take_warnings().is_empty());
        let stats = reader.channel_stats();
        assert_eq!(
            stats.values().map(|s| s.count).sum::<u64>(),
            want.len() as u64
        );

        // Only the first bytes of the clouds (decoded lazily): the same, cut.
        let mut reader = McapReader::open(&path, 0, every_channel()).unwrap();
        reader.set_prefix_only(1);
        let mut n = 0;
        while let Some(m) = reader.next_message().unwrap() {
            let full = &want[n].2;
            assert_eq!(m.data, &full[..full.len().min(PREFIX_BYTES - MESSAGE_HEAD)]);
            assert_eq!(m.loc, locs[n]);
            n += 1;
        }
        assert_eq!(n, want.len());

        // Read again: in order (chunks decoded ahead), then backwards.
        let mut reader = McapReader::open(&path, 0, Arc::new(|_| None)).unwrap();
        let mut cache = ChunkCache::default();
        for (i, loc) in locs.iter().enumerate() {
            let data = reader.reread(*loc, &mut cache).unwrap();
            assert_eq!(data.bytes(), &want[i].2[..]);
            drop(data);
            reader.prefetch(locs[i + 1..].iter().copied(), &mut cache);
        }
        for (i, loc) in locs.iter().enumerate().rev() {
            let data = reader.reread(*loc, &mut cache).unwrap();
            assert_eq!(data.bytes(), &want[i].2[..], "{compression:?} backwards");
        }
    }
}
