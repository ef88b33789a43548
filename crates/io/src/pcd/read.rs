//! Decoding PCD data (ascii, binary, binary_compressed) into a [`PointCloud`].

use std::io::BufRead;
use std::path::Path;

use nalgebra::Point3;
use raypath_geometry::PointCloud;

use super::header::{DataEncoding, FieldType, PcdField, PcdHeader, read_header};
use super::lzf;
use super::{LabelSource, PcdCloud, ReadOptions};
use crate::{Error, Location, Result};

/// LZF expands at most 264 bytes out of a 3-byte token; a larger ratio is corruption.
const MAX_LZF_RATIO: u64 = 90;
/// Points reserved up front for ASCII data, whatever `POINTS` claims.
const ASCII_RESERVE: usize = 1 << 16;

/// Reads a PCD cloud from `reader`; `path` names the source in errors.
pub(super) fn read(
    mut reader: impl BufRead,
    path: &Path,
    options: &ReadOptions,
) -> Result<PcdCloud> {
    let header = read_header(&mut reader, path)?;
    let roles = Roles::new(&header, path, options)?;
    let cloud = match header.data {
        DataEncoding::Ascii => read_ascii(reader, path, &header, &roles)?,
        DataEncoding::Binary | DataEncoding::BinaryCompressed => {
            let mut data = Vec::new();
            reader.read_to_end(&mut data).map_err(|e| {
                Error::io(
                    path,
                    Location::Byte(header.data_offset + data.len() as u64),
                    e,
                )
            })?;
            if header.data == DataEncoding::Binary {
                read_binary(&data, path, &header, &roles)?
            } else {
                read_compressed(&data, path, &header, &roles)?
            }
        }
    };
    Ok(PcdCloud {
        cloud_from_sensor: header.cloud_from_sensor,
        header,
        cloud,
    })
}

/// What the reader does with each field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Role {
    /// 0, 1, 2 for x, y, z.
    coordinate: Option<usize>,
    intensity: bool,
    label: bool,
    rgb: bool,
}

impl Role {
    fn is_used(self) -> bool {
        self.coordinate.is_some() || self.intensity || self.label || self.rgb
    }
}

struct Roles {
    roles: Vec<Role>,
    has_intensity: bool,
    has_label: bool,
    has_rgb: bool,
}

impl Roles {
    fn new(header: &PcdHeader, path: &Path, options: &ReadOptions) -> Result<Self> {
        let label_name = match &options.label_from {
            LabelSource::LabelField => Some("label"),
            LabelSource::Intensity => Some("intensity"),
            LabelSource::Field(name) => Some(name.as_str()),
            LabelSource::None => None,
        };
        if let Some(name) = label_name
            && options.label_from != LabelSource::LabelField
            && header.field(name).is_none()
        {
            return Err(Error::malformed(
                path,
                Location::File,
                format!(
                    "no field {name:?} to read labels from (fields: {})",
                    header.field_names().join(" ")
                ),
            ));
        }
        let roles: Vec<Role> = header
            .fields
            .iter()
            .map(|f| Role {
                coordinate: ["x", "y", "z"].iter().position(|c| *c == f.name),
                intensity: f.name == "intensity",
                label: Some(f.name.as_str()) == label_name,
                rgb: f.name == "rgb" || f.name == "rgba",
            })
            .collect();
        for (role, field) in roles.iter().zip(&header.fields) {
            if !role.is_used() {
                continue;
            }
            let problem = if field.count != 1 {
                Some(format!(
                    "has COUNT {}; raypath reads it only as a scalar",
                    field.count
                ))
            } else if role.rgb && field.size != 4 {
                Some(format!(
                    "has SIZE {}; packed colour needs 4 bytes",
                    field.size
                ))
            } else if field.kind == FieldType::Float && field.size < 4 {
                Some(format!(
                    "is a {}-byte float; only 4 and 8 bytes are supported",
                    field.size
                ))
            } else {
                None
            };
            if let Some(problem) = problem {
                return Err(Error::malformed(
                    path,
                    Location::Line(header.data_line),
                    format!("field {:?} {problem}", field.name),
                ));
            }
        }
        Ok(Self {
            has_intensity: roles.iter().any(|r| r.intensity),
            has_label: roles.iter().any(|r| r.label),
            has_rgb: roles.iter().any(|r| r.rgb),
            roles,
        })
    }
}

