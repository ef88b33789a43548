//! rosbag2 MCAP: round trips through our writer (CARMEN and KITTI to bags and back), bag
//! layouts (directory, file, compression, unindexed, truncated), topic choice, info, and the
//! "not a ROS 2 bag" answer for ROS 1 recordings.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::Point3;
use raypath_geometry::{PointCloud, Pose2, Pose3, Range, Scan2};
use raypath_io::rosbag::{self, BagCompression, BagWriteOptions, BagWriter, Stamp, Transform};
use raypath_io::sequence::{
    Origin, PlanarFrame, PlanarOptions, SweepFormat, SweepOptions, SweepSequence, Topics,
    read_planar,
};

mod common;
use common::{assert_pose2, assert_pose3, assert_same_scan};

fn opts(compression: BagCompression) -> BagWriteOptions {
    BagWriteOptions {
        compression,
        chunk_size_bytes: 64 * 1024,
    }
}

fn assert_same_frames(a: &[PlanarFrame], b: &[PlanarFrame]) {
    assert_eq!(a.len(), b.len());
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        let what = format!("frame {k}");
        assert!((x.stamp_secs - y.stamp_secs).abs() < 1e-9, "{what}: stamp");
        assert_same_scan(&x.scan, &y.scan, &what);
        assert_pose2(&x.world_from_robot, &y.world_from_robot, 1e-9, &what);
        assert_pose2(&x.world_from_laser, &y.world_from_laser, 1e-9, &what);
        match (&x.reference, &y.reference) {
            (Some(p), Some(q)) => assert_pose2(p, q, 1e-9, &what),
            (None, None) => {}
            other => panic!("{what}: reference {other:?}"),
        }
    }
}

fn synthetic_frames(n: usize, moving_mount: bool, reference: bool) -> Vec<PlanarFrame> {
    (0..n)
        .map(|k| {
            let t = 1_700_000_000.0 + 0.1 * k as f64;
            let robot = Pose2::new(0.3 * k as f64, -0.1 * k as f64, 0.05 * k as f64 - 1.0);
            let mount = if moving_mount {
                Pose2::new(0.2, 0.01 * k as f64, 0.02 * k as f64)
            } else {
                Pose2::new(0.2, 0.0, 0.0)
            };
            let ranges: Vec<f64> = (0..37)
                .map(|i| {
                    if i % 7 == 3 {
                        30.0
                    } else {
                        1.0 + 0.125 * i as f64 + k as f64
                    }
                })
                .collect();
            PlanarFrame {
                stamp_secs: t,
                ipc_stamp_secs: None,
                scan: Scan2 {
                    angle_min_rad: -std::f64::consts::FRAC_PI_2,
                    angle_increment_rad: std::f64::consts::PI / 36.0,
                    max_range_m: 30.0,
                    intensities: Some(ranges.iter().map(|r| r * 2.0).collect()),
                    ranges,
                },
                world_from_robot: robot,
                world_from_laser: robot * mount,
                reference: reference.then(|| Pose2::new(0.31 * k as f64, 0.0, 0.1) * mount),
                origin: Origin::Line(k as u64 + 1),
            }
        })
        .collect()
}

fn read_bag(path: &Path) -> Vec<PlanarFrame> {
    read_planar(path, &PlanarOptions::default()).unwrap()
}

#[test]
fn synthetic_round_trips_every_layout() {
    let dir = tempfile::tempdir().unwrap();
    for (moving, reference) in [(false, false), (true, true), (false, true)] {
        let frames = synthetic_frames(50, moving, reference);
        for compression in [
            BagCompression::Zstd,
            BagCompression::Lz4,
            BagCompression::None,
        ] {
            for as_dir in [false, true] {
                let name = format!("b-{moving}-{reference}-{compression:?}-{as_dir}");
                let path = if as_dir {
                    dir.path().join(&name)
                } else {
                    dir.path().join(format!("{name}.mcap"))
                };
                rosbag::write_planar(&path, &frames, &opts(compression)).unwrap();
                assert!(rosbag::is_bag(&path).unwrap());
                let back = read_bag(&path);
                assert_same_frames(&frames, &back);
                assert!(matches!(back[0].origin, Origin::LogTimeNs(_)));
            }
        }
    }
}

