//! Lidar packet layout and column decoding (Ouster Sensor Docs, "Lidar Data Packet Format",
//! firmware 2.x–3.x; legacy layout from the firmware 1.x software user manual).
//!
//! A packet holds `columns_per_packet` measurement columns of `H` pixels. Profile-based
//! packets (firmware ≥ 2.0) start with a 32-byte packet header, give each column a 12-byte
//! header (timestamp u64 ns, measurement id u16, status u16) and end with a 32-byte footer.
//! Legacy packets have no packet header or footer; each column has a 16-byte header
//! (timestamp u64, measurement id u16, frame id u16, encoder count u32) and a 4-byte status
//! footer. Bit 0 of the status marks a valid column. All fields are little-endian.

use super::frame::FrameBuilder;
use super::metadata::{HeaderType, LidarProfile, SensorInfo};

/// Sizes of one packet's parts, from the metadata.
#[derive(Clone, Debug)]
pub(crate) struct PacketLayout {
    pub profile: LidarProfile,
    pub header_type: HeaderType,
    pub columns_per_packet: usize,
    pub pixels: usize,
    pub packet_header: usize,
    pub column_header: usize,
    pub pixel_bytes: usize,
    pub column_bytes: usize,
    pub packet_bytes: usize,
}

/// What the packet header says (legacy packets: the first column's frame id only).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PacketHeader {
    /// 1 for lidar packets (absent in legacy packets).
    pub packet_type: Option<u16>,
    /// Frame (rotation) counter: 16 bits, 32 bits with the FUSA header.
    pub frame_id: u32,
    /// Initialization id (absent in legacy packets).
    pub init_id: Option<u32>,
    /// Serial number (absent in legacy packets).
    pub serial: Option<u64>,
}

/// One decoded pixel, ranges in millimetres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Pixel {
    pub range_mm: u32,
    pub reflectivity: u8,
    pub signal: u16,
    pub near_ir: u16,
    pub range2_mm: u32,
    pub reflectivity2: u8,
    pub signal2: u16,
}

fn le16(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn le32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn le64(b: &[u8], at: usize) -> u64 {
    let mut v = [0u8; 8];
    v.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(v)
}

/// Decodes one pixel of `profile` from its bytes (at least `profile.pixel_bytes()` long).
///
/// Bit fields (Ouster Sensor Docs, "Lidar Data Packet Format"): RNG19 profiles keep the range
/// in the low 19 bits of the first word, legacy in the low 20; low-data profiles keep it in
/// the low 15 bits in units of 8 mm, and near-IR in 8 bits in units of 16.
#[inline]
pub(crate) fn decode_pixel(profile: LidarProfile, px: &[u8]) -> Pixel {
    match profile {
        LidarProfile::Legacy => Pixel {
            range_mm: le32(px, 0) & 0x000f_ffff,
            reflectivity: px[4],
            signal: le16(px, 6),
            near_ir: le16(px, 8),
            ..Pixel::default()
        },
        LidarProfile::Rng19Rfl8Sig16Nir16 => Pixel {
            range_mm: le32(px, 0) & 0x0007_ffff,
            reflectivity: px[4],
            signal: le16(px, 6),
            near_ir: le16(px, 8),
            ..Pixel::default()
        },
        LidarProfile::Rng19Rfl8Sig16Nir16Dual => Pixel {
            range_mm: le32(px, 0) & 0x0007_ffff,
            reflectivity: px[3],
            range2_mm: le32(px, 4) & 0x0007_ffff,
            reflectivity2: px[7],
            signal: le16(px, 8),
            signal2: le16(px, 10),
            near_ir: le16(px, 12),
        },
        LidarProfile::Rng15Rfl8Nir8 => Pixel {
            range_mm: u32::from(le16(px, 0) & 0x7fff) << 3,
            reflectivity: px[2],
            near_ir: u16::from(px[3]) << 4,
            ..Pixel::default()
        },
        LidarProfile::Rng15Rfl8Nir8Dual => Pixel {
            range_mm: u32::from(le16(px, 0) & 0x7fff) << 3,
            reflectivity: px[2],
            near_ir: u16::from(px[3]) << 4,
            range2_mm: u32::from(le16(px, 4) & 0x7fff) << 3,
            reflectivity2: px[6],
            ..Pixel::default()
        },
    }
}

/// A column's header fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ColumnHeader {
    pub timestamp_ns: u64,
    pub measurement_id: u16,
    pub valid: bool,
}

