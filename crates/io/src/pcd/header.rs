//! The PCD text header: `VERSION`, `FIELDS`, `SIZE`, `TYPE`, `COUNT`, `WIDTH`, `HEIGHT`,
//! `VIEWPOINT`, `POINTS`, `DATA`, with `#` comments.

use std::fmt;
use std::io::BufRead;
use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use raypath_geometry::Pose3;

use crate::{Error, Location, Result};

/// Longest header the reader accepts, in bytes (a real header has a few hundred).
const MAX_HEADER_BYTES: u64 = 1 << 20;
/// Most values a single field may hold per point (`COUNT`).
const MAX_COUNT: usize = 1 << 16;

/// How a field's values are stored: the PCD `TYPE` letter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldType {
    /// `I`: signed integer.
    Signed,
    /// `U`: unsigned integer.
    Unsigned,
    /// `F`: IEEE floating point.
    Float,
}

impl FieldType {
    /// The PCD letter (`I`, `U` or `F`).
    pub fn letter(self) -> char {
        match self {
            FieldType::Signed => 'I',
            FieldType::Unsigned => 'U',
            FieldType::Float => 'F',
        }
    }
}

/// One field (column group) of a PCD file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PcdField {
    /// The name, for example `x`, `intensity`, `rgb`, `normal_x` or `_` (padding).
    pub name: String,
    /// Bytes per value: 1, 2, 4 or 8.
    pub size: usize,
    /// Value type.
    pub kind: FieldType,
    /// Values per point (1 for scalars).
    pub count: usize,
}

impl PcdField {
    /// Bytes the field takes per point (`size × count`).
    pub fn bytes(&self) -> usize {
        self.size * self.count
    }
}

/// The `DATA` encoding of a PCD file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DataEncoding {
    /// One point per text line.
    Ascii,
    /// Little-endian binary, point by point (array of structures).
    Binary,
    /// LZF-compressed binary, field by field (structure of arrays).
    BinaryCompressed,
}

impl DataEncoding {
    /// The keyword after `DATA`.
    pub fn name(self) -> &'static str {
        match self {
            DataEncoding::Ascii => "ascii",
            DataEncoding::Binary => "binary",
            DataEncoding::BinaryCompressed => "binary_compressed",
        }
    }

    /// All encodings.
    pub const ALL: [DataEncoding; 3] = [
        DataEncoding::Ascii,
        DataEncoding::Binary,
        DataEncoding::BinaryCompressed,
    ];
}

impl fmt::Display for DataEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A parsed and validated PCD header.
#[derive(Clone, Debug, PartialEq)]
pub struct PcdHeader {
    /// The `VERSION` value as written (`.7`, `0.7`, …; empty when absent).
    pub version: String,
    /// The fields in storage order.
    pub fields: Vec<PcdField>,
    /// Columns of an organized cloud, or the number of points.
    pub width: usize,
    /// Rows of an organized cloud, or 1.
    pub height: usize,
    /// The acquisition viewpoint `VIEWPOINT tx ty tz qw qx qy qz`: the pose of the sensor in
    /// the frame of the points (`cloud_from_sensor`), metres; identity when absent.
    pub cloud_from_sensor: Pose3,
    /// Number of points (`POINTS`, equal to `width × height`).
    pub points: usize,
    /// The data encoding.
    pub data: DataEncoding,
    /// Bytes of the header including the `DATA` line: where the data starts.
    pub data_offset: u64,
    /// Lines of the header including the `DATA` line (ASCII data starts on the next line).
    pub data_line: u64,
}

impl PcdHeader {
    /// Bytes of one point in binary storage (sum of `size × count`).
    pub fn point_bytes(&self) -> usize {
        self.fields.iter().map(PcdField::bytes).sum()
    }

    /// Values per point in ASCII storage (sum of `count`).
    pub fn point_values(&self) -> usize {
        self.fields.iter().map(|f| f.count).sum()
    }

    /// The field called `name`, with its index.
    pub fn field(&self, name: &str) -> Option<(usize, &PcdField)> {
        self.fields.iter().enumerate().find(|(_, f)| f.name == name)
    }