#[test]
fn carmen_round_trip() {
    let Some(log) = raypath_io::data::require("carmen/corrected/intel-corrected.log.gz") else {
        return;
    };
    let frames = read_planar(&log, &PlanarOptions::default()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("intel");
    rosbag::write_planar(&path, &frames, &BagWriteOptions::default()).unwrap();
    assert!(path.join("metadata.yaml").is_file());
    let back = read_bag(&path);
    assert_eq!(back.len(), 910);
    assert_same_frames(&frames, &back);
    // The mounting varies in the corrected log (corrected laser pose vs raw odometry): it
    // went to /tf with each scan.
    let info = rosbag::info(&path).unwrap();
    let counts: BTreeMap<_, _> = info
        .topics
        .iter()
        .map(|t| (t.name.as_str(), t.message_count))
        .collect();
    assert_eq!(counts.get("/scan"), Some(&910));
    assert_eq!(counts.get("/odom"), Some(&910));
    assert_eq!(counts.get("/tf"), Some(&910));
}

fn kitti_sequence(dir: &Path) -> SweepSequence {
    SweepSequence::open(dir, &SweepOptions::default()).unwrap()
}

#[test]
fn kitti_round_trip() {
    let Some(seq_dir) = raypath_io::data::require("kitti/sequences/00") else {
        return;
    };
    let seq = kitti_sequence(&seq_dir);
    let dir = tempfile::tempdir().unwrap();
    for compression in [BagCompression::Zstd, BagCompression::None] {
        let path = dir.path().join(format!("kitti-{compression:?}.mcap"));
        rosbag::write_sweeps(&path, &seq, &opts(compression)).unwrap();
        let back = SweepSequence::open(&path, &SweepOptions::default()).unwrap();
        assert_eq!(back.format, SweepFormat::Bag);
        assert_eq!(back.len(), seq.len());
        for i in 0..seq.len() {
            assert!((back.stamps_secs[i] - seq.stamps_secs[i]).abs() < 1e-9);
            let what = format!("sweep {i}");
            assert_pose3(
                &back.odometry.as_ref().unwrap()[i],
                &seq.odometry.as_ref().unwrap()[i],
                1e-9,
                &what,
            );
            assert_pose3(
                &back.reference.as_ref().unwrap()[i],
                &seq.reference.as_ref().unwrap()[i],
                1e-9,
                &what,
            );
        }
        // Random access, backwards, and again.
        for i in [3, 0, 9, 3] {
            assert_eq!(back.sweep(i).unwrap(), seq.sweep(i).unwrap(), "sweep {i}");
        }
        assert_eq!(back.count_points().unwrap(), seq.count_points().unwrap());
    }
}

fn organized_cloud(k: usize) -> PointCloud {
    let (w, h) = (8, 4);
    let mut cloud = PointCloud::from_points(
        (0..w * h)
            .map(|i| {
                if i % 5 == 2 {
                    Point3::new(f32::NAN, f32::NAN, f32::NAN)
                } else {
                    Point3::new(i as f32, k as f32, 0.5)
                }
            })
            .collect(),
    );
    cloud.intensity = Some((0..w * h).map(|i| i as f32).collect());
    cloud.width = w;
    cloud.height = h;
    cloud
}

#[test]
fn organized_clouds_and_tf_only_poses() {
    let n = 12;
    let stamps: Vec<f64> = (0..n).map(|k| 100.0 + k as f64 * 0.1).collect();
    let odometry: Vec<Pose3> = (0..n)
        .map(|k| Pose3::from_xyz_rpy(k as f64, 0.5, 0.0, 0.0, 0.1, 0.02 * k as f64))
        .collect();
    let seq = SweepSequence::from_fn(
        "memory",
        SweepFormat::Bag,
        stamps.clone(),
        None,
        Some(odometry.clone()),
        Box::new(|i| Ok(organized_cloud(i))),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("org.mcap");
    rosbag::write_sweeps(&path, &seq, &opts(BagCompression::Lz4)).unwrap();
    let back = SweepSequence::open(&path, &SweepOptions::default()).unwrap();
    assert!(back.reference.is_none());
    for (k, want_pose) in odometry.iter().enumerate() {
        assert_pose3(
            &back.odometry.as_ref().unwrap()[k],
            want_pose,
            1e-9,
            "odometry",
        );
        let cloud = back.sweep(k).unwrap();
        let want = organized_cloud(k);
        assert_eq!((cloud.width, cloud.height), (8, 4));
        assert_eq!(cloud.intensity, want.intensity);
        for i in 0..cloud.len() {
            assert_eq!(cloud.is_valid(i), want.is_valid(i));
            if want.is_valid(i) {
                assert_eq!(cloud.points[i], want.points[i]);
            }
        }
    }
}

/// A bag written message by message: odometry at 50 Hz, scans at 10 Hz in a `laser` frame
/// mounted through `/tf_static`, a second scan topic, and a reference topic.
fn hand_written(path: &Path, second_scan_topic: bool) {
    let mut w = BagWriter::create(path, &opts(BagCompression::Zstd)).unwrap();
    let mount = Pose3::from_xyz_rpy(0.3, 0.0, 0.2, 0.0, 0.0, 0.5);
    let tf = Transform {
        stamp: Stamp::default(),
        parent: "base_link".into(),
        child: "laser".into(),
        parent_from_child: mount,
    };
    w.write_tf("/tf_static", 10.0, &[tf]).unwrap();
    for k in 0..=100 {
        let t = 10.0 + 0.02 * k as f64;
        let pose = Pose3::from_xyz_rpy(t - 10.0, 0.0, 0.0, 0.0, 0.0, 0.1 * (t - 10.0));
        w.write_odometry("/odom", t, "odom", "base_link", &pose)
            .unwrap();
        w.write_pose(
            "/truth",
            t,
            "map",
            &Pose3::from_xyz_rpy(2.0 * (t - 10.0), 1.0, 0.0, 0.0, 0.0, 0.0),
        )
        .unwrap();
    }
    let scan = Scan2 {
        angle_min_rad: -1.0,
        angle_increment_rad: 0.5,
        max_range_m: 20.0,
        ranges: vec![1.0, f64::INFINITY, 3.0, 4.0, 5.0],
        intensities: None,
    };
    for k in 0..20 {
        let t = 10.01 + 0.1 * k as f64;
        w.write_scan("/scan", t, "laser", &scan).unwrap();
        if second_scan_topic {
            w.write_scan("/rear_scan", t, "laser", &scan).unwrap();
        }
    }
    w.finish().unwrap();
}

#[test]
fn poses_are_interpolated_and_composed() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("hand.mcap");
    hand_written(&path, false);
    let frames = read_bag(&path);
    assert_eq!(frames.len(), 20);
    let mount = Pose3::from_xyz_rpy(0.3, 0.0, 0.2, 0.0, 0.0, 0.5);
    for f in &frames {
        let dt = f.stamp_secs - 10.0;
        let robot = Pose3::from_xyz_rpy(dt, 0.0, 0.0, 0.0, 0.0, 0.1 * dt);
        assert_pose2(&f.world_from_robot, &robot.to_planar(), 1e-9, "robot");
        assert_pose2(
            &f.world_from_laser,
            &(robot * mount).to_planar(),
            1e-9,
            "laser",
        );
        let truth = Pose3::from_xyz_rpy(2.0 * dt, 1.0, 0.0, 0.0, 0.0, 0.0) * mount;
        assert_pose2(
            f.reference.as_ref().unwrap(),
            &truth.to_planar(),
            1e-9,
            "reference",
        );
        // +inf: beyond range, stored as range_max (a no-return).
        assert_eq!(f.scan.ranges[1], 20.0);
        assert_eq!(f.scan.range(1), Range::NoReturn);
    }
    let info = rosbag::info(&path).unwrap();
    assert!(info.indexed);
    assert_eq!(info.profile, "ros2");
    assert_eq!(info.compression, vec!["zstd".to_string()]);
    let odom = info.topics.iter().find(|t| t.name == "/odom").unwrap();
    assert_eq!(odom.type_name, "nav_msgs/msg/Odometry");
    assert_eq!(odom.message_count, 101);
    assert!((odom.rate_hz.unwrap() - 50.0).abs() < 1e-6);
    assert!((odom.first_secs.unwrap() - 10.0).abs() < 1e-9);
    assert!((info.duration_secs - 2.0).abs() < 1e-9);
    let text = info.to_string();
    assert!(
        text.contains("/scan") && text.contains("sensor_msgs/msg/LaserScan"),
        "{text}"
    );
    let json = serde_json::to_value(&info).unwrap();
    assert_eq!(json["topics"][0]["type"], "nav_msgs/msg/Odometry");
}

#[test]
fn topic_choice() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.mcap");
    hand_written(&path, true);
    let e = rosbag::open_planar(&path, &Topics::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("/rear_scan") && e.contains("/scan") && e.contains("--scan-topic"),
        "{e}"
    );
    let topics = Topics {
        scan: Some("/rear_scan".into()),
        ..Topics::default()
    };
    assert_eq!(rosbag::open_planar(&path, &topics).unwrap().count(), 20);
    let wrong = Topics {
        scan: Some("/odom".into()),
        ..Topics::default()
    };
    let e = rosbag::open_planar(&path, &wrong)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("--scan-topic /odom"), "{e}");
    let e = rosbag::open_sweeps(&path, &Topics::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("no supported topics") && e.contains("PointCloud2"),
        "{e}"
    );
    // An explicit fixed frame the tree does not know.
    let frame = Topics {
        scan: Some("/scan".into()),
        frame: Some("world".into()),
        ..Topics::default()
    };
    let frames = rosbag::open_planar(&path, &frame).unwrap().count();
    assert_eq!(
        frames, 0,
        "every scan is skipped: tf has no frame \"world\""
    );
}

