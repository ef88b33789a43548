//! The sensor metadata JSON an Ouster recording needs: beam angles, lidar mode, data format
//! (packet profile, pixel shifts, column window) and intrinsic transforms.
//!
//! Two layouts exist (Ouster Sensor Docs, "Sensor Metadata"; the SDK's `metadata.cpp`
//! converts the first into the second): the **legacy flat** layout of firmware before 3.0
//! (`beam_altitude_angles`, `lidar_mode`, `data_format`, … at the top level; no
//! `data_format` before firmware 2.0, which means the legacy packet profile), and the
//! **nested** layout of firmware 3.x (`sensor_info`, `config_params`, `lidar_data_format`,
//! `beam_intrinsics`, `lidar_intrinsics`). Both read into one [`SensorInfo`].

use std::path::{Path, PathBuf};

use nalgebra::Matrix4;

use crate::error::{Error, Location, Result};

/// How the lidar packets of a stream are laid out (the metadata's `udp_profile_lidar`).
///
/// Pixel layouts from the Ouster Sensor Docs, "Lidar Data Packet Format" (firmware 2.x/3.x);
/// all values little-endian, ranges in millimetres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LidarProfile {
    /// Firmware before 2.0 (`LEGACY`): no packet header; each column has a 16-byte header
    /// (timestamp, measurement id, frame id, encoder count), 12-byte pixels (20-bit range,
    /// reflectivity, signal, near-IR) and a 4-byte status footer.
    Legacy,
    /// `RNG19_RFL8_SIG16_NIR16`: 12-byte pixels, 19-bit range, reflectivity, signal, near-IR.
    Rng19Rfl8Sig16Nir16,
    /// `RNG19_RFL8_SIG16_NIR16_DUAL`: 16-byte pixels with the strongest and second-strongest
    /// return (range, reflectivity, signal each) and near-IR.
    Rng19Rfl8Sig16Nir16Dual,
    /// `RNG15_RFL8_NIR8` ("low data rate"): 4-byte pixels, range in units of 8 mm,
    /// reflectivity, near-IR in units of 16.
    Rng15Rfl8Nir8,
    /// `RNG15_RFL8_NIR8_DUAL` and `FUSA_RNG15_RFL8_NIR8_DUAL`: 8-byte pixels, two low-data
    /// returns and near-IR.
    Rng15Rfl8Nir8Dual,
}

impl LidarProfile {
    /// The profile of a metadata `udp_profile_lidar` name, and the packet header that name
    /// implies when the metadata does not state one.
    pub fn from_name(name: &str) -> Option<(Self, HeaderType)> {
        Some(match name {
            "LEGACY" => (Self::Legacy, HeaderType::Standard),
            "RNG19_RFL8_SIG16_NIR16" => (Self::Rng19Rfl8Sig16Nir16, HeaderType::Standard),
            "RNG19_RFL8_SIG16_NIR16_DUAL" => (Self::Rng19Rfl8Sig16Nir16Dual, HeaderType::Standard),
            "RNG15_RFL8_NIR8" => (Self::Rng15Rfl8Nir8, HeaderType::Standard),
            "RNG15_RFL8_NIR8_DUAL" => (Self::Rng15Rfl8Nir8Dual, HeaderType::Standard),
            "FUSA_RNG15_RFL8_NIR8_DUAL" => (Self::Rng15Rfl8Nir8Dual, HeaderType::Fusa),
            _ => return None,
        })
    }

    /// Bytes per pixel.
    pub fn pixel_bytes(self) -> usize {
        match self {
            Self::Legacy | Self::Rng19Rfl8Sig16Nir16 => 12,
            Self::Rng19Rfl8Sig16Nir16Dual => 16,
            Self::Rng15Rfl8Nir8 => 4,
            Self::Rng15Rfl8Nir8Dual => 8,
        }
    }

    /// True for the profiles with a second return.
    pub fn is_dual(self) -> bool {
        matches!(
            self,
            Self::Rng19Rfl8Sig16Nir16Dual | Self::Rng15Rfl8Nir8Dual
        )
    }

    /// True for the profiles with a signal (photon count) channel.
    pub fn has_signal(self) -> bool {
        matches!(
            self,
            Self::Legacy | Self::Rng19Rfl8Sig16Nir16 | Self::Rng19Rfl8Sig16Nir16Dual
        )
    }
}

