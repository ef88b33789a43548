//! Ouster lidar recordings: UDP lidar packets in a packet capture (`.pcap`/`.pcapng`) decoded
//! with the sensor's metadata JSON into organized range images and point clouds.
//!
//! An Ouster OS-0/1/2 sends one UDP packet per `columns_per_packet` measurement columns; a
//! column holds one pixel per beam (range, reflectivity, signal, near-IR, a second return in
//! the dual-return profiles). The packets only make sense with the sensor's metadata
//! ([`SensorInfo`]): the packet profile, image size, beam angles and pixel shifts. The reader
//! follows the Ouster Sensor Docs ("Lidar Data Packet Format", "Sensor Metadata", "Lidar Range
//! Data To Sensor XYZ Coordinate Frame") for firmware 1.x (legacy packets, flat metadata), 2.x
//! (profile-based packets, flat metadata with `data_format`) and 3.x (nested metadata), and is
//! checked against the vendor's Python SDK (`ouster-sdk`) in `tests/ouster_python.rs`.
//!
//! * [`SensorInfo::read`] reads the metadata (both JSON layouts).
//! * [`OusterReader`] streams the frames of a capture ([`OusterFrame`]: destaggered `H × W`
//!   images of range, reflectivity, signal, near-IR and second return), assembled by frame
//!   id; missing columns are no-returns. [`read_frames`] reads them all.
//! * [`OusterFrame::to_point_cloud`] and [`XyzLut`] turn ranges into an organized
//!   [`raypath_geometry::PointCloud`] in the sensor frame (REP-103 axes, metres; NaN for no-returns;
//!   reflectivity as intensity).
//! * [`find_metadata`] finds the JSON of a capture (the rule is there); with it
//!   [`crate::Format::detect`] recognizes Ouster captures and `raypath info` summarizes them,
//!   and [`crate::sequence::SweepSequence::open`] opens a capture as a sweep sequence
//!   ([`open_sweeps`], with poses from a KITTI-layout `<stem>_poses_kitti.txt` beside it).
//!
//! Ouster's own recording format OSF (`.osf`) is recognized but not read: convert it with
//! `ouster-cli source FILE.osf save FILE.pcap` (Ouster SDK), which writes the pcap and its JSON.
//!
//! ```no_run
//! use raypath_io::ouster::{self, SensorInfo, OusterReader};
//! let pcap = std::path::Path::new("OS-1-128_v2.3.0_1024x10_lb_n3.pcap");
//! let info = SensorInfo::read(&ouster::find_metadata(pcap)?)?;
//! for frame in OusterReader::open(pcap, &info)? {
//!     let frame = frame?;
//!     let cloud = frame.to_point_cloud(&info)?; // 128 × 1024, NaN where no return
//!     println!("frame {}: {} returns", frame.frame_id, cloud.num_valid());
//! }
//! # Ok::<(), raypath_io::Error>(())
//! ```

mod frame;
mod json;
mod metadata;
mod net;
mod packet;
mod pcap;
mod reader;
mod sweeps;
mod xyz;

#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

pub use frame::OusterFrame;
pub use metadata::{HeaderType, LidarProfile, MetadataLayout, SensorInfo};
pub use pcap::CaptureStats;
pub use reader::{OusterOptions, OusterReader, ReadStats};
pub use sweeps::{open_sweeps, poses_path};
pub use xyz::XyzLut;

use crate::error::{Error, Location, Result};
use crate::summary::{BoundingBox, Summary, TimeSpan};

/// Reads every frame of a capture with its metadata JSON.
pub fn read_frames(pcap: &Path, json: &Path) -> Result<Vec<OusterFrame>> {
    let info = SensorInfo::read(json)?;
    OusterReader::open(pcap, &info)?.collect()
}

/// True for file names of packet captures (`.pcap`, `.pcapng`, optionally `.gz`/`.bz2`).
pub fn is_capture_name(path: &Path) -> bool {
    let name = file_name(path);
    let name = strip_compression(&name);
    name.ends_with(".pcap") || name.ends_with(".pcapng")
}

/// True for Ouster OSF recordings (`.osf`, or the OSF file identifier `OSF$` at byte 8).
pub fn is_osf(path: &Path, head: &[u8]) -> bool {
    file_name(path).ends_with(".osf") || head.get(8..12) == Some(b"OSF$".as_slice())
}

