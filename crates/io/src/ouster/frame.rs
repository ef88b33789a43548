//! Frames: the columns of one rotation (one frame id), destaggered into an `H × W` image.

use raypath_geometry::PointCloud;

use super::metadata::{LidarProfile, SensorInfo};
use super::packet::{Pixel, decode_pixel};
use super::xyz::XyzLut;
use crate::error::Result;

/// One rotation of the sensor as an organized image of `height` beams × `width` columns.
///
/// Images are row-major (`row * width + col`) and **destaggered**: column `j` holds, for every
/// beam, the measurement that points in (nearly) the same azimuth, following the metadata's
/// `pixel_shift_by_row` (beam `r` of measurement id `m` lands in column `(m + shift[r]) mod
/// W`; Ouster Sensor Docs, "Staggered vs destaggered 2D images"). With the usual
/// lidar-to-sensor transform column `j` looks along azimuth `π − 2π j / W + δ` in the sensor
/// frame (column 0 near −x; δ, the mean over beams of `2π shift / W` minus the beam azimuth,
/// is 4.2° on the OS-1-128 here), and azimuth decreases (clockwise from above) with the
/// column index, as the sensor spins. A pixel without a return, and every pixel of a missing
/// or invalid column, has range 0 and zero channels.
#[derive(Clone, Debug, PartialEq)]
pub struct OusterFrame {
    /// The frame id of its packets (16-bit counter; 32-bit with the FUSA header).
    pub frame_id: u32,
    /// Timestamp of the first valid column, seconds (the sensor's clock: time since boot, or
    /// UNIX time when the sensor is synchronized by PTP or GPS).
    pub timestamp_s: f64,
    /// Capture time of the frame's first packet, seconds (the capturing host's clock, UNIX
    /// time; NaN for pcapng simple packet blocks, which have none).
    pub capture_time_s: f64,
    /// Columns `W`.
    pub width: usize,
    /// Beams `H`.
    pub height: usize,
    /// Range of the (strongest) return, metres; 0 = no return.
    pub range_m: Vec<f32>,
    /// Calibrated reflectivity of the (strongest) return (0–255).
    pub reflectivity: Vec<u8>,
    /// Signal photons of the (strongest) return, for the profiles that carry it.
    pub signal: Option<Vec<u16>>,
    /// Near-infrared ambient photons (low-data profiles: in units of 16).
    pub near_ir: Vec<u16>,
    /// Range of the second return, metres (dual-return profiles); 0 = none.
    pub range2_m: Option<Vec<f32>>,
    /// Reflectivity of the second return (dual-return profiles).
    pub reflectivity2: Option<Vec<u8>>,
    /// Signal photons of the second return (`RNG19_RFL8_SIG16_NIR16_DUAL` only).
    pub signal2: Option<Vec<u16>>,
    /// Per measurement id (staggered column): timestamp in nanoseconds, 0 when missing.
    pub column_timestamp_ns: Vec<u64>,
    /// Per measurement id: true when a valid column arrived.
    pub column_present: Vec<bool>,
    /// Lidar packets that made up the frame.
    pub packets: usize,
}

impl OusterFrame {
    /// Number of pixels with a (first) return.
    pub fn valid_returns(&self) -> usize {
        self.range_m.iter().filter(|&&r| r > 0.0).count()
    }

    /// Number of pixels with a second return (0 for single-return profiles).
    pub fn valid_second_returns(&self) -> usize {
        self.range2_m
            .as_ref()
            .map_or(0, |r| r.iter().filter(|&&r| r > 0.0).count())
    }

    /// Number of measurement ids whose column arrived valid.
    pub fn columns_present(&self) -> usize {
        self.column_present.iter().filter(|&&p| p).count()
    }

    /// The lowest measurement id present.
    pub fn first_column(&self) -> Option<usize> {
        self.column_present.iter().position(|&p| p)
    }

    /// The highest measurement id present.
    pub fn last_column(&self) -> Option<usize> {
        self.column_present.iter().rposition(|&p| p)
    }

    /// True when every column of the metadata's column window arrived.
    pub fn is_complete(&self, info: &SensorInfo) -> bool {
        self.column_present
            .iter()
            .enumerate()
            .all(|(m, &present)| present || !info.in_window(m))
    }

    /// Shortest and longest first-return range, metres (`None` without returns).
    pub fn range_span_m(&self) -> Option<(f32, f32)> {
        self.range_m
            .iter()
            .filter(|&&r| r > 0.0)
            .fold(None, |span, &r| match span {
                None => Some((r, r)),
                Some((lo, hi)) => Some((lo.min(r), hi.max(r))),
            })
    }

