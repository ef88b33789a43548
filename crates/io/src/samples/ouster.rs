//! Ouster captures: sensor metadata of every firmware generation and packet profile, and
//! captures of their lidar packets.

use super::pcap::{classic_pcap, pcapng, udp_frames};
use crate::ouster::{HeaderType, LidarProfile, SensorInfo};

/// An Ouster sensor for the synthetic captures: its metadata and the capture layout.
#[derive(Clone, Debug)]
pub struct OusterSample {
    /// The metadata JSON, as the sensor or `ouster-cli` writes it.
    pub json: String,
    /// How [`ouster_capture`] packages this sensor's packets.
    pub capture: Capture,
}

/// How a synthetic capture is packaged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Capture {
    /// Classic pcap, little-endian, microseconds.
    Classic,
    /// Classic pcap, big-endian, nanoseconds.
    ClassicBigNanos,
    /// pcapng with a section header, an interface, a block to skip and enhanced packets.
    Pcapng,
    /// Classic pcap with the lidar packets cut into IP fragments and an 802.1Q tag.
    Fragmented,
}

fn lidar_transform() -> &'static str {
    "[-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1]"
}

/// Nested (firmware 3.x) metadata.
fn nested_json(profile: &str, w: usize, h: usize, cpp: usize, shifts: &[i32]) -> String {
    let altitudes: Vec<String> = (0..h)
        .map(|r| format!("{}", 10.0 - 20.0 * r as f64 / (h.max(2) - 1) as f64))
        .collect();
    let azimuths: Vec<String> = (0..h).map(|r| format!("{}", 1.5 - r as f64)).collect();
    let shifts: Vec<String> = shifts.iter().map(i32::to_string).collect();
    format!(
        r#"{{
  "sensor_info": {{"prod_line": "OS-1-16", "prod_sn": "991234567890", "build_rev": "v3.0.1",
                  "initialization_id": 4242}},
  "config_params": {{"lidar_mode": "{w}x10", "udp_port_lidar": 7502,
                    "udp_profile_lidar": "{profile}"}},
  "lidar_data_format": {{"columns_per_frame": {w}, "columns_per_packet": {cpp},
                        "pixels_per_column": {h}, "column_window": [0, {last}],
                        "pixel_shift_by_row": [{shifts}],
                        "udp_profile_lidar": "{profile}"}},
  "beam_intrinsics": {{"beam_altitude_angles": [{alt}],
                      "beam_azimuth_angles": [{azi}],
                      "lidar_origin_to_beam_origin_mm": 15.806}},
  "lidar_intrinsics": {{"lidar_to_sensor_transform": {tr}}}
}}"#,
        last = w - 1,
        shifts = shifts.join(", "),
        alt = altitudes.join(", "),
        azi = azimuths.join(", "),
        tr = lidar_transform(),
    )
}

/// Four sensors: nested metadata with the standard profile, nested with the low-data
/// profile in FUSA packets, flat (firmware 2.x) with the dual-return profile, flat without a
/// data format (firmware 1.x, legacy packets; a partial frame).
pub fn ouster_sensors() -> Vec<OusterSample> {
    let flat2 = format!(
        r#"{{"prod_line": "OS-0-32", "prod_sn": "992000000001", "build_rev": "v2.3.0",
 "initialization_id": 77, "lidar_mode": "512x20", "udp_port_lidar": 7502,
 "data_format": {{"columns_per_frame": 8, "columns_per_packet": 4, "pixels_per_column": 2,
                 "column_window": [6, 3], "pixel_shift_by_row": [1, 0],
                 "udp_profile_lidar": "RNG19_RFL8_SIG16_NIR16_DUAL"}},
 "beam_altitude_angles": [4.5, -4.5], "beam_azimuth_angles": [0.5, -0.5],
 "lidar_origin_to_beam_origin_mm": 27.116, "lidar_to_sensor_transform": {tr}}}"#,
        tr = lidar_transform(),
    );
    let legacy = r#"{"prod_line": "OS-1-64", "prod_sn": "991900001", "build_rev": "v1.13.0",
 "lidar_mode": "512x10", "beam_altitude_angles": [16.0, 15.5, 15.0, 14.5],
 "beam_azimuth_angles": [3.0, 1.0, -1.0, -3.0]}"#
        .to_string();
    vec![
        OusterSample {
            json: nested_json("RNG19_RFL8_SIG16_NIR16", 16, 4, 4, &[3, 2, -1, 0]),
            capture: Capture::Classic,
        },
        OusterSample {
            json: nested_json("RNG19_RFL8_SIG16_NIR16", 16, 4, 4, &[3, 2, -1, 0]),
            capture: Capture::Fragmented,
        },
        OusterSample {
            json: nested_json("FUSA_RNG15_RFL8_NIR8_DUAL", 8, 4, 4, &[0, 0, 0, 0]),
            capture: Capture::Pcapng,
        },
        OusterSample {
            json: flat2,
            capture: Capture::ClassicBigNanos,
        },
        OusterSample {
            json: legacy,
            capture: Capture::Classic,
        },
    ]
}