    /// The field names in order.
    pub fn field_names(&self) -> Vec<String> {
        self.fields.iter().map(|f| f.name.clone()).collect()
    }
}

/// Reads a PCD header from `reader`, leaving it at the first byte of the data. `path` names
/// the file in errors.
pub fn read_header(reader: &mut dyn BufRead, path: &Path) -> Result<PcdHeader> {
    let mut raw = RawHeader::default();
    let mut offset = 0u64;
    let mut line_no = 0u64;
    let mut bytes = Vec::new();
    loop {
        bytes.clear();
        let n = reader
            .read_until(b'\n', &mut bytes)
            .map_err(|e| Error::io(path, Location::Line(line_no + 1), e))?;
        if n == 0 {
            return Err(Error::truncated(
                path,
                Location::Line(line_no + 1),
                "the PCD header (no DATA line)",
            ));
        }
        line_no += 1;
        offset += n as u64;
        let at = Location::Line(line_no);
        if offset > MAX_HEADER_BYTES {
            return Err(Error::malformed(
                path,
                at,
                "PCD header is longer than 1 MiB",
            ));
        }
        let text = std::str::from_utf8(&bytes)
            .map_err(|_| Error::malformed(path, at, "header line is not UTF-8 text"))?;
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let mut words = text.split_whitespace();
        let keyword = words.next().unwrap_or_default();
        let values: Vec<&str> = words.collect();
        let bad = |reason: String| Error::malformed(path, at, reason);
        if raw.apply(keyword, &values, line_no).map_err(bad)? {
            break;
        }
    }
    raw.finish(path, offset, line_no)
}

/// Header entries as found, with the line each was on.
#[derive(Default)]
struct RawHeader {
    version: Option<String>,
    fields: Option<(Vec<String>, u64)>,
    sizes: Option<(Vec<usize>, u64)>,
    types: Option<(Vec<FieldType>, u64)>,
    counts: Option<(Vec<usize>, u64)>,
    width: Option<(usize, u64)>,
    height: Option<(usize, u64)>,
    viewpoint: Option<Pose3>,
    points: Option<(usize, u64)>,
    data: Option<(DataEncoding, u64)>,
}

impl RawHeader {
    /// Records one header line; `Ok(true)` after `DATA`.
    fn apply(&mut self, keyword: &str, values: &[&str], line: u64) -> Result<bool, String> {
        let once = |present: bool| {
            if present {
                Err(format!("{keyword} appears twice"))
            } else {
                Ok(())
            }
        };
        match keyword.to_ascii_uppercase().as_str() {
            "VERSION" => {
                once(self.version.is_some())?;
                self.version = Some(values.join(" "));
            }
            "FIELDS" | "COLUMNS" => {
                once(self.fields.is_some())?;
                if values.is_empty() {
                    return Err("FIELDS lists no field".into());
                }
                self.fields = Some((values.iter().map(|s| (*s).to_owned()).collect(), line));
            }
            "SIZE" => {
                once(self.sizes.is_some())?;
                let sizes = values
                    .iter()
                    .map(|v| match v.parse::<usize>() {
                        Ok(s @ (1 | 2 | 4 | 8)) => Ok(s),
                        _ => Err(format!("SIZE {v:?} is not 1, 2, 4 or 8")),
                    })
                    .collect::<Result<_, _>>()?;
                self.sizes = Some((sizes, line));
            }
            "TYPE" => {
                once(self.types.is_some())?;
                let types = values
                    .iter()
                    .map(|v| match *v {
                        "I" | "i" => Ok(FieldType::Signed),
                        "U" | "u" => Ok(FieldType::Unsigned),
                        "F" | "f" => Ok(FieldType::Float),
                        _ => Err(format!("TYPE {v:?} is not I, U or F")),
                    })
                    .collect::<Result<_, _>>()?;
                self.types = Some((types, line));
            }
            "COUNT" => {
                once(self.counts.is_some())?;
                let counts = values
                    .iter()
                    .map(|v| match v.parse::<usize>() {
                        Ok(c) if (1..=MAX_COUNT).contains(&c) => Ok(c),
                        _ => Err(format!("COUNT {v:?} is not a number from 1 to {MAX_COUNT}")),
                    })
                    .collect::<Result<_, _>>()?;
                self.counts = Some((counts, line));
            }
            "WIDTH" => {
                once(self.width.is_some())?;
                self.width = Some((single_number(keyword, values)?, line));
            }
            "HEIGHT" => {
                once(self.height.is_some())?;
                self.height = Some((single_number(keyword, values)?, line));
            }
            "POINTS" => {
                once(self.points.is_some())?;
                self.points = Some((single_number(keyword, values)?, line));
            }
            "VIEWPOINT" => {
                once(self.viewpoint.is_some())?;
                self.viewpoint = Some(parse_viewpoint(values)?);
            }
            "DATA" => {
                let encoding = match values {
                    [v] if v.eq_ignore_ascii_case("ascii") => DataEncoding::Ascii,
                    [v] if v.eq_ignore_ascii_case("binary") => DataEncoding::Binary,
                    [v] if v.eq_ignore_ascii_case("binary_compressed") => {
                        DataEncoding::BinaryCompressed
                    }
                    _ => {
                        return Err(format!(
                            "DATA {:?} is not ascii, binary or binary_compressed",
                            values.join(" ")
                        ));
                    }
                };
                self.data = Some((encoding, line));
                return Ok(true);
            }
            _ => return Err(format!("unknown header keyword {keyword:?}")),
        }
        Ok(false)
    }