/// The error for reading an OSF recording.
pub fn osf_unsupported(path: &Path) -> Error {
    Error::UnknownFormat {
        path: path.to_path_buf(),
        reason: "Ouster OSF recordings are not supported; convert with ouster-cli to pcap \
                 (`ouster-cli source FILE.osf save FILE.pcap`, which writes the pcap and its \
                 metadata JSON)"
            .into(),
    }
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

fn strip_compression(name: &str) -> &str {
    name.strip_suffix(".gz")
        .or_else(|| name.strip_suffix(".bz2"))
        .unwrap_or(name)
}

/// The capture's name without `.pcap`/`.pcapng` and compression suffixes (case kept).
fn capture_stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    let mut keep = strip_compression(&lower).len();
    for suffix in [".pcapng", ".pcap"] {
        if lower[..keep].ends_with(suffix) {
            keep -= suffix.len();
            break;
        }
    }
    name[..keep].to_owned()
}

/// Datagrams sampled from the start of a capture to match metadata against it.
const SAMPLE_DATAGRAMS: usize = 2000;
/// Largest JSON file considered as metadata.
const MAX_JSON_BYTES: u64 = 16 << 20;

/// Finds the metadata JSON of an Ouster capture in its folder:
///
/// 1. `<stem>.json` beside `<stem>.pcap` (the name `ouster-cli` and Ouster's own samples
///    use), taken as is;
/// 2. otherwise, among the `.json` files of the folder that parse as Ouster metadata, those
///    whose lidar packet size (from their profile, lidar mode and beams) occurs among the
///    first 2000 UDP datagrams of the capture on their lidar port: the one there is, or, of
///    several, the one whose stem is the longest prefix of the capture's stem (as in
///    `OS-1-128_v2.3.0_1024x10.json` for `OS-1-128_v2.3.0_1024x10_lb_n3.pcap`).
///
/// Fails, naming the candidates, when none or several remain.
pub fn find_metadata(pcap: &Path) -> Result<PathBuf> {
    let stem = capture_stem(pcap);
    let dir = match pcap.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let same = dir.join(format!("{stem}.json"));
    if same.is_file() {
        return Ok(same);
    }
    let sizes = datagram_sizes(pcap)?;
    let entries = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, Location::File, e))?;
    let mut matching = Vec::new();
    for entry in entries.flatten() {
        let path = entry.path();
        let is_json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let small = entry
            .metadata()
            .is_ok_and(|m| m.is_file() && m.len() <= MAX_JSON_BYTES);
        if !is_json || !small {
            continue;
        }
        let Ok(info) = SensorInfo::read(&path) else {
            continue;
        };
        let bytes = info.lidar_packet_bytes();
        if sizes
            .iter()
            .any(|&(port, size)| size == bytes && info.udp_port_lidar.is_none_or(|p| p == port))
        {
            matching.push(path);
        }
    }
    matching.sort();
    if matching.len() > 1 {
        let prefix_len = |p: &PathBuf| {
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .filter(|s| stem.starts_with(s.as_str()))
                .map_or(0, |s| s.len())
        };
        let best = matching.iter().map(prefix_len).max().unwrap_or(0);
        if best > 0 {
            matching.retain(|p| prefix_len(p) == best);
        }
    }
    match matching.as_slice() {
        [one] => Ok(one.clone()),
        [] => Err(Error::UnknownFormat {
            path: pcap.to_path_buf(),
            reason: format!(
                "a packet capture without Ouster metadata: no {stem}.json beside it, and no \
                 .json in {} whose lidar packet size matches the capture's datagrams",
                dir.display()
            ),
        }),
        several => Err(Error::UnknownFormat {
            path: pcap.to_path_buf(),
            reason: format!(
                "several Ouster metadata files match this capture ({}); name one {stem}.json",
                several
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }),
    }
}