/// A byte that looks random: every bit pattern turns up across frames, columns and bytes.
fn scrambled(frame: u32, column: usize, k: usize) -> u8 {
    let x = (u64::from(frame) << 40 ^ (column as u64) << 20 ^ k as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    (x >> 56) as u8
}

/// Writes the packet header of frame `f` (packet type, frame id, initialization id and
/// serial number in the standard or FUSA layout; legacy packets have none).
pub(crate) fn write_packet_header(b: &mut [u8], info: &SensorInfo, f: u32) {
    let serial: u64 = info.serial.trim().parse().unwrap_or(0);
    let init_id = info.init_id.unwrap_or(0);
    match (info.profile == LidarProfile::Legacy, info.header_type) {
        (true, _) => {}
        (false, HeaderType::Standard) => {
            put16(b, 0, 1);
            put16(b, 2, f as u16);
            put32(b, 4, init_id);
            b[7..12].copy_from_slice(&serial.to_le_bytes()[..5]);
        }
        (false, HeaderType::Fusa) => {
            put32(b, 0, 1 | init_id << 8);
            put32(b, 4, f);
            b[11..16].copy_from_slice(&serial.to_le_bytes()[..5]);
        }
    }
}

pub(crate) fn put16(b: &mut [u8], at: usize, v: u16) {
    b[at..at + 2].copy_from_slice(&v.to_le_bytes());
}

pub(crate) fn put32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// One lidar packet of frame `f` with columns `first..first + cpp`; pixel bytes are
/// scrambled (every bit pattern is a valid pixel).
fn ouster_packet(info: &SensorInfo, f: u32, first: usize) -> Vec<u8> {
    let legacy = info.profile == LidarProfile::Legacy;
    let (packet_header, column_header, column_footer) =
        if legacy { (0, 16, 4) } else { (32, 12, 0) };
    let pixels = info.pixels_per_column * info.profile.pixel_bytes();
    let column_bytes = column_header + pixels + column_footer;
    let mut b = vec![0u8; info.lidar_packet_bytes()];
    write_packet_header(&mut b, info, f);
    for c in 0..info.columns_per_packet {
        let m = first + c;
        let at = packet_header + c * column_bytes;
        let col = &mut b[at..at + column_bytes];
        col[..8].copy_from_slice(&(1_000_000_000 * u64::from(f) + 1000 * m as u64).to_le_bytes());
        put16(col, 8, m as u16);
        if legacy {
            put16(col, 10, f as u16);
            put32(col, column_bytes - 4, u32::MAX);
        } else {
            put16(col, 10, 1);
        }
        for (k, byte) in col[column_header..column_header + pixels]
            .iter_mut()
            .enumerate()
        {
            *byte = scrambled(f, m, k);
        }
    }
    b
}

/// A capture of the sensor of `json`: two frames (legacy: the first two packets of one frame
/// and one of the next), with a non-lidar datagram after each frame.
pub fn ouster_capture(info: &SensorInfo, capture: Capture) -> Vec<u8> {
    let cpp = info.columns_per_packet;
    let packets: Vec<(u32, usize)> = if info.profile == LidarProfile::Legacy {
        vec![(5, 0), (5, cpp), (6, 0)]
    } else {
        [5u32, 6]
            .iter()
            .flat_map(|&f| {
                (0..info.columns_per_frame)
                    .step_by(cpp)
                    .map(move |m| (f, m))
            })
            .collect()
    };
    let (mtu, vlan) = match capture {
        Capture::Fragmented => (96, true),
        _ => (usize::MAX / 2, false),
    };
    let mut frames = Vec::new();
    for (k, &(f, first)) in packets.iter().enumerate() {
        let packet = ouster_packet(info, f, first);
        frames.extend(udp_frames(&packet, 7502, k as u16, mtu, vlan));
        let last_of_frame = packets.get(k + 1).is_none_or(|next| next.0 != f);
        if last_of_frame {
            frames.extend(udp_frames(&[7u8; 48], 7503, 1000 + k as u16, mtu, vlan));
        }
    }
    match capture {
        Capture::Classic | Capture::Fragmented => classic_pcap(&frames, false, false),
        Capture::ClassicBigNanos => classic_pcap(&frames, true, true),
        Capture::Pcapng => pcapng(&frames),
    }
}
