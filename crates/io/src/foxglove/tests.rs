//! Tests of the message bodies against the schemas, and of the recorder through the `mcap`
//! crate's reader.

use std::collections::BTreeMap;
use std::f64::consts::FRAC_PI_2;

use nalgebra::Point3;
use raypath_geometry::{Grid2, PointCloud, Pose2, Pose3, Scan2};
use serde_json::Value;

use super::base64;
use super::messages::{self, first_null};
use super::scene;
use super::*;

const T: Stamp = Stamp {
    sec: 12,
    nsec: 500_000_000,
};

/// Checks `value` against `schema` (the subset of JSON Schema our schemas use): objects have
/// exactly the listed properties (all are required), arrays' items, numbers, integers with
/// their bounds, enumerations (`oneOf` of constants), strings and base64 strings, booleans.
fn conforms(value: &Value, schema: &Value, path: &str) -> Result<(), String> {
    let fail = |what: &str| Err(format!("{path}: {what}, found {value}"));
    if let Some(cases) = schema.get("oneOf").and_then(Value::as_array) {
        return if cases.iter().any(|c| c.get("const") == Some(value)) {
            Ok(())
        } else {
            fail("not one of the enumeration's constants")
        };
    }
    match schema["type"].as_str() {
        Some("object") => {
            let Some(map) = value.as_object() else {
                return fail("not an object");
            };
            let properties = schema["properties"].as_object().unwrap();
            let expected: Vec<&String> = properties.keys().collect();
            let found: Vec<&String> = map.keys().collect();
            if expected != found {
                return Err(format!("{path}: keys {found:?}, schema has {expected:?}"));
            }
            for required in schema["required"].as_array().into_iter().flatten() {
                assert!(properties.contains_key(required.as_str().unwrap()));
            }
            for (key, item) in map {
                conforms(item, &properties[key], &format!("{path}.{key}"))?;
            }
            Ok(())
        }
        Some("array") => {
            let Some(items) = value.as_array() else {
                return fail("not an array");
            };
            for (i, item) in items.iter().enumerate() {
                conforms(item, &schema["items"], &format!("{path}[{i}]"))?;
            }
            Ok(())
        }
        Some("number") if value.is_number() => Ok(()),
        Some("integer") => {
            let Some(v) = value.as_i64() else {
                return fail("not an integer");
            };
            let min = schema.get("minimum").and_then(Value::as_i64);
            let max = schema.get("maximum").and_then(Value::as_i64);
            if min.is_some_and(|m| v < m) || max.is_some_and(|m| v > m) {
                return fail("out of bounds");
            }
            Ok(())
        }
        Some("string") => match (value.as_str(), schema.get("contentEncoding")) {
            (Some(text), Some(_)) if base64::decode(text).is_none() => fail("not base64"),
            (Some(_), _) => Ok(()),
            (None, _) => fail("not a string"),
        },
        Some("boolean") if value.is_boolean() => Ok(()),
        other => fail(&format!("not of type {other:?}")),
    }
}

fn assert_conforms(schema: Schema, message: &Value) {
    if let Err(e) = conforms(message, &schema.json_schema(), schema.name()) {
        panic!("{e}");
    }
}

fn data_bytes(message: &Value) -> Vec<u8> {
    base64::decode(message["data"].as_str().unwrap()).unwrap()
}

fn f32_at(bytes: &[u8], offset: usize) -> f32 {
    f32::from_le_bytes(bytes[offset..offset + 4].try_into().unwrap())
}

fn field_names(message: &Value) -> Vec<(String, u64, u64)> {
    message["fields"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["name"].as_str().unwrap().to_owned(),
                f["offset"].as_u64().unwrap(),
                f["type"].as_u64().unwrap(),
            )
        })
        .collect()
}

