//! The Ouster reader never panics on truncated or mutated captures and metadata: it returns
//! frames or an error naming the file and the byte (capture) or line (JSON). Inputs: a small
//! synthetic capture with its metadata, and, when RAYPATH_DATA is set, the start of the real
//! OS-2 capture and the real FUSA dual-return capture with their metadata.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::io::Cursor;
use std::path::Path;
use std::sync::OnceLock;

use proptest::prelude::*;
use raypath_io::ouster::{OusterOptions, OusterReader, SensorInfo, XyzLut};
use raypath_io::{Error, Location};

/// Nested metadata of a 16-column, 4-beam sensor with 4 columns per packet.
const JSON: &str = r#"{
  "sensor_info": {"prod_line": "OS-1-16", "prod_sn": "991234567890", "build_rev": "v3.0.1",
                  "initialization_id": 4242},
  "config_params": {"lidar_mode": "16x10", "udp_port_lidar": 7502,
                    "udp_profile_lidar": "RNG19_RFL8_SIG16_NIR16"},
  "lidar_data_format": {"columns_per_frame": 16, "columns_per_packet": 4,
                        "pixels_per_column": 4, "column_window": [0, 15],
                        "pixel_shift_by_row": [3, 2, -1, 0],
                        "udp_profile_lidar": "RNG19_RFL8_SIG16_NIR16"},
  "beam_intrinsics": {"beam_altitude_angles": [10.0, 3.3, -3.3, -10.0],
                      "beam_azimuth_angles": [1.5, 0.5, -0.5, -1.5],
                      "lidar_origin_to_beam_origin_mm": 15.806},
  "lidar_intrinsics": {"lidar_to_sensor_transform":
                       [-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1]}
}"#;

/// A UDP datagram to `port` in IPv4 in an Ethernet frame.
fn ethernet(payload: &[u8], port: u16) -> Vec<u8> {
    let mut f = vec![0u8; 12];
    f.extend_from_slice(&[0x08, 0x00, 0x45, 0]);
    f.extend_from_slice(&((28 + payload.len()) as u16).to_be_bytes());
    f.extend_from_slice(&[0, 1, 0, 0, 64, 17, 0, 0, 10, 5, 5, 1, 10, 5, 5, 2]);
    f.extend_from_slice(&port.to_be_bytes());
    f.extend_from_slice(&port.to_be_bytes());
    f.extend_from_slice(&((8 + payload.len()) as u16).to_be_bytes());
    f.extend_from_slice(&[0, 0]);
    f.extend_from_slice(payload);
    f
}

/// Two frames of the sensor of [`JSON`] and an IMU datagram, as a classic pcap.
fn synthetic_capture() -> Vec<u8> {
    let mut frames = Vec::new();
    for frame_id in [5u16, 6] {
        for first in (0..16).step_by(4) {
            let mut p = vec![0u8; 32 + 4 * (12 + 4 * 12) + 32];
            p[0] = 1;
            p[2..4].copy_from_slice(&frame_id.to_le_bytes());
            p[4..8].copy_from_slice(&4242u32.to_le_bytes());
            p[7..12].copy_from_slice(&991_234_567_890u64.to_le_bytes()[..5]);
            for c in 0..4 {
                let m = first + c;
                let col = 32 + c * 60;
                p[col..col + 8]
                    .copy_from_slice(&(u64::from(frame_id) * 100 + m as u64).to_le_bytes());
                p[col + 8..col + 10].copy_from_slice(&(m as u16).to_le_bytes());
                p[col + 10] = 1;
                for r in 0..4 {
                    let px = col + 12 + 12 * r;
                    let range = if (r + m) % 3 == 0 {
                        0
                    } else {
                        1000 + 37 * (r * 16 + m) as u32
                    };
                    p[px..px + 4].copy_from_slice(&range.to_le_bytes());
                    p[px + 4] = (r * 16 + m) as u8;
                }
            }
            frames.push(ethernet(&p, 7502));
        }
        frames.push(ethernet(&[0u8; 48], 7503));
    }
    let mut b = vec![0xd4, 0xc3, 0xb2, 0xa1, 2, 0, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    b.extend_from_slice(&65535u32.to_le_bytes());
    b.extend_from_slice(&1u32.to_le_bytes());
    for (k, f) in frames.iter().enumerate() {
        b.extend_from_slice(&(1_700_000_000 + k as u32).to_le_bytes());
        b.extend_from_slice(&0u32.to_le_bytes());
        b.extend_from_slice(&(f.len() as u32).to_le_bytes());
        b.extend_from_slice(&(f.len() as u32).to_le_bytes());
        b.extend_from_slice(f);
    }
    b
}

/// The first `records` records of a classic pcap.
fn first_records(bytes: &[u8], records: usize) -> Vec<u8> {
    let mut end = 24;
    for _ in 0..records {
        if end + 16 > bytes.len() {
            break;
        }
        let len = u32::from_le_bytes(bytes[end + 8..end + 12].try_into().unwrap()) as usize;
        end += 16 + len;
    }
    bytes[..end.min(bytes.len())].to_vec()
}

/// `(capture, metadata JSON)` pairs: synthetic, and real ones when installed.
fn inputs() -> &'static Vec<(Vec<u8>, Vec<u8>)> {
    static INPUTS: OnceLock<Vec<(Vec<u8>, Vec<u8>)>> = OnceLock::new();
    INPUTS.get_or_init(|| {
        let mut inputs = vec![(synthetic_capture(), JSON.as_bytes().to_vec())];
        let real = [
            ("OS-2-128-U1_v2.3.0_1024x10", 6),
            ("OS-1-128_767798045_1024x10_20230712_120049", 4),
        ];
        for (stem, records) in real {
            if let Some(pcap) = raypath_io::data::require(format!("ouster/{stem}.pcap")) {
                let capture = first_records(&std::fs::read(&pcap).unwrap(), records);
                let json = std::fs::read(pcap.with_extension("json")).unwrap();
                inputs.push((capture, json));
            }
        }
        inputs
    })
}

