//! Our Ouster decoding against the vendor's Python SDK (`pip install ouster-sdk`): for the
//! real captures of RAYPATH_DATA/ouster, for frames the SDK re-encodes into the legacy and
//! `RNG19_RFL8_SIG16_NIR16_DUAL` profiles (recorded with Linux cooked capture framing), and
//! for the OSF recordings the SDK writes out as captures, every pixel's range, reflectivity,
//! signal and near-IR equal the SDK's (destaggered), and every point is within 1 mm and
//! 1e-4 rad of the SDK's `XYZLut` point (sensor frame).
//!
//! Skips with a message when `python3 -c "import ouster.sdk"` fails (unless
//! `RAYPATH_REQUIRE_PYTHON=1`, where that is a failure) or the data is not installed.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

use raypath_io::data::{require, require_python_in};
use raypath_io::ouster::{self, OusterFrame, OusterReader, SensorInfo, XyzLut};
use serde_json::Value;

/// The SDK side. `decode PCAP JSON OUT`: per frame, the destaggered fields and `XYZLut`
/// points as raw little-endian arrays plus `frames.json`. `reencode PCAP JSON PROFILE
/// OUT_PCAP OUT_JSON SLL`: the first frame in another profile (synthetic second returns for
/// dual profiles). `osf OSF OUT_PCAP OUT_JSON`: an OSF recording's frames as packets.
const SDK_SCRIPT: &str = r#"
import json, os, sys
import numpy as np
import ouster.sdk as sdk
from ouster.sdk import core, pcap

def first_frames(source):
    for frame_set in source:
        frame = frame_set[0]
        if frame is not None:
            yield frame

def record(frames, info, out_pcap, out_json, sll):
    fmt = core.PacketFormat(info)
    packets = []
    for frame in frames:
        packets += core.frame_to_packets(frame, fmt, info.init_id, info.sn)
    pcap.record(packets, out_pcap, lidar_port=7502, imu_port=7503, use_sll_encapsulation=sll)
    with open(out_json, "w") as f:
        f.write(info.to_json_string())

mode = sys.argv[1]
if mode == "decode":
    pcap_path, json_path, out = sys.argv[2:5]
    source = pcap.PcapFrameSetSource(pcap_path, meta=[json_path])
    info = source.sensor_info[0]
    lut = core.XYZLut(info, use_extrinsics=False)
    records = []
    for k, frame in enumerate(first_frames(source)):
        rec = {"frame_id": int(frame.frame_id), "h": int(frame.h), "w": int(frame.w), "fields": {}}
        def dump(name, image, dtype):
            data = np.ascontiguousarray(core.destagger(info, image)).astype(dtype)
            file = f"{k}_{name}.bin"
            data.tofile(os.path.join(out, file))
            rec["fields"][name] = file
        for name, dtype in [("RANGE", "<u4"), ("REFLECTIVITY", "<u2"), ("SIGNAL", "<u4"),
                            ("NEAR_IR", "<u4"), ("RANGE2", "<u4"), ("REFLECTIVITY2", "<u2"),
                            ("SIGNAL2", "<u4")]:
            if frame.has_field(name):
                dump(name, frame.field(name), dtype)
        dump("XYZ", lut(frame.field("RANGE")), "<f8")
        if frame.has_field("RANGE2"):
            dump("XYZ2", lut(frame.field("RANGE2")), "<f8")
        valid = np.flatnonzero(frame.status & 1)
        rec["timestamp_ns"] = int(frame.timestamp[valid[0]]) if valid.size else 0
        records.append(rec)
    with open(os.path.join(out, "frames.json"), "w") as f:
        json.dump(records, f)
