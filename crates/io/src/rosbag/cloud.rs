//! `sensor_msgs/msg/PointCloud2` ↔ [`PointCloud`].

use nalgebra::Point3;
use raypath_geometry::PointCloud;

use super::cdr::{CdrError, CdrReader, CdrResult, CdrWriter};
use super::msgs::{Header, Stamp, read_header, write_header};

/// `sensor_msgs/msg/PointField` datatypes.
const INT8: u8 = 1;
const UINT8: u8 = 2;
const INT16: u8 = 3;
const UINT16: u8 = 4;
const INT32: u8 = 5;
const UINT32: u8 = 6;
const FLOAT32: u8 = 7;
const FLOAT64: u8 = 8;

fn datatype_size(datatype: u8) -> Option<usize> {
    match datatype {
        INT8 | UINT8 => Some(1),
        INT16 | UINT16 => Some(2),
        INT32 | UINT32 | FLOAT32 => Some(4),
        FLOAT64 => Some(8),
        _ => None,
    }
}

/// Where one scalar of each point is.
#[derive(Clone, Copy, Debug)]
struct Field {
    offset: usize,
    datatype: u8,
}

impl Field {
    /// Reads the value of the point that starts at `point` (bounds checked by the caller:
    /// `offset + size <= point_step`).
    #[inline]
    fn get(self, point: &[u8], big_endian: bool) -> f32 {
        let b = &point[self.offset..];
        macro_rules! num {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big_endian {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self.datatype {
            INT8 => f32::from(b[0] as i8),
            UINT8 => f32::from(b[0]),
            INT16 => f32::from(num!(i16, 2)),
            UINT16 => f32::from(num!(u16, 2)),
            INT32 => num!(i32, 4) as f32,
            UINT32 => num!(u32, 4) as f32,
            FLOAT32 => num!(f32, 4),
            _ => num!(f64, 8) as f32,
        }
    }
}

struct Layout {
    width: usize,
    height: usize,
    point_step: usize,
    row_step: usize,
    big_endian: bool,
    xyz: [Field; 3],
    intensity: Option<Field>,
}

fn read_layout<'a>(r: &mut CdrReader<'a>) -> CdrResult<(Layout, &'a [u8])> {
    let height = r.u32()? as usize;
    let width = r.u32()? as usize;
    let fields_at = r.offset();
    // name (≥ 5) + offset 4 + datatype 1 + count 4
    let n_fields = r.seq_len(14, "fields")?;
    let mut found: [Option<(Field, u32)>; 5] = [None; 5];
    const NAMES: [&str; 5] = ["x", "y", "z", "intensity", "reflectivity"];
    for _ in 0..n_fields {
        let at = r.offset();
        let name = r.string()?;
        let offset = r.u32()? as usize;
        let datatype = r.u8()?;
        let count = r.u32()?;
        if let Some(k) = NAMES.iter().position(|&n| n == name) {
            if datatype_size(datatype).is_none() {
                return Err(CdrError {
                    offset: at,
                    reason: format!("field {name:?} has unknown datatype {datatype}"),
                });
            }
            found[k] = Some((Field { offset, datatype }, count));
        }
    }
    let big_endian = r.bool()?;
    let point_step = r.u32()? as usize;
    let row_step = r.u32()? as usize;
    let data = r.byte_seq("data")?;
    let _is_dense = r.bool()?;
    let bad = |reason: String| CdrError {
        offset: fields_at,
        reason,
    };
    let mut xyz = [Field {
        offset: 0,
        datatype: FLOAT32,
    }; 3];
    for k in 0..3 {
        let Some((field, _)) = found[k] else {
            return Err(bad(format!(
                "no field {:?} (fields x, y, z are needed)",
                NAMES[k]
            )));
        };
        if !matches!(field.datatype, FLOAT32 | FLOAT64) {
            return Err(bad(format!(
                "field {:?} has datatype {}, not float32 (7) or float64 (8)",
                NAMES[k], field.datatype
            )));
        }
        xyz[k] = field;
    }
    let intensity = found[3].or(found[4]).map(|(f, _)| f);
    for f in xyz.iter().chain(intensity.iter()) {
        let size = datatype_size(f.datatype).unwrap_or(8);
        if f.offset.saturating_add(size) > point_step {
            return Err(bad(format!(
                "a field at offset {} does not fit in point_step {point_step}",
                f.offset
            )));
        }
    }
    let need_row = point_step.checked_mul(width);
    if need_row.is_none_or(|n| n > row_step) {
        return Err(bad(format!(
            "width {width} × point_step {point_step} exceeds row_step {row_step}"
        )));
    }
    if row_step
        .checked_mul(height.saturating_sub(1))
        .and_then(|n| n.checked_add(need_row.unwrap_or(usize::MAX)))
        .is_none_or(|n| n > data.len())
    {
        return Err(bad(format!(
            "{height} rows of {row_step} bytes need more than the {} data bytes",
            data.len()
        )));
    }
    Ok((
        Layout {
            width,
            height,
            point_step,
            row_step,
            big_endian,
            xyz,
            intensity,
        },
        data,
    ))
}

/// Reads every point of the grid with `read` (bounds were checked by [`read_layout`]).
fn fill(
    layout: &Layout,
    bytes: &[u8],
    organized: bool,
    points: &mut Vec<Point3<f32>>,
    intensity: &mut Option<Vec<f32>>,
    read: impl Fn(&[u8], Field) -> f32,
) {
    let [fx, fy, fz] = layout.xyz;
    for row in 0..layout.height {
        let start = row * layout.row_step;
        let row_bytes = &bytes[start..start + layout.width * layout.point_step];
        for point in row_bytes.chunks_exact(layout.point_step.max(1)) {
            let p = Point3::new(read(point, fx), read(point, fy), read(point, fz));
            let finite = p.x.is_finite() && p.y.is_finite() && p.z.is_finite();
            if !(organized || finite) {
                continue;
            }
            points.push(p);
            if let (Some(out), Some(f)) = (intensity.as_mut(), layout.intensity) {
                out.push(read(point, f));
            }
        }
    }
}

/// Decodes a `sensor_msgs/msg/PointCloud2`: fields `x`, `y`, `z` (float32 or float64) and
/// `intensity` (else `reflectivity`, any numeric datatype, converted to `f32`); other fields
/// are ignored. Organized clouds (`height > 1`) keep their grid, invalid pixels as NaN;
/// points of unorganized clouds with non-finite coordinates are dropped.
pub fn decode_cloud(data: &[u8]) -> CdrResult<(Header<'_>, PointCloud)> {
    let mut r = CdrReader::new(data)?;
    let header = read_header(&mut r)?;
    let (layout, bytes) = read_layout(&mut r)?;
    let n = layout.width * layout.height;
    let organized = layout.height > 1;
    let mut points = Vec::with_capacity(n);
    let mut intensity = layout.intensity.map(|_| Vec::with_capacity(n));
    let be = layout.big_endian;
    let all_f32_le = !be
        && layout
            .xyz
            .iter()
            .chain(layout.intensity.iter())
            .all(|f| f.datatype == FLOAT32);
    if all_f32_le {
        fill(
            &layout,
            bytes,
            organized,
            &mut points,
            &mut intensity,
            |p, f| {
                let b = &p[f.offset..f.offset + 4];
                f32::from_le_bytes([b[0], b[1], b[2], b[3]])
            },
        );
    } else {
        fill(
            &layout,
            bytes,
            organized,
            &mut points,
            &mut intensity,
            |p, f| f.get(p, be),
        );
    }
    let mut cloud = PointCloud::from_points(points);
    cloud.intensity = intensity;
    if organized {
        cloud.width = layout.width;
        cloud.height = layout.height;
    }
    Ok((header, cloud))
}

/// Encodes a `sensor_msgs/msg/PointCloud2`: little-endian float32 `x`, `y`, `z` and
/// `intensity` when the cloud has one; organized (`height × width`) when the cloud is.
pub fn encode_cloud(w: &mut CdrWriter, stamp: Stamp, frame_id: &str, cloud: &PointCloud) {
    write_header(w, stamp, frame_id);
    let (height, width) = if cloud.is_organized() {
        (cloud.height, cloud.width)
    } else {
        (1, cloud.len())
    };
    w.u32(height as u32);
    w.u32(width as u32);
    let intensity = cloud
        .intensity
        .as_deref()
        .filter(|v| v.len() == cloud.len());
    let mut names = vec!["x", "y", "z"];
    if intensity.is_some() {
        names.push("intensity");
    }
    w.seq_len(names.len());
    for (k, name) in names.iter().enumerate() {
        w.string(name);
        w.u32(4 * k as u32);
        w.u8(FLOAT32);
        w.u32(1);
    }
    let point_step = 4 * names.len();
    w.bool(false);
    w.u32(point_step as u32);
    w.u32((point_step * width) as u32);
    w.byte_seq_with(point_step * cloud.len(), |buf| {
        for (i, p) in cloud.points.iter().enumerate() {
            for v in [p.x, p.y, p.z] {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            if let Some(v) = intensity {
                buf.extend_from_slice(&v[i].to_le_bytes());
            }
        }
    });
    let dense = cloud.points.iter().all(|p| p.iter().all(|v| v.is_finite()));
    w.bool(dense);
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn header(w: &mut CdrWriter) {
        write_header(w, Stamp { sec: 5, nanosec: 7 }, "velodyne");
    }

    /// A hand-made cloud: float64 coordinates, uint16 reflectivity, padding, big endian.
    fn exotic(big_endian: bool, height: u32, width: u32) -> Vec<u8> {
        let mut w = CdrWriter::new();
        header(&mut w);
        w.u32(height);
        w.u32(width);
        let fields = [
            ("ring", 0, UINT16),
            ("z", 2, FLOAT64),
            ("x", 10, FLOAT64),
            ("y", 18, FLOAT64),
            ("reflectivity", 26, UINT16),
        ];
        w.seq_len(fields.len());
        for (name, off, dt) in fields {
            w.string(name);
            w.u32(off);
            w.u8(dt);
            w.u32(1);
        }
        w.bool(big_endian);
        let point_step = 30;
        let row_step = point_step * width as usize + 6; // padded rows
        w.u32(point_step as u32);
        w.u32(row_step as u32);
        let n = (height * width) as usize;
        w.byte_seq_with(row_step * height as usize, |buf| {
            for i in 0..n {
                let f = |v: f64| {
                    if big_endian {
                        v.to_be_bytes()
                    } else {
                        v.to_le_bytes()
                    }
                };
                let u = |v: u16| {
                    if big_endian {
                        v.to_be_bytes()
                    } else {
                        v.to_le_bytes()
                    }
                };
                buf.extend_from_slice(&u(i as u16));
                let x = if i == 1 { f64::NAN } else { i as f64 };
                buf.extend_from_slice(&f(-(i as f64)));
                buf.extend_from_slice(&f(x));
                buf.extend_from_slice(&f(0.5 * i as f64));
                buf.extend_from_slice(&u(100 + i as u16));
                buf.extend_from_slice(&[0xAB; 2]); // unused bytes of the point
                if (i + 1) % width as usize == 0 {
                    buf.extend_from_slice(&[0; 6]);
                }
            }
        });
        w.bool(false);
        w.bytes().to_vec()
    }

    #[test]
    fn any_layout() {
        for be in [false, true] {
            let bytes = exotic(be, 1, 4);
            let (h, cloud) = decode_cloud(&bytes).unwrap();
            assert_eq!(h.frame_id, "velodyne");
            // Point 1 (NaN x) dropped from the unorganized cloud.
            assert_eq!(cloud.len(), 3);
            assert_eq!((cloud.width, cloud.height), (3, 1));
            assert_eq!(cloud.points[1], Point3::new(2.0, 1.0, -2.0));
            assert_eq!(cloud.intensity.as_deref(), Some(&[100.0, 102.0, 103.0][..]));

            let (_, grid) = decode_cloud(&exotic(be, 2, 3)).unwrap();
            assert_eq!((grid.width, grid.height, grid.len()), (3, 2, 6));
            assert!(!grid.is_valid(1));
            assert_eq!(grid.points[5], Point3::new(5.0, 2.5, -5.0));
            grid.validate().unwrap();
        }
    }

    #[test]
    fn round_trip() {
        let mut cloud = PointCloud::from_points(vec![
            Point3::new(1.0, 2.0, 3.0),
            Point3::new(f32::NAN, f32::NAN, f32::NAN),
            Point3::new(-1.0, 0.5, 0.25),
            Point3::new(4.0, 5.0, 6.0),
        ]);
        cloud.intensity = Some(vec![1.0, 0.0, 7.5, 2.0]);
        cloud.width = 2;
        cloud.height = 2;
        let mut w = CdrWriter::new();
        encode_cloud(&mut w, Stamp { sec: 1, nanosec: 2 }, "os", &cloud);
        let (h, back) = decode_cloud(w.bytes()).unwrap();
        assert_eq!(h.stamp, Stamp { sec: 1, nanosec: 2 });
        assert_eq!((back.width, back.height), (2, 2));
        assert_eq!(back.points[3], cloud.points[3]);
        assert!(!back.is_valid(1));
        assert_eq!(back.intensity, cloud.intensity);

        let flat = PointCloud::from_points(vec![Point3::new(1.0, 2.0, 3.0)]);
        w.reset();
        encode_cloud(&mut w, Stamp::default(), "os", &flat);
        assert_eq!(decode_cloud(w.bytes()).unwrap().1, flat);
    }

    #[test]
    fn bad_layouts() {
        let mut bytes = exotic(false, 1, 4);
        // Claim 5 points per row: row_step too small.
        bytes[32..36].copy_from_slice(&5u32.to_le_bytes());
        let e = decode_cloud(&bytes).unwrap_err();
        assert!(e.reason.contains("row_step"), "{e}");
    }
}
