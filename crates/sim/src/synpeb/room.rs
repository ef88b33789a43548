//! A SynPEB-style room: walls, floor and ceiling, objects placed on the floor (free-standing or
//! against a wall, without overlaps), small objects on tables and boxes, and sensor poses in
//! the free space.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{Point2, Point3, Rotation2, Vector2, Vector3};
use rand::Rng;
use raypath_geometry::Pose3;

use super::SynpebConfig;
use super::objects::{Kind, Labeler, Shape, kind_mix};
use crate::error::{Result, SimError};
use crate::rng::{self, SimRng};
use crate::scene3::Scene3;

/// Random-stream domain of room layouts (index: room).
const DOMAIN_ROOM: u64 = 0x5359_4e50_4542_0001;
/// Random-stream domain of sensor poses (index: scan).
const DOMAIN_POSE: u64 = 0x5359_4e50_4542_0002;

/// Gap between objects, metres.
const OBJECT_GAP_M: f64 = 0.05;
/// Free space kept around a sensor station (half side of a square), metres.
const SENSOR_CLEARANCE_M: f64 = 0.5;
/// Largest offset of a sensor from its station, metres.
const SENSOR_JITTER_M: f64 = 0.2;
/// Smallest distance between two sensor stations, metres.
const STATION_SPACING_M: f64 = 1.0;
/// Distance of the sensor from the walls, metres.
const SENSOR_WALL_MARGIN_M: f64 = 0.8;
/// The point the sensor looks at is at least this far away, metres.
const MIN_VIEW_DISTANCE_M: f64 = 2.5;
/// Placement attempts per object.
const ATTEMPTS: usize = 40;

/// An oriented rectangle on the floor.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Footprint {
    pub(crate) center: Point2<f64>,
    pub(crate) yaw: f64,
    pub(crate) half: Vector2<f64>,
}

impl Footprint {
    fn axes(&self) -> [Vector2<f64>; 2] {
        let r = Rotation2::new(self.yaw);
        [r * Vector2::x(), r * Vector2::y()]
    }

    /// Half width of the rectangle projected on the unit `axis`.
    pub(crate) fn radius_along(&self, axis: &Vector2<f64>) -> f64 {
        let [u, v] = self.axes();
        self.half.x * u.dot(axis).abs() + self.half.y * v.dot(axis).abs()
    }

    /// Separating-axis test with a gap of `margin`.
    pub(crate) fn overlaps(&self, other: &Footprint, margin: f64) -> bool {
        let d = other.center - self.center;
        self.axes().iter().chain(other.axes().iter()).all(|axis| {
            d.dot(axis).abs() < self.radius_along(axis) + other.radius_along(axis) + margin
        })
    }
}

/// A top that small objects can stand on.
struct Support {
    footprint: Footprint,
    top_z: f64,
}

/// One room of the data set.
pub struct SynpebRoom {
    /// The geometry; floor at z = 0, walls at x ∈ {0, length}, y ∈ {0, width}, ceiling at
    /// z = height (world frame).
    pub scene: Scene3,
    /// Interior size (length along x, width along y, height), metres.
    pub size_m: Vector3<f64>,
    /// Objects in the room (standing and stacked).
    pub objects: usize,
    /// Plane labels in the room (visible or not): walls, floor, ceiling and object faces.
    pub planar_faces: usize,
    /// Sensor stations (x, y): free spots kept clear of objects, metres.
    pub stations: Vec<Point2<f64>>,
    footprints: Vec<Footprint>,
}