elif mode == "reencode":
    pcap_path, json_path, profile, out_pcap, out_json, sll = sys.argv[2:8]
    source = pcap.PcapFrameSetSource(pcap_path, meta=[json_path])
    frame = next(first_frames(source))
    info = core.SensorInfo(source.sensor_info[0].to_json_string())
    info.format.udp_profile_lidar = getattr(core.UDPProfileLidar, profile)
    if profile.endswith("_DUAL"):
        r = frame.field("RANGE")
        every_third = (np.arange(r.size).reshape(r.shape) % 3) == 0
        frame.add_field("RANGE2", np.where((r > 0) & every_third,
                                           np.minimum(r + 5000, (1 << 19) - 1), 0).astype(np.uint32))
        frame.add_field("REFLECTIVITY2", (frame.field("REFLECTIVITY") // 2).astype(np.uint8))
        frame.add_field("SIGNAL2", (frame.field("SIGNAL") // 3).astype(np.uint16))
    record([frame], info, out_pcap, out_json, sll == "1")
elif mode == "osf":
    osf_path, out_pcap, out_json = sys.argv[2:5]
    source = sdk.open_source(osf_path)
    record(list(first_frames(source)), source.sensor_info[0], out_pcap, out_json, False)
"#;

/// The interpreter with the Ouster SDK: `RAYPATH_OUSTER_PYTHON` (CI points it at a virtual
/// environment, since the SDK pins older versions of packages the other cross-checks use),
/// else `python3`.
fn interpreter() -> String {
    std::env::var("RAYPATH_OUSTER_PYTHON")
        .ok()
        .filter(|p| !p.is_empty())
        .unwrap_or_else(|| "python3".to_owned())
}

fn python(args: &[&str]) {
    let out = Command::new(interpreter())
        .arg("-c")
        .arg(SDK_SCRIPT)
        .args(args)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "python {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn read_array<T: Copy>(path: &Path, from: fn(&[u8]) -> T, size: usize) -> Vec<T> {
    let bytes = std::fs::read(path).unwrap();
    bytes.chunks_exact(size).map(from).collect()
}

fn u32s(path: &Path) -> Vec<u32> {
    read_array(path, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]), 4)
}

fn f64s(path: &Path) -> Vec<f64> {
    read_array(
        path,
        |b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        8,
    )
}

/// Decodes `pcap` with the SDK and with us (metadata found by [`ouster::find_metadata`],
/// which must be `json`), and compares every frame; returns the number of frames.
fn compare(pcap: &Path, json: &Path, work: &Path) -> usize {
    let found = ouster::find_metadata(pcap).unwrap();
    assert_eq!(found, json, "metadata of {}", pcap.display());
    let out = work.join(format!(
        "sdk_{}",
        pcap.file_stem().unwrap().to_string_lossy()
    ));
    std::fs::create_dir_all(&out).unwrap();
    python(&[
        "decode",
        pcap.to_str().unwrap(),
        json.to_str().unwrap(),
        out.to_str().unwrap(),
    ]);
    let records: Vec<Value> =
        serde_json::from_slice(&std::fs::read(out.join("frames.json")).unwrap()).unwrap();
    let info = SensorInfo::read(json).unwrap();
    let lut = XyzLut::new(&info).unwrap();
    let frames: Vec<OusterFrame> = OusterReader::open(pcap, &info)
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(frames.len(), records.len(), "{}", pcap.display());
    for (frame, rec) in frames.iter().zip(&records) {
        let what = format!("{} frame {}", pcap.display(), frame.frame_id);
        assert_eq!(u64::from(frame.frame_id), rec["frame_id"].as_u64().unwrap());
        assert_eq!(frame.height as u64, rec["h"].as_u64().unwrap());
        assert_eq!(frame.width as u64, rec["w"].as_u64().unwrap());
        let ts = rec["timestamp_ns"].as_u64().unwrap() as f64 * 1e-9;
        assert!((frame.timestamp_s - ts).abs() < 1e-6, "{what}: timestamp");
        let field = |name: &str| rec["fields"][name].as_str().map(|file| out.join(file));
        let mm =
            |r: &[f32]| -> Vec<u32> { r.iter().map(|&v| (v * 1000.0).round() as u32).collect() };
        assert_eq!(
            mm(&frame.range_m),
            u32s(&field("RANGE").unwrap()),
            "{what}: range"
        );
        let reflectivity: Vec<u32> = read_array(
            &field("REFLECTIVITY").unwrap(),
            |b| u32::from(u16::from_le_bytes([b[0], b[1]])),
            2,
        );
        assert!(
            frame
                .reflectivity
                .iter()
                .map(|&v| u32::from(v))
                .eq(reflectivity),
            "{what}: reflectivity"
        );
        if let Some(path) = field("NEAR_IR") {
            let nir: Vec<u32> = frame.near_ir.iter().map(|&v| u32::from(v)).collect();
            assert_eq!(nir, u32s(&path), "{what}: near-IR");
        }
        match (&frame.signal, field("SIGNAL")) {
            (Some(ours), Some(path)) => {
                let ours: Vec<u32> = ours.iter().map(|&v| u32::from(v)).collect();
                assert_eq!(ours, u32s(&path), "{what}: signal");
            }
            (None, None) => {}
            (ours, theirs) => panic!("{what}: signal {:?} vs {theirs:?}", ours.is_some()),
        }
        let cloud = lut.cloud(frame).unwrap();
        compare_points(
            &cloud.points,
            &frame.range_m,
            &f64s(&field("XYZ").unwrap()),
            &what,
        );
        match (&frame.range2_m, field("RANGE2")) {
            (Some(r2), Some(path)) => {
                assert_eq!(mm(r2), u32s(&path), "{what}: second range");
                let second = lut.second_return_cloud(frame).unwrap().unwrap();
                compare_points(&second.points, r2, &f64s(&field("XYZ2").unwrap()), &what);
                if let (Some(ours), Some(path)) = (&frame.signal2, field("SIGNAL2")) {
                    let ours: Vec<u32> = ours.iter().map(|&v| u32::from(v)).collect();
                    assert_eq!(ours, u32s(&path), "{what}: second signal");
                }
            }
            (None, None) => {}
            (ours, theirs) => panic!("{what}: second return {:?} vs {theirs:?}", ours.is_some()),
        }
    }
    frames.len()
}

/// Within 1 mm and 1e-4 rad of the SDK's points where there is a return; NaN where not.
fn compare_points(ours: &[nalgebra::Point3<f32>], range_m: &[f32], sdk: &[f64], what: &str) {
    assert_eq!(sdk.len(), 3 * ours.len(), "{what}: points");
    let (mut worst_m, mut worst_rad, mut n) = (0.0f64, 0.0f64, 0);
    for (i, p) in ours.iter().enumerate() {
        if range_m[i] == 0.0 {
            assert!(p.x.is_nan(), "{what}: pixel {i} has no return");
            continue;
        }
        let q = nalgebra::Vector3::new(sdk[3 * i], sdk[3 * i + 1], sdk[3 * i + 2]);
        let p = p.coords.cast::<f64>();
        worst_m = worst_m.max((p - q).norm());
        if q.norm() > 0.5 {
            worst_rad = worst_rad.max(p.angle(&q));
        }
        n += 1;
    }
    assert!(
        worst_m < 1e-3,
        "{what}: {n} points, worst distance {worst_m} m"
    );
    assert!(
        worst_rad < 1e-4,
        "{what}: {n} points, worst angle {worst_rad} rad"
    );
    eprintln!("{what}: {n} points, worst {worst_m:.2e} m, {worst_rad:.2e} rad");
}

fn setup() -> Option<(PathBuf, tempfile::TempDir)> {
    if !require_python_in(&interpreter(), "ouster.sdk, numpy") {
        return None;
    }
    let dir = require("ouster")?;
    Some((dir, tempfile::tempdir().unwrap()))
}

#[test]
fn real_captures_match_the_sdk() {
    let Some((dir, work)) = setup() else {
        return;
    };
    for (pcap, json, frames) in [
        (
            "OS-1-128_v2.3.0_1024x10_lb_n3.pcap",
            "OS-1-128_v2.3.0_1024x10.json",
            3,
        ),
        (
            "OS-2-128-U1_v2.3.0_1024x10.pcap",
            "OS-2-128-U1_v2.3.0_1024x10.json",
            1,
        ),
        (
            "OS-1-128_767798045_1024x10_20230712_120049.pcap",
            "OS-1-128_767798045_1024x10_20230712_120049.json",
            1,
        ),
    ] {
        assert_eq!(
            compare(&dir.join(pcap), &dir.join(json), work.path()),
            frames
        );
    }
}

/// The SDK's encoder writes an OS-2 frame as legacy packets (Linux cooked capture framing)
/// and as `RNG19_RFL8_SIG16_NIR16_DUAL` packets with synthetic second returns.
#[test]
fn reencoded_profiles_match_the_sdk() {
    let Some((dir, work)) = setup() else {
        return;
    };
    let source = dir.join("OS-2-128-U1_v2.3.0_1024x10.pcap");
    let json = dir.join("OS-2-128-U1_v2.3.0_1024x10.json");
    for (profile, sll) in [("LEGACY", "1"), ("RNG19_RFL8_SIG16_NIR16_DUAL", "0")] {
        let pcap = work.path().join(format!("{profile}.pcap"));
        let out_json = work.path().join(format!("{profile}.json"));
        python(&[
            "reencode",
            source.to_str().unwrap(),
            json.to_str().unwrap(),
            profile,
            pcap.to_str().unwrap(),
            out_json.to_str().unwrap(),
            sll,
        ]);
        assert_eq!(compare(&pcap, &out_json, work.path()), 1, "{profile}");
    }
}

/// OSF recordings (firmware 3.0 OS-0-128; firmware 3.2 8-beam OS-0 at 2048 columns) written
/// out as captures by the SDK, with metadata named `<stem>_meta.json` (found by matching
/// packet sizes).
#[test]
fn osf_recordings_as_captures_match_the_sdk() {
    let Some((dir, work)) = setup() else {
        return;
    };
    for (osf, frames) in [
        ("OS-0-128_v3.0.1_1024x10_20241017_141645.osf", 3),
        ("osf_fw_3.2_10scans.osf", 10),
    ] {
        let stem = osf.trim_end_matches(".osf");
        let pcap = work.path().join(format!("{stem}.pcap"));
        let json = work.path().join(format!("{stem}_meta.json"));
        python(&[
            "osf",
            dir.join(osf).to_str().unwrap(),
            pcap.to_str().unwrap(),
            json.to_str().unwrap(),
        ]);
        assert_eq!(compare(&pcap, &json, work.path()), frames, "{osf}");
    }
}