impl PacketLayout {
    pub fn new(info: &SensorInfo) -> Self {
        let legacy = info.profile == LidarProfile::Legacy;
        let (packet_header, column_header, column_footer, packet_footer) = if legacy {
            (0, 16, 4, 0)
        } else {
            (32, 12, 0, 32)
        };
        let pixel_bytes = info.profile.pixel_bytes();
        let column_bytes = column_header + info.pixels_per_column * pixel_bytes + column_footer;
        Self {
            profile: info.profile,
            header_type: info.header_type,
            columns_per_packet: info.columns_per_packet,
            pixels: info.pixels_per_column,
            packet_header,
            column_header,
            pixel_bytes,
            column_bytes,
            packet_bytes: packet_header + info.columns_per_packet * column_bytes + packet_footer,
        }
    }

    /// The packet header of `packet` (exactly `packet_bytes` long).
    pub fn header(&self, packet: &[u8]) -> PacketHeader {
        match (self.profile, self.header_type) {
            (LidarProfile::Legacy, _) => PacketHeader {
                packet_type: None,
                frame_id: u32::from(le16(packet, 10)),
                init_id: None,
                serial: None,
            },
            (_, HeaderType::Standard) => PacketHeader {
                packet_type: Some(le16(packet, 0)),
                frame_id: u32::from(le16(packet, 2)),
                init_id: Some(le32(packet, 4) & 0x00ff_ffff),
                serial: Some(le64(packet, 7) & 0x00ff_ffff_ffff),
            },
            (_, HeaderType::Fusa) => PacketHeader {
                packet_type: Some(u16::from(packet[0])),
                frame_id: le32(packet, 4),
                init_id: Some(le32(packet, 0) >> 8),
                serial: Some(le64(packet, 8) >> 24),
            },
        }
    }

    /// Byte offset of column `c` in the packet.
    pub fn column_offset(&self, c: usize) -> usize {
        self.packet_header + c * self.column_bytes
    }

    /// The header of the column at `column` (its bytes).
    pub fn column_header(&self, column: &[u8]) -> ColumnHeader {
        let status = if self.profile == LidarProfile::Legacy {
            le32(column, self.column_bytes - 4)
        } else {
            u32::from(le16(column, 10))
        };
        ColumnHeader {
            timestamp_ns: le64(column, 0),
            measurement_id: le16(column, 8),
            valid: status & 1 != 0,
        }
    }

    /// Decodes every valid column of `packet` into `frame`. Returns the first column whose
    /// measurement id is not below `W` (its index in the packet), if any: those point at
    /// metadata that does not match the data.
    pub fn decode_into(&self, packet: &[u8], frame: &mut FrameBuilder) -> Option<(usize, u16)> {
        let width = frame.width();
        for c in 0..self.columns_per_packet {
            let at = self.column_offset(c);
            let column = &packet[at..at + self.column_bytes];
            let header = self.column_header(column);
            if !header.valid {
                continue;
            }
            let m = usize::from(header.measurement_id);
            if m >= width {
                return Some((c, header.measurement_id));
            }
            let pixels =
                &column[self.column_header..self.column_header + self.pixels * self.pixel_bytes];
            frame.put_column(
                self.profile,
                m,
                header.timestamp_ns,
                pixels,
                self.pixel_bytes,
            );
        }
        None
    }
}
