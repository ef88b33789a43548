//! Unit tests of the Ouster reader on synthetic metadata, packets and captures with known
//! answers; the real captures and the vendor SDK are in `tests/ouster_data.rs` and
//! `tests/ouster_python.rs`.

#![allow(clippy::unwrap_used)]

use std::io::Cursor;
use std::path::Path;

use serde_json::{Value, json};

use super::packet::{PacketLayout, Pixel, decode_pixel};
use super::*;
use crate::samples::ouster::{put16, put32, write_packet_header};
use crate::samples::{classic_pcap as classic, ip_frames, pcapng, udp_datagram, udp_frames};

/// Nested (firmware 3.x) metadata of a small sensor: `w` columns, `h` beams, `cpp` columns
/// per packet, altitudes 10° down to −10°, no beam azimuth offsets.
fn nested(profile: &str, w: usize, h: usize, cpp: usize, shifts: &[i32]) -> Value {
    let altitudes: Vec<f64> = (0..h)
        .map(|r| 10.0 - 20.0 * r as f64 / (h.max(2) - 1) as f64)
        .collect();
    json!({
        "sensor_info": {"prod_line": "OS-1-16", "prod_sn": "991234567890", "build_rev": "v3.0.1",
                        "initialization_id": 4242},
        "config_params": {"lidar_mode": format!("{w}x10"), "udp_port_lidar": 7502,
                          "udp_profile_lidar": profile},
        "lidar_data_format": {"columns_per_frame": w, "columns_per_packet": cpp,
                              "pixels_per_column": h, "column_window": [0, w - 1],
                              "pixel_shift_by_row": shifts, "udp_profile_lidar": profile},
        "beam_intrinsics": {"beam_altitude_angles": altitudes, "beam_azimuth_angles": vec![0.0; h],
                            "lidar_origin_to_beam_origin_mm": 15.0},
        "lidar_intrinsics": {"lidar_to_sensor_transform":
                             [-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1]},
    })
}

fn info_of(value: &Value) -> SensorInfo {
    SensorInfo::parse(
        serde_json::to_string_pretty(value).unwrap().as_bytes(),
        "test.json",
    )
    .unwrap()
}

fn small(profile: &str) -> SensorInfo {
    info_of(&nested(profile, 8, 4, 4, &[3, 2, 1, 0]))
}

/// The bytes of one pixel in `profile` (the encoder the decoder is tested against).
fn encode_pixel(profile: LidarProfile, p: &Pixel) -> Vec<u8> {
    let mut b = vec![0u8; profile.pixel_bytes()];
    match profile {
        LidarProfile::Legacy | LidarProfile::Rng19Rfl8Sig16Nir16 => {
            put32(
                &mut b,
                0,
                p.range_mm | (0x0010_0000 * u32::from(profile != LidarProfile::Legacy)),
            );
            b[4] = p.reflectivity;
            put16(&mut b, 6, p.signal);
            put16(&mut b, 8, p.near_ir);
        }
        LidarProfile::Rng19Rfl8Sig16Nir16Dual => {
            put32(&mut b, 0, p.range_mm | u32::from(p.reflectivity) << 24);
            put32(&mut b, 4, p.range2_mm | u32::from(p.reflectivity2) << 24);
            put16(&mut b, 8, p.signal);
            put16(&mut b, 10, p.signal2);
            put16(&mut b, 12, p.near_ir);
        }
        LidarProfile::Rng15Rfl8Nir8 | LidarProfile::Rng15Rfl8Nir8Dual => {
            put16(&mut b, 0, (p.range_mm / 8) as u16 | 0x8000);
            b[2] = p.reflectivity;
            b[3] = (p.near_ir / 16) as u8;
            if profile.is_dual() {
                put16(&mut b, 4, (p.range2_mm / 8) as u16);
                b[6] = p.reflectivity2;
            }
        }
    }
    b
}