fn cloud() -> PointCloud {
    let mut cloud = PointCloud::from_points(vec![
        Point3::new(1.0, 2.0, 3.0),
        Point3::new(f32::NAN, f32::NAN, f32::NAN),
        Point3::new(-4.0, 5.5, 0.25),
    ]);
    cloud.intensity = Some(vec![10.0, 20.0, 30.0]);
    cloud.label = Some(vec![7, 8, 9]);
    cloud
}

fn pole() -> Entity {
    let mut entity = Entity::new("pole 3");
    entity.cylinders.push(Cylinder {
        base: Point3::new(1.0, 2.0, 0.5),
        diameter_m: 0.3,
        height_m: 4.0,
        color: [1.0, 0.5, 0.0, 1.0],
    });
    entity.lines.push(Line {
        kind: LineKind::Loop,
        points: vec![
            Point3::origin(),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ],
        thickness_m: 0.05,
        color: [0.0, 0.0, 1.0, 1.0],
    });
    entity.triangles.push(Triangles {
        points: vec![
            Point3::origin(),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ],
        color: [0.0, 1.0, 0.0, 0.5],
    });
    entity.cubes.push(Cube {
        center: Point3::new(0.1, 0.1, 0.1),
        size_m: [0.2, 0.2, 0.2],
        color: [0.5, 0.5, 0.5, 1.0],
    });
    entity.metadata.push(("radius_m".into(), "0.15".into()));
    entity
}

fn scan() -> Scan2 {
    Scan2 {
        angle_min_rad: -FRAC_PI_2,
        angle_increment_rad: FRAC_PI_2,
        max_range_m: 10.0,
        ranges: vec![1.0, f64::INFINITY, 12.0],
        intensities: Some(vec![0.5, f64::NAN, 2.0]),
    }
}

/// One message of every kind, with every option used.
fn every_message() -> Vec<(Schema, Value)> {
    let cells = [0.0f32, 0.5, f32::NAN, 1.0, 0.25, 0.75];
    let layer = GridLayer {
        frame_id: "map",
        origin: Pose2::new(-1.0, -2.0, 0.0).to_pose3(),
        cell_size_m: 0.5,
        columns: 3,
        rows: 2,
        field: "probability",
        values: GridValues::F32(&cells),
    };
    let colors = [[1.0, 0.0, 0.0, 1.0]; 3];
    let pose = Pose3::from_xyz_rpy(1.0, 2.0, 3.0, 0.1, 0.2, 0.3);
    vec![
        (Schema::Grid, messages::grid_message(T, &layer).unwrap()),
        (
            Schema::PointCloud,
            messages::point_cloud_message(T, "map", &cloud(), Some(&colors)).unwrap(),
        ),
        (
            Schema::PosesInFrame,
            messages::poses_message(T, "map", &[pose, pose]),
        ),
        (
            Schema::FrameTransform,
            messages::transform_message(T, "map", "base_link", &pose),
        ),
        (
            Schema::SceneUpdate,
            scene::scene_message(T, "map", &[pole(), Entity::new("e")]).unwrap(),
        ),
        (
            Schema::LaserScan,
            messages::laser_scan_message(T, "base_link", &scan(), &pose).unwrap(),
        ),
    ]
}

#[test]
fn every_message_has_exactly_the_fields_of_its_schema() {
    let messages = every_message();
    let kinds: Vec<Schema> = messages.iter().map(|(s, _)| *s).collect();
    assert_eq!(kinds, Schema::ALL);
    for (schema, message) in &messages {
        assert_conforms(*schema, message);
        assert_eq!(first_null(message), None, "{}", schema.name());
    }
}

#[test]
fn the_checker_rejects_missing_extra_and_mistyped_fields() {
    let (schema, message) = every_message().swap_remove(3);
    let mut missing = message.clone();
    missing.as_object_mut().unwrap().remove("rotation");
    let mut extra = message.clone();
    extra["stamp"] = Value::from(1);
    let mut mistyped = message.clone();
    mistyped["timestamp"]["nsec"] = Value::from(1.5);
    for bad in [missing, extra, mistyped] {
        assert!(conforms(&bad, &schema.json_schema(), "").is_err(), "{bad}");
    }
}

