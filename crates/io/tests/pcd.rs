//! PCD reader and writer: known answers, round trips in all encodings, the SynPEB sample.
#![allow(clippy::unwrap_used)]

use nalgebra::{Point3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::pcd::{self, DataEncoding, LabelSource, PcdCloud, ReadOptions, WriteOptions, lzf};
use raypath_io::{Location, summarize};

fn write(cloud: &PointCloud, options: &WriteOptions) -> Vec<u8> {
    let mut bytes = Vec::new();
    pcd::write_pcd_to(&mut bytes, cloud, "mem.pcd".as_ref(), options).unwrap();
    bytes
}

fn read(bytes: &[u8], options: &ReadOptions) -> PcdCloud {
    pcd::read_pcd_bytes(bytes, "mem.pcd", options).unwrap()
}

fn same_f32(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn assert_same_cloud(a: &PointCloud, b: &PointCloud) {
    assert_eq!((a.width, a.height, a.len()), (b.width, b.height, b.len()));
    for (p, q) in a.points.iter().zip(&b.points) {
        assert!(
            p.iter().zip(q.iter()).all(|(u, v)| same_f32(*u, *v)),
            "{p} vs {q}"
        );
    }
    match (&a.intensity, &b.intensity) {
        (Some(x), Some(y)) => assert!(x.iter().zip(y).all(|(u, v)| same_f32(*u, *v))),
        (None, None) => {}
        _ => panic!("intensity presence differs"),
    }
    assert_eq!(a.label, b.label);
    assert_eq!(a.rgb, b.rgb);
}

/// A binary PCD with fields of every type and size around x y z.
fn exotic_binary() -> Vec<u8> {
    let mut bytes = b"# exotic\nVERSION 0.7\nFIELDS _ x y z normal t label rgb d\n\
        SIZE 1 4 4 4 2 8 1 4 8\nTYPE I F F F I F U F U\nCOUNT 3 1 1 1 3 1 1 1 1\n\
        WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n"
        .to_vec();
    for i in 0..2u8 {
        bytes.extend([0xff, 0xfe, 0xfd]); // _ padding
        for v in [1.5f32 + f32::from(i), -2.0, 0.25] {
            bytes.extend(v.to_le_bytes());
        }
        for v in [-7i16, 8, 9] {
            bytes.extend(v.to_le_bytes());
        }
        bytes.extend(1e300f64.to_le_bytes());
        bytes.push(40 + i);
        bytes.extend(f32::from_bits(0x00ab_cdef).to_le_bytes());
        bytes.extend(u64::MAX.to_le_bytes());
    }
    bytes
}

#[test]
fn skips_exotic_fields_and_reads_the_rest() {
    let read = read(&exotic_binary(), &ReadOptions::default());
    let cloud = &read.cloud;
    assert_eq!(
        cloud.points,
        vec![Point3::new(1.5, -2.0, 0.25), Point3::new(2.5, -2.0, 0.25)]
    );
    assert_eq!(cloud.label, Some(vec![40, 41]));
    assert_eq!(cloud.rgb, Some(vec![0x00ab_cdef; 2]));
    assert_eq!(cloud.intensity, None);
    assert_eq!(read.header.point_bytes(), 3 + 12 + 6 + 8 + 1 + 4 + 8);
}

#[test]
fn ascii_with_organized_nan_and_viewpoint() {
    let text = "VERSION .7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n\
                WIDTH 2\nHEIGHT 2\nVIEWPOINT 1 2 3 0.7071068 0 0 0.7071068\nPOINTS 4\nDATA ascii\n\
                1 2 3 10\nnan nan nan nan\n-1 0 0.5 11\n4 5 6 12\n";
    let read = read(text.as_bytes(), &ReadOptions::synpeb());
    assert!(read.cloud.is_organized());
    assert_eq!(read.cloud.label, Some(vec![10, 0, 11, 12]));
    assert_eq!(read.cloud.num_valid(), 3);
    assert!(!read.cloud.is_valid(1));
    let moved = read.cloud_from_sensor * Point3::new(1.0, 0.0, 0.0);
    assert!(
        (moved - Point3::new(1.0, 3.0, 3.0)).norm() < 1e-6,
        "{moved}"
    );
}

#[test]
fn errors_name_line_and_byte() {
    let header = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";
    let err = pcd::read_pcd_bytes(
        format!("{header}DATA ascii\n1 2 3\n1 2\n").as_bytes(),
        "a.pcd",
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "a.pcd:9: 2 values on the line, the header declares 3"
    );
    let err = pcd::read_pcd_bytes(
        format!("{header}DATA ascii\n1 2 3\n1 2 x\n").as_bytes(),
        "a.pcd",
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert_eq!(err.to_string(), "a.pcd:9: field \"z\": cannot parse \"x\"");
    let err = pcd::read_pcd_bytes(
        format!("{header}DATA ascii\n1 2 3\n").as_bytes(),
        "a.pcd",
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .starts_with("a.pcd:9: unexpected end of file while reading point 2 of 2"),
        "{err}"
    );
    let mut binary = format!("{header}DATA binary\n").into_bytes();
    let offset = binary.len() as u64;
    binary.extend([0u8; 20]);
    let err = pcd::read_pcd_bytes(&binary, "b.pcd", &ReadOptions::default()).unwrap_err();
    assert_eq!(err.location(), Location::Byte(offset + 12));
    assert!(err.to_string().contains("point 2 of 2"), "{err}");
    let err = pcd::read_pcd_bytes(
        format!("{header}DATA ascii\n1 2 3 4\n").as_bytes(),
        "a.pcd",
        &ReadOptions::synpeb(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("no field \"intensity\""), "{err}");
    // A non-integral label is an error naming the line.
    let text =
        "FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nWIDTH 1\nDATA ascii\n1 2 3 4.5\n";
    let err = pcd::read_pcd_bytes(text.as_bytes(), "c.pcd", &ReadOptions::synpeb()).unwrap_err();
    assert_eq!(err.location(), Location::Line(6));
}

#[test]
fn compressed_errors_name_offsets() {
    let cloud = PointCloud::from_points(vec![Point3::new(1.0, 2.0, 3.0); 50]);
    let mut bytes = write(&cloud, &WriteOptions::new(DataEncoding::BinaryCompressed));
    let data_offset = bytes
        .windows(23)
        .position(|w| w == b"DATA binary_compressed\n")
        .unwrap()
        + 23;
    // Claim a different uncompressed size.
    bytes[data_offset + 4] ^= 1;
    let err = pcd::read_pcd_bytes(&bytes, "z.pcd", &ReadOptions::default()).unwrap_err();
    assert_eq!(err.location(), Location::Byte(data_offset as u64 + 4));
    bytes[data_offset + 4] ^= 1;
    bytes.truncate(bytes.len() - 1);
    let err = pcd::read_pcd_bytes(&bytes, "z.pcd", &ReadOptions::default()).unwrap_err();
    assert_eq!(err.location(), Location::Byte(data_offset as u64 + 8));
}

#[test]
fn empty_cloud_round_trips() {
    for encoding in DataEncoding::ALL {
        let cloud = PointCloud::from_points(Vec::new());
        let back = read(
            &write(&cloud, &WriteOptions::new(encoding)),
            &ReadOptions::default(),
        );
        assert_same_cloud(&cloud, &back.cloud);
    }
}

#[test]
fn writer_rejects_inconsistent_clouds() {
    let mut cloud = PointCloud::from_points(vec![Point3::origin(); 3]);
    cloud.label = Some(vec![1]);
    let mut bytes = Vec::new();
    let err = pcd::write_pcd_to(
        &mut bytes,
        &cloud,
        "w.pcd".as_ref(),
        &WriteOptions::new(DataEncoding::Binary),
    )
    .unwrap_err();
    assert!(err.to_string().starts_with("w.pcd: cannot write"), "{err}");
}

fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![8 => -1e4f32..1e4, 1 => Just(f32::NAN), 1 => any::<f32>().prop_filter("finite", |v| v.is_finite())]
}

prop_compose! {
    fn arb_cloud()(width in 0usize..9, height in 1usize..5, organized in any::<bool>())
        (points in prop::collection::vec((coordinate(), coordinate(), coordinate()), width * height),
         intensity in prop::option::of(prop::collection::vec(coordinate(), width * height)),
         label in prop::option::of(prop::collection::vec(any::<u32>(), width * height)),
         rgb in prop::option::of(prop::collection::vec(0u32..=0xff_ffff, width * height)),
         width in Just(width), height in Just(height), organized in Just(organized))
        -> PointCloud {
        let n = points.len();
        PointCloud {
            points: points.into_iter().map(|(x, y, z)| Point3::new(x, y, z)).collect(),
            intensity,
            label,
            rgb,
            width: if organized { width } else { n },
            height: if organized { height } else { 1 },
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn round_trip_all_encodings(cloud in arb_cloud(),
                                t in prop::array::uniform3(-100.0f64..100.0),
                                axis_angle in prop::array::uniform3(-3.0f64..3.0)) {
        let pose = Pose3::from_parts(Vector3::from(t), UnitQuaternion::from_scaled_axis(Vector3::from(axis_angle)));
        for encoding in DataEncoding::ALL {
            let options = WriteOptions { encoding, cloud_from_sensor: pose };
            let back = read(&write(&cloud, &options), &ReadOptions::default());
            assert_same_cloud(&cloud, &back.cloud);
            prop_assert_eq!(back.header.data, encoding);
            let error = pose.inverse() * back.cloud_from_sensor;
            prop_assert!(error.translation().norm() < 1e-9 && error.rotation().angle() < 1e-9);
        }
    }
}

#[test]
fn lzf_is_reachable_from_the_public_api() {
    let data = b"raypath raypath raypath".repeat(10);
    assert_eq!(
        lzf::decompress(&lzf::compress(&data), data.len()).unwrap(),
        data
    );
}

#[test]
fn synpeb_sample_reads_and_round_trips() {
    let Some(path) = raypath_io::data::require("planes/synpeb-sample-100x100.pcd") else {
        return;
    };
    let read = pcd::read_pcd(&path, &ReadOptions::synpeb()).unwrap();
    let cloud = &read.cloud;
    assert_eq!((cloud.width, cloud.height, cloud.len()), (100, 100, 10_000));
    assert_eq!(read.header.data, DataEncoding::Ascii);
    assert_eq!(cloud.points[0], Point3::new(4.302361, -1.651522, 1.495239));
    let labels = cloud.label.as_ref().unwrap();
    let mut distinct: Vec<u32> = labels.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert_eq!(
        distinct,
        vec![3, 14, 15, 18, 30, 31, 35, 36, 38, 44, 45, 46, 47]
    );
    assert_eq!(labels.iter().filter(|&&l| l == 18).count(), 3068);
    assert_eq!(labels.iter().filter(|&&l| l == 3).count(), 20);
    assert_eq!(read.cloud_from_sensor, Pose3::identity());

    let dir = tempfile::tempdir().unwrap();
    for encoding in DataEncoding::ALL {
        let out = dir.path().join(format!("synpeb-{encoding}.pcd"));
        pcd::write_pcd(&out, cloud, encoding).unwrap();
        let back = pcd::read_pcd(&out, &ReadOptions::default()).unwrap();
        assert_eq!(back.header.data, encoding);
        assert_same_cloud(cloud, &back.cloud);
        // Written with a `label` field, the labels come back without asking.
        let summary = summarize(&out).unwrap();
        assert_eq!(summary.labels.as_deref(), Some(&distinct[..]));
        assert_eq!(summary.extra["label_field"], "label");
    }
    let compressed = std::fs::metadata(dir.path().join("synpeb-binary_compressed.pcd"))
        .unwrap()
        .len();
    let binary = std::fs::metadata(dir.path().join("synpeb-binary.pcd"))
        .unwrap()
        .len();
    assert!(compressed < binary, "{compressed} ≥ {binary}");

    let summary = summarize(&path).unwrap();
    assert_eq!(summary.format, "pcd");
    assert_eq!(
        (summary.points, summary.width, summary.height),
        (Some(10_000), Some(100), Some(100))
    );
    assert_eq!(summary.labels, Some(distinct));
    assert_eq!(summary.extra["label_field"], "intensity");
    assert_eq!(summary.extra["data"], "ascii");
    assert_eq!(
        summary.extra["fields"],
        serde_json::json!(["x", "y", "z", "intensity"])
    );
    let bbox = summary.bbox.unwrap();
    assert!(bbox.min[0] > -10.0 && bbox.max[0] < 10.0 && bbox.min[0] < bbox.max[0]);

    // Reading labels from a field that the file has: `intensity` by name gives the same.
    let by_name = pcd::read_pcd(
        &path,
        &ReadOptions {
            label_from: LabelSource::Field("intensity".into()),
        },
    )
    .unwrap();
    assert_eq!(by_name.cloud.label, cloud.label);
}
