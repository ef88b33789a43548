//! NCLT velodyne data: `velodyne_sync/<utime>.bin` revolutions and the `velodyne_hits.bin`
//! packet stream. Both store points as 8-byte records:
//!
//! ```text
//! u16 x, u16 y, u16 z (little-endian; metres = raw · 0.005 − 100), u8 intensity, u8 laser id
//! ```
//!
//! `velodyne_hits.bin` is a sequence of packets, each a 24-byte header
//! `{u64 magic = 0xad9cad9cad9cad9c, u32 num_hits, u64 utime, 4 bytes padding}` followed by
//! `num_hits` records. The reader is strict: a header without the magic number is an error
//! naming its byte offset (no resynchronization).

use std::io::BufRead;
use std::path::{Path, PathBuf};

use nalgebra::Point3;
use raypath_geometry::PointCloud;

use crate::source::{self, ByteReader};
use crate::{Error, Location, Result};

/// Magic number of a `velodyne_hits.bin` packet header.
pub const HITS_MAGIC: u64 = 0xad9c_ad9c_ad9c_ad9c;
/// Bytes of a packet header of `velodyne_hits.bin`.
pub const HITS_HEADER_BYTES: u64 = 24;
/// Bytes of one point record.
pub const RECORD_BYTES: u64 = 8;
/// Metres per raw coordinate unit.
pub const SCALE_M: f64 = 0.005;
/// Offset added after scaling, metres (raw 20000 is 0 m).
pub const OFFSET_M: f64 = -100.0;
/// Largest `num_hits` accepted in a packet header. A Velodyne HDL-32E packet holds
/// 12 × 32 = 384 returns; the limit leaves ample room while stopping a corrupt count from
/// allocating gigabytes.
pub const MAX_HITS_PER_PACKET: u32 = 1 << 16;

/// Metres of a raw coordinate: `raw · 0.005 − 100`.
pub fn decode_coordinate(raw: u16) -> f64 {
    f64::from(raw) * SCALE_M + OFFSET_M
}

/// The microsecond timestamp in a file name (`1326030975726043.bin`).
pub fn utime_from_path(path: &Path) -> Option<u64> {
    path.file_stem()?.to_str()?.parse().ok()
}

/// Reads one `velodyne_sync` revolution (plain or compressed): points in the velodyne frame
/// as stored, intensity (0–255) and laser id (0–31, in `label`).
pub fn read_velodyne_sync(path: &Path) -> Result<PointCloud> {
    parse_velodyne_sync(&source::read_all(path)?, path)
}

/// Parses a revolution held in memory; `name` is used in errors. Fails when the length is
/// not a multiple of 8 bytes.
pub fn parse_velodyne_sync(bytes: &[u8], name: impl Into<PathBuf>) -> Result<PointCloud> {
    let name = name.into();
    let len = bytes.len() as u64;
    if len % RECORD_BYTES != 0 {
        return Err(Error::malformed(
            name,
            Location::Byte(len - len % RECORD_BYTES),
            format!("file size {len} is not a multiple of {RECORD_BYTES}-byte point records"),
        ));
    }
    let mut cloud = Cloud::with_capacity(bytes.len() / RECORD_BYTES as usize);
    for record in bytes.chunks_exact(RECORD_BYTES as usize) {
        cloud.push(record);
    }
    Ok(cloud.finish())
}

/// Turns a cloud from a z-down frame (x forward, y right, z down) into REP-103 axes
/// (x forward, y left, z up) by negating y and z.
pub fn flu_from_frd(cloud: &mut PointCloud) {
    for p in &mut cloud.points {
        p.y = -p.y;
        p.z = -p.z;
    }
}

/// Output vectors of a decoded cloud.
struct Cloud {
    points: Vec<Point3<f32>>,
    intensity: Vec<f32>,
    laser: Vec<u32>,
}

impl Cloud {
    fn with_capacity(n: usize) -> Self {
        Self {
            points: Vec::with_capacity(n),
            intensity: Vec::with_capacity(n),
            laser: Vec::with_capacity(n),
        }
    }

    /// Decodes one 8-byte record (`record` has exactly 8 bytes).
    fn push(&mut self, record: &[u8]) {
        let raw = |i: usize| {
            let lo = record.get(2 * i).copied().unwrap_or(0);
            let hi = record.get(2 * i + 1).copied().unwrap_or(0);
            decode_coordinate(u16::from_le_bytes([lo, hi])) as f32
        };
        self.points.push(Point3::new(raw(0), raw(1), raw(2)));
        self.intensity
            .push(f32::from(record.get(6).copied().unwrap_or(0)));
        self.laser
            .push(u32::from(record.get(7).copied().unwrap_or(0)));
    }