#[test]
fn schemas_are_named_and_mark_bytes_as_base64() {
    for schema in Schema::ALL {
        let json = schema.json_schema();
        assert_eq!(json["title"], schema.name());
        assert!(schema.name().starts_with("foxglove."));
        let text = schema.text();
        let reparsed: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(reparsed, json);
    }
    for schema in [Schema::Grid, Schema::PointCloud] {
        assert_eq!(
            schema.json_schema()["properties"]["data"]["contentEncoding"],
            "base64"
        );
    }
}

#[test]
fn stamps_split_seconds_and_round_to_the_nanosecond() {
    let cases = [
        (0.0, 0, 0),
        (12.5, 12, 500_000_000),
        (1_300_000_000.25, 1_300_000_000, 250_000_000),
        (3.999_999_999_9, 4, 0),
    ];
    for (secs, sec, nsec) in cases {
        let stamp = Stamp::from_secs(secs).unwrap();
        assert_eq!((stamp.sec, stamp.nsec), (sec, nsec), "{secs}");
        assert_eq!(stamp.nanos(), sec * 1_000_000_000 + u64::from(nsec));
    }
    for bad in [-0.5, f64::NAN, f64::INFINITY, 1e20] {
        assert!(Stamp::from_secs(bad).is_err(), "{bad}");
    }
}

#[test]
fn grid_of_bytes_is_laid_out_row_by_row() {
    let grid = Grid2::new(nalgebra::Point2::new(-3.0, 4.0), 0.25, [3, 2]).unwrap();
    let cells = [0u8, 1, 2, 10, 11, 12];
    let layer = GridLayer::from_grid2(&grid, "map", "occupancy", GridValues::U8(&cells));
    let message = messages::grid_message(T, &layer).unwrap();
    assert_conforms(Schema::Grid, &message);
    assert_eq!(
        message["timestamp"],
        serde_json::json!({ "sec": 12, "nsec": 500_000_000 })
    );
    assert_eq!(message["column_count"], 3);
    assert_eq!(message["cell_stride"], 1);
    assert_eq!(message["row_stride"], 3);
    assert_eq!(message["cell_size"]["x"], 0.25);
    assert_eq!(
        message["pose"]["position"],
        serde_json::json!({ "x": -3.0, "y": 4.0, "z": 0.0 })
    );
    assert_eq!(message["pose"]["orientation"]["w"], 1.0);
    assert_eq!(field_names(&message), [("occupancy".to_owned(), 0, 1)]);
    assert_eq!(message["data"], "AAECCgsM");
    assert_eq!(data_bytes(&message), cells);
}

#[test]
fn grid_of_floats_keeps_nan_cells_and_checks_its_size() {
    let (_, message) = every_message().swap_remove(0);
    let data = data_bytes(&message);
    assert_eq!(message["row_stride"], 12);
    assert_eq!(message["cell_stride"], 4);
    assert_eq!(field_names(&message), [("probability".to_owned(), 0, 7)]);
    assert_eq!(data.len(), 6 * 4);
    assert_eq!(f32_at(&data, 4), 0.5);
    assert!(f32_at(&data, 8).is_nan());
    assert_eq!(f32_at(&data, 20), 0.75);

    let cells = [1u8; 5];
    let mut layer = GridLayer {
        frame_id: "map",
        origin: Pose3::identity(),
        cell_size_m: 1.0,
        columns: 3,
        rows: 2,
        field: "f",
        values: GridValues::U8(&cells),
    };
    let err = messages::grid_message(T, &layer).unwrap_err();
    assert!(err.contains("5 values for a grid of 3 × 2"), "{err}");
    layer.rows = 1;
    layer.columns = 5;
    layer.cell_size_m = 0.0;
    assert!(
        messages::grid_message(T, &layer)
            .unwrap_err()
            .contains("cell size")
    );
}