/// The pixel of beam `r`, measurement id `m`, frame `f` in our test streams (no return where
/// `(r + m) % 5 == 4`).
fn pixel(profile: LidarProfile, f: u32, r: usize, m: usize) -> Pixel {
    let range = if (r + m) % 5 == 4 {
        0
    } else {
        8 * (1000 + 100 * r as u32 + 8 * m as u32 + f)
    };
    let mut p = Pixel {
        range_mm: range,
        reflectivity: (10 * r + m) as u8,
        near_ir: 16 * (r + 2 * m) as u16,
        ..Pixel::default()
    };
    if profile.has_signal() {
        p.signal = (1000 + r * 10 + m) as u16;
    }
    if profile.is_dual() {
        p.range2_mm = if range > 0 && m % 2 == 0 {
            range + 800
        } else {
            0
        };
        p.reflectivity2 = (r + m) as u8;
        if profile == LidarProfile::Rng19Rfl8Sig16Nir16Dual {
            p.signal2 = (500 + m) as u16;
        }
    }
    p
}

/// One lidar packet of frame `f` holding columns `first..first + cpp` (`invalid` marks a
/// column invalid).
fn packet(info: &SensorInfo, f: u32, first: usize, invalid: Option<usize>) -> Vec<u8> {
    let layout = PacketLayout::new(info);
    let legacy = info.profile == LidarProfile::Legacy;
    let mut b = vec![0u8; layout.packet_bytes];
    write_packet_header(&mut b, info, f);
    for c in 0..info.columns_per_packet {
        let m = first + c;
        let at = layout.column_offset(c);
        let col = &mut b[at..at + layout.column_bytes];
        col[..8]
            .copy_from_slice(&(1_000_000_000 * u64::from(f) + 1000 * m as u64 + 7).to_le_bytes());
        put16(col, 8, m as u16);
        let valid = invalid != Some(m);
        if legacy {
            put16(col, 10, f as u16);
            let end = layout.column_bytes - 4;
            put32(col, end, if valid { u32::MAX } else { 0 });
        } else {
            put16(col, 10, u16::from(valid));
        }
        for r in 0..info.pixels_per_column {
            let px = encode_pixel(info.profile, &pixel(info.profile, f, r, m));
            let at = layout.column_header + r * layout.pixel_bytes;
            col[at..at + px.len()].copy_from_slice(&px);
        }
    }
    b
}

/// An Ethernet frame (with an 802.1Q tag when `vlan`) carrying a UDP datagram in IPv4.
fn ethernet(payload: &[u8], port: u16, vlan: bool) -> Vec<u8> {
    udp_frames(payload, port, 1, usize::MAX, vlan).remove(0)
}

fn read(info: &SensorInfo, bytes: Vec<u8>) -> Result<Vec<OusterFrame>> {
    OusterReader::new(
        Cursor::new(bytes),
        "test.pcap",
        info,
        OusterOptions::default(),
    )?
    .collect()
}

/// Two frames of two packets each, an IMU-sized datagram between them.
fn two_frames(info: &SensorInfo) -> Vec<Vec<u8>> {
    let mut frames = Vec::new();
    for f in [41u32, 42] {
        for first in (0..info.columns_per_frame).step_by(info.columns_per_packet) {
            frames.push(ethernet(&packet(info, f, first, None), 7502, false));
        }
        frames.push(ethernet(&[0u8; 48], 7503, false));
    }
    frames
}

/// Checks frame `f` holds every pixel of [`pixel`], destaggered.
fn check_frame(info: &SensorInfo, frame: &OusterFrame, f: u32) {
    let (w, h) = (info.columns_per_frame, info.pixels_per_column);
    assert_eq!((frame.width, frame.height, frame.frame_id), (w, h, f));
    for r in 0..h {
        for m in 0..w {
            let p = pixel(info.profile, f, r, m);
            let col = (m as i64 + i64::from(info.pixel_shift_by_row[r])).rem_euclid(w as i64);
            let i = r * w + col as usize;
            assert_eq!(frame.range_m[i], p.range_mm as f32 * 1e-3, "({r}, {m})");
            assert_eq!(frame.reflectivity[i], p.reflectivity);
            assert_eq!(frame.near_ir[i], p.near_ir);
            if let Some(s) = &frame.signal {
                assert_eq!(s[i], p.signal);
            }
            if let Some(r2) = &frame.range2_m {
                assert_eq!(r2[i], p.range2_mm as f32 * 1e-3);
                assert_eq!(frame.reflectivity2.as_ref().unwrap()[i], p.reflectivity2);
            }
            if let Some(s2) = &frame.signal2 {
                assert_eq!(s2[i], p.signal2);
            }
        }
    }
    assert!((frame.timestamp_s - (f64::from(f) + 7e-9)).abs() < 1e-9);
    assert!(frame.is_complete(info));
}

