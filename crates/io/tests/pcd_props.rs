//! PCD reader robustness: thousands of truncated and mutated files never make it panic.
#![allow(clippy::unwrap_used)]

use nalgebra::Point3;
use proptest::prelude::*;
use raypath_geometry::PointCloud;
use raypath_io::pcd::{self, DataEncoding, LabelSource, ReadOptions, WriteOptions};

/// Valid files of every encoding, with labels, colour, NaN points and exotic skipped fields.
fn bases() -> Vec<Vec<u8>> {
    let n = 12;
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
        width: 4,
        height: 3,
    };
    let mut files: Vec<Vec<u8>> = DataEncoding::ALL
        .iter()
        .map(|&encoding| {
            let mut bytes = Vec::new();
            pcd::write_pcd_to(
                &mut bytes,
                &cloud,
                "p.pcd".as_ref(),
                &WriteOptions::new(encoding),
            )
            .unwrap();
            bytes
        })
        .collect();
    let mut exotic = b"VERSION .7\nFIELDS x y z w _ label\nSIZE 8 4 4 2 1 2\nTYPE F F F I U U\n\
        COUNT 1 1 1 2 3 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n"
        .to_vec();
    exotic.extend_from_slice(
        b"1.5 2 3 -1 4 0 0 0 7\nnan nan nan 0 0 1 1 1 8\n-2 1e3 0 5 5 2 2 2 9\n",
    );
    files.push(exotic);
    files
}

fn mutated() -> impl Strategy<Value = (Vec<u8>, usize)> {
    let bases = bases();
    (
        0..bases.len(),
        0.0f64..1.0,
        prop::collection::vec((0.0f64..1.0, any::<u8>()), 0..6),
        0usize..4,
    )
        .prop_map(move |(which, cut, edits, option)| {
            let mut bytes = bases[which].clone();
            // Half the cases keep the whole file and only mutate it.
            if cut < 0.5 {
                let keep = (cut * 2.0 * bytes.len() as f64) as usize;
                bytes.truncate(keep);
            }
            for (at, value) in edits {
                if !bytes.is_empty() {
                    let i = ((at * bytes.len() as f64) as usize).min(bytes.len() - 1);
                    bytes[i] = value;
                }
            }
            (bytes, option)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn truncated_and_mutated_files_never_panic((bytes, option) in mutated()) {
        let label_from = match option {
            0 => LabelSource::LabelField,
            1 => LabelSource::Intensity,
            2 => LabelSource::Field("w".into()),
            _ => LabelSource::None,
        };
        let options = ReadOptions { label_from };
        if let Ok(read) = pcd::read_pcd_bytes(&bytes, "m.pcd", &options) {
            // Whatever is accepted is consistent.
            prop_assert!(read.cloud.validate().is_ok());
            prop_assert_eq!(read.cloud.len(), read.header.points);
        }
    }
}

#[test]
fn unmutated_bases_read() {
    for bytes in bases() {
        let read = pcd::read_pcd_bytes(&bytes, "b.pcd", &ReadOptions::default()).unwrap();
        assert_eq!(read.cloud.len(), read.header.points);
    }
}
