//! An Ouster capture as a [`SweepSequence`]: one sweep per frame, with poses from a
//! KITTI-layout poses file beside the capture when there is one.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::metadata::SensorInfo;
use super::pcap::CaptureFormat;
use super::reader::{FrameStart, OusterOptions, OusterReader};
use super::xyz::XyzLut;
use super::{capture_stem, find_metadata};
use crate::error::{Error, Result};
use crate::sequence::SweepSequence;

/// The poses file of a capture, `<stem>_poses_kitti.txt` beside `<stem>.pcap` (the name
/// Ouster's sample data uses), when it exists.
pub fn poses_path(pcap: &Path) -> Option<PathBuf> {
    let path = pcap.with_file_name(format!("{}_poses_kitti.txt", capture_stem(pcap)));
    path.is_file().then_some(path)
}

/// Opens an Ouster capture as a sweep sequence: its metadata from [`find_metadata`], one
/// sweep per frame (the organized first-return cloud of [`XyzLut::cloud`]: sensor frame,
/// REP-103 axes, NaN for no-returns), stamped with the frame timestamps (the sensor's clock).
/// Frames without any valid column carry no points and are left out.
///
/// With a [`poses_path`] file, its poses (KITTI 3 × 4 layout, one per frame) are taken as
/// `world_from_sensor` of each sweep, for both the reference and the odometry tracks (as for
/// KITTI, which has no separate odometry). The sequence reports
/// [`crate::sequence::SweepFormat::Ouster`].
///
/// Sweeps are read on demand: an uncompressed capture is re-opened at the frame's first
/// packet; a compressed one is read from the start.
pub fn open_sweeps(pcap: &Path) -> Result<SweepSequence> {
    let json = find_metadata(pcap)?;
    let info = SensorInfo::read(&json)?;
    let mut reader = OusterReader::open(pcap, &info)?;
    let mut stamps = Vec::new();
    let mut starts: Vec<Option<(FrameStart, CaptureFormat)>> = Vec::new();
    let mut frame_index = Vec::new();
    let mut k = 0usize;
    while let Some(frame) = reader.next() {
        let frame = frame?;
        if frame.timestamp_s.is_finite() {
            stamps.push(frame.timestamp_s);
            frame_index.push(k);
            starts.push(
                reader
                    .last_frame_start()
                    .cloned()
                    .map(|s| (s, reader.capture_format().clone())),
            );
        }
        k += 1;
    }
    let reference = match poses_path(pcap) {
        Some(path) => {
            let poses = crate::kitti::read_poses(&path)?;
            if poses.len() != k {
                return Err(Error::UnknownFormat {
                    path,
                    reason: format!(
                        "{} poses for the {k} frames of {}",
                        poses.len(),
                        pcap.display()
                    ),
                });
            }
            Some(frame_index.iter().map(|&i| poses[i]).collect::<Vec<_>>())
        }
        None => None,
    };
    let plain = crate::source::plain_len(pcap)?.is_some();
    let lut = Arc::new(XyzLut::new(&info)?);
    let path = pcap.to_path_buf();
    let read = move |index: usize| {
        let frame = match (plain, starts.get(index)) {
            (true, Some(Some((start, format)))) => OusterReader::open_at(
                &path,
                &info,
                OusterOptions::default(),
                format.clone(),
                start,
            )?
            .next(),
            _ => {
                let skip = frame_index.get(index).copied().unwrap_or(usize::MAX);
                OusterReader::open(&path, &info)?.nth(skip)
            }
        };
        let frame = frame.ok_or_else(|| Error::UnknownFormat {
            path: path.clone(),
            reason: format!("no frame for sweep {index}"),
        })??;
        lut.cloud(&frame)
    };
    SweepSequence::from_reader(
        pcap.to_path_buf(),
        crate::sequence::SweepFormat::Ouster,
        stamps,
        reference.clone(),
        reference,
        Box::new(read),
    )
}