/// `(destination port, payload size)` of the first datagrams of a capture.
fn datagram_sizes(pcap: &Path) -> Result<Vec<(u16, usize)>> {
    let mut reader = pcap::PcapReader::new(crate::source::open(pcap)?, pcap)?;
    let mut sizes = Vec::new();
    for _ in 0..SAMPLE_DATAGRAMS {
        let Some(d) = reader.next_datagram()? else {
            break;
        };
        let key = (d.dst_port, d.payload.len());
        if !sizes.contains(&key) {
            sizes.push(key);
        }
    }
    Ok(sizes)
}

/// True when `head` (a file's first bytes) starts like a pcap or pcapng capture.
pub fn is_capture_head(head: &[u8]) -> bool {
    pcap::is_capture(head)
}

/// What `raypath info` prints for an Ouster capture: frames (`scans`), beams, `width` ×
/// `height` (columns × beams), pixels (`points`), the bounding box of all returns (sensor
/// frame), the time span (sensor clock), and under their own names the metadata file,
/// product line, firmware, lidar mode, profile, complete frames, the first and last frame id
/// and the number of gaps between them, valid returns per frame (`min`, `mean`, `max`), the
/// range span (m) and, for dual-return profiles, second returns per frame.
pub fn summarize(path: &Path) -> Result<Summary> {
    let json = find_metadata(path)?;
    let info = SensorInfo::read(&json)?;
    let lut = XyzLut::new(&info)?;
    let mut summary = Summary::new(crate::Format::OusterPcap.name());
    let mut aabb = raypath_geometry::Aabb3::empty();
    let (mut ids, mut returns, mut returns2) = (Vec::new(), Vec::new(), Vec::new());
    let (mut complete, mut span, mut time) = (0u64, None::<(f32, f32)>, None);
    for frame in OusterReader::open(path, &info)? {
        let frame = frame?;
        ids.push(frame.frame_id);
        returns.push(frame.valid_returns());
        returns2.push(frame.valid_second_returns());
        complete += u64::from(frame.is_complete(&info));
        if let Some((lo, hi)) = frame.range_span_m() {
            span = Some(span.map_or((lo, hi), |(a, b): (f32, f32)| (a.min(lo), b.max(hi))));
        }
        TimeSpan::extend(&mut time, frame.timestamp_s);
        aabb = aabb.union(&lut.cloud(&frame)?.bounding_box());
    }
    let frames = ids.len() as u64;
    let (w, h) = (info.columns_per_frame as u64, info.pixels_per_column as u64);
    summary.scans = Some(frames);
    summary.beams = Some(h);
    summary.width = Some(w);
    summary.height = Some(h);
    summary.points = Some(frames * w * h);
    summary.bbox = BoundingBox::from_aabb(&aabb);
    summary.time_span = time;
    summary = summary
        .with_extra("metadata", json.display().to_string())
        .with_extra("product", info.prod_line.clone())
        .with_extra("firmware", info.firmware.clone())
        .with_extra("lidar_mode", info.lidar_mode.clone())
        .with_extra("profile", info.profile_name.clone())
        .with_extra("complete_frames", complete);
    if let (Some(&first), Some(&last)) = (ids.first(), ids.last()) {
        // Steps other than +1 (16-bit counters wrap to 0).
        let gaps = ids
            .windows(2)
            .filter(|p| p[1] != p[0].wrapping_add(1) && !(p[0] == 65_535 && p[1] == 0))
            .count();
        summary = summary
            .with_extra("frame_ids", vec![first, last])
            .with_extra("frame_id_gaps", gaps)
            .with_extra("valid_returns", per_frame(&returns));
    }
    if let Some((lo, hi)) = span {
        let mm = |v: f32| (f64::from(v) * 1e3).round() / 1e3;
        summary = summary.with_extra("range_span_m", vec![mm(lo), mm(hi)]);
    }
    if info.profile.is_dual() && !returns2.is_empty() {
        summary = summary.with_extra("second_returns", per_frame(&returns2));
    }
    Ok(summary)
}

/// `{min, mean, max}` of per-frame counts.
fn per_frame(counts: &[usize]) -> serde_json::Value {
    let min = counts.iter().min().copied().unwrap_or(0);
    let max = counts.iter().max().copied().unwrap_or(0);
    let mean = counts.iter().sum::<usize>() as f64 / counts.len().max(1) as f64;
    serde_json::json!({ "min": min, "mean": (mean * 10.0).round() / 10.0, "max": max })
}
