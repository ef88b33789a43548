//! Reading a capture frame by frame: lidar packets picked from the UDP datagrams, checked
//! against the metadata, and assembled by frame id.

use std::fs::File;
use std::io::{BufRead, BufReader, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use super::frame::{FrameBuilder, OusterFrame};
use super::metadata::SensorInfo;
use super::packet::{PacketHeader, PacketLayout};
use super::pcap::{CaptureFormat, CaptureStats, PcapReader};
use crate::error::{Error, Location, Result};

/// How [`OusterReader`] picks and checks lidar packets.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OusterOptions {
    /// UDP destination port of the lidar packets. Default `None`: the metadata's
    /// `udp_port_lidar`, or, when the metadata names none, every datagram of the lidar
    /// packet size.
    pub lidar_port: Option<u16>,
    /// Require the packets' initialization id and serial number to equal the metadata's
    /// (default true, as the Ouster SDK does: metadata of another sensor or power cycle
    /// decodes wrongly).
    pub check_sensor_ids: bool,
}

impl Default for OusterOptions {
    fn default() -> Self {
        Self {
            lidar_port: None,
            check_sensor_ids: true,
        }
    }
}

/// Counts of what a reader saw and passed over.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReadStats {
    /// The capture layer: records, non-UDP records, fragments.
    pub capture: CaptureStats,
    /// Lidar packets decoded.
    pub lidar_packets: u64,
    /// UDP datagrams that are not lidar packets (IMU packets, other ports), skipped.
    pub other_datagrams: u64,
    /// Lidar packets of the frame just finished that arrived after the next frame began,
    /// skipped (as the Ouster SDK does).
    pub late_packets: u64,
    /// Datagrams of the lidar packet size on other ports than the lidar port.
    pub lidar_sized_elsewhere: u64,
}

/// Where a frame starts in the capture, so it can be read again without reading the frames
/// before it.
#[derive(Clone, Debug)]
pub(crate) struct FrameStart {
    /// Offset of the capture record (pcapng: block) of the frame's first packet.
    pub record_offset: u64,
    /// The frame id of the frame before (its late packets are skipped).
    pub previous_frame_id: Option<u32>,
}

/// Reads the frames of an Ouster packet capture, one [`OusterFrame`] per frame id.
///
/// A frame ends when a packet of another frame id arrives, or at the end of the capture;
/// columns that never arrived stay no-returns. Packets of the frame just finished that
/// arrive late are skipped (counted in [`ReadStats::late_packets`]), as the Ouster SDK does.
/// Every lidar packet is checked against the metadata (size, packet type, sensor ids,
/// measurement ids); a mismatch is an error naming the file and byte. After an error the
/// iterator ends.
pub struct OusterReader {
    pcap: PcapReader<Box<dyn BufRead + Send>>,
    name: PathBuf,
    info: SensorInfo,
    layout: PacketLayout,
    options: OusterOptions,
    serial: Option<u64>,
    port: Option<u16>,
    current: Option<(FrameBuilder, FrameStart)>,
    last_finished: Option<u32>,
    last_start: Option<FrameStart>,
    stats: ReadStats,
    done: bool,
}

impl OusterReader {
    /// Opens a capture (`.pcap` or `.pcapng`, plain or gzip/bzip2) with default options.
    pub fn open(path: &Path, info: &SensorInfo) -> Result<Self> {
        Self::open_with(path, info, OusterOptions::default())
    }

    /// Opens a capture with `options`.
    pub fn open_with(path: &Path, info: &SensorInfo, options: OusterOptions) -> Result<Self> {
        Self::new(crate::source::open(path)?, path, info, options)
    }

