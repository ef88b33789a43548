//! The Ouster reader on the real captures of RAYPATH_DATA/ouster (OS-1-128 low-data
//! profile, OS-2-128 single-return profile, OS-1-128 FUSA dual-return profile): image size,
//! complete frames, consecutive frame ids, valid returns and range against the data set's
//! README, destaggering (one azimuth per column), format detection, `raypath info`'s summary
//! and the sweep-sequence view with the vendor's poses.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use raypath_io::Format;
use raypath_io::data::require;
use raypath_io::ouster::{self, LidarProfile, MetadataLayout, OusterReader, SensorInfo};
use raypath_io::sequence::{SweepOptions, SweepSequence};

const LB: &str = "ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap";
const OS2: &str = "ouster/OS-2-128-U1_v2.3.0_1024x10.pcap";
const DUAL: &str = "ouster/OS-1-128_767798045_1024x10_20230712_120049.pcap";

fn open(relative: &str) -> Option<(PathBuf, SensorInfo)> {
    let pcap = require(relative)?;
    let info = SensorInfo::read(&ouster::find_metadata(&pcap).unwrap()).unwrap();
    Some((pcap, info))
}

/// The README: 3 consecutive frames of 1024 × 128, ≈ 107.6 k valid returns per frame,
/// ranges up to 247 m.
#[test]
fn os1_low_data_frames_match_the_readme() {
    let Some((pcap, info)) = open(LB) else {
        return;
    };
    assert_eq!(
        info.source.file_name().unwrap(),
        "OS-1-128_v2.3.0_1024x10.json"
    );
    assert_eq!(info.layout, MetadataLayout::LegacyFlat);
    assert_eq!(info.profile, LidarProfile::Rng15Rfl8Nir8);
    assert_eq!(
        (info.pixels_per_column, info.columns_per_frame),
        (128, 1024)
    );
    let frames = ouster::read_frames(&pcap, &info.source).unwrap();
    assert_eq!(frames.len(), 3);
    let mut max_range = 0.0f32;
    for (k, frame) in frames.iter().enumerate() {
        assert_eq!((frame.height, frame.width), (128, 1024));
        assert_eq!(frame.range_m.len(), 128 * 1024);
        assert_eq!(frame.first_column(), Some(0), "frame {k}");
        assert_eq!(frame.last_column(), Some(1023), "frame {k}");
        assert!(frame.is_complete(&info), "frame {k}");
        assert_eq!(frame.packets, 64, "frame {k}: 1024 columns / 16 per packet");
        let valid = frame.valid_returns();
        assert!(
            (valid as f64 - 107_600.0).abs() < 0.01 * 107_600.0,
            "frame {k}: {valid} valid returns"
        );
        let (lo, hi) = frame.range_span_m().unwrap();
        assert!(lo > 0.0 && lo < 5.0, "frame {k}: shortest range {lo}");
        max_range = max_range.max(hi);
        // The low-data profile: ranges are multiples of 8 mm, near-IR of 16, no signal.
        assert!(frame.signal.is_none() && frame.range2_m.is_none());
        assert!(
            frame
                .range_m
                .iter()
                .all(|&r| ((r * 1000.0 / 8.0).round() * 8.0 - r * 1000.0).abs() < 0.05)
        );
        assert!(frame.near_ir.iter().all(|&v| v % 16 == 0));
        assert!(frame.near_ir.iter().any(|&v| v > 0));
        // Reflectivity is there where ranges are.
        let lit = (0..frame.range_m.len())
            .filter(|&i| frame.range_m[i] > 0.0 && frame.reflectivity[i] > 0)
            .count();
        assert!(
            lit as f64 > 0.9 * valid as f64,
            "frame {k}: {lit} of {valid}"
        );
    }
    assert!((max_range - 247.0).abs() < 1.0, "max range {max_range}");
    // Consecutive frame ids, 0.1 s apart (10 Hz).
    for pair in frames.windows(2) {
        assert_eq!(pair[1].frame_id, pair[0].frame_id + 1);
        let dt = pair[1].timestamp_s - pair[0].timestamp_s;
        assert!((dt - 0.1).abs() < 0.002, "frame period {dt}");
        assert!(pair[1].capture_time_s > pair[0].capture_time_s);
    }
}