    /// The first returns as an organized `H × W` cloud in the sensor frame (REP-103 axes,
    /// metres), NaN where there is no return, reflectivity as intensity. Builds the lookup
    /// table each call; for many frames build one [`XyzLut`] and use [`XyzLut::cloud`].
    pub fn to_point_cloud(&self, info: &SensorInfo) -> Result<PointCloud> {
        XyzLut::new(info)?.cloud(self)
    }
}

/// Accumulates the columns of one frame.
pub(crate) struct FrameBuilder {
    frame: OusterFrame,
    /// Per beam: the destagger shift as a column offset in `0..W`.
    shifts: Vec<usize>,
}

impl FrameBuilder {
    pub fn new(info: &SensorInfo, frame_id: u32, capture_time_s: f64) -> Self {
        let (w, h) = (info.columns_per_frame, info.pixels_per_column);
        let n = w * h;
        let profile = info.profile;
        let shifts = info
            .pixel_shift_by_row
            .iter()
            .map(|&s| (i64::from(s).rem_euclid(w as i64)) as usize)
            .collect();
        Self {
            frame: OusterFrame {
                frame_id,
                timestamp_s: f64::NAN,
                capture_time_s,
                width: w,
                height: h,
                range_m: vec![0.0; n],
                reflectivity: vec![0; n],
                signal: profile.has_signal().then(|| vec![0; n]),
                near_ir: vec![0; n],
                range2_m: profile.is_dual().then(|| vec![0.0; n]),
                reflectivity2: profile.is_dual().then(|| vec![0; n]),
                signal2: (profile == LidarProfile::Rng19Rfl8Sig16Nir16Dual).then(|| vec![0; n]),
                column_timestamp_ns: vec![0; w],
                column_present: vec![false; w],
                packets: 0,
            },
            shifts,
        }
    }

    pub fn width(&self) -> usize {
        self.frame.width
    }

    pub fn frame_id(&self) -> u32 {
        self.frame.frame_id
    }

    /// Writes the pixels of measurement id `m` (checked `< W` by the caller).
    pub fn put_column(
        &mut self,
        profile: LidarProfile,
        m: usize,
        timestamp_ns: u64,
        pixels: &[u8],
        pixel_bytes: usize,
    ) {
        self.frame.column_timestamp_ns[m] = timestamp_ns;
        self.frame.column_present[m] = true;
        // One loop per profile, so the pixel layout is fixed inside it.
        match profile {
            LidarProfile::Legacy => self.put(m, pixels, pixel_bytes, |px| {
                decode_pixel(LidarProfile::Legacy, px)
            }),
            LidarProfile::Rng19Rfl8Sig16Nir16 => self.put(m, pixels, pixel_bytes, |px| {
                decode_pixel(LidarProfile::Rng19Rfl8Sig16Nir16, px)
            }),
            LidarProfile::Rng19Rfl8Sig16Nir16Dual => self.put(m, pixels, pixel_bytes, |px| {
                decode_pixel(LidarProfile::Rng19Rfl8Sig16Nir16Dual, px)
            }),
            LidarProfile::Rng15Rfl8Nir8 => self.put(m, pixels, pixel_bytes, |px| {
                decode_pixel(LidarProfile::Rng15Rfl8Nir8, px)
            }),
            LidarProfile::Rng15Rfl8Nir8Dual => self.put(m, pixels, pixel_bytes, |px| {
                decode_pixel(LidarProfile::Rng15Rfl8Nir8Dual, px)
            }),
        }
    }

    #[inline(always)]
    fn put(
        &mut self,
        m: usize,
        pixels: &[u8],
        pixel_bytes: usize,
        decode: impl Fn(&[u8]) -> Pixel,
    ) {
        let w = self.frame.width;
        let f = &mut self.frame;
        for (r, (px, &shift)) in pixels
            .chunks_exact(pixel_bytes)
            .zip(&self.shifts)
            .enumerate()
        {
            let mut col = m + shift;
            if col >= w {
                col -= w;
            }
            let i = r * w + col;
            let p = decode(px);
            f.range_m[i] = p.range_mm as f32 * 1e-3;
            f.reflectivity[i] = p.reflectivity;
            f.near_ir[i] = p.near_ir;
            if let Some(s) = &mut f.signal {
                s[i] = p.signal;
            }
            if let Some(r2) = &mut f.range2_m {
                r2[i] = p.range2_mm as f32 * 1e-3;
            }
            if let Some(v) = &mut f.reflectivity2 {
                v[i] = p.reflectivity2;
            }
            if let Some(v) = &mut f.signal2 {
                v[i] = p.signal2;
            }
        }
    }

    pub fn count_packet(&mut self) {
        self.frame.packets += 1;
    }

    pub fn finish(mut self) -> OusterFrame {
        let f = &mut self.frame;
        f.timestamp_s = f
            .column_present
            .iter()
            .position(|&p| p)
            .map_or(f64::NAN, |m| f.column_timestamp_ns[m] as f64 * 1e-9);
        self.frame
    }
}