/// A value as stored, before conversion.
#[derive(Clone, Copy, Debug)]
enum Value {
    F32(f32),
    F64(f64),
    U(u64),
    I(i64),
}

impl Value {
    fn is_non_finite(self) -> bool {
        match self {
            Value::F32(v) => !v.is_finite(),
            Value::F64(v) => !v.is_finite(),
            Value::U(_) | Value::I(_) => false,
        }
    }

    fn as_f32(self) -> f32 {
        match self {
            Value::F32(v) => v,
            Value::F64(v) => v as f32,
            Value::U(v) => v as f32,
            Value::I(v) => v as f32,
        }
    }

    /// The value as a label, `None` when it is not a non-negative integer that fits `u32`.
    fn as_label(self) -> Option<u32> {
        match self {
            Value::U(v) => u32::try_from(v).ok(),
            Value::I(v) => u32::try_from(v).ok(),
            Value::F32(v) => float_label(f64::from(v)),
            Value::F64(v) => float_label(v),
        }
    }
}

fn float_label(v: f64) -> Option<u32> {
    (v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&v)).then_some(v as u32)
}

/// The fields of the point being assembled.
struct PointValues {
    xyz: [f32; 3],
    intensity: f32,
    label: Value,
    rgb: u32,
}

impl Default for PointValues {
    fn default() -> Self {
        Self {
            xyz: [f32::NAN; 3],
            intensity: f32::NAN,
            label: Value::U(0),
            rgb: 0,
        }
    }
}

struct Builder {
    cloud: PointCloud,
}

impl Builder {
    fn new(header: &PcdHeader, roles: &Roles, reserve: usize) -> Self {
        Self {
            cloud: PointCloud {
                points: Vec::with_capacity(reserve),
                intensity: roles.has_intensity.then(|| Vec::with_capacity(reserve)),
                label: roles.has_label.then(|| Vec::with_capacity(reserve)),
                rgb: roles.has_rgb.then(|| Vec::with_capacity(reserve)),
                width: header.width,
                height: header.height,
            },
        }
    }

    /// Adds a point; `Err(reason)` when its label is not a label.
    fn push(&mut self, p: &PointValues) -> std::result::Result<(), String> {
        let point = Point3::new(p.xyz[0], p.xyz[1], p.xyz[2]);
        let valid = point.iter().all(|v| v.is_finite());
        if let Some(labels) = &mut self.cloud.label {
            let label = match p.label.as_label() {
                Some(label) => label,
                // A missing pixel may carry a NaN "label" (intensity of a no-return).
                None if !valid && p.label.is_non_finite() => 0,
                None => {
                    return Err(format!(
                        "label value {:?} is not a non-negative integer",
                        p.label
                    ));
                }
            };
            labels.push(label);
        }
        self.cloud.points.push(point);
        if let Some(v) = &mut self.cloud.intensity {
            v.push(p.intensity);
        }
        if let Some(v) = &mut self.cloud.rgb {
            v.push(p.rgb & 0x00ff_ffff);
        }
        Ok(())
    }
}