#[test]
fn inputs_read_cleanly() {
    for (capture, json) in inputs() {
        let info = SensorInfo::parse(json, "m.json").unwrap();
        let frames: Vec<_> = OusterReader::new(
            Cursor::new(capture.clone()),
            "c.pcap",
            &info,
            OusterOptions::default(),
        )
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
        assert!(!frames.is_empty());
        let cloud = frames[0].to_point_cloud(&info).unwrap();
        assert_eq!(cloud.num_valid(), frames[0].valid_returns());
    }
    let info = SensorInfo::parse(JSON.as_bytes(), "m.json").unwrap();
    let frames: Vec<_> = OusterReader::new(
        Cursor::new(synthetic_capture()),
        "c.pcap",
        &info,
        OusterOptions::default(),
    )
    .unwrap()
    .collect::<Result<_, _>>()
    .unwrap();
    assert_eq!(frames.len(), 2);
    assert!(frames.iter().all(|f| f.is_complete(&info)));
    // Every third pixel has no return.
    assert_eq!(frames[0].valid_returns(), 64 - 22);
}

/// Reads a whole capture; checks what comes back.
fn read_all(capture: Vec<u8>, info: &SensorInfo) -> Result<(), Error> {
    let len = capture.len() as u64;
    let reader = OusterReader::new(
        Cursor::new(capture),
        "c.pcap",
        info,
        OusterOptions::default(),
    );
    let check = |e: Error| {
        assert_eq!(e.path(), Path::new("c.pcap"), "{e}");
        match e.location() {
            Location::Byte(at) => assert!(at <= len, "{e}"),
            // Only the end-of-capture verdict about ports is about the whole file.
            _ => assert!(e.to_string().contains("lidar_port"), "{e}"),
        }
        e
    };
    let lut = XyzLut::new(info).unwrap();
    for frame in reader.map_err(check)? {
        let frame = frame.map_err(check)?;
        let n = frame.width * frame.height;
        assert_eq!((frame.range_m.len(), frame.reflectivity.len()), (n, n));
        assert!(frame.range_m.iter().all(|r| r.is_finite() && *r >= 0.0));
        let cloud = lut.cloud(&frame).unwrap();
        assert_eq!(cloud.num_valid(), frame.valid_returns());
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn captures_never_panic(
        which in any::<prop::sample::Index>(),
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), any::<bool>()), 0..6),
    ) {
        let inputs = inputs();
        let (capture, json) = &inputs[which.index(inputs.len())];
        let info = SensorInfo::parse(json, "m.json").unwrap();
        let mut bytes = capture[..((capture.len() as f64 * cut) as usize)].to_vec();
        for (at, value, in_headers) in &edits {
            if bytes.is_empty() {
                break;
            }
            // Half the edits hit the first 200 bytes: file, record, link, IP, UDP and
            // packet headers.
            let span = if *in_headers { bytes.len().min(200) } else { bytes.len() };
            let i = at.index(span);
            bytes[i] = *value;
        }
        let _ = read_all(bytes, &info);
    }

    #[test]
    fn metadata_never_panics(
        which in any::<prop::sample::Index>(),
        cut in prop_oneof![Just(1.0), 0.0..1.0f64],
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<prop::sample::Index>()), 0..4),
    ) {
        const ALPHABET: &[u8] = b"0123456789.-e,:[]{}\" x";
        let inputs = inputs();
        let (capture, json) = &inputs[which.index(inputs.len())];
        let mut text = json[..((json.len() as f64 * cut) as usize)].to_vec();
        for (at, c) in &edits {
            if !text.is_empty() {
                let i = at.index(text.len());
                text[i] = ALPHABET[c.index(ALPHABET.len())];
            }
        }
        let lines = text.iter().filter(|&&b| b == b'\n').count() as u64 + 1;
        match SensorInfo::parse(&text, "m.json") {
            Ok(info) => {
                // Any metadata that parses reads any capture without panicking.
                let _ = read_all(capture.clone(), &info);
            }
            Err(e) => {
                prop_assert_eq!(e.path(), Path::new("m.json"));
                match e.location() {
                    Location::Line(n) => prop_assert!(n >= 1 && n <= lines, "{}", e),
                    Location::File => {}
                    Location::Byte(_) => prop_assert!(false, "{}", e),
                }
            }
        }
    }
}