/// The lidar packet header (Ouster Sensor Docs, "Lidar Data Packet Format").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HeaderType {
    /// 32-byte header: packet type (16 bits), frame id (16 bits), initialization id
    /// (24 bits), serial number (40 bits), alerts and shutdown countdowns.
    Standard,
    /// Functional-safety header of the `FUSA_…` profiles: packet type (8 bits),
    /// initialization id (24 bits), frame id (32 bits), serial number (40 bits at byte 11).
    Fusa,
}

/// Which JSON layout the metadata file used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MetadataLayout {
    /// Top-level keys (firmware before 3.0).
    LegacyFlat,
    /// `sensor_info`, `config_params`, `lidar_data_format`, `beam_intrinsics`,
    /// `lidar_intrinsics` sections (firmware 3.x).
    Nested,
}

/// What a decoder needs to know about the sensor that recorded a stream.
///
/// Angles are degrees and lengths millimetres as in the file; the transforms are 4 × 4,
/// row-major in the file, translations in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorInfo {
    /// The metadata file (or the name given to [`SensorInfo::parse`]), used in errors.
    pub source: PathBuf,
    /// The JSON layout it was read from.
    pub layout: MetadataLayout,
    /// Product line, e.g. `OS-1-128` (empty when absent).
    pub prod_line: String,
    /// Serial number as written (empty when absent).
    pub serial: String,
    /// Firmware revision (`build_rev`), e.g. `v2.3.0` (empty when absent).
    pub firmware: String,
    /// The sensor's initialization id, which its packets repeat (firmware ≥ 2.0).
    pub init_id: Option<u32>,
    /// Lidar mode, e.g. `1024x10` (columns × rotation rate in Hz).
    pub lidar_mode: String,
    /// The packet profile.
    pub profile: LidarProfile,
    /// The profile's name in the metadata, e.g. `RNG19_RFL8_SIG16_NIR16` (`LEGACY` when the
    /// metadata has no data format).
    pub profile_name: String,
    /// The packet header layout.
    pub header_type: HeaderType,
    /// Measurement columns per rotation (the range image width `W`).
    pub columns_per_frame: usize,
    /// Columns per UDP packet.
    pub columns_per_packet: usize,
    /// Beams (the range image height `H`).
    pub pixels_per_column: usize,
    /// First and last measurement id the sensor sends (inclusive; may wrap past `W − 1`).
    pub column_window: [usize; 2],
    /// Per beam: the column shift that destaggers the image (pixel `(r, m)` of measurement
    /// id `m` goes to column `(m + shift[r]) mod W`).
    pub pixel_shift_by_row: Vec<i32>,
    /// Per beam: elevation above the horizontal plane, degrees.
    pub beam_altitude_angles_deg: Vec<f64>,
    /// Per beam: azimuth offset from the column's encoder angle, degrees.
    pub beam_azimuth_angles_deg: Vec<f64>,
    /// Distance from the lidar axis to the beams' origin, mm.
    pub lidar_origin_to_beam_origin_mm: f64,
    /// Beam origin relative to the lidar frame: `(0, 3)` is the radial offset and `(2, 3)`
    /// the height offset, mm.
    pub beam_to_lidar_transform: Matrix4<f64>,
    /// The sensor frame from the lidar frame (`sensor_from_lidar`), translation in mm.
    pub lidar_to_sensor_transform: Matrix4<f64>,
    /// UDP destination port of lidar packets, when the metadata names one (not 0).
    pub udp_port_lidar: Option<u16>,
}

/// Largest image the reader accepts (Ouster sensors have at most 128 beams and 4096
/// columns); bounds allocation on corrupt metadata.
pub(super) const MAX_PIXELS_PER_COLUMN: usize = 512;
pub(super) const MAX_COLUMNS_PER_FRAME: usize = 8192;
const MAX_PIXELS_PER_FRAME: usize = 1 << 21;
/// Largest UDP payload over IPv4.
const MAX_UDP_PAYLOAD: usize = 65_507;

/// The lidar-to-sensor transform the SDK assumes when the metadata lacks one (OS-1 housing,
/// z = 36.18 mm; Ouster SDK `metadata.cpp`, `DEFAULT_LIDAR_TO_SENSOR`).
pub(super) fn default_lidar_to_sensor() -> Matrix4<f64> {
    Matrix4::new(
        -1.0, 0.0, 0.0, 0.0, //
        0.0, -1.0, 0.0, 0.0, //
        0.0, 0.0, 1.0, 36.18, //
        0.0, 0.0, 0.0, 1.0,
    )
}

