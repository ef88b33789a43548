//! The JSON bodies of the Foxglove messages: typed inputs in raypath's geometry types, one
//! function per schema returning the message as a [`serde_json::Value`].
//!
//! Inputs are checked here (lengths, finite numbers); a problem is returned as a sentence that
//! the recorder prefixes with the file, topic and time.

use nalgebra::{Point3, UnitQuaternion, Vector3};
use raypath_geometry::{Grid2, PointCloud, Pose2, Pose3, Scan2};
use serde_json::{Value, json};

use super::base64;

/// A colour as red, green, blue, alpha in `0..=1` (alpha 1 is opaque).
pub type Rgba = [f32; 4];

/// A time as Foxglove stores it: whole seconds and nanoseconds `0..1e9`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Stamp {
    /// Whole seconds.
    pub sec: u64,
    /// Nanoseconds past `sec`, below 1 000 000 000.
    pub nsec: u32,
}

impl Stamp {
    /// The stamp of `secs` seconds, rounded to the nanosecond; fails for negative, non-finite
    /// or too large times (above `u64::MAX` nanoseconds, the year 2554).
    pub fn from_secs(secs: f64) -> Result<Self, String> {
        if !(secs.is_finite() && secs >= 0.0 && secs < u64::MAX as f64 / 1e9) {
            return Err(format!("time {secs} s is not a non-negative finite time"));
        }
        let mut sec = secs.floor();
        let mut nsec = ((secs - sec) * 1e9).round();
        if nsec >= 1e9 {
            sec += 1.0;
            nsec -= 1e9;
        }
        Ok(Stamp {
            sec: sec as u64,
            nsec: nsec as u32,
        })
    }

    /// Nanoseconds since the epoch (the MCAP log time).
    pub fn nanos(self) -> u64 {
        self.sec
            .saturating_mul(1_000_000_000)
            .saturating_add(u64::from(self.nsec))
    }

    pub(super) fn json(self) -> Value {
        json!({ "sec": self.sec, "nsec": self.nsec })
    }
}

/// The cell values of a [`GridLayer`], row by row from the grid's origin corner (x fastest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridValues<'a> {
    /// One byte per cell (`UINT8`), e.g. a `map_server` grey level or occupancy in percent.
    U8(&'a [u8]),
    /// One `FLOAT32` per cell, e.g. a probability; NaN for unknown cells is kept as NaN.
    F32(&'a [f32]),
}

impl GridValues<'_> {
    fn len(&self) -> usize {
        match self {
            GridValues::U8(v) => v.len(),
            GridValues::F32(v) => v.len(),
        }
    }
}

/// A 2-D map layer for `foxglove.Grid`: `columns × rows` cells of `cell_size_m`, cell
/// `(column, row)` at `origin · (column · cell_size_m, row · cell_size_m)`, its corner nearest
/// to the origin (the layout of [`Grid2`] and of the `map_server` YAML `origin`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridLayer<'a> {
    /// The frame the grid is given in (e.g. `map`).
    pub frame_id: &'a str,
    /// The pose of the corner of cell `(0, 0)` in `frame_id`; the grid lies in its x-y plane.
    pub origin: Pose3,
    /// Edge length of a square cell in metres.
    pub cell_size_m: f64,
    /// Number of cells along x.
    pub columns: usize,
    /// Number of cells along y.
    pub rows: usize,
    /// The name of the field Foxglove colours by (e.g. `occupancy`, `reflection`).
    pub field: &'a str,
    /// The values, `columns · rows` of them.
    pub values: GridValues<'a>,
}

impl<'a> GridLayer<'a> {
    /// The layer of `values` (in [`Grid2::linear_index`] order) over `grid`, lying in the
    /// `z = 0` plane of `frame_id`.
    pub fn from_grid2(
        grid: &Grid2,
        frame_id: &'a str,
        field: &'a str,
        values: GridValues<'a>,
    ) -> Self {
        let origin = grid.origin();
        let [columns, rows] = grid.dims();
        GridLayer {
            frame_id,
            origin: Pose2::new(origin.x, origin.y, 0.0).to_pose3(),
            cell_size_m: grid.cell_size(),
            columns,
            rows,
            field,
            values,
        }
    }
}