fn summary_start(bytes: &[u8]) -> usize {
    // Footer: opcode, length, summary_start, summary_offset_start, crc, then the magic.
    let footer = bytes.len() - 8 - 20;
    u64::from_le_bytes(bytes[footer..footer + 8].try_into().unwrap()) as usize
}

#[test]
fn unindexed_and_truncated_files() {
    let dir = tempfile::tempdir().unwrap();
    let frames = synthetic_frames(200, false, false);
    let full = dir.path().join("full.mcap");
    rosbag::write_planar(&full, &frames, &opts(BagCompression::Zstd)).unwrap();
    let bytes = std::fs::read(&full).unwrap();

    // No summary, no footer: a linear scan reads everything.
    let unindexed = dir.path().join("unindexed.mcap");
    std::fs::write(&unindexed, &bytes[..summary_start(&bytes)]).unwrap();
    assert_same_frames(&frames, &read_bag(&unindexed));
    let info = rosbag::info(&unindexed).unwrap();
    assert!(!info.indexed);
    assert_eq!(info.message_count, 600 + 1);
    assert!(
        info.warnings.iter().any(|w| w.contains("footer")),
        "{:?}",
        info.warnings
    );

    // Cut inside the last chunk: the messages before the cut, a warning naming the place.
    for cut in [bytes.len() / 2, bytes.len() * 2 / 3] {
        let truncated = dir.path().join(format!("cut{cut}.mcap"));
        std::fs::write(&truncated, &bytes[..cut]).unwrap();
        let mut scans = rosbag::BagScans::open(&truncated, &Topics::default()).unwrap();
        let got: Vec<PlanarFrame> = scans.by_ref().map(|f| f.unwrap()).collect();
        assert!(!got.is_empty() && got.len() < frames.len());
        assert_same_frames(&frames[..got.len()], &got);
        let warnings = scans.warnings().join("\n");
        assert!(warnings.contains("truncated"), "{warnings}");
        assert!(warnings.contains("log time"), "{warnings}");
    }
}