/// The beam-origin radius the SDK assumes per product line when the metadata lacks one
/// (Ouster SDK `sensor_info.cpp`, `default_lidar_origin_to_beam_origin`).
pub(super) fn default_beam_origin_mm(prod_line: &str) -> f64 {
    if prod_line.starts_with("OS-0-") {
        27.67
    } else if prod_line.starts_with("OS-1-") {
        15.806
    } else if prod_line.starts_with("OS-2-") {
        13.762
    } else {
        12.163
    }
}

impl SensorInfo {
    /// Reads a metadata JSON file (plain or compressed).
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = crate::source::read_all(path)?;
        Self::parse(&bytes, path)
    }

    /// Parses metadata JSON held in memory; `name` is used in errors.
    pub fn parse(bytes: &[u8], name: impl AsRef<Path>) -> Result<Self> {
        super::json::parse(bytes, name.as_ref())
    }

    /// Checks that the fields agree with each other (image size within bounds, one angle and
    /// one pixel shift per beam, finite angles and transforms, a column window inside the
    /// frame, packets that fit a UDP datagram). [`SensorInfo::parse`] checks this; readers
    /// and [`crate::ouster::XyzLut::new`] check it again for values built in code.
    pub fn validate(&self) -> Result<()> {
        let (w, h) = (self.columns_per_frame, self.pixels_per_column);
        let fail = |reason: String| Err(Error::malformed(&self.source, Location::File, reason));
        if !(1..=MAX_COLUMNS_PER_FRAME).contains(&w)
            || !(1..=MAX_PIXELS_PER_COLUMN).contains(&h)
            || w * h > MAX_PIXELS_PER_FRAME
        {
            return fail(format!(
                "a {w} × {h} image is out of range (at most {MAX_COLUMNS_PER_FRAME} columns, \
                 {MAX_PIXELS_PER_COLUMN} beams, {MAX_PIXELS_PER_FRAME} pixels)"
            ));
        }
        for (what, len) in [
            ("beam altitude angles", self.beam_altitude_angles_deg.len()),
            ("beam azimuth angles", self.beam_azimuth_angles_deg.len()),
            ("pixel shifts", self.pixel_shift_by_row.len()),
        ] {
            if len != h {
                return fail(format!("{len} {what} for {h} beams"));
            }
        }
        let finite = self
            .beam_altitude_angles_deg
            .iter()
            .chain(&self.beam_azimuth_angles_deg)
            .chain(self.beam_to_lidar_transform.iter())
            .chain(self.lidar_to_sensor_transform.iter())
            .all(|v| v.is_finite());
        if !finite || !self.lidar_origin_to_beam_origin_mm.is_finite() {
            return fail("non-finite beam angle, offset or transform".into());
        }
        if self.column_window.iter().any(|&c| c >= w) {
            return fail(format!(
                "column window {:?} outside 0..{w}",
                self.column_window
            ));
        }
        if self.columns_per_packet == 0 || self.columns_per_packet > w {
            return fail(format!(
                "{} columns per packet for {w} columns per frame",
                self.columns_per_packet
            ));
        }
        let bytes = self.lidar_packet_bytes();
        if bytes > MAX_UDP_PAYLOAD {
            return fail(format!(
                "{} columns of {h} pixels make {bytes}-byte lidar packets, more than a UDP \
                 datagram holds",
                self.columns_per_packet
            ));
        }
        Ok(())
    }

    /// Bytes of one lidar packet of this format.
    pub fn lidar_packet_bytes(&self) -> usize {
        crate::ouster::packet::PacketLayout::new(self).packet_bytes
    }

    /// Number of measurement ids in the column window (all `W` for a full rotation).
    pub fn columns_in_window(&self) -> usize {
        let [start, end] = self.column_window;
        let w = self.columns_per_frame;
        if end >= start {
            end - start + 1
        } else {
            w - start + end + 1
        }
    }

    /// True when measurement id `m` lies in the column window.
    pub fn in_window(&self, m: usize) -> bool {
        let [start, end] = self.column_window;
        if end >= start {
            (start..=end).contains(&m)
        } else {
            m >= start || m <= end
        }
    }

    /// Rotation rate from the lidar mode (`1024x10` → 10 Hz), when it has one.
    pub fn frequency_hz(&self) -> Option<f64> {
        self.lidar_mode
            .split_once('x')
            .and_then(|(_, hz)| hz.parse().ok())
    }
}