#[test]
fn every_profile_round_trips_through_a_capture() {
    for name in [
        "LEGACY",
        "RNG19_RFL8_SIG16_NIR16",
        "RNG19_RFL8_SIG16_NIR16_DUAL",
        "RNG15_RFL8_NIR8",
        "RNG15_RFL8_NIR8_DUAL",
        "FUSA_RNG15_RFL8_NIR8_DUAL",
    ] {
        let info = small(name);
        assert_eq!(
            info.header_type == HeaderType::Fusa,
            name.starts_with("FUSA")
        );
        let frames = read(&info, classic(&two_frames(&info), false, false)).unwrap();
        assert_eq!(frames.len(), 2, "{name}");
        check_frame(&info, &frames[0], 41);
        check_frame(&info, &frames[1], 42);
        assert_eq!(frames[0].packets, 2);
        assert_eq!(frames[0].capture_time_s, 1_700_000_000.000_5);
    }
}

#[test]
fn capture_variants_read_alike() {
    let info = small("RNG19_RFL8_SIG16_NIR16");
    let frames = two_frames(&info);
    let expected = read(&info, classic(&frames, false, false)).unwrap();
    let tagged: Vec<_> = frames
        .iter()
        .map(|f| {
            let mut t = f[..12].to_vec();
            t.extend_from_slice(&[0x81, 0x00, 0x00, 0x07]);
            t.extend_from_slice(&f[12..]);
            t
        })
        .collect();
    for bytes in [
        classic(&frames, true, false),
        classic(&frames, false, true),
        classic(&tagged, false, false),
        pcapng(&frames),
    ] {
        let got = read(&info, bytes).unwrap();
        assert_eq!(got.len(), 2);
        for (a, b) in got.iter().zip(&expected) {
            assert_eq!(a.range_m, b.range_m);
            assert_eq!(a.column_timestamp_ns, b.column_timestamp_ns);
        }
    }
    let ng = read(&info, pcapng(&frames)).unwrap();
    assert_eq!(ng[0].capture_time_s, 1_700_000_000.0);
}

/// IPv4 fragments (out of order, interleaved with another datagram) are reassembled.
#[test]
fn fragments_are_reassembled() {
    let info = small("RNG19_RFL8_SIG16_NIR16");
    let mut frames = Vec::new();
    for (k, first) in [0usize, 4].into_iter().enumerate() {
        let payload = packet(&info, 41, first, None);
        let mut parts = ip_frames(&udp_datagram(&payload, 7502), 100 + k as u16, 64, false);
        assert!(parts.len() > 3);
        parts.swap(0, 2);
        frames.push(parts);
    }
    let (a, b) = (frames[0].clone(), frames[1].clone());
    let interleaved: Vec<Vec<u8>> = a
        .iter()
        .zip(&b)
        .flat_map(|(x, y)| [x.clone(), y.clone()])
        .chain(a.iter().skip(b.len()).cloned())
        .chain(b.iter().skip(a.len()).cloned())
        .collect();
    let mut reader = OusterReader::new(
        Cursor::new(classic(&interleaved, false, false)),
        "frag.pcap",
        &info,
        OusterOptions::default(),
    )
    .unwrap();
    let frame = reader.next().unwrap().unwrap();
    assert!(reader.next().is_none());
    check_frame(&info, &frame, 41);
    let stats = reader.stats();
    assert_eq!(stats.capture.reassembled, 2);
    assert_eq!(stats.capture.incomplete, 0);
}