/// Builds room `room_index` of the data set `seed`.
pub fn build_room(config: &SynpebConfig, seed: u64, room_index: u64) -> Result<SynpebRoom> {
    config.validate()?;
    let mut rng = rng::stream(seed, DOMAIN_ROOM, room_index);
    let mut size = Vector3::zeros();
    for i in 0..3 {
        let (nominal, jitter) = (config.room_size_m[i], config.room_size_jitter_m[i]);
        size[i] = nominal + jitter * rng.random_range(-1.0..=1.0);
    }
    let mut labels = Labeler::new();
    add_shell(&mut labels, &size);

    let stations = choose_stations(config.sensor_stations, &size, &mut rng)?;
    // The stations' clear squares take part in the overlap tests like objects.
    let mut footprints: Vec<Footprint> = stations
        .iter()
        .map(|&center| Footprint {
            center,
            yaw: 0.0,
            half: Vector2::repeat(SENSOR_CLEARANCE_M),
        })
        .collect();
    let mut supports = Vec::new();
    let mut objects = 0;
    for kind in kind_mix(config.objects_per_room, &mut rng) {
        let shape = Shape::random(kind, &mut rng, false);
        let Some(footprint) = place(&shape, &size, &footprints, &mut rng) else {
            continue;
        };
        let pose = floor_pose(&footprint, 0.0);
        shape.add_to(&mut labels, &pose)?;
        if let Some(half) = shape.support_top() {
            supports.push(Support {
                footprint: Footprint { half, ..footprint },
                top_z: shape.height(),
            });
        }
        footprints.push(footprint);
        objects += 1;
    }
    for support in &supports {
        if !rng.random_bool(config.stack_probability) {
            continue;
        }
        let kinds = [
            Kind::Cuboid,
            Kind::Wedge,
            Kind::Prism,
            Kind::Sphere,
            Kind::TumbledCuboid,
        ];
        let kind = kinds[rng.random_range(0..kinds.len())];
        let shape = Shape::random(kind, &mut rng, true);
        let half = shape.half_footprint();
        let room = support.footprint.half - half;
        if room.x <= 0.0 || room.y <= 0.0 {
            continue;
        }
        let offset = Vector2::new(
            rng.random_range(-room.x..=room.x),
            rng.random_range(-room.y..=room.y),
        );
        let turn = Rotation2::new(support.footprint.yaw) * offset;
        let footprint = Footprint {
            center: support.footprint.center + turn,
            yaw: support.footprint.yaw,
            half,
        };
        shape.add_to(&mut labels, &floor_pose(&footprint, support.top_z))?;
        objects += 1;
    }
    let planar_faces = labels.planes_created();
    Ok(SynpebRoom {
        scene: labels.builder.build()?,
        size_m: size,
        objects,
        planar_faces,
        stations,
        footprints,
    })
}

/// `n` sensor stations at least 0.8 m from the walls and 1 m apart.
fn choose_stations(n: usize, size: &Vector3<f64>, rng: &mut SimRng) -> Result<Vec<Point2<f64>>> {
    let m = SENSOR_WALL_MARGIN_M;
    let mut stations: Vec<Point2<f64>> = Vec::with_capacity(n);
    for _ in 0..n.saturating_mul(1000) {
        if stations.len() == n {
            break;
        }
        let p = Point2::new(
            rng.random_range(m..size.x - m),
            rng.random_range(m..size.y - m),
        );
        if stations.iter().all(|s| (s - p).norm() >= STATION_SPACING_M) {
            stations.push(p);
        }
    }
    if stations.len() < n {
        return Err(SimError::InvalidScene {
            reason: format!(
                "{n} sensor stations 1 m apart do not fit a room of {:.1} × {:.1} m",
                size.x, size.y
            ),
        });
    }
    Ok(stations)
}

/// Floor, ceiling and the four walls, each its own plane.
fn add_shell(labels: &mut Labeler, size: &Vector3<f64>) {
    let (l, w, h) = (size.x, size.y, size.z);
    let p = Point3::new;
    let quads = [
        [
            p(0.0, 0.0, 0.0),
            p(l, 0.0, 0.0),
            p(l, w, 0.0),
            p(0.0, w, 0.0),
        ],
        [p(0.0, 0.0, h), p(0.0, w, h), p(l, w, h), p(l, 0.0, h)],
        [
            p(0.0, 0.0, 0.0),
            p(0.0, w, 0.0),
            p(0.0, w, h),
            p(0.0, 0.0, h),
        ],
        [p(l, 0.0, 0.0), p(l, 0.0, h), p(l, w, h), p(l, w, 0.0)],
        [
            p(0.0, 0.0, 0.0),
            p(0.0, 0.0, h),
            p(l, 0.0, h),
            p(l, 0.0, 0.0),
        ],
        [p(0.0, w, 0.0), p(l, w, 0.0), p(l, w, h), p(0.0, w, h)],
    ];
    for quad in quads {
        let surface = labels.plane();
        labels.builder.add_polygon(&quad, surface);
    }
}

pub(crate) fn floor_pose(footprint: &Footprint, z: f64) -> Pose3 {
    Pose3::from_xyz_rpy(
        footprint.center.x,
        footprint.center.y,
        z,
        0.0,
        0.0,
        footprint.yaw,
    )
}

