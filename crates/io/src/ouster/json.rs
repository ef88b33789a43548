//! Parsing the metadata JSON, in either layout, into a [`SensorInfo`].

use std::path::Path;

use nalgebra::Matrix4;
use serde_json::Value;

use super::metadata::{
    HeaderType, LidarProfile, MAX_COLUMNS_PER_FRAME, MAX_PIXELS_PER_COLUMN, MetadataLayout,
    SensorInfo, default_beam_origin_mm, default_lidar_to_sensor,
};
use crate::error::{Error, Location, Result};

/// Parses metadata JSON held in memory; `name` is used in errors.
pub(super) fn parse(bytes: &[u8], name: &Path) -> Result<SensorInfo> {
    let root: Value = serde_json::from_slice(bytes).map_err(|e| {
        Error::malformed(
            name,
            Location::Line(e.line() as u64),
            format!("not valid JSON: {e}"),
        )
    })?;
    let doc = Doc {
        name,
        text: bytes,
        root: &root,
        layout: layout_of(&root),
    };
    doc.sensor_info()
}

fn layout_of(root: &Value) -> MetadataLayout {
    const NESTED: [&str; 5] = [
        "sensor_info",
        "config_params",
        "beam_intrinsics",
        "lidar_intrinsics",
        "lidar_data_format",
    ];
    if NESTED
        .iter()
        .any(|k| root.get(k).is_some_and(Value::is_object))
    {
        MetadataLayout::Nested
    } else {
        MetadataLayout::LegacyFlat
    }
}

/// The parsed JSON with its text (to find the line of a key for errors).
struct Doc<'a> {
    name: &'a Path,
    text: &'a [u8],
    root: &'a Value,
    layout: MetadataLayout,
}