    /// Reads a capture from `reader`; `name` is used in errors.
    pub fn new(
        reader: impl BufRead + Send + 'static,
        name: impl Into<PathBuf>,
        info: &SensorInfo,
        options: OusterOptions,
    ) -> Result<Self> {
        let name = name.into();
        let reader: Box<dyn BufRead + Send> = Box::new(reader);
        info.validate()?;
        let pcap = PcapReader::new(reader, &name)?;
        Ok(Self::with_pcap(pcap, name, info, options))
    }

    fn with_pcap(
        pcap: PcapReader<Box<dyn BufRead + Send>>,
        name: PathBuf,
        info: &SensorInfo,
        options: OusterOptions,
    ) -> Self {
        Self {
            pcap,
            layout: PacketLayout::new(info),
            serial: info.serial.trim().parse().ok(),
            info: info.clone(),
            port: options.lidar_port.or(info.udp_port_lidar),
            options,
            name,
            current: None,
            last_finished: None,
            last_start: None,
            stats: ReadStats::default(),
            done: false,
        }
    }

    /// Opens a plain (uncompressed) capture at a frame start found by an earlier reader with
    /// `options`, whose header gave `format`.
    pub(crate) fn open_at(
        path: &Path,
        info: &SensorInfo,
        options: OusterOptions,
        format: CaptureFormat,
        start: &FrameStart,
    ) -> Result<Self> {
        let mut file = File::open(path).map_err(|e| Error::io(path, Location::File, e))?;
        file.seek(SeekFrom::Start(start.record_offset))
            .map_err(|e| Error::io(path, Location::Byte(start.record_offset), e))?;
        let reader: Box<dyn BufRead + Send> = Box::new(BufReader::with_capacity(1 << 16, file));
        let pcap = PcapReader::resume(reader, path, format, start.record_offset);
        let mut out = Self::with_pcap(pcap, path.to_path_buf(), info, options);
        out.last_finished = start.previous_frame_id;
        Ok(out)
    }

    /// The metadata the reader decodes with.
    pub fn info(&self) -> &SensorInfo {
        &self.info
    }

    /// What the reader saw and passed over so far.
    pub fn stats(&self) -> ReadStats {
        ReadStats {
            capture: self.pcap.stats(),
            ..self.stats
        }
    }

    pub(crate) fn capture_format(&self) -> &CaptureFormat {
        self.pcap.format()
    }

    /// Where the frame last returned by [`Iterator::next`] starts.
    pub(crate) fn last_frame_start(&self) -> Option<&FrameStart> {
        self.last_start.as_ref()
    }

    fn error(&self, at: u64, reason: String) -> Error {
        Error::malformed(&self.name, Location::Byte(at), reason)
    }

    /// Reads datagrams until a frame is complete.
    fn next_frame(&mut self) -> Result<Option<OusterFrame>> {
        loop {
            let Some(datagram) = self.pcap.next_datagram()? else {
                return self.finish_at_end();
            };
            let size = datagram.payload.len();
            let on_port = self.port.is_none_or(|p| p == datagram.dst_port);
            if size != self.layout.packet_bytes || !on_port {
                if size == self.layout.packet_bytes {
                    self.stats.lidar_sized_elsewhere += 1;
                } else if on_port && self.port.is_some() {
                    let reason = format!(
                        "a {size}-byte datagram on the lidar port {}, but the metadata {} ({}, \
                         {} columns of {} pixels) makes {}-byte lidar packets: the metadata \
                         does not belong to this capture",
                        datagram.dst_port,
                        self.info.source.display(),
                        self.info.profile_name,
                        self.info.columns_per_packet,
                        self.info.pixels_per_column,
                        self.layout.packet_bytes
                    );
                    let at = datagram.payload_offset;
                    return Err(self.error(at, reason));
                }
                self.stats.other_datagrams += 1;
                continue;
            }
            let (at, record) = (datagram.payload_offset, datagram.record_offset);
            let capture_time_s = datagram.stamp_s;
            let packet = datagram.payload;
            let header = self.layout.header(packet);
            if let Some(reason) = check_header(&self.info, self.serial, &self.options, &header) {
                return Err(Error::malformed(&self.name, Location::Byte(at), reason));
            }
            let mut finished = None;
            match &self.current {
                Some((b, _)) if b.frame_id() == header.frame_id => {}
                _ if self.last_finished == Some(header.frame_id) => {
                    self.stats.late_packets += 1;
                    continue;
                }
                _ => {
                    let previous = self.current.as_ref().map(|(b, _)| b.frame_id());
                    let start = FrameStart {
                        record_offset: record,
                        previous_frame_id: previous.or(self.last_finished),
                    };
                    let next = FrameBuilder::new(&self.info, header.frame_id, capture_time_s);
                    finished = self.current.replace((next, start));
                }
            }
            let Some((builder, _)) = self.current.as_mut() else {
                continue;
            };
            if let Some((c, m)) = self.layout.decode_into(packet, builder) {
                let at = at + self.layout.column_offset(c) as u64 + 8;
                let reason = format!(
                    "measurement id {m} is not below the {} columns per frame of the metadata \
                     ({})",
                    self.info.columns_per_frame, self.info.lidar_mode
                );
                return Err(self.error(at, reason));
            }
            builder.count_packet();
            self.stats.lidar_packets += 1;
            if let Some(done) = finished {
                return Ok(Some(self.complete(done)));
            }
        }
    }

