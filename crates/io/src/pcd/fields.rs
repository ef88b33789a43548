//! What the PCD reader does with each field, and how a point is assembled from the values.

use nalgebra::Point3;
use raypath_geometry::PointCloud;

use super::header::{FieldType, PcdHeader};
use super::{LabelSource, ReadOptions};
use crate::{Error, Location, Result};
use std::path::Path;

/// What the reader does with each field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Role {
    /// 0, 1, 2 for x, y, z.
    pub(super) coordinate: Option<usize>,
    pub(super) intensity: bool,
    pub(super) label: bool,
    pub(super) rgb: bool,
}

impl Role {
    pub(super) fn is_used(self) -> bool {
        self.coordinate.is_some() || self.intensity || self.label || self.rgb
    }
}

pub(super) struct Roles {
    pub(super) roles: Vec<Role>,
    pub(super) has_intensity: bool,
    pub(super) has_label: bool,
    pub(super) has_rgb: bool,
}

impl Roles {
    pub(super) fn new(header: &PcdHeader, path: &Path, options: &ReadOptions) -> Result<Self> {
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
pub(super) enum Value {
    F32(f32),
    F64(f64),
    U(u64),
    I(i64),
}

impl Value {
    pub(super) fn is_non_finite(self) -> bool {
        match self {
            Value::F32(v) => !v.is_finite(),
            Value::F64(v) => !v.is_finite(),
            Value::U(_) | Value::I(_) => false,
        }
    }

    pub(super) fn as_f32(self) -> f32 {
        match self {
            Value::F32(v) => v,
            Value::F64(v) => v as f32,
            Value::U(v) => v as f32,
            Value::I(v) => v as f32,
        }
    }

    /// The value as a label, `None` when it is not a non-negative integer that fits `u32`.
    pub(super) fn as_label(self) -> Option<u32> {
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
pub(super) struct PointValues {
    pub(super) xyz: [f32; 3],
    pub(super) intensity: f32,
    pub(super) label: Value,
    pub(super) rgb: u32,
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

pub(super) struct Builder {
    pub(super) cloud: PointCloud,
}

impl Builder {
    pub(super) fn new(header: &PcdHeader, roles: &Roles, reserve: usize) -> Self {
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
    pub(super) fn push(&mut self, p: &PointValues) -> std::result::Result<(), String> {
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

pub(super) fn assign(values: &mut PointValues, role: Role, value: Value) {
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