#[test]
fn point_cloud_packs_valid_points_with_their_attributes() {
    let colors = [[1.0, 0.5, 0.0, 1.0], [0.0; 4], [0.2, 2.0, f32::NAN, 0.0]];
    let message = messages::point_cloud_message(T, "map", &cloud(), Some(&colors)).unwrap();
    assert_conforms(Schema::PointCloud, &message);
    let fields = field_names(&message);
    let names: Vec<&str> = fields.iter().map(|(n, _, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "x",
            "y",
            "z",
            "intensity",
            "label",
            "red",
            "green",
            "blue",
            "alpha"
        ]
    );
    assert_eq!(fields[4], ("label".to_owned(), 16, 5));
    assert_eq!(fields[8], ("alpha".to_owned(), 23, 1));
    assert_eq!(message["point_stride"], 24);
    let data = data_bytes(&message);
    assert_eq!(data.len(), 2 * 24, "the NaN point is left out");
    assert_eq!(
        [f32_at(&data, 0), f32_at(&data, 4), f32_at(&data, 8)],
        [1.0, 2.0, 3.0]
    );
    assert_eq!(f32_at(&data, 12), 10.0);
    assert_eq!(&data[16..20], &7u32.to_le_bytes());
    assert_eq!(&data[20..24], &[255, 128, 0, 255]);
    let second = &data[24..];
    assert_eq!(
        [f32_at(second, 0), f32_at(second, 4), f32_at(second, 8)],
        [-4.0, 5.5, 0.25]
    );
    assert_eq!(f32_at(second, 12), 30.0);
    assert_eq!(&second[16..20], &9u32.to_le_bytes());
    assert_eq!(&second[20..24], &[51, 255, 0, 0], "clamped, NaN as 0");
}

#[test]
fn point_cloud_takes_packed_rgb_and_checks_lengths() {
    let mut plain = PointCloud::from_points(vec![Point3::new(0.5, 0.0, 0.0)]);
    let message = messages::point_cloud_message(T, "velodyne", &plain, None).unwrap();
    assert_eq!(message["point_stride"], 12);
    assert_eq!(message["frame_id"], "velodyne");
    assert_eq!(data_bytes(&message).len(), 12);
    plain.rgb = Some(vec![0x00A1_B2C3]);
    let message = messages::point_cloud_message(T, "map", &plain, None).unwrap();
    assert_eq!(message["point_stride"], 16);
    assert_eq!(&data_bytes(&message)[12..], &[0xA1, 0xB2, 0xC3, 255]);
    let err = messages::point_cloud_message(T, "map", &plain, Some(&[[0.0; 4]; 2])).unwrap_err();
    assert_eq!(err, "2 colors values for 1 points");
}

#[test]
fn poses_and_transforms_carry_translation_and_quaternion() {
    let robot = Pose2::new(1.0, -2.0, FRAC_PI_2).to_pose3();
    let message = messages::transform_message(T, "map", "base_link", &robot);
    assert_conforms(Schema::FrameTransform, &message);
    assert_eq!(message["parent_frame_id"], "map");
    assert_eq!(message["child_frame_id"], "base_link");
    assert_eq!(
        message["translation"],
        serde_json::json!({ "x": 1.0, "y": -2.0, "z": 0.0 })
    );
    let q = &message["rotation"];
    let half = std::f64::consts::FRAC_1_SQRT_2;
    for (key, want) in [("x", 0.0), ("y", 0.0), ("z", half), ("w", half)] {
        assert!(
            (q[key].as_f64().unwrap() - want).abs() < 1e-12,
            "{key}: {q}"
        );
    }
    let message = messages::poses_message(T, "map", &[Pose3::identity(), robot]);
    assert_eq!(message["poses"].as_array().unwrap().len(), 2);
    assert_eq!(message["poses"][1]["position"]["y"], -2.0);
    assert_eq!(message["poses"][1]["orientation"], *q);
}