fn read_ascii(
    mut reader: impl BufRead,
    path: &Path,
    header: &PcdHeader,
    roles: &Roles,
) -> Result<PointCloud> {
    let mut builder = Builder::new(header, roles, header.points.min(ASCII_RESERVE));
    // For every value column: (field index, used?).
    let columns: Vec<(usize, bool)> = header
        .fields
        .iter()
        .enumerate()
        .flat_map(|(f, field)| (0..field.count).map(move |k| (f, k == 0)))
        .collect();
    let mut line_no = header.data_line;
    let mut bytes = Vec::new();
    let mut values = PointValues::default();
    while builder.cloud.points.len() < header.points {
        bytes.clear();
        let n = reader
            .read_until(b'\n', &mut bytes)
            .map_err(|e| Error::io(path, Location::Line(line_no + 1), e))?;
        if n == 0 {
            return Err(Error::truncated(
                path,
                Location::Line(line_no + 1),
                format!(
                    "point {} of {} (ASCII data ends early)",
                    builder.cloud.points.len() + 1,
                    header.points
                ),
            ));
        }
        line_no += 1;
        let at = Location::Line(line_no);
        let text = std::str::from_utf8(&bytes)
            .map_err(|_| Error::malformed(path, at, "data line is not UTF-8 text"))?;
        if text.trim().is_empty() {
            continue;
        }
        let mut tokens = text.split_ascii_whitespace();
        for (column, &(f, first)) in columns.iter().enumerate() {
            let Some(token) = tokens.next() else {
                return Err(Error::malformed(
                    path,
                    at,
                    format!(
                        "{} values on the line, the header declares {}",
                        column,
                        columns.len()
                    ),
                ));
            };
            let (Some(role), Some(field)) = (roles.roles.get(f), header.fields.get(f)) else {
                continue;
            };
            if !first || !role.is_used() {
                continue;
            }
            let value = parse_ascii(token, field, role.rgb).ok_or_else(|| {
                Error::malformed(
                    path,
                    at,
                    format!("field {:?}: cannot parse {token:?}", field.name),
                )
            })?;
            assign(&mut values, *role, value);
        }
        if tokens.next().is_some() {
            return Err(Error::malformed(
                path,
                at,
                format!(
                    "more values on the line than the {} the header declares",
                    columns.len()
                ),
            ));
        }
        builder
            .push(&values)
            .map_err(|reason| Error::malformed(path, at, reason))?;
    }
    // Only blank lines may follow the last point.
    loop {
        bytes.clear();
        let n = reader
            .read_until(b'\n', &mut bytes)
            .map_err(|e| Error::io(path, Location::Line(line_no + 1), e))?;
        if n == 0 {
            break;
        }
        line_no += 1;
        if !bytes.iter().all(u8::is_ascii_whitespace) {
            return Err(Error::malformed(
                path,
                Location::Line(line_no),
                format!("data after the last of the {} points", header.points),
            ));
        }
    }
    Ok(builder.cloud)
}

fn parse_ascii(token: &str, field: &PcdField, rgb: bool) -> Option<Value> {
    if rgb {
        // Packed colour: a float whose bits are the colour (PCL), or an integer.
        return match field.kind {
            FieldType::Float => token
                .parse::<f32>()
                .ok()
                .map(|v| Value::U(u64::from(v.to_bits()))),
            FieldType::Unsigned => token.parse::<u32>().ok().map(|v| Value::U(u64::from(v))),
            FieldType::Signed => token
                .parse::<i32>()
                .ok()
                .map(|v| Value::U(u64::from(v as u32))),
        };
    }
    match field.kind {
        FieldType::Float if field.size == 4 => token.parse::<f32>().ok().map(Value::F32),
        FieldType::Float => token.parse::<f64>().ok().map(Value::F64),
        FieldType::Unsigned => token.parse::<u64>().ok().map(Value::U).or_else(|| {
            integral(token)
                .and_then(|v| u64::try_from(v).ok())
                .map(Value::U)
        }),
        FieldType::Signed => token
            .parse::<i64>()
            .ok()
            .map(Value::I)
            .or_else(|| integral(token).map(Value::I)),
    }
}

/// An integer written as a float (`3.000000`).
fn integral(token: &str) -> Option<i64> {
    let v = token.parse::<f64>().ok()?;
    (v.fract() == 0.0 && v.abs() < 9.0e18).then_some(v as i64)
}