pub(super) fn vector_json(v: &Vector3<f64>) -> Value {
    json!({ "x": v.x, "y": v.y, "z": v.z })
}

pub(super) fn point_json(p: &Point3<f64>) -> Value {
    vector_json(&p.coords)
}

pub(super) fn quaternion_json(q: &UnitQuaternion<f64>) -> Value {
    json!({ "x": q.i, "y": q.j, "z": q.k, "w": q.w })
}

pub(super) fn pose_json(pose: &Pose3) -> Value {
    json!({
        "position": vector_json(&pose.translation()),
        "orientation": quaternion_json(&pose.rotation()),
    })
}

pub(super) fn position_pose_json(p: &Point3<f64>) -> Value {
    pose_json(&Pose3::from_parts(p.coords, UnitQuaternion::identity()))
}

pub(super) fn color_json(c: &Rgba) -> Value {
    json!({ "r": c[0], "g": c[1], "b": c[2], "a": c[3] })
}

fn field_json(name: &str, offset: usize, numeric_type: u8) -> Value {
    json!({ "name": name, "offset": offset, "type": numeric_type })
}

/// `foxglove.NumericType` codes.
const UINT8: u8 = 1;
const UINT32: u8 = 5;
const FLOAT32: u8 = 7;

/// The first place in `value` holding `null` (serde_json's image of a NaN or infinite `f64`),
/// as a path like `entities[2].cylinders[0].size.x`.
pub(crate) fn first_null(value: &Value) -> Option<String> {
    match value {
        Value::Null => Some(String::new()),
        Value::Array(items) => items
            .iter()
            .enumerate()
            .find_map(|(i, item)| first_null(item).map(|rest| format!("[{i}]{rest}"))),
        Value::Object(map) => map
            .iter()
            .find_map(|(key, item)| first_null(item).map(|rest| format!(".{key}{rest}"))),
        _ => None,
    }
}

/// `foxglove.Grid` for `layer`.
pub fn grid_message(stamp: Stamp, layer: &GridLayer<'_>) -> Result<Value, String> {
    let cells = layer
        .columns
        .checked_mul(layer.rows)
        .ok_or_else(|| format!("{} × {} cells overflow", layer.columns, layer.rows))?;
    if layer.values.len() != cells {
        return Err(format!(
            "{} values for a grid of {} × {} cells",
            layer.values.len(),
            layer.columns,
            layer.rows
        ));
    }
    if !(layer.cell_size_m.is_finite() && layer.cell_size_m > 0.0) {
        return Err(format!("cell size {} m is not positive", layer.cell_size_m));
    }
    let (cell_stride, numeric_type, data) = match layer.values {
        GridValues::U8(values) => (1, UINT8, base64::encode(values)),
        GridValues::F32(values) => {
            let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
            (4, FLOAT32, base64::encode(&bytes))
        }
    };
    Ok(json!({
        "timestamp": stamp.json(),
        "frame_id": layer.frame_id,
        "pose": pose_json(&layer.origin),
        "column_count": layer.columns,
        "cell_size": { "x": layer.cell_size_m, "y": layer.cell_size_m },
        "row_stride": layer.columns * cell_stride,
        "cell_stride": cell_stride,
        "fields": [field_json(layer.field, 0, numeric_type)],
        "data": data,
    }))
}

