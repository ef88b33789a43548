//! Writing a [`PointCloud`] as PCD in any of the three encodings.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use raypath_geometry::{PointCloud, Pose3};

use super::header::DataEncoding;
use super::lzf;
use crate::{Error, Location, Result};

/// How [`write_pcd_with`] and [`write_pcd_to`] write a cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WriteOptions {
    /// The `DATA` encoding.
    pub encoding: DataEncoding,
    /// Written as `VIEWPOINT`: the sensor pose in the frame of the points.
    pub cloud_from_sensor: Pose3,
}

impl WriteOptions {
    /// Options for `encoding` with an identity viewpoint.
    pub fn new(encoding: DataEncoding) -> Self {
        Self {
            encoding,
            cloud_from_sensor: Pose3::identity(),
        }
    }
}

/// Writes `cloud` to the file `path` in `encoding`, with an identity viewpoint.
///
/// Fields written: `x y z` (F 4), then `intensity` (F 4), `label` (U 4) and `rgb` (U 4,
/// `0x00RRGGBB`) when the cloud has them. `WIDTH`/`HEIGHT` are the cloud's, so organized clouds
/// stay organized; NaN points are written as `nan`.
pub fn write_pcd(path: &Path, cloud: &PointCloud, encoding: DataEncoding) -> Result<()> {
    write_pcd_with(path, cloud, &WriteOptions::new(encoding))
}

/// Writes `cloud` to the file `path` with `options`.
pub fn write_pcd_with(path: &Path, cloud: &PointCloud, options: &WriteOptions) -> Result<()> {
    let file = File::create(path).map_err(|e| Error::io(path, Location::File, e))?;
    let mut writer = BufWriter::new(file);
    write_pcd_to(&mut writer, cloud, path, options)?;
    writer
        .flush()
        .map_err(|e| Error::io(path, Location::File, e))
}

/// Writes `cloud` to `writer`; `name` names the destination in errors.
pub fn write_pcd_to(
    mut writer: impl Write,
    cloud: &PointCloud,
    name: &Path,
    options: &WriteOptions,
) -> Result<()> {
    cloud.validate().map_err(|e| Error::Unwritable {
        path: name.to_path_buf(),
        reason: e.to_string(),
    })?;
    let io = |e| Error::io(name, Location::File, e);
    writer
        .write_all(header_text(cloud, options).as_bytes())
        .map_err(io)?;
    match options.encoding {
        DataEncoding::Ascii => write_ascii(&mut writer, cloud).map_err(io),
        DataEncoding::Binary => writer.write_all(&binary_points(cloud)).map_err(io),
        DataEncoding::BinaryCompressed => {
            let raw = columns(cloud);
            let packed = lzf::compress(&raw);
            let too_big = |what: &str| Error::Unwritable {
                path: name.to_path_buf(),
                reason: format!("{what} exceeds the 4 GiB that binary_compressed can describe"),
            };
            let packed_len = u32::try_from(packed.len()).map_err(|_| too_big("compressed data"))?;
            let raw_len = u32::try_from(raw.len()).map_err(|_| too_big("point data"))?;
            writer.write_all(&packed_len.to_le_bytes()).map_err(io)?;
            writer.write_all(&raw_len.to_le_bytes()).map_err(io)?;
            writer.write_all(&packed).map_err(io)
        }
    }
}

