//! Reading a PCD file: the header, then ASCII data here or binary data in `binary`.

use std::io::BufRead;
use std::path::Path;

use raypath_geometry::PointCloud;

use super::binary::{read_binary, read_compressed};
use super::fields::{Builder, PointValues, Roles, Value, assign};
use super::header::{DataEncoding, FieldType, PcdField, PcdHeader, read_header};
use super::{PcdCloud, ReadOptions};
use crate::{Error, Location, Result};

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