    fn complete(&mut self, (builder, start): (FrameBuilder, FrameStart)) -> OusterFrame {
        self.last_finished = Some(builder.frame_id());
        self.last_start = Some(start);
        builder.finish()
    }

    /// At the end of the capture: the last frame, or an error when lidar-sized packets were
    /// all on another port than the lidar port.
    fn finish_at_end(&mut self) -> Result<Option<OusterFrame>> {
        if let Some(done) = self.current.take() {
            return Ok(Some(self.complete(done)));
        }
        if self.last_finished.is_none() && self.stats.lidar_sized_elsewhere > 0 {
            return Err(Error::malformed(
                &self.name,
                Location::File,
                format!(
                    "no lidar packets on UDP port {} (from {}), but {} datagrams of the lidar \
                     packet size ({} bytes) on other ports: set OusterOptions::lidar_port",
                    self.port.unwrap_or(0),
                    if self.options.lidar_port.is_some() {
                        "the options".to_owned()
                    } else {
                        self.info.source.display().to_string()
                    },
                    self.stats.lidar_sized_elsewhere,
                    self.layout.packet_bytes
                ),
            ));
        }
        Ok(None)
    }
}

/// Why a packet header does not fit the metadata, if it does not.
fn check_header(
    info: &SensorInfo,
    serial: Option<u64>,
    options: &OusterOptions,
    header: &PacketHeader,
) -> Option<String> {
    if let Some(t) = header.packet_type
        && t != 1
    {
        return Some(format!("packet type {t} is not a lidar packet (1)"));
    }
    if !options.check_sensor_ids {
        return None;
    }
    if let (Some(ours), Some(theirs)) = (info.init_id, header.init_id)
        && ours != theirs
    {
        return Some(format!(
            "the packet's initialization id {theirs} differs from the metadata's {ours} \
             ({}): the metadata is from another sensor or power cycle (or turn off \
             OusterOptions::check_sensor_ids)",
            info.source.display()
        ));
    }
    if let (Some(ours), Some(theirs)) = (serial, header.serial)
        && ours != theirs
    {
        return Some(format!(
            "the packet's serial number {theirs} differs from the metadata's {ours} ({})",
            info.source.display()
        ));
    }
    None
}

impl Iterator for OusterReader {
    type Item = Result<OusterFrame>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match self.next_frame() {
            Ok(Some(frame)) => Some(Ok(frame)),
            Ok(None) => {
                self.done = true;
                None
            }
            Err(e) => {
                self.done = true;
                Some(Err(e))
            }
        }
    }
}