fn assign(values: &mut PointValues, role: Role, value: Value) {
    if role.rgb {
        if let Value::U(bits) = value {
            values.rgb = bits as u32;
        }
        return;
    }
    if let Some(axis) = role.coordinate
        && let Some(slot) = values.xyz.get_mut(axis)
    {
        *slot = value.as_f32();
    }
    if role.intensity {
        values.intensity = value.as_f32();
    }
    if role.label {
        values.label = value;
    }
}

fn decode_binary(bytes: &[u8], field: &PcdField, rgb: bool) -> Option<Value> {
    let b = |n: usize| bytes.get(..n);
    if rgb {
        let raw: [u8; 4] = b(4)?.try_into().ok()?;
        return Some(Value::U(u64::from(u32::from_le_bytes(raw))));
    }
    Some(match (field.kind, field.size) {
        (FieldType::Float, 4) => Value::F32(f32::from_le_bytes(b(4)?.try_into().ok()?)),
        (FieldType::Float, _) => Value::F64(f64::from_le_bytes(b(8)?.try_into().ok()?)),
        (FieldType::Unsigned, 1) => Value::U(u64::from(*bytes.first()?)),
        (FieldType::Unsigned, 2) => Value::U(u64::from(u16::from_le_bytes(b(2)?.try_into().ok()?))),
        (FieldType::Unsigned, 4) => Value::U(u64::from(u32::from_le_bytes(b(4)?.try_into().ok()?))),
        (FieldType::Unsigned, _) => Value::U(u64::from_le_bytes(b(8)?.try_into().ok()?)),
        (FieldType::Signed, 1) => Value::I(i64::from(i8::from_le_bytes([*bytes.first()?]))),
        (FieldType::Signed, 2) => Value::I(i64::from(i16::from_le_bytes(b(2)?.try_into().ok()?))),
        (FieldType::Signed, 4) => Value::I(i64::from(i32::from_le_bytes(b(4)?.try_into().ok()?))),
        (FieldType::Signed, _) => Value::I(i64::from_le_bytes(b(8)?.try_into().ok()?)),
    })
}

/// Decodes binary point data laid out with field `f` of point `i` at
/// `starts[f] + i × strides[f]`. `location(i, f)` names the place for errors.
fn decode_points(
    data: &[u8],
    path: &Path,
    header: &PcdHeader,
    roles: &Roles,
    starts: &[usize],
    strides: &[usize],
    location: impl Fn(usize, usize) -> (Location, String),
) -> Result<PointCloud> {
    let mut builder = Builder::new(header, roles, header.points);
    let used: Vec<(usize, Role, &PcdField, usize, usize)> = roles
        .roles
        .iter()
        .zip(&header.fields)
        .zip(starts.iter().zip(strides))
        .enumerate()
        .filter(|(_, ((role, _), _))| role.is_used())
        .map(|(f, ((role, field), (&start, &stride)))| (f, *role, field, start, stride))
        .collect();
    let mut values = PointValues::default();
    for i in 0..header.points {
        for &(f, role, field, start, stride) in &used {
            let at = start + i * stride;
            let value = data
                .get(at..at + field.size)
                .and_then(|bytes| decode_binary(bytes, field, role.rgb));
            let Some(value) = value else {
                let (loc, what) = location(i, f);
                return Err(Error::truncated(path, loc, what));
            };
            assign(&mut values, role, value);
        }
        builder.push(&values).map_err(|reason| {
            let f = used.iter().find(|u| u.1.label).map_or(0, |u| u.0);
            let (loc, what) = location(i, f);
            Error::malformed(path, loc, format!("{what}: {reason}"))
        })?;
    }
    Ok(builder.cloud)
}