/// `foxglove.PointCloud` of the finite points of `cloud` (missing pixels of organized clouds
/// are left out): fields `x y z` (`FLOAT32`), then `intensity` (`FLOAT32`) and `label`
/// (`UINT32`) when the cloud has them, then `red green blue alpha` (`UINT8`) from `colors`
/// (one per point of the cloud), else from the cloud's `rgb` (alpha 255).
pub fn point_cloud_message(
    stamp: Stamp,
    frame_id: &str,
    cloud: &PointCloud,
    colors: Option<&[Rgba]>,
) -> Result<Value, String> {
    let n = cloud.len();
    for (name, len) in [
        ("intensity", cloud.intensity.as_ref().map(Vec::len)),
        ("label", cloud.label.as_ref().map(Vec::len)),
        ("rgb", cloud.rgb.as_ref().map(Vec::len)),
        ("colors", colors.map(<[Rgba]>::len)),
    ] {
        if let Some(len) = len
            && len != n
        {
            return Err(format!("{len} {name} values for {n} points"));
        }
    }
    let mut fields = vec![
        field_json("x", 0, FLOAT32),
        field_json("y", 4, FLOAT32),
        field_json("z", 8, FLOAT32),
    ];
    let mut stride = 12;
    if cloud.intensity.is_some() {
        fields.push(field_json("intensity", stride, FLOAT32));
        stride += 4;
    }
    if cloud.label.is_some() {
        fields.push(field_json("label", stride, UINT32));
        stride += 4;
    }
    let has_color = colors.is_some() || cloud.rgb.is_some();
    if has_color {
        for (i, name) in ["red", "green", "blue", "alpha"].into_iter().enumerate() {
            fields.push(field_json(name, stride + i, UINT8));
        }
        stride += 4;
    }
    let mut data = Vec::with_capacity(cloud.num_valid() * stride);
    for (i, p) in cloud.points.iter().enumerate() {
        if !cloud.is_valid(i) {
            continue;
        }
        for v in [p.x, p.y, p.z] {
            data.extend_from_slice(&v.to_le_bytes());
        }
        if let Some(intensity) = &cloud.intensity {
            data.extend_from_slice(&intensity[i].to_le_bytes());
        }
        if let Some(label) = &cloud.label {
            data.extend_from_slice(&label[i].to_le_bytes());
        }
        if let Some(colors) = colors {
            data.extend(colors[i].map(unit_to_byte));
        } else if let Some(rgb) = &cloud.rgb {
            let [_, r, g, b] = rgb[i].to_be_bytes();
            data.extend([r, g, b, 255]);
        }
    }
    Ok(json!({
        "timestamp": stamp.json(),
        "frame_id": frame_id,
        "pose": pose_json(&Pose3::identity()),
        "point_stride": stride,
        "fields": fields,
        "data": base64::encode(&data),
    }))
}

/// A colour channel in `0..=1` as a byte (clamped; NaN gives 0).
fn unit_to_byte(v: f32) -> u8 {
    if v.is_nan() {
        0
    } else {
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    }
}

/// `foxglove.PosesInFrame` of `poses`.
pub fn poses_message(stamp: Stamp, frame_id: &str, poses: &[Pose3]) -> Value {
    json!({
        "timestamp": stamp.json(),
        "frame_id": frame_id,
        "poses": poses.iter().map(pose_json).collect::<Vec<_>>(),
    })
}

/// `foxglove.FrameTransform`: `parent_from_child` maps points of `child` into `parent`.
pub fn transform_message(
    stamp: Stamp,
    parent: &str,
    child: &str,
    parent_from_child: &Pose3,
) -> Value {
    json!({
        "timestamp": stamp.json(),
        "parent_frame_id": parent,
        "child_frame_id": child,
        "translation": vector_json(&parent_from_child.translation()),
        "rotation": quaternion_json(&parent_from_child.rotation()),
    })
}

/// `foxglove.LaserScan` of `scan` seen from `frame_from_sensor`. No-returns (see
/// [`Scan2::range`]) are written as range 0 — the schema has no range limits and JSON no
/// infinities — and non-finite intensities as 0.
pub fn laser_scan_message(
    stamp: Stamp,
    frame_id: &str,
    scan: &Scan2,
    frame_from_sensor: &Pose3,
) -> Result<Value, String> {
    scan.validate().map_err(|e| e.to_string())?;
    let ranges: Vec<f64> = (0..scan.len())
        .map(|i| scan.range(i).hit().unwrap_or(0.0))
        .collect();
    let intensities: Vec<f64> = scan
        .intensities
        .iter()
        .flatten()
        .map(|&v| if v.is_finite() { v } else { 0.0 })
        .collect();
    Ok(json!({
        "timestamp": stamp.json(),
        "frame_id": frame_id,
        "pose": pose_json(frame_from_sensor),
        "start_angle": scan.angle_min_rad,
        "end_angle": scan.angle_max_rad(),
        "ranges": ranges,
        "intensities": intensities,
    }))
}
