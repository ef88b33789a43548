//! `foxglove.SceneUpdate`: entities made of primitives — poles as cylinders, polylines as
//! line strips, planes as triangle lists and outlines, octree leaves as cubes.

use nalgebra::{Point3, Vector3};
use raypath_geometry::Pose3;
use serde_json::{Value, json};

use super::messages::{Rgba, Stamp, color_json, point_json, pose_json, position_pose_json};

/// How the points of a [`Line`] are joined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineKind {
    /// Each point joined to the next (a polyline).
    Strip,
    /// A strip closed back to the first point (an outline).
    Loop,
    /// Points taken in pairs, each pair a segment.
    List,
}

/// An upright cylinder standing on `base` (a pole).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    /// The centre of the bottom face.
    pub base: Point3<f64>,
    /// Diameter in metres.
    pub diameter_m: f64,
    /// Height in metres (along +z).
    pub height_m: f64,
    /// Colour.
    pub color: Rgba,
}

/// Line segments: a polyline, an outline, or a list of segments.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// How the points are joined.
    pub kind: LineKind,
    /// The points in the entity's frame.
    pub points: Vec<Point3<f64>>,
    /// Line width in metres.
    pub thickness_m: f64,
    /// Colour.
    pub color: Rgba,
}

/// Filled triangles: points taken in threes (plane patches).
#[derive(Clone, Debug, PartialEq)]
pub struct Triangles {
    /// Three points per triangle, in the entity's frame.
    pub points: Vec<Point3<f64>>,
    /// Colour.
    pub color: Rgba,
}

/// An axis-aligned box (an octree leaf).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cube {
    /// The centre.
    pub center: Point3<f64>,
    /// Edge lengths along x, y, z in metres.
    pub size_m: [f64; 3],
    /// Colour.
    pub color: Rgba,
}

/// One object of a `foxglove.SceneUpdate`: an id and the primitives that draw it. An entity
/// replaces the earlier entity of the same id on the same topic.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Entity {
    /// Identifier, unique on the topic (e.g. `pole 17`).
    pub id: String,
    /// Cylinders (poles).
    pub cylinders: Vec<Cylinder>,
    /// Line strips, loops and lists (polylines, outlines).
    pub lines: Vec<Line>,
    /// Triangle lists (planes).
    pub triangles: Vec<Triangles>,
    /// Boxes (octree leaves).
    pub cubes: Vec<Cube>,
    /// Key-value pairs Foxglove shows when the entity is selected.
    pub metadata: Vec<(String, String)>,
}

impl Entity {
    /// An entity without primitives.
    pub fn new(id: impl Into<String>) -> Self {
        Entity {
            id: id.into(),
            ..Entity::default()
        }
    }
}

/// `foxglove.SceneUpdate` adding (or replacing) `entities`, all in `frame_id`, kept until
/// replaced.
pub fn scene_message(stamp: Stamp, frame_id: &str, entities: &[Entity]) -> Result<Value, String> {
    let entities = entities
        .iter()
        .map(|e| entity_json(stamp, frame_id, e))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(json!({ "deletions": [], "entities": entities }))
}

fn entity_json(stamp: Stamp, frame_id: &str, entity: &Entity) -> Result<Value, String> {
    let cylinders: Vec<Value> = entity
        .cylinders
        .iter()
        .map(|c| {
            let center = c.base + Vector3::new(0.0, 0.0, c.height_m / 2.0);
            json!({
                "pose": position_pose_json(&center),
                "size": { "x": c.diameter_m, "y": c.diameter_m, "z": c.height_m },
                "bottom_scale": 1.0,
                "top_scale": 1.0,
                "color": color_json(&c.color),
            })
        })
        .collect();
    let lines: Vec<Value> = entity
        .lines
        .iter()
        .map(|l| {
            let kind = match l.kind {
                LineKind::Strip => 0,
                LineKind::Loop => 1,
                LineKind::List => 2,
            };
            json!({
                "type": kind,
                "pose": pose_json(&Pose3::identity()),
                "thickness": l.thickness_m,
                "scale_invariant": false,
                "points": l.points.iter().map(point_json).collect::<Vec<_>>(),
                "color": color_json(&l.color),
                "colors": [],
                "indices": [],
            })
        })
        .collect();
    let mut triangles = Vec::with_capacity(entity.triangles.len());
    for t in &entity.triangles {
        if t.points.len() % 3 != 0 {
            return Err(format!(
                "entity {:?}: {} triangle points are not a multiple of 3",
                entity.id,
                t.points.len()
            ));
        }
        triangles.push(json!({
            "pose": pose_json(&Pose3::identity()),
            "points": t.points.iter().map(point_json).collect::<Vec<_>>(),
            "color": color_json(&t.color),
            "colors": [],
            "indices": [],
        }));
    }
    let cubes: Vec<Value> = entity
        .cubes
        .iter()
        .map(|c| {
            let [x, y, z] = c.size_m;
            json!({
                "pose": position_pose_json(&c.center),
                "size": { "x": x, "y": y, "z": z },
                "color": color_json(&c.color),
            })
        })
        .collect();
    let metadata: Vec<Value> = entity
        .metadata
        .iter()
        .map(|(key, value)| json!({ "key": key, "value": value }))
        .collect();
    Ok(json!({
        "timestamp": stamp.json(),
        "frame_id": frame_id,
        "id": entity.id,
        "lifetime": { "sec": 0, "nsec": 0 },
        "frame_locked": false,
        "metadata": metadata,
        "arrows": [],
        "cubes": cubes,
        "spheres": [],
        "cylinders": cylinders,
        "lines": lines,
        "triangles": triangles,
        "texts": [],
        "models": [],
    }))
}
