//! Decoding `binary` (point by point) and `binary_compressed` (LZF, field by field) data.

use std::path::Path;

use raypath_geometry::PointCloud;

use super::fields::{Builder, PointValues, Role, Roles, Value, assign};
use super::header::{FieldType, PcdField, PcdHeader};
use super::lzf;
use crate::{Error, Location, Result};

/// LZF expands at most 264 bytes out of a 3-byte token; a larger ratio is corruption.
const MAX_LZF_RATIO: u64 = 90;

pub(super) fn decode_binary(bytes: &[u8], field: &PcdField, rgb: bool) -> Option<Value> {
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
pub(super) fn decode_points(
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

pub(super) fn read_binary(
    data: &[u8],
    path: &Path,
    header: &PcdHeader,
    roles: &Roles,
) -> Result<PointCloud> {
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

pub(super) fn read_compressed(
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
pub(super) fn check_trailing(data: &[u8], end: usize, path: &Path, base: u64) -> Result<()> {
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