/// Missing and invalid columns are no-returns; late packets of a finished frame are
/// skipped; the frame id alone starts frames.
#[test]
fn missing_invalid_and_late_columns() {
    let info = small("RNG19_RFL8_SIG16_NIR16");
    let eth = |f, first, invalid| ethernet(&packet(&info, f, first, invalid), 7502, false);
    let capture = vec![
        eth(7, 4, Some(5)), // frame 7 starts with its second packet, column 5 invalid
        eth(8, 0, None),
        eth(7, 0, None), // late: frame 7 already ended
        eth(8, 4, None),
    ];
    let mut reader = OusterReader::new(
        Cursor::new(classic(&capture, false, false)),
        "t.pcap",
        &info,
        OusterOptions::default(),
    )
    .unwrap();
    let first = reader.next().unwrap().unwrap();
    let second = reader.next().unwrap().unwrap();
    assert!(reader.next().is_none());
    assert_eq!(reader.stats().late_packets, 1);
    assert_eq!(
        first.column_present,
        [false, false, false, false, true, false, true, true]
    );
    assert_eq!(
        (first.first_column(), first.last_column()),
        (Some(4), Some(7))
    );
    assert!(!first.is_complete(&info));
    for r in 0..4 {
        for m in [0, 1, 2, 3, 5] {
            let col = (m + info.pixel_shift_by_row[r] as usize) % 8;
            assert_eq!(first.range_m[r * 8 + col], 0.0);
        }
    }
    assert!((first.timestamp_s - (7.0 + 4e-6 + 7e-9)).abs() < 1e-9);
    check_frame(&info, &second, 8);
}

#[test]
fn pixels_decode_to_known_values() {
    // RNG19: range 0x7ffff in 19 bits with flag bits above it set.
    let px = [0xff, 0xff, 0xff, 0xff, 200, 0, 0x34, 0x12, 0x78, 0x56, 0, 0];
    let p = decode_pixel(LidarProfile::Rng19Rfl8Sig16Nir16, &px);
    assert_eq!(
        (p.range_mm, p.reflectivity, p.signal, p.near_ir),
        (0x7ffff, 200, 0x1234, 0x5678)
    );
    // Legacy keeps 20 bits of range.
    assert_eq!(decode_pixel(LidarProfile::Legacy, &px).range_mm, 0xfffff);
    // Low data: 15 bits of 8 mm, near-IR × 16, the flag bit ignored.
    let p = decode_pixel(LidarProfile::Rng15Rfl8Nir8, &[0x01, 0x80, 7, 3]);
    assert_eq!((p.range_mm, p.reflectivity, p.near_ir), (8, 7, 48));
}