#[test]
fn laser_scan_writes_no_returns_as_zero() {
    let message = messages::laser_scan_message(T, "laser", &scan(), &Pose3::identity()).unwrap();
    assert_conforms(Schema::LaserScan, &message);
    assert_eq!(message["start_angle"], -FRAC_PI_2);
    assert_eq!(message["end_angle"], FRAC_PI_2);
    assert_eq!(message["ranges"], serde_json::json!([1.0, 0.0, 0.0]));
    assert_eq!(message["intensities"], serde_json::json!([0.5, 0.0, 2.0]));
    let mut bad = scan();
    bad.intensities = Some(vec![1.0]);
    assert!(messages::laser_scan_message(T, "laser", &bad, &Pose3::identity()).is_err());
    bad.intensities = None;
    let message = messages::laser_scan_message(T, "laser", &bad, &Pose3::identity()).unwrap();
    assert_eq!(message["intensities"], serde_json::json!([]));
}

#[test]
fn scene_entities_place_their_primitives() {
    let message = scene::scene_message(T, "map", &[pole()]).unwrap();
    assert_conforms(Schema::SceneUpdate, &message);
    let entity = &message["entities"][0];
    assert_eq!(entity["id"], "pole 3");
    assert_eq!(entity["frame_id"], "map");
    assert_eq!(
        entity["lifetime"],
        serde_json::json!({ "sec": 0, "nsec": 0 })
    );
    let cylinder = &entity["cylinders"][0];
    assert_eq!(
        cylinder["pose"]["position"],
        serde_json::json!({ "x": 1.0, "y": 2.0, "z": 2.5 })
    );
    assert_eq!(
        cylinder["size"],
        serde_json::json!({ "x": 0.3, "y": 0.3, "z": 4.0 })
    );
    assert_eq!(cylinder["color"]["g"], 0.5);
    assert_eq!(entity["lines"][0]["type"], 1);
    assert_eq!(entity["lines"][0]["points"].as_array().unwrap().len(), 3);
    assert_eq!(entity["triangles"][0]["color"]["a"], 0.5);
    assert_eq!(entity["cubes"][0]["size"]["z"], 0.2);
    assert_eq!(
        entity["metadata"][0],
        serde_json::json!({ "key": "radius_m", "value": "0.15" })
    );
    let mut bad = pole();
    bad.triangles[0].points.pop();
    let err = scene::scene_message(T, "map", &[bad]).unwrap_err();
    assert!(err.contains("\"pole 3\": 2 triangle points"), "{err}");
}

#[test]
fn first_null_names_the_non_finite_field() {
    let mut bad = pole();
    bad.cylinders[0].height_m = f64::NAN;
    let message = scene::scene_message(T, "map", &[pole(), bad]).unwrap();
    let place = first_null(&message).unwrap();
    assert!(place.starts_with(".entities[1].cylinders[0]."), "{place}");
}

/// Reads a recording with the `mcap` crate: (topic, schema name, schema encoding, message
/// encoding, log time, message).
fn read_back(path: &std::path::Path) -> Vec<(String, String, String, String, u64, Value)> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let schema = m.channel.schema.clone().unwrap();
            let value: Value = serde_json::from_slice(&m.data).unwrap();
            (
                m.channel.topic.clone(),
                schema.name.clone(),
                schema.encoding.clone(),
                m.channel.message_encoding.clone(),
                m.log_time,
                value,
            )
        })
        .collect()
}

