//! The JSON Schema texts of the Foxglove well-known schemas we write.
//!
//! Written by us from Foxglove's schema definitions (`schemas/jsonschema/*.json` of the
//! foxglove-sdk repository; field names, types and required lists are theirs, descriptions are
//! left out). Foxglove recognises a channel by the schema *name* (`foxglove.Grid`, …); the
//! schema text tells it which string fields are base64 bytes (`"contentEncoding": "base64"`),
//! and lets any JSON Schema validator check our messages.

use serde_json::{Map, Value, json};

/// A Foxglove well-known schema that [`super::Recorder`] writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Schema {
    /// `foxglove.Grid`: a 2-D grid of cells with packed numeric fields.
    Grid,
    /// `foxglove.PointCloud`: points with packed numeric fields.
    PointCloud,
    /// `foxglove.PosesInFrame`: a list of poses (a trajectory).
    PosesInFrame,
    /// `foxglove.FrameTransform`: one parent-from-child transform.
    FrameTransform,
    /// `foxglove.SceneUpdate`: entities made of primitives (cylinders, lines, triangles, cubes).
    SceneUpdate,
    /// `foxglove.LaserScan`: ranges of a planar laser at equally spaced angles.
    LaserScan,
}

impl Schema {
    /// Every schema, in the order of the enum.
    pub const ALL: [Schema; 6] = [
        Schema::Grid,
        Schema::PointCloud,
        Schema::PosesInFrame,
        Schema::FrameTransform,
        Schema::SceneUpdate,
        Schema::LaserScan,
    ];

    /// The schema name Foxglove recognises, e.g. `foxglove.Grid`.
    pub fn name(self) -> &'static str {
        match self {
            Schema::Grid => "foxglove.Grid",
            Schema::PointCloud => "foxglove.PointCloud",
            Schema::PosesInFrame => "foxglove.PosesInFrame",
            Schema::FrameTransform => "foxglove.FrameTransform",
            Schema::SceneUpdate => "foxglove.SceneUpdate",
            Schema::LaserScan => "foxglove.LaserScan",
        }
    }

    /// The JSON Schema (draft 2020-12 keywords) as a value; its `title` is [`Schema::name`].
    pub fn json_schema(self) -> Value {
        let stamp = ("timestamp", time());
        let frame = ("frame_id", string());
        match self {
            Schema::Grid => object(
                self.name(),
                vec![
                    stamp,
                    frame,
                    ("pose", pose()),
                    ("column_count", count()),
                    ("cell_size", vector2()),
                    ("row_stride", count()),
                    ("cell_stride", count()),
                    ("fields", array(packed_element_field())),
                    ("data", bytes()),
                ],
            ),
            Schema::PointCloud => object(
                self.name(),
                vec![
                    stamp,
                    frame,
                    ("pose", pose()),
                    ("point_stride", count()),
                    ("fields", array(packed_element_field())),
                    ("data", bytes()),
                ],
            ),
            Schema::PosesInFrame => {
                object(self.name(), vec![stamp, frame, ("poses", array(pose()))])
            }
            Schema::FrameTransform => object(
                self.name(),
                vec![
                    stamp,
                    ("parent_frame_id", string()),
                    ("child_frame_id", string()),
                    ("translation", vector3("foxglove.Vector3")),
                    ("rotation", quaternion()),
                ],
            ),
            Schema::SceneUpdate => object(
                self.name(),
                vec![
                    ("deletions", array(scene_entity_deletion())),
                    ("entities", array(scene_entity())),
                ],
            ),
            Schema::LaserScan => object(
                self.name(),
                vec![
                    stamp,
                    frame,
                    ("pose", pose()),
                    ("start_angle", number()),
                    ("end_angle", number()),
                    ("ranges", array(number())),
                    ("intensities", array(number())),
                ],
            ),
        }
    }

    /// The schema text stored in the MCAP `Schema` record (compact JSON).
    pub fn text(self) -> String {
        self.json_schema().to_string()
    }
}

/// An object schema whose properties are all required (true of every Foxglove schema we use).
fn object(title: &str, properties: Vec<(&str, Value)>) -> Value {
    let required: Vec<&str> = properties.iter().map(|(name, _)| *name).collect();
    let properties: Map<String, Value> = properties
        .into_iter()
        .map(|(name, schema)| (name.to_owned(), schema))
        .collect();
    json!({ "title": title, "type": "object", "properties": properties, "required": required })
}

fn number() -> Value {
    json!({ "type": "number" })
}

fn string() -> Value {
    json!({ "type": "string" })
}

fn boolean() -> Value {
    json!({ "type": "boolean" })
}

fn count() -> Value {
    json!({ "type": "integer", "minimum": 0 })
}

fn bytes() -> Value {
    json!({ "type": "string", "contentEncoding": "base64" })
}

fn array(items: Value) -> Value {
    json!({ "type": "array", "items": items })
}

fn time() -> Value {
    json!({
        "type": "object",
        "title": "time",
        "properties": {
            "sec": { "type": "integer", "minimum": 0 },
            "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 }
        }
    })
}