/// Column j of the destaggered image is one azimuth: far points of every beam in column j
/// lie along `π − 2π j / W + δ` in the sensor frame (column 0 looks along −x, REP-103 axes;
/// δ = the mean over beams of `2π shift / W − beam azimuth`, 4.2° here), and the lowest
/// beams see the ground below the sensor.
#[test]
fn destaggered_columns_share_an_azimuth() {
    let Some((pcap, info)) = open(LB) else {
        return;
    };
    let frame = OusterReader::open(&pcap, &info)
        .unwrap()
        .next()
        .unwrap()
        .unwrap();
    let cloud = frame.to_point_cloud(&info).unwrap();
    assert_eq!((cloud.height, cloud.width), (128, 1024));
    assert_eq!(cloud.num_valid(), frame.valid_returns());
    assert_eq!(cloud.intensity.as_ref().unwrap().len(), cloud.len());
    let w = info.columns_per_frame as f64;
    let delta = (0..info.pixels_per_column)
        .map(|r| {
            std::f64::consts::TAU * f64::from(info.pixel_shift_by_row[r]) / w
                - info.beam_azimuth_angles_deg[r].to_radians()
        })
        .sum::<f64>()
        / info.pixels_per_column as f64;
    assert!((delta.to_degrees() - 4.2).abs() < 0.1, "{delta}");
    let (mut checked, mut worst) = (0, 0.0f64);
    for row in 0..cloud.height {
        for col in 0..cloud.width {
            let i = cloud.index(row, col);
            if frame.range_m[i] < 10.0 {
                continue;
            }
            let p = cloud.points[i];
            let expected = std::f64::consts::PI - std::f64::consts::TAU * col as f64 / w + delta;
            let error =
                raypath_geometry::wrap_angle(f64::from(p.y).atan2(f64::from(p.x)) - expected);
            worst = worst.max(error.abs());
            checked += 1;
            // The point is `range` from the sensor, up to the beam offset and housing height.
            let norm = p.coords.norm();
            assert!(
                (norm - frame.range_m[i]).abs() < 0.06,
                "pixel ({row}, {col})"
            );
        }
    }
    assert!(checked > 10_000);
    assert!(worst < 1f64.to_radians(), "worst azimuth error {worst} rad");
    // The 16 lowest beams look 16° to 22° down: mostly ground, below the sensor.
    let low: Vec<f32> = (112..128)
        .flat_map(|r| (0..1024).map(move |c| (r, c)))
        .map(|(r, c)| cloud.points[cloud.index(r, c)].z)
        .filter(|z| z.is_finite())
        .collect();
    let below = low.iter().filter(|&&z| z < 0.0).count();
    assert!(below as f64 > 0.95 * low.len() as f64);
}

#[test]
fn os2_single_return_profile() {
    let Some((pcap, info)) = open(OS2) else {
        return;
    };
    assert_eq!(
        info.source.file_name().unwrap(),
        "OS-2-128-U1_v2.3.0_1024x10.json"
    );
    assert_eq!(info.profile, LidarProfile::Rng19Rfl8Sig16Nir16);
    let frames: Vec<_> = OusterReader::open(&pcap, &info)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(frames.len(), 1);
    let frame = &frames[0];
    assert!(frame.is_complete(&info));
    assert_eq!(
        (frame.first_column(), frame.last_column()),
        (Some(0), Some(1023))
    );
    let signal = frame.signal.as_ref().unwrap();
    assert!(signal.iter().any(|&s| s > 0));
    // An OS-2 sees far: most pixels return, some beyond 200 m.
    assert!(frame.valid_returns() > 128 * 1024 / 2);
    assert!(frame.range_span_m().unwrap().1 > 200.0);
}