#[test]
fn recorder_writes_channels_that_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let mut recorder = Recorder::create(&path).unwrap();
    let robot = Pose2::new(1.0, 2.0, 0.5);
    for i in 0..3 {
        let t = 100.0 + f64::from(i) * 0.1;
        recorder
            .transform(t, "map", "base_link", &robot.to_pose3())
            .unwrap();
        recorder
            .laser_scan(topic::SCAN, t, "base_link", &scan(), &Pose3::identity())
            .unwrap();
    }
    recorder
        .planar_poses(topic::TRAJECTORY, 100.2, "map", &[robot, robot])
        .unwrap();
    recorder
        .point_cloud(topic::POINTS, 100.2, "map", &cloud(), None)
        .unwrap();
    recorder
        .scene(topic::POLES, 100.2, "map", &[pole()])
        .unwrap();
    let cells = [5u8; 4];
    let layer = GridLayer {
        frame_id: "map",
        origin: Pose3::identity(),
        cell_size_m: 0.1,
        columns: 2,
        rows: 2,
        field: "occupancy",
        values: GridValues::U8(&cells),
    };
    recorder.grid(topic::MAP, 100.2, &layer).unwrap();
    let counts = recorder.finish().unwrap();
    let want: BTreeMap<String, u64> = [
        ("/map", 1),
        ("/points", 1),
        ("/poles", 1),
        ("/scan", 3),
        ("/tf", 3),
        ("/trajectory", 1),
    ]
    .into_iter()
    .map(|(t, n)| (t.to_owned(), n))
    .collect();
    assert_eq!(counts, want);

    let messages = read_back(&path);
    assert_eq!(messages.len(), 10);
    for (topic, schema_name, schema_encoding, encoding, log_time, value) in &messages {
        let schema = Schema::ALL
            .into_iter()
            .find(|s| s.name() == schema_name)
            .unwrap();
        assert_eq!(schema_encoding, "jsonschema");
        assert_eq!(encoding, "json");
        assert_conforms(schema, value);
        let stamp = &value
            .get("timestamp")
            .unwrap_or(&value["entities"][0]["timestamp"]);
        let nanos =
            stamp["sec"].as_u64().unwrap() * 1_000_000_000 + stamp["nsec"].as_u64().unwrap();
        assert_eq!(*log_time, nanos, "{topic}");
    }
    let scan_times: Vec<u64> = messages
        .iter()
        .filter(|m| m.0 == "/scan")
        .map(|m| m.4)
        .collect();
    assert_eq!(
        scan_times,
        [100_000_000_000, 100_100_000_000, 100_200_000_000]
    );
}

#[test]
fn recorder_errors_name_the_file_topic_and_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mcap");
    let mut recorder = Recorder::create(&path).unwrap();
    recorder
        .poses("/trajectory", 1.0, "map", &[Pose3::identity()])
        .unwrap();
    let err = recorder
        .transform(1.0, "map", "base_link", &Pose3::identity())
        .and_then(|()| recorder.point_cloud("/trajectory", 2.0, "map", &cloud(), None))
        .unwrap_err()
        .to_string();
    assert!(err.starts_with(&path.display().to_string()), "{err}");
    assert!(
        err.contains("topic /trajectory at 2 s: the topic carries foxglove.PosesInFrame"),
        "{err}"
    );
    let nan_pose = Pose2::new(f64::NAN, 0.0, 0.0).to_pose3();
    let err = recorder
        .poses("/trajectory", 3.0, "map", &[nan_pose])
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("field poses[0].position.x is not finite"),
        "{err}"
    );
    let err = recorder
        .transform(-1.0, "a", "b", &Pose3::identity())
        .unwrap_err()
        .to_string();
    assert!(err.contains("topic /tf at -1 s"), "{err}");
    // The failed messages were not written; the good ones were.
    let counts = recorder.finish().unwrap();
    assert_eq!(counts.values().sum::<u64>(), 2);
    assert_eq!(read_back(&path).len(), 2);

    let missing = dir.path().join("no such dir").join("x.mcap");
    let err = Recorder::create(&missing).unwrap_err();
    assert_eq!(err.path(), missing);
}