/// A free footprint for `shape`: against a wall (its +x towards the wall) or anywhere.
fn place(
    shape: &Shape,
    size: &Vector3<f64>,
    taken: &[Footprint],
    rng: &mut SimRng,
) -> Option<Footprint> {
    if shape.height() > size.z - 0.1 {
        return None;
    }
    let half = shape.half_footprint();
    let wall_probability = shape.wall_probability();
    for _ in 0..ATTEMPTS {
        let candidate = if rng.random_bool(wall_probability) {
            // Walls by outward direction: −x, +x, −y, +y.
            let wall = rng.random_range(0..4);
            let (yaw, along_len) = match wall {
                0 => (PI, size.y),
                1 => (0.0, size.y),
                2 => (-FRAC_PI_2, size.x),
                _ => (FRAC_PI_2, size.x),
            };
            let margin = half.y + OBJECT_GAP_M;
            if along_len <= 2.0 * margin {
                continue;
            }
            let along = rng.random_range(margin..along_len - margin);
            let depth = half.x + 0.01;
            let center = match wall {
                0 => Point2::new(depth, along),
                1 => Point2::new(size.x - depth, along),
                2 => Point2::new(along, depth),
                _ => Point2::new(along, size.y - depth),
            };
            Footprint { center, yaw, half }
        } else {
            let yaw = rng.random_range(-PI..PI);
            let probe = Footprint {
                center: Point2::origin(),
                yaw,
                half,
            };
            let rx = probe.radius_along(&Vector2::x()) + OBJECT_GAP_M;
            let ry = probe.radius_along(&Vector2::y()) + OBJECT_GAP_M;
            if size.x <= 2.0 * rx || size.y <= 2.0 * ry {
                continue;
            }
            let center = Point2::new(
                rng.random_range(rx..size.x - rx),
                rng.random_range(ry..size.y - ry),
            );
            Footprint { center, ..probe }
        };
        if taken.iter().all(|t| !t.overlaps(&candidate, OBJECT_GAP_M)) {
            return Some(candidate);
        }
    }
    None
}

impl SynpebRoom {
    /// The sensor pose of scan `scan_index`: a random station, moved by up to 0.2 m, at a
    /// height within `config.sensor_height_m`, heading towards a random object at least
    /// 2.5 m away (a random point of the room when there is none), with a random pitch and
    /// roll up to the configured limits.
    pub fn sensor_pose(&self, config: &SynpebConfig, seed: u64, scan_index: u64) -> Result<Pose3> {
        let mut rng = rng::stream(seed, DOMAIN_POSE, scan_index);
        let s = &self.size_m;
        if self.stations.is_empty() {
            return Err(SimError::InvalidScene {
                reason: "the room has no sensor stations".into(),
            });
        }
        let station = self.stations[rng.random_range(0..self.stations.len())];
        let jitter = SENSOR_JITTER_M;
        let p = station
            + Vector2::new(
                rng.random_range(-jitter..=jitter),
                rng.random_range(-jitter..=jitter),
            );
        // Look at an object at least 2.5 m away, else at a far point of the room.
        let objects = self.footprints.get(self.stations.len()..).unwrap_or(&[]);
        let far: Vec<&Footprint> = objects
            .iter()
            .filter(|f| (f.center - p).norm() >= MIN_VIEW_DISTANCE_M)
            .collect();
        let target = if far.is_empty() {
            let corners = [
                Point2::new(0.0, 0.0),
                Point2::new(s.x, 0.0),
                Point2::new(0.0, s.y),
                Point2::new(s.x, s.y),
            ];
            corners
                .iter()
                .copied()
                .max_by(|a, b| (a - p).norm().total_cmp(&(b - p).norm()))
                .unwrap_or(Point2::new(s.x / 2.0, s.y / 2.0))
        } else {
            far[rng.random_range(0..far.len())].center
        };
        let view = target - p;
        let [z_lo, z_hi] = config.sensor_height_m;
        let z = rng.random_range(z_lo..=z_hi);
        let pitch = config.sensor_pitch_max_deg.to_radians() * rng.random_range(-1.0..=1.0);
        let roll = config.sensor_roll_max_deg.to_radians() * rng.random_range(-1.0..=1.0);
        let yaw = view.y.atan2(view.x);
        Ok(Pose3::from_xyz_rpy(p.x, p.y, z, roll, pitch, yaw))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn footprints_overlap_like_rectangles() {
        let a = Footprint {
            center: Point2::new(0.0, 0.0),
            yaw: 0.0,
            half: Vector2::new(1.0, 0.5),
        };
        let mut b = Footprint {
            center: Point2::new(2.2, 0.0),
            yaw: 0.0,
            half: Vector2::new(1.0, 0.5),
        };
        assert!(!a.overlaps(&b, 0.1));
        assert!(a.overlaps(&b, 0.3));
        // Rotated by 45°, the corner reaches 0.5·√2 + 1·√2/2·… further along x.
        b.yaw = PI / 4.0;
        b.center.x = 2.0;
        assert!(a.overlaps(&b, 0.0));
        b.center.x = 2.1;
        b.center.y = 1.6;
        assert!(!a.overlaps(&b, 0.0));
    }
}