#[test]
fn bad_messages_name_topic_and_log_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mcap");
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .compression(None)
        .create(std::io::BufWriter::new(
            std::fs::File::create(&path).unwrap(),
        ))
        .unwrap();
    let schema = w
        .add_schema("sensor_msgs/msg/LaserScan", "ros2msg", b"")
        .unwrap();
    let channel = w
        .add_channel(schema, "/scan", "cdr", &BTreeMap::new())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 0,
        log_time: 5_000_000_000,
        publish_time: 0,
    };
    w.write_to_known_channel(&header, &[0, 1, 0, 0, 1, 2, 3])
        .unwrap();
    w.finish().unwrap();
    drop(w);
    let e = read_planar(&path, &PlanarOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("/scan at log time 5.000000000 s: CDR byte"),
        "{e}"
    );
    assert!(e.contains("bad.mcap: byte "), "{e}");
}

/// A small ROS 1 recording like the `mcap` repository's samples (whose files are Git LFS
/// objects and so not available here): profile `ros1`, `ros1msg` schemas, `ros1` messages.
fn ros1_bag(path: &Path) {
    let mut w = mcap::WriteOptions::new()
        .profile("ros1")
        .create(std::io::BufWriter::new(
            std::fs::File::create(path).unwrap(),
        ))
        .unwrap();
    let schema = w
        .add_schema(
            "sensor_msgs/LaserScan",
            "ros1msg",
            b"Header header\nfloat32 angle_min\n",
        )
        .unwrap();
    let channel = w
        .add_channel(schema, "/scan", "ros1", &BTreeMap::new())
        .unwrap();
    for k in 0..3u32 {
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: k,
            log_time: u64::from(k) * 100_000_000,
            publish_time: 0,
        };
        w.write_to_known_channel(&header, &[1, 2, 3, 4]).unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn ros1_recordings_are_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("demo-ros1.mcap");
    ros1_bag(&path);
    let e = rosbag::open_planar(&path, &Topics::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("not a ROS 2 bag") && e.contains("ros1"), "{e}");
    let e = rosbag::open_sweeps(&path, &Topics::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("not a ROS 2 bag"), "{e}");
    // info still lists what is there.
    let info = rosbag::info(&path).unwrap();
    assert_eq!(info.profile, "ros1");
    assert_eq!(info.topics[0].message_encoding, "ros1");
    // A recording without a profile and with ROS 1 messages: no supported topics.
    let mut w = mcap::WriteOptions::new()
        .create(std::io::BufWriter::new(
            std::fs::File::create(dir.path().join("p.mcap")).unwrap(),
        ))
        .unwrap();
    let ch = w
        .add_channel(0, "/chatter", "json", &BTreeMap::new())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: ch,
        sequence: 0,
        log_time: 1,
        publish_time: 0,
    };
    w.write_to_known_channel(&header, b"{}").unwrap();
    w.finish().unwrap();
    drop(w);
    let e = rosbag::open_planar(&dir.path().join("p.mcap"), &Topics::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("not a ROS 2 bag") && e.contains("/chatter"),
        "{e}"
    );
}