fn duration() -> Value {
    json!({
        "type": "object",
        "title": "duration",
        "properties": {
            "sec": { "type": "integer" },
            "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 }
        }
    })
}

fn vector2() -> Value {
    object("foxglove.Vector2", vec![("x", number()), ("y", number())])
}

fn vector3(title: &str) -> Value {
    object(
        title,
        vec![("x", number()), ("y", number()), ("z", number())],
    )
}

fn quaternion() -> Value {
    object(
        "foxglove.Quaternion",
        vec![
            ("x", number()),
            ("y", number()),
            ("z", number()),
            ("w", number()),
        ],
    )
}

fn pose() -> Value {
    object(
        "foxglove.Pose",
        vec![
            ("position", vector3("foxglove.Vector3")),
            ("orientation", quaternion()),
        ],
    )
}

fn color() -> Value {
    object(
        "foxglove.Color",
        vec![
            ("r", number()),
            ("g", number()),
            ("b", number()),
            ("a", number()),
        ],
    )
}

/// An enumeration as Foxglove writes it: `oneOf` constants with their names as titles.
fn enumeration(title: &str, names: &[&str]) -> Value {
    let cases: Vec<Value> = names
        .iter()
        .enumerate()
        .map(|(value, name)| json!({ "title": name, "const": value }))
        .collect();
    json!({ "title": title, "oneOf": cases })
}

fn packed_element_field() -> Value {
    object(
        "foxglove.PackedElementField",
        vec![
            ("name", string()),
            ("offset", count()),
            (
                "type",
                enumeration(
                    "foxglove.NumericType",
                    &[
                        "UNKNOWN", "UINT8", "INT8", "UINT16", "INT16", "UINT32", "INT32",
                        "FLOAT32", "FLOAT64",
                    ],
                ),
            ),
        ],
    )
}

fn scene_entity_deletion() -> Value {
    object(
        "foxglove.SceneEntityDeletion",
        vec![
            ("timestamp", time()),
            (
                "type",
                enumeration("foxglove.SceneEntityDeletionType", &["MATCHING_ID", "ALL"]),
            ),
            ("id", string()),
        ],
    )
}

fn scene_entity() -> Value {
    let key_value = object(
        "foxglove.KeyValuePair",
        vec![("key", string()), ("value", string())],
    );
    let sized = |title: &str| {
        object(
            title,
            vec![
                ("pose", pose()),
                ("size", vector3("foxglove.Vector3")),
                ("color", color()),
            ],
        )
    };
    let arrow = object(
        "foxglove.ArrowPrimitive",
        vec![
            ("pose", pose()),
            ("shaft_length", number()),
            ("shaft_diameter", number()),
            ("head_length", number()),
            ("head_diameter", number()),
            ("color", color()),
        ],
    );
    let cylinder = object(
        "foxglove.CylinderPrimitive",
        vec![
            ("pose", pose()),
            ("size", vector3("foxglove.Vector3")),
            ("bottom_scale", number()),
            ("top_scale", number()),
            ("color", color()),
        ],
    );
    let point3 = vector3("foxglove.Point3");
    let line = object(
        "foxglove.LinePrimitive",
        vec![
            (
                "type",
                enumeration(
                    "foxglove.LineType",
                    &["LINE_STRIP", "LINE_LOOP", "LINE_LIST"],
                ),
            ),
            ("pose", pose()),
            ("thickness", number()),
            ("scale_invariant", boolean()),
            ("points", array(point3.clone())),
            ("color", color()),
            ("colors", array(color())),
            ("indices", array(count())),
        ],
    );
    let triangles = object(
        "foxglove.TriangleListPrimitive",
        vec![
            ("pose", pose()),
            ("points", array(point3)),
            ("color", color()),
            ("colors", array(color())),
            ("indices", array(count())),
        ],
    );
    let text = object(
        "foxglove.TextPrimitive",
        vec![
            ("pose", pose()),
            ("billboard", boolean()),
            ("font_size", number()),
            ("scale_invariant", boolean()),
            ("color", color()),
            ("text", string()),
        ],
    );
    let model = object(
        "foxglove.ModelPrimitive",
        vec![
            ("pose", pose()),
            ("scale", vector3("foxglove.Vector3")),
            ("color", color()),
            ("override_color", boolean()),
            ("url", string()),
            ("media_type", string()),
            ("data", bytes()),
        ],
    );
    object(
        "foxglove.SceneEntity",
        vec![
            ("timestamp", time()),
            ("frame_id", string()),
            ("id", string()),
            ("lifetime", duration()),
            ("frame_locked", boolean()),
            ("metadata", array(key_value)),
            ("arrows", array(arrow)),
            ("cubes", array(sized("foxglove.CubePrimitive"))),
            ("spheres", array(sized("foxglove.SpherePrimitive"))),
            ("cylinders", array(cylinder)),
            ("lines", array(line)),
            ("triangles", array(triangles)),
            ("texts", array(text)),
            ("models", array(model)),
        ],
    )
}