impl<'a> Doc<'a> {
    /// The value of `key` in `section` (nested layout) or at the top level (flat layout;
    /// the section `lidar_data_format` is the flat layout's `data_format`).
    fn get(&self, section: &str, key: &str) -> Option<&'a Value> {
        let holder = match (self.layout, section) {
            (MetadataLayout::Nested, _) => self.root.get(section)?,
            (MetadataLayout::LegacyFlat, "lidar_data_format") => self.root.get("data_format")?,
            (MetadataLayout::LegacyFlat, _) => self.root,
        };
        holder.get(key).filter(|v| !v.is_null())
    }

    fn path(&self, section: &str, key: &str) -> String {
        match (self.layout, section) {
            (MetadataLayout::Nested, _) => format!("{section}.{key}"),
            (MetadataLayout::LegacyFlat, "lidar_data_format") => format!("data_format.{key}"),
            (MetadataLayout::LegacyFlat, _) => key.to_owned(),
        }
    }

    /// An error about `key`, at the line where the key is written (else the whole file); in
    /// the nested layout, the key inside a section that holds it.
    fn error(&self, key: &str, reason: impl Into<String>) -> Error {
        let section = match (self.layout, self.root.as_object()) {
            (MetadataLayout::Nested, Some(map)) => map
                .iter()
                .find(|(_, v)| v.get(key).is_some())
                .map(|(name, _)| name.as_str()),
            _ => None,
        };
        let from = section
            .and_then(|name| find(self.text, format!("\"{name}\"").as_bytes()))
            .unwrap_or(0);
        let needle = format!("\"{key}\"");
        let location = find(&self.text[from..], needle.as_bytes()).map_or(Location::File, |at| {
            let at = from + at;
            Location::Line(1 + self.text[..at].iter().filter(|&&b| b == b'\n').count() as u64)
        });
        Error::malformed(self.name, location, reason)
    }

    fn require(&self, section: &str, key: &str) -> Result<&'a Value> {
        self.get(section, key).ok_or_else(|| {
            Error::malformed(
                self.name,
                Location::File,
                format!(
                    "Ouster metadata: missing {} ({} layout)",
                    self.path(section, key),
                    match self.layout {
                        MetadataLayout::Nested => "nested firmware 3.x",
                        MetadataLayout::LegacyFlat => "legacy flat",
                    }
                ),
            )
        })
    }

    fn string(&self, section: &str, key: &str) -> Result<Option<String>> {
        match self.get(section, key) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.clone())),
            Some(Value::Number(n)) => Ok(Some(n.to_string())),
            Some(_) => Err(self.error(key, format!("{} is not a string", self.path(section, key)))),
        }
    }

    fn integer(&self, section: &str, key: &str, max: u64) -> Result<Option<u64>> {
        let Some(value) = self.get(section, key) else {
            return Ok(None);
        };
        match value.as_u64() {
            Some(v) if v <= max => Ok(Some(v)),
            _ => Err(self.error(
                key,
                format!(
                    "{} must be an integer in 0..={max}, found {value}",
                    self.path(section, key)
                ),
            )),
        }
    }

    fn numbers(&self, section: &str, key: &str) -> Result<Option<Vec<f64>>> {
        let Some(value) = self.get(section, key) else {
            return Ok(None);
        };
        let bad = || {
            self.error(
                key,
                format!("{} must be a list of numbers", self.path(section, key)),
            )
        };
        let items = value.as_array().ok_or_else(bad)?;
        let mut out = Vec::with_capacity(items.len().min(MAX_COLUMNS_PER_FRAME));
        for item in items {
            match item.as_f64() {
                Some(v) if v.is_finite() => out.push(v),
                _ => return Err(bad()),
            }
        }
        Ok(Some(out))
    }

    fn transform(&self, section: &str, key: &str) -> Result<Option<Matrix4<f64>>> {
        match self.numbers(section, key)? {
            None => Ok(None),
            Some(v) if v.len() == 16 => Ok(Some(Matrix4::from_row_slice(&v))),
            Some(v) => Err(self.error(
                key,
                format!(
                    "{} must have 16 numbers (row-major 4 × 4), found {}",
                    self.path(section, key),
                    v.len()
                ),
            )),
        }
    }

    fn sensor_info(&self) -> Result<SensorInfo> {
        let text =
            |section, key| -> Result<String> { Ok(self.string(section, key)?.unwrap_or_default()) };
        let prod_line = text("sensor_info", "prod_line")?;
        let lidar_mode = text("config_params", "lidar_mode")?;
        let (profile, header_type, profile_name) = self.profile()?;
        let (columns_per_frame, pixels_per_column) = self.dimensions(&lidar_mode)?;
        let columns_per_packet = self
            .integer(
                "lidar_data_format",
                "columns_per_packet",
                MAX_COLUMNS_PER_FRAME as u64,
            )?
            .or(self.integer(
                "config_params",
                "columns_per_packet",
                MAX_COLUMNS_PER_FRAME as u64,
            )?)
            .unwrap_or(16) as usize;
        if columns_per_packet == 0 {
            return Err(self.error("columns_per_packet", "columns_per_packet must be positive"));
        }
        let column_window = self.column_window(columns_per_frame)?;
        let pixel_shift_by_row = self.pixel_shifts(columns_per_frame, pixels_per_column)?;
        let altitudes = self.angles("beam_altitude_angles", pixels_per_column)?;
        let azimuths = self.angles("beam_azimuth_angles", pixels_per_column)?;
        let origin_mm =
            match self.numbers_scalar("beam_intrinsics", "lidar_origin_to_beam_origin_mm")? {
                Some(v) => v,
                None => default_beam_origin_mm(&prod_line),
            };
        let beam_to_lidar = self
            .transform("beam_intrinsics", "beam_to_lidar_transform")?
            .unwrap_or_else(|| {
                let mut m = Matrix4::identity();
                m[(0, 3)] = origin_mm;
                m
            });
        let lidar_to_sensor = self
            .transform("lidar_intrinsics", "lidar_to_sensor_transform")?
            .unwrap_or_else(default_lidar_to_sensor);
        let header_type = match self.string("lidar_data_format", "header_type")?.as_deref() {
            Some("STANDARD") => HeaderType::Standard,
            Some("FUSA") => HeaderType::Fusa,
            Some(other) => {
                return Err(self.error(
                    "header_type",
                    format!("unknown header_type {other:?} (STANDARD or FUSA)"),
                ));
            }
            None => header_type,
        };
        let init_id = self
            .integer("sensor_info", "initialization_id", u64::from(u32::MAX))?
            .map(|v| v as u32);
        let udp_port_lidar = self
            .integer("config_params", "udp_port_lidar", u64::from(u16::MAX))?
            .map(|v| v as u16)
            .filter(|&p| p != 0);
        let info = SensorInfo {
            source: self.name.to_path_buf(),
            layout: self.layout,
            serial: text("sensor_info", "prod_sn")?,
            firmware: text("sensor_info", "build_rev")?,
            prod_line,
            init_id,
            lidar_mode,
            profile,
            profile_name,
            header_type,
            columns_per_frame,
            columns_per_packet,
            pixels_per_column,
            column_window,
            pixel_shift_by_row,
            beam_altitude_angles_deg: altitudes,
            beam_azimuth_angles_deg: azimuths,
            lidar_origin_to_beam_origin_mm: origin_mm,
            beam_to_lidar_transform: beam_to_lidar,
            lidar_to_sensor_transform: lidar_to_sensor,
            udp_port_lidar,
        };
        info.validate()?;
        Ok(info)
    }

    fn numbers_scalar(&self, section: &str, key: &str) -> Result<Option<f64>> {
        match self.get(section, key) {
            None => Ok(None),
            Some(v) => match v.as_f64() {
                Some(x) if x.is_finite() => Ok(Some(x)),
                _ => Err(self.error(key, format!("{} must be a number", self.path(section, key)))),
            },
        }
    }

    /// The packet profile: `udp_profile_lidar` of the data format, else of the config, else
    /// `LEGACY` when the file has no data format at all (firmware before 2.0).
    fn profile(&self) -> Result<(LidarProfile, HeaderType, String)> {
        let name = match self.string("lidar_data_format", "udp_profile_lidar")? {
            Some(name) => name,
            None => self
                .string("config_params", "udp_profile_lidar")?
                .unwrap_or_else(|| "LEGACY".to_owned()),
        };
        let (profile, header) = LidarProfile::from_name(&name).ok_or_else(|| {
            self.error(
                "udp_profile_lidar",
                format!(
                    "unsupported lidar profile {name:?}; raypath reads LEGACY, \
                     RNG19_RFL8_SIG16_NIR16[_DUAL], RNG15_RFL8_NIR8[_DUAL] and \
                     FUSA_RNG15_RFL8_NIR8_DUAL"
                ),
            )
        })?;
        Ok((profile, header, name))
    }

    /// `(W, H)`: columns per frame from the data format or the lidar mode; beams from the data
    /// format or the number of altitude angles.
    fn dimensions(&self, lidar_mode: &str) -> Result<(usize, usize)> {
        let from_mode = lidar_mode
            .split_once('x')
            .and_then(|(w, _)| w.parse::<usize>().ok());
        let w = match self.integer(
            "lidar_data_format",
            "columns_per_frame",
            MAX_COLUMNS_PER_FRAME as u64,
        )? {
            Some(w) => w as usize,
            None => from_mode.ok_or_else(|| {
                self.error(
                    "lidar_mode",
                    format!(
                        "cannot tell the columns per frame: no data format and lidar mode \
                         {lidar_mode:?} is not like 1024x10"
                    ),
                )
            })?,
        };
        if w == 0 || w > MAX_COLUMNS_PER_FRAME {
            return Err(self.error(
                "lidar_mode",
                format!("{w} columns per frame is out of range"),
            ));
        }
        let h = match self.integer(
            "lidar_data_format",
            "pixels_per_column",
            MAX_PIXELS_PER_COLUMN as u64,
        )? {
            Some(h) => h as usize,
            None => self
                .require("beam_intrinsics", "beam_altitude_angles")?
                .as_array()
                .map_or(0, Vec::len),
        };
        if h == 0 || h > MAX_PIXELS_PER_COLUMN {
            return Err(self.error("pixels_per_column", format!("{h} beams is out of range")));
        }
        Ok((w, h))
    }

    fn column_window(&self, w: usize) -> Result<[usize; 2]> {
        match self.numbers("lidar_data_format", "column_window")? {
            None => Ok([0, w - 1]),
            Some(v) => match v.as_slice() {
                [a, b]
                    if a.fract() == 0.0
                        && b.fract() == 0.0
                        && (0.0..w as f64).contains(a)
                        && (0.0..w as f64).contains(b) =>
                {
                    Ok([*a as usize, *b as usize])
                }
                _ => Err(self.error(
                    "column_window",
                    format!("column_window must be two measurement ids in 0..{w}"),
                )),
            },
        }
    }

    /// The data format's pixel shifts, or the SDK's default for a file without a data format
    /// (Ouster SDK `default_data_format`: a 64-beam pattern of `3k·W/512`, k = 3, 2, 1, 0,
    /// zero-padded to `H`).
    fn pixel_shifts(&self, w: usize, h: usize) -> Result<Vec<i32>> {
        match self.numbers("lidar_data_format", "pixel_shift_by_row")? {
            Some(v) => {
                if v.len() != h
                    || v.iter()
                        .any(|s| s.fract() != 0.0 || s.abs() > MAX_COLUMNS_PER_FRAME as f64)
                {
                    return Err(self.error(
                        "pixel_shift_by_row",
                        format!("pixel_shift_by_row must be {h} integer column shifts"),
                    ));
                }
                Ok(v.iter().map(|&s| s as i32).collect())
            }
            None => Ok((0..h)
                .map(|r| {
                    if r < 64 {
                        ((3 - r % 4) * 3 * w / 512) as i32
                    } else {
                        0
                    }
                })
                .collect()),
        }
    }

    fn angles(&self, key: &str, h: usize) -> Result<Vec<f64>> {
        self.require("beam_intrinsics", key)?;
        let angles = self.numbers("beam_intrinsics", key)?.unwrap_or_default();
        if angles.len() != h {
            return Err(self.error(
                key,
                format!(
                    "{} has {} angles for {h} beams",
                    self.path("beam_intrinsics", key),
                    angles.len()
                ),
            ));
        }
        Ok(angles)
    }
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}