/// The FUSA dual-return capture holds the first 128 columns of one frame.
#[test]
fn fusa_dual_return_profile() {
    let Some((pcap, info)) = open(DUAL) else {
        return;
    };
    assert_eq!(info.layout, MetadataLayout::Nested);
    assert_eq!(info.profile, LidarProfile::Rng15Rfl8Nir8Dual);
    assert_eq!(info.header_type, ouster::HeaderType::Fusa);
    let frames: Vec<_> = OusterReader::open(&pcap, &info)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(frames.len(), 1);
    let frame = &frames[0];
    assert_eq!(frame.frame_id, 229);
    assert_eq!(frame.columns_present(), 128);
    assert_eq!(
        (frame.first_column(), frame.last_column()),
        (Some(0), Some(127))
    );
    assert!(!frame.is_complete(&info));
    let range2 = frame.range2_m.as_ref().unwrap();
    assert!(frame.valid_second_returns() > 0);
    // A second return only comes with a first one.
    assert!(
        range2
            .iter()
            .zip(&frame.range_m)
            .all(|(&r2, &r1)| r2 == 0.0 || r1 > 0.0)
    );
    let lut = ouster::XyzLut::new(&info).unwrap();
    let second = lut.second_return_cloud(frame).unwrap().unwrap();
    assert_eq!(second.num_valid(), frame.valid_second_returns());
}

#[test]
fn detection_and_summary() {
    let Some(pcap) = require(LB) else {
        return;
    };
    assert_eq!(Format::detect(&pcap).unwrap(), Format::OusterPcap);
    let summary = raypath_io::summarize(&pcap).unwrap();
    assert_eq!(summary.format, "ouster-pcap");
    assert_eq!(summary.scans, Some(3));
    assert_eq!((summary.width, summary.height), (Some(1024), Some(128)));
    assert_eq!(summary.extra["profile"], "RNG15_RFL8_NIR8");
    assert_eq!(summary.extra["complete_frames"], 3);
    assert_eq!(summary.extra["frame_ids"], serde_json::json!([1795, 1797]));
    assert_eq!(summary.extra["frame_id_gaps"], 0);
    let returns = &summary.extra["valid_returns"];
    assert_eq!(returns["min"], 107_357);
    assert_eq!(returns["max"], 107_647);
    let span = summary.extra["range_span_m"].as_array().unwrap();
    assert!((span[1].as_f64().unwrap() - 247.0).abs() < 1.0);
    assert!((summary.time_span.unwrap().duration - 0.2).abs() < 0.01);

    let osf = pcap.with_extension("osf");
    assert_eq!(Format::detect(&osf).unwrap(), Format::OusterOsf);
    let error = raypath_io::summarize(&osf).unwrap_err().to_string();
    assert!(
        error.contains("not supported") && error.contains("ouster-cli"),
        "{error}"
    );
}

/// The poses of `…_lb_n3_poses_kitti.txt` (vendor SLAM, 0.25 m apart) come with the sweeps.
#[test]
fn capture_as_sweep_sequence() {
    let Some((pcap, info)) = open(LB) else {
        return;
    };
    let sequence = SweepSequence::open(&pcap, &SweepOptions::default()).unwrap();
    assert_eq!(sequence.len(), 3);
    assert_eq!(sequence.format, raypath_io::sequence::SweepFormat::Ouster);
    let poses = sequence.require_reference().unwrap();
    assert!(poses[0].translation().norm() < 1e-9);
    let step = (poses[1].translation() - poses[0].translation()).norm();
    assert!((step - 0.25).abs() < 0.02, "{step}");
    let frames = ouster::read_frames(&pcap, &info.source).unwrap();
    for k in [2, 0, 1] {
        let sweep = sequence.sweep(k).unwrap();
        let expected = frames[k].to_point_cloud(&info).unwrap();
        assert_eq!(sweep.num_valid(), expected.num_valid(), "sweep {k}");
        assert!(
            sweep
                .points
                .iter()
                .zip(&expected.points)
                .all(|(a, b)| a == b || (a.x.is_nan() && b.x.is_nan())),
            "sweep {k}"
        );
        assert!((sequence.stamps_secs[k] - frames[k].timestamp_s).abs() < 1e-9);
    }
}