fn header_text(cloud: &PointCloud, options: &WriteOptions) -> String {
    let mut names = vec!["x", "y", "z"];
    let mut types = vec!["F", "F", "F"];
    if cloud.intensity.is_some() {
        names.push("intensity");
        types.push("F");
    }
    if cloud.label.is_some() {
        names.push("label");
        types.push("U");
    }
    if cloud.rgb.is_some() {
        names.push("rgb");
        types.push("U");
    }
    let n = names.len();
    let t = options.cloud_from_sensor.translation();
    let q = options.cloud_from_sensor.rotation().into_inner();
    let mut text = String::with_capacity(256);
    text.push_str("# .PCD v0.7 - Point Cloud Data file format (written by raypath)\nVERSION 0.7\n");
    let _ = writeln!(text, "FIELDS {}", names.join(" "));
    let _ = writeln!(text, "SIZE{}", " 4".repeat(n));
    let _ = writeln!(text, "TYPE {}", types.join(" "));
    let _ = writeln!(text, "COUNT{}", " 1".repeat(n));
    let _ = writeln!(text, "WIDTH {}", cloud.width);
    let _ = writeln!(text, "HEIGHT {}", cloud.height);
    let _ = writeln!(
        text,
        "VIEWPOINT {} {} {} {} {} {} {}",
        t.x, t.y, t.z, q.w, q.i, q.j, q.k
    );
    let _ = writeln!(text, "POINTS {}", cloud.len());
    let _ = writeln!(text, "DATA {}", options.encoding.name());
    text
}

fn push_float(line: &mut String, v: f32) {
    if v.is_nan() {
        line.push_str("nan");
    } else {
        let _ = write!(line, "{v}");
    }
}

fn write_ascii(writer: &mut dyn Write, cloud: &PointCloud) -> std::io::Result<()> {
    let mut line = String::with_capacity(128);
    for (i, p) in cloud.points.iter().enumerate() {
        line.clear();
        for (k, v) in p.iter().enumerate() {
            if k > 0 {
                line.push(' ');
            }
            push_float(&mut line, *v);
        }
        if let Some(v) = cloud.intensity.as_ref().and_then(|v| v.get(i)) {
            line.push(' ');
            push_float(&mut line, *v);
        }
        if let Some(v) = cloud.label.as_ref().and_then(|v| v.get(i)) {
            let _ = write!(line, " {v}");
        }
        if let Some(v) = cloud.rgb.as_ref().and_then(|v| v.get(i)) {
            let _ = write!(line, " {v}");
        }
        line.push('\n');
        writer.write_all(line.as_bytes())?;
    }
    Ok(())
}

/// The 4-byte little-endian values of each field, in field order, for point `i`.
fn point_words(cloud: &PointCloud, i: usize) -> impl Iterator<Item = [u8; 4]> + '_ {
    let p = cloud.points.get(i).copied().unwrap_or_default();
    let xyz = [p.x, p.y, p.z].map(f32::to_le_bytes);
    let intensity = cloud
        .intensity
        .as_ref()
        .map(|v| v.get(i).copied().unwrap_or(f32::NAN).to_le_bytes());
    let label = cloud
        .label
        .as_ref()
        .map(|v| v.get(i).copied().unwrap_or_default().to_le_bytes());
    let rgb = cloud
        .rgb
        .as_ref()
        .map(|v| v.get(i).copied().unwrap_or_default().to_le_bytes());
    xyz.into_iter().chain(intensity).chain(label).chain(rgb)
}

fn field_count(cloud: &PointCloud) -> usize {
    3 + usize::from(cloud.intensity.is_some())
        + usize::from(cloud.label.is_some())
        + usize::from(cloud.rgb.is_some())
}

/// Point-by-point binary data.
fn binary_points(cloud: &PointCloud) -> Vec<u8> {
    let mut data = Vec::with_capacity(cloud.len() * field_count(cloud) * 4);
    for i in 0..cloud.len() {
        for word in point_words(cloud, i) {
            data.extend_from_slice(&word);
        }
    }
    data
}

/// Field-by-field binary data (the layout binary_compressed compresses).
fn columns(cloud: &PointCloud) -> Vec<u8> {
    let fields = field_count(cloud);
    let n = cloud.len();
    let mut data = vec![0u8; n * fields * 4];
    for i in 0..n {
        for (f, word) in point_words(cloud, i).enumerate() {
            let at = (f * n + i) * 4;
            if let Some(slot) = data.get_mut(at..at + 4) {
                slot.copy_from_slice(&word);
            }
        }
    }
    data
}