fn read_binary(data: &[u8], path: &Path, header: &PcdHeader, roles: &Roles) -> Result<PointCloud> {
    let point_bytes = header.point_bytes();
    let needed = header.points.checked_mul(point_bytes);
    if needed.is_none_or(|n| n > data.len()) {
        let complete = data.len() / point_bytes.max(1);
        return Err(Error::truncated(
            path,
            Location::Byte(header.data_offset + (complete * point_bytes) as u64),
            format!(
                "point {} of {} ({} bytes of binary data for {} points of {point_bytes} bytes)",
                complete + 1,
                header.points,
                data.len(),
                header.points
            ),
        ));
    }
    let needed = needed.unwrap_or_default();
    check_trailing(data, needed, path, header.data_offset)?;
    let mut starts = Vec::with_capacity(header.fields.len());
    let mut offset = 0;
    for field in &header.fields {
        starts.push(offset);
        offset += field.bytes();
    }
    let strides = vec![point_bytes; header.fields.len()];
    let base = header.data_offset;
    decode_points(data, path, header, roles, &starts, &strides, |i, f| {
        let start = starts.get(f).copied().unwrap_or_default();
        let name = header.fields.get(f).map_or("", |x| x.name.as_str());
        (
            Location::Byte(base + (i * point_bytes + start) as u64),
            format!("point {} field {name:?}", i + 1),
        )
    })
}

fn read_compressed(
    data: &[u8],
    path: &Path,
    header: &PcdHeader,
    roles: &Roles,
) -> Result<PointCloud> {
    let base = header.data_offset;
    let word = |at: usize| -> Result<u32> {
        data.get(at..at + 4)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_le_bytes)
            .ok_or_else(|| {
                Error::truncated(
                    path,
                    Location::Byte(base + at as u64),
                    "the compressed-size words",
                )
            })
    };
    let compressed = word(0)? as usize;
    let uncompressed = word(4)? as usize;
    let expected = header.points.checked_mul(header.point_bytes());
    if expected != Some(uncompressed) {
        return Err(Error::malformed(
            path,
            Location::Byte(base + 4),
            format!(
                "uncompressed size {uncompressed} differs from {} points × {} bytes",
                header.points,
                header.point_bytes()
            ),
        ));
    }
    if uncompressed as u64 > (compressed as u64) * MAX_LZF_RATIO + 64 {
        return Err(Error::malformed(
            path,
            Location::Byte(base),
            format!("{compressed} compressed bytes cannot expand to {uncompressed}"),
        ));
    }
    let Some(stream) = data.get(8..8 + compressed) else {
        return Err(Error::truncated(
            path,
            Location::Byte(base + 8),
            format!(
                "{compressed} bytes of LZF data ({} present)",
                data.len().saturating_sub(8)
            ),
        ));
    };
    check_trailing(data, 8 + compressed, path, base)?;
    let unpacked = lzf::decompress(stream, uncompressed).map_err(|e| {
        Error::malformed(
            path,
            Location::Byte(base + 8 + e.offset as u64),
            format!("LZF data: {}", e.reason),
        )
    })?;
    let mut starts = Vec::with_capacity(header.fields.len());
    let mut strides = Vec::with_capacity(header.fields.len());
    let mut offset = 0;
    for field in &header.fields {
        starts.push(offset);
        strides.push(field.bytes());
        offset += field.bytes() * header.points;
    }
    decode_points(&unpacked, path, header, roles, &starts, &strides, |i, f| {
        let start = starts.get(f).copied().unwrap_or_default()
            + i * strides.get(f).copied().unwrap_or_default();
        let name = header.fields.get(f).map_or("", |x| x.name.as_str());
        (
            Location::Byte(base + 8),
            format!(
                "point {} field {name:?} (byte {start} of the decompressed data)",
                i + 1
            ),
        )
    })
}

/// Bytes after the data must be zero padding; anything else would be data we drop.
fn check_trailing(data: &[u8], end: usize, path: &Path, base: u64) -> Result<()> {
    let rest = data.get(end..).unwrap_or_default();
    if let Some(k) = rest.iter().position(|&b| b != 0) {
        return Err(Error::malformed(
            path,
            Location::Byte(base + (end + k) as u64),
            format!("{} unexpected bytes after the point data", rest.len()),
        ));
    }
    Ok(())
}