    fn finish(self, path: &Path, data_offset: u64, data_line: u64) -> Result<PcdHeader> {
        let at_line =
            |line: u64, reason: String| Error::malformed(path, Location::Line(line), reason);
        let Some((names, fields_line)) = self.fields else {
            return Err(at_line(data_line, "header has no FIELDS line".into()));
        };
        let n = names.len();
        let Some((sizes, sizes_line)) = self.sizes else {
            return Err(at_line(data_line, "header has no SIZE line".into()));
        };
        let Some((types, types_line)) = self.types else {
            return Err(at_line(data_line, "header has no TYPE line".into()));
        };
        let counts = match self.counts {
            Some((c, line)) if c.len() != n => {
                return Err(at_line(
                    line,
                    format!("COUNT has {} values for {n} fields", c.len()),
                ));
            }
            Some((c, _)) => c,
            None => vec![1; n],
        };
        if sizes.len() != n {
            return Err(at_line(
                sizes_line,
                format!("SIZE has {} values for {n} fields", sizes.len()),
            ));
        }
        if types.len() != n {
            return Err(at_line(
                types_line,
                format!("TYPE has {} values for {n} fields", types.len()),
            ));
        }
        let mut fields = Vec::with_capacity(n);
        for (((name, size), kind), count) in names.into_iter().zip(sizes).zip(types).zip(counts) {
            if kind == FieldType::Float && size == 1 {
                return Err(at_line(
                    types_line,
                    format!("field {name:?} is a 1-byte float"),
                ));
            }
            if name != "_" && fields.iter().any(|f: &PcdField| f.name == name) {
                return Err(at_line(
                    fields_line,
                    format!("field {name:?} appears twice"),
                ));
            }
            fields.push(PcdField {
                name,
                size,
                kind,
                count,
            });
        }
        for required in ["x", "y", "z"] {
            if !fields.iter().any(|f| f.name == required) {
                return Err(at_line(fields_line, format!("FIELDS has no {required:?}")));
            }
        }
        let Some((width, width_line)) = self.width else {
            return Err(at_line(data_line, "header has no WIDTH line".into()));
        };
        let (height, height_line) = self.height.unwrap_or((1, width_line));
        let Some(product) = width.checked_mul(height) else {
            return Err(at_line(height_line, "WIDTH × HEIGHT overflows".into()));
        };
        let points = match self.points {
            Some((p, line)) if p != product => {
                return Err(at_line(
                    line,
                    format!("POINTS {p} differs from WIDTH {width} × HEIGHT {height} = {product}"),
                ));
            }
            _ => product,
        };
        let Some((data, _)) = self.data else {
            return Err(at_line(data_line, "header has no DATA line".into()));
        };
        let header = PcdHeader {
            version: self.version.unwrap_or_default(),
            fields,
            width,
            height,
            cloud_from_sensor: self.viewpoint.unwrap_or_else(Pose3::identity),
            points,
            data,
            data_offset,
            data_line,
        };
        if header.point_bytes() > u32::MAX as usize {
            return Err(at_line(sizes_line, "a point takes more than 4 GiB".into()));
        }
        Ok(header)
    }
}