#[test]
fn directory_with_other_storage_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths:\n    - a_0.db3\n",
    )
    .unwrap();
    assert!(rosbag::is_bag(dir.path()).unwrap());
    let e = rosbag::open_planar(dir.path(), &Topics::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("sqlite3"), "{e}");
    let not_bag = dir.path().join("x.mcap");
    std::fs::write(&not_bag, b"hello").unwrap();
    assert!(!rosbag::is_bag(&not_bag).unwrap());
}

#[test]
fn out_of_order_messages_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("order.mcap");
    let mut w = BagWriter::create(&path, &opts(BagCompression::None)).unwrap();
    let scan = Scan2 {
        angle_min_rad: 0.0,
        angle_increment_rad: 0.1,
        max_range_m: 10.0,
        ranges: vec![1.0; 3],
        intensities: None,
    };
    for t in [5.0, 5.1, 4.9, 5.2] {
        w.write_scan("/scan", t, "laser", &scan).unwrap();
    }
    w.finish().unwrap();
    let mut scans = rosbag::BagScans::open(&path, &Topics::default()).unwrap();
    assert_eq!(scans.by_ref().count(), 4);
    let warnings = scans.warnings().join("\n");
    assert!(
        warnings.contains("/scan: log time 4.900000000 s comes after 5.100000000 s"),
        "{warnings}"
    );
}