    fn finish(self) -> PointCloud {
        let mut cloud = PointCloud::from_points(self.points);
        cloud.intensity = Some(self.intensity);
        cloud.label = Some(self.laser);
        cloud
    }
}

/// A packet header of `velodyne_hits.bin`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HitsHeader {
    /// Byte offset of the header in the file.
    pub offset: u64,
    /// Number of point records after the header.
    pub num_hits: u32,
    /// Timestamp, microseconds since the UNIX epoch.
    pub utime: u64,
}

/// One packet of `velodyne_hits.bin`.
#[derive(Clone, Debug, PartialEq)]
pub struct HitsPacket {
    /// The packet header.
    pub header: HitsHeader,
    /// Its points (velodyne frame as stored, intensity, laser id in `label`).
    pub points: PointCloud,
}

/// Streams the packets of `velodyne_hits.bin` (gigabytes per session) one at a time.
pub struct HitsReader<R> {
    bytes: ByteReader<R>,
    len: Option<u64>,
    failed: bool,
}

impl HitsReader<Box<dyn BufRead + Send>> {
    /// Opens a packet stream (plain or compressed).
    pub fn open(path: &Path) -> Result<Self> {
        let len = source::plain_len(path)?;
        Ok(Self::new(source::open(path)?, path, len))
    }
}

impl<R: BufRead> HitsReader<R> {
    /// Reads packets from `reader`; `name` is used in errors, `len` (the input length when
    /// known) checks hit counts before anything is allocated.
    pub fn new(reader: R, name: impl Into<PathBuf>, len: Option<u64>) -> Self {
        Self {
            bytes: ByteReader::new(reader, name, 0),
            len,
            failed: false,
        }
    }

    /// The next packet, `None` at the end of the stream.
    pub fn next_packet(&mut self) -> Result<Option<HitsPacket>> {
        let Some(header) = self.next_header()? else {
            return Ok(None);
        };
        let mut cloud = Cloud::with_capacity(header.num_hits as usize);
        let mut record = [0u8; RECORD_BYTES as usize];
        for _ in 0..header.num_hits {
            self.bytes.read_exact(&mut record, "point record")?;
            cloud.push(&record);
        }
        Ok(Some(HitsPacket {
            header,
            points: cloud.finish(),
        }))
    }

    /// The next packet header, skipping its points (for counting), `None` at the end.
    pub fn next_header_skip_points(&mut self) -> Result<Option<HitsHeader>> {
        let Some(header) = self.next_header()? else {
            return Ok(None);
        };
        let mut left = u64::from(header.num_hits) * RECORD_BYTES;
        let mut buf = [0u8; 4096];
        while left > 0 {
            let n = left.min(buf.len() as u64) as usize;
            self.bytes.read_exact(&mut buf[..n], "point records")?;
            left -= n as u64;
        }
        Ok(Some(header))
    }

    fn next_header(&mut self) -> Result<Option<HitsHeader>> {
        if self.bytes.at_end()? {
            return Ok(None);
        }
        let offset = self.bytes.offset();
        let mut raw = [0u8; HITS_HEADER_BYTES as usize];
        self.bytes.read_exact(&mut raw, "packet header")?;
        let field = |range: std::ops::Range<usize>| {
            let mut b = [0u8; 8];
            if let (Some(dst), Some(src)) = (b.get_mut(..range.len()), raw.get(range)) {
                dst.copy_from_slice(src);
            }
            u64::from_le_bytes(b)
        };
        let magic = field(0..8);
        let num_hits = field(8..12) as u32;
        let utime = field(12..20);
        if magic != HITS_MAGIC {
            return Err(self.bytes.error_at(
                offset,
                format!("packet header magic is {magic:#018x}, expected {HITS_MAGIC:#018x}"),
            ));
        }
        if num_hits > MAX_HITS_PER_PACKET {
            return Err(self.bytes.error_at(
                offset + 8,
                format!("packet claims {num_hits} hits (more than {MAX_HITS_PER_PACKET})"),
            ));
        }
        if let Some(len) = self.len {
            let needed = u64::from(num_hits) * RECORD_BYTES;
            let remaining = len.saturating_sub(self.bytes.offset());
            if needed > remaining {
                return Err(Error::truncated(
                    self.bytes.path(),
                    Location::Byte(offset),
                    format!("packet of {num_hits} hits ({needed} bytes; {remaining} bytes remain)"),
                ));
            }
        }
        Ok(Some(HitsHeader {
            offset,
            num_hits,
            utime,
        }))
    }
}

impl<R: BufRead> Iterator for HitsReader<R> {
    type Item = Result<HitsPacket>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        let packet = self.next_packet().transpose();
        self.failed = !matches!(packet, Some(Ok(_)));
        packet
    }
}