fn single_number(keyword: &str, values: &[&str]) -> Result<usize, String> {
    match values {
        [v] => v
            .parse::<usize>()
            .map_err(|_| format!("{keyword} {v:?} is not a non-negative integer")),
        _ => Err(format!("{keyword} needs exactly one value")),
    }
}

fn parse_viewpoint(values: &[&str]) -> Result<Pose3, String> {
    let numbers = values
        .iter()
        .map(|v| v.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<Vec<f64>>>()
        .ok_or("VIEWPOINT values must be finite numbers")?;
    let [tx, ty, tz, qw, qx, qy, qz] = numbers[..] else {
        return Err(format!(
            "VIEWPOINT needs 7 values (tx ty tz qw qx qy qz), found {}",
            numbers.len()
        ));
    };
    let q = Quaternion::new(qw, qx, qy, qz);
    if q.norm() < 1e-9 {
        return Err("VIEWPOINT quaternion is zero".into());
    }
    Ok(Pose3::from_parts(
        Vector3::new(tx, ty, tz),
        UnitQuaternion::from_quaternion(q),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn parse(text: &str) -> Result<PcdHeader> {
        read_header(&mut Cursor::new(text.as_bytes()), Path::new("h.pcd"))
    }

    #[test]
    fn parses_full_header() {
        let h = parse(
            "# c\nVERSION .7\nFIELDS x y z rgb normal\nSIZE 4 4 4 4 2\nTYPE F F F U I\n\
             COUNT 1 1 1 1 3\nWIDTH 2\nHEIGHT 3\nVIEWPOINT 1 2 3 0 0 0 1\nPOINTS 6\nDATA binary\nxx",
        )
        .unwrap();
        assert_eq!(h.fields.len(), 5);
        assert_eq!(h.point_bytes(), 22);
        assert_eq!(h.point_values(), 7);
        assert_eq!((h.width, h.height, h.points), (2, 3, 6));
        assert_eq!(h.data, DataEncoding::Binary);
        assert_eq!(h.data_line, 11);
        assert_eq!(h.data_offset as usize, h.data_offset as usize);
        let t = h.cloud_from_sensor.translation();
        assert_eq!((t.x, t.y, t.z), (1.0, 2.0, 3.0));
        let (_, _, yaw) = h.cloud_from_sensor.rpy();
        assert!((yaw.abs() - std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("VERSION .7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "h.pcd:3: SIZE has 2 values for 3 fields");
        let e = parse(
            "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 5\nDATA ascii\n",
        )
        .unwrap_err()
        .to_string();
        assert_eq!(e, "h.pcd:6: POINTS 5 differs from WIDTH 2 × HEIGHT 2 = 4");
        let e = parse("FIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 2\nDATA ascii\n").unwrap_err();
        assert_eq!(e.location(), Location::Line(1));
        let e = parse("FIELDS x y z\nSIZE 4 4 3\n").unwrap_err().to_string();
        assert!(e.starts_with("h.pcd:2: SIZE \"3\""), "{e}");
        let e = parse("FIELDS x y z\n").unwrap_err().to_string();
        assert!(e.contains("no DATA line"), "{e}");
        let e = parse("FIELDS x y z\nBOGUS 1\n").unwrap_err().to_string();
        assert_eq!(e, "h.pcd:2: unknown header keyword \"BOGUS\"");
    }
}