/// Packet headers of the real captures (the first 16 bytes of their first lidar packets).
#[test]
fn headers_decode_real_bytes() {
    let hex = |s: &str| -> Vec<u8> {
        let mut b: Vec<u8> = (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
            .collect();
        b.resize(64, 0);
        b
    };
    let standard = PacketLayout::new(&small("RNG15_RFL8_NIR8"));
    let h = standard.header(&hex("01000307767c6c264cbf731c00000000"));
    assert_eq!((h.packet_type, h.frame_id), (Some(1), 1795));
    assert_eq!(
        (h.init_id, h.serial),
        (Some(7_109_750), Some(122_201_000_998))
    );
    let fusa = PacketLayout::new(&small("FUSA_RNG15_RFL8_NIR8_DUAL"));
    let h = fusa.header(&hex("01bcf305e50000008c0000a5ee6d761c"));
    assert_eq!((h.packet_type, h.frame_id), (Some(1), 229));
    assert_eq!(
        (h.init_id, h.serial),
        (Some(390_076), Some(122_246_000_293))
    );
}

/// Pre-2.0 metadata: flat, no data format; the legacy profile, the SDK's default pixel
/// shifts and beam origin.
#[test]
fn legacy_flat_metadata_without_data_format() {
    let text = json!({
        "prod_line": "OS-1-64", "prod_sn": "991900001", "build_rev": "v1.13.0",
        "lidar_mode": "1024x10",
        "beam_altitude_angles": (0..64).map(|r| 16.0 - 0.5 * f64::from(r)).collect::<Vec<_>>(),
        "beam_azimuth_angles": vec![0.0; 64],
    })
    .to_string();
    let info = SensorInfo::parse(text.as_bytes(), "old.json").unwrap();
    assert_eq!(info.layout, MetadataLayout::LegacyFlat);
    assert_eq!(info.profile, LidarProfile::Legacy);
    assert_eq!((info.columns_per_frame, info.pixels_per_column), (1024, 64));
    assert_eq!(info.pixel_shift_by_row[..4], [18, 12, 6, 0]);
    assert_eq!(info.lidar_origin_to_beam_origin_mm, 15.806);
    assert_eq!(info.beam_to_lidar_transform[(0, 3)], 15.806);
    assert_eq!(info.lidar_to_sensor_transform[(2, 3)], 36.18);
    assert_eq!(info.udp_port_lidar, None);
    assert_eq!(info.lidar_packet_bytes(), 16 * (16 + 64 * 12 + 4));
    assert_eq!(info.frequency_hz(), Some(10.0));
}

#[test]
fn metadata_errors_name_the_line() {
    let mut value = nested("RNG19_RFL8_SIG16_NIR16", 8, 4, 4, &[0, 0, 0, 0]);
    value["beam_intrinsics"]["beam_altitude_angles"] = json!([1.0, 2.0]);
    let text = serde_json::to_string_pretty(&value).unwrap();
    let error = SensorInfo::parse(text.as_bytes(), "m.json").unwrap_err();
    let line = text
        .lines()
        .position(|l| l.contains("\"beam_altitude_angles\""))
        .unwrap() as u64
        + 1;
    assert_eq!(error.location(), Location::Line(line), "{error}");
    assert!(
        error.to_string().contains("2 angles for 4 beams"),
        "{error}"
    );

    let mut value = nested("RNG99", 8, 4, 4, &[0, 0, 0, 0]);
    let error = SensorInfo::parse(value.to_string().as_bytes(), "m.json").unwrap_err();
    assert!(
        error.to_string().contains("unsupported lidar profile"),
        "{error}"
    );
    value = nested("LEGACY", 8, 4, 4, &[0, 0, 0, 0]);
    value["lidar_data_format"]["pixel_shift_by_row"] = json!([0, 1.5, 0, 0]);
    assert!(SensorInfo::parse(value.to_string().as_bytes(), "m.json").is_err());
    let error = SensorInfo::parse(b"{\n  \"a\": [1,\n", "m.json").unwrap_err();
    assert!(matches!(error.location(), Location::Line(3)), "{error}");
}

#[test]
fn packets_that_do_not_fit_the_metadata_are_errors() {
    let info = small("RNG19_RFL8_SIG16_NIR16");
    // Wrong size on the lidar port: the metadata is for another profile.
    let other = small("RNG15_RFL8_NIR8");
    let capture = classic(&two_frames(&other), false, false);
    let error = read(&info, capture).unwrap_err();
    assert_eq!(error.location(), Location::Byte(24 + 16 + 42), "{error}");
    assert!(error.to_string().contains("does not belong"), "{error}");
    // Measurement id beyond the frame width.
    let mut p = packet(&info, 1, 0, None);
    let at = PacketLayout::new(&info).column_offset(2) + 8;
    put16(&mut p, at, 8);
    let error = read(&info, classic(&[ethernet(&p, 7502, false)], false, false)).unwrap_err();
    assert_eq!(
        error.location(),
        Location::Byte((24 + 16 + 42 + at) as u64),
        "{error}"
    );
    // Another sensor's initialization id.
    let mut p = packet(&info, 1, 0, None);
    put32(&mut p, 4, 99);
    let error = read(&info, classic(&[ethernet(&p, 7502, false)], false, false)).unwrap_err();
    assert!(
        error.to_string().contains("initialization id 99"),
        "{error}"
    );
    let options = OusterOptions {
        check_sensor_ids: false,
        ..OusterOptions::default()
    };
    let bytes = classic(&[ethernet(&p, 7502, false)], false, false);
    assert!(
        OusterReader::new(Cursor::new(bytes), "t", &info, options)
            .unwrap()
            .all(|f| f.is_ok())
    );
    // Lidar packets on another port than the metadata's.
    let moved = classic(
        &[ethernet(&packet(&info, 1, 0, None), 9000, false)],
        false,
        false,
    );
    let error = read(&info, moved.clone()).unwrap_err();
    assert!(error.to_string().contains("lidar_port"), "{error}");
    let options = OusterOptions {
        lidar_port: Some(9000),
        ..OusterOptions::default()
    };
    let frames: Vec<_> = OusterReader::new(Cursor::new(moved), "t", &info, options)
        .unwrap()
        .collect();
    assert_eq!(frames.len(), 1);
    // A truncated capture names the record.
    let mut bytes = classic(&two_frames(&info), false, false);
    bytes.truncate(bytes.len() - 10);
    let error = read(&info, bytes).unwrap_err();
    assert!(matches!(error, Error::Truncated { .. }), "{error}");
}

/// XYZ of known pixels: the encoder angle, beam elevation, beam-origin offset and the
/// lidar-to-sensor transform (Ouster Sensor Docs equations).
#[test]
fn xyz_known_answers() {
    let mut value = nested("RNG19_RFL8_SIG16_NIR16", 8, 2, 4, &[0, 0]);
    value["beam_intrinsics"]["beam_altitude_angles"] = json!([0.0, 30.0]);
    value["lidar_intrinsics"]["lidar_to_sensor_transform"] =
        json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    let info = info_of(&value);
    let lut = XyzLut::new(&info).unwrap();
    let mut range = vec![0.0f32; 16];
    range[0] = 10.0; // beam 0, m = 0: θ_e = 2π, straight along +x
    range[2] = 10.0; // beam 0, m = 2: θ_e = 2π · 3/4, along −y
    range[8] = 10.0; // beam 1 (30° up), m = 0
    let points = lut.points(&range).unwrap();
    let near =
        |p: nalgebra::Point3<f32>, q: [f32; 3]| (p - nalgebra::Point3::from(q)).norm() < 1e-5;
    assert!(near(points[0], [10.0, 0.0, 0.0]), "{:?}", points[0]);
    assert!(near(points[2], [0.0, -10.0, 0.0]), "{:?}", points[2]);
    // x = (r − n) cos φ + n, z = (r − n) sin φ with n = 15 mm.
    let (c, s) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
    assert!(
        near(points[8], [9.985 * c + 0.015, 0.0, 9.985 * s]),
        "{:?}",
        points[8]
    );
    assert!(points[1].x.is_nan());
    assert!(lut.points(&[1.0; 3]).is_err());
    // The default transform turns the lidar frame half around z and lifts it 36.18 mm.
    let turned = XyzLut::new(&small("RNG19_RFL8_SIG16_NIR16")).unwrap();
    let mut range = vec![0.0f32; 32];
    range[24] = 5.0; // beam 3 (shift 0, −10°), m = 0
    let p = turned.points(&range).unwrap()[24];
    let (c, s) = (10f32.to_radians().cos(), 10f32.to_radians().sin());
    assert!(
        near(p, [-(4.985 * c + 0.015), 0.0, -4.985 * s + 0.03618]),
        "{p:?}"
    );
}

#[test]
fn osf_and_names() {
    assert!(is_osf(Path::new("a.OSF"), b""));
    assert!(is_osf(Path::new("x"), b"4\0\0\0\x14\0\0\0OSF$"));
    assert!(is_capture_name(Path::new("x/y.pcap.gz")));
    assert!(!is_capture_name(Path::new("y.pcapx")));
    assert_eq!(capture_stem(Path::new("d/Run_1.PCAP")), "Run_1");
    assert!(
        osf_unsupported(Path::new("a.osf"))
            .to_string()
            .contains("ouster-cli")
    );
}
