//! Street scenery around a given trajectory and pole map (for semi-synthetic worlds built
//! around real drives): a ground height field that follows the road, curbs and sidewalks,
//! building facades and parked cars on both sides, and poles at the given positions.
//!
//! The trajectory is the vehicle's (the right-hand lane); the road extends
//! [`Scenery::left_road_edge_m`] to its left and [`Scenery::right_road_edge_m`] to its right,
//! narrowed where a pole stands closer. Sidewalks run from the road edge to the facades, which
//! stand behind the poles of the sidewalk band. Nothing is placed where any pass of the
//! trajectory drives (buildings keep 4 m, cars 2.4 m, sidewalks 1 m from every trajectory
//! sample), so crossings and revisits stay open.

use nalgebra::{Point2, Vector2};
use rand::Rng;

use super::kinds::{Canopy, Pole, PoleKind};
use super::streets::sample;
use super::world::{Building, Car, Footprint, Ground, PoleObject, Slab, SlabKind, World};
use crate::rng::{self, SimRng};

const DOMAIN_BUILDINGS: u64 = 0x5552_4250_4255_494c;
const DOMAIN_CARS: u64 = 0x5552_4250_4341_5253;
const DOMAIN_POLES: u64 = 0x5552_4250_504f_4c45;

/// Parameters of the scenery. Ranges `(a, b)` are sampled uniformly.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Scenery {
    /// Road edge to the left of the trajectory, metres (the oncoming lane and parking).
    pub left_road_edge_m: f64,
    /// Road edge to the right of the trajectory, metres (parking lane).
    pub right_road_edge_m: f64,
    /// Sidewalk width, metres.
    pub sidewalk_width_m: (f64, f64),
    /// Set-back of a facade behind the sidewalk, metres.
    pub setback_m: (f64, f64),
    /// Building length along the road, metres.
    pub building_length_m: (f64, f64),
    /// Building height, metres.
    pub building_height_m: (f64, f64),
    /// Probability of a gap (2–12 m) after a building.
    pub gap_probability: f64,
    /// Probability that a parking place (every 6 m) holds a car.
    pub parked_car_probability: f64,
    /// Relative frequencies of street lights, sign posts, tree trunks and bollards among the
    /// given poles.
    pub pole_kind_weights: [f64; 4],
    /// Edge of the ground height-field cells, metres.
    pub ground_cell_m: f64,
    /// Ground is built within this distance of the trajectory, metres.
    pub ground_margin_m: f64,
    /// Sensor height above the road, metres (the ground is this far below the trajectory).
    pub sensor_height_m: f64,
}

impl Default for Scenery {
    fn default() -> Self {
        Self {
            left_road_edge_m: 6.0,
            right_road_edge_m: 3.0,
            sidewalk_width_m: (2.0, 4.0),
            setback_m: (0.0, 4.0),
            building_length_m: (10.0, 30.0),
            building_height_m: (6.0, 20.0),
            gap_probability: 0.35,
            parked_car_probability: 0.45,
            // Most poles in the KITTI maps are sign and light posts; a third are trunks.
            pole_kind_weights: [0.35, 0.35, 0.3, 0.0],
            ground_cell_m: 2.0,
            ground_margin_m: 60.0,
            sensor_height_m: super::kitti_out::KITTI_VELODYNE_HEIGHT_M,
        }
    }
}

/// A sample of the trajectory: position, heading and the height of the road below.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSample {
    /// Position, metres.
    pub position: Point2<f64>,
    /// Heading, radians.
    pub heading_rad: f64,
    /// Height of the road, metres.
    pub ground_z: f64,
}

/// Points in a uniform grid for radius queries (deterministic).
struct GridIndex {
    origin: Point2<f64>,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl GridIndex {
    fn new(points: &[Point2<f64>], cell: f64) -> Self {
        let (mut lo, mut hi) = (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        );
        for p in points {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if points.is_empty() {
            lo = Point2::origin();
            hi = Point2::origin();
        }
        let nx = ((hi.x - lo.x) / cell).floor() as usize + 1;
        let ny = ((hi.y - lo.y) / cell).floor() as usize + 1;
        let mut index = Self {
            origin: lo,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        for (i, p) in points.iter().enumerate() {
            let (cx, cy) = index.cell_of(p);
            index.cells[cy * nx + cx].push(i as u32);
        }
        index
    }

    fn cell_of(&self, p: &Point2<f64>) -> (usize, usize) {
        let cx = ((p.x - self.origin.x) / self.cell)
            .floor()
            .clamp(0.0, (self.nx - 1) as f64);
        let cy = ((p.y - self.origin.y) / self.cell)
            .floor()
            .clamp(0.0, (self.ny - 1) as f64);
        (cx as usize, cy as usize)
    }

    /// Indices of the points in the cells overlapping the square of half side `r` at `p`.
    fn near(&self, p: &Point2<f64>, r: f64, out: &mut Vec<u32>) {
        out.clear();
        let lo = self.cell_of(&(p - Vector2::new(r, r)));
        let hi = self.cell_of(&(p + Vector2::new(r, r)));
        let outside = p.x + r < self.origin.x
            || p.y + r < self.origin.y
            || p.x - r > self.origin.x + self.cell * self.nx as f64
            || p.y - r > self.origin.y + self.cell * self.ny as f64;
        if outside {
            return;
        }
        for cy in lo.1..=hi.1 {
            for cx in lo.0..=hi.0 {
                out.extend_from_slice(&self.cells[cy * self.nx + cx]);
            }
        }
    }
}

/// The trajectory and the poles with their indices.
struct Context<'a> {
    samples: &'a [PathSample],
    positions: Vec<Point2<f64>>,
    path_index: GridIndex,
    poles: &'a [Point2<f64>],
    pole_index: GridIndex,
    scratch: Vec<u32>,
}

impl Context<'_> {
    /// Distance from `p` to the nearest trajectory sample within `r` (∞ if none).
    fn path_distance(&mut self, p: &Point2<f64>, r: f64) -> f64 {
        self.path_index.near(p, r, &mut self.scratch);
        self.scratch
            .iter()
            .map(|&i| (self.positions[i as usize] - p).norm())
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether `fp` keeps `clearance` from every trajectory sample.
    fn footprint_clear_of_path(&mut self, fp: &Footprint, clearance: f64) -> bool {
        let r = fp.half_length_m.hypot(fp.half_width_m) + clearance;
        self.path_index.near(&fp.center, r, &mut self.scratch);
        self.scratch
            .iter()
            .all(|&i| fp.distance(&self.positions[i as usize]) >= clearance)
    }

    /// Whether `fp` keeps `clearance` from every pole.
    fn footprint_clear_of_poles(&mut self, fp: &Footprint, clearance: f64) -> bool {
        let r = fp.half_length_m.hypot(fp.half_width_m) + clearance;
        self.pole_index.near(&fp.center, r, &mut self.scratch);
        self.scratch
            .iter()
            .all(|&i| fp.distance(&self.poles[i as usize]) >= clearance)
    }

    /// Lateral offsets (positive to the left) of the poles within `along_m` of sample `i` and
    /// `max_lateral_m` of the trajectory.
    fn pole_offsets(&mut self, i: usize, along_m: f64, max_lateral_m: f64) -> Vec<f64> {
        let s = self.samples[i];
        self.pole_index
            .near(&s.position, along_m.max(max_lateral_m), &mut self.scratch);
        let (sn, cs) = s.heading_rad.sin_cos();
        self.scratch
            .iter()
            .filter_map(|&k| {
                let d = self.poles[k as usize] - s.position;
                let along = d.x * cs + d.y * sn;
                let lateral = -d.x * sn + d.y * cs;
                (along.abs() <= along_m && lateral.abs() <= max_lateral_m).then_some(lateral)
            })
            .collect()
    }

    /// Ground height at `p`: inverse-distance weighted heights of the trajectory samples
    /// within 30 m (the nearest within 100 m otherwise).
    fn ground_z(&mut self, p: &Point2<f64>) -> Option<f64> {
        self.path_index.near(p, 30.0, &mut self.scratch);
        let (mut sum, mut weight) = (0.0, 0.0);
        for &i in &self.scratch {
            let d2 = (self.positions[i as usize] - p).norm_squared();
            if d2 <= 900.0 {
                let w = 1.0 / (d2 + 1.0);
                sum += w * self.samples[i as usize].ground_z;
                weight += w;
            }
        }
        if weight > 0.0 {
            return Some(sum / weight);
        }
        self.path_index.near(p, 100.0, &mut self.scratch);
        self.scratch
            .iter()
            .map(|&i| ((self.positions[i as usize] - p).norm(), i))
            .filter(|(d, _)| *d <= 100.0)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, i)| self.samples[i as usize].ground_z)
    }
}

/// What [`world_along_path`] placed.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PlacementReport {
    /// Indices of the input poles placed in the world (the pole id is the index).
    pub placed_poles: Vec<usize>,
    /// Indices of input poles left out because the trajectory passes within 1 m of them.
    pub poles_on_trajectory: Vec<usize>,
}

/// Builds the world around `samples` (spaced about 2 m) with poles at `poles`.
pub fn world_along_path(
    samples: &[PathSample],
    poles: &[Point2<f64>],
    scenery: &Scenery,
    seed: u64,
) -> (World, PlacementReport) {
    let positions: Vec<Point2<f64>> = samples.iter().map(|s| s.position).collect();
    let mut ctx = Context {
        samples,
        path_index: GridIndex::new(&positions, 10.0),
        positions,
        poles,
        pole_index: GridIndex::new(poles, 10.0),
        scratch: Vec::new(),
    };
    let mut world = World {
        ground: height_field(&mut ctx, scenery),
        slabs: Vec::new(),
        buildings: Vec::new(),
        poles: Vec::new(),
        cars: Vec::new(),
        fences: Vec::new(),
        barrels: Vec::new(),
        foliage: 1.0,
        mesh_seed: seed,
    };
    let mut report = PlacementReport::default();
    let mut parked = std::collections::BTreeMap::new();
    place_poles(&mut ctx, &mut world, scenery, seed, &mut report);
    for (k, side) in [1.0, -1.0].into_iter().enumerate() {
        let mut rng = rng::stream(seed, DOMAIN_BUILDINGS, k as u64);
        line_side(&mut ctx, &mut world, scenery, side, &mut rng);
        let mut rng = rng::stream(seed, DOMAIN_CARS, k as u64);
        park_side(&mut ctx, &mut world, scenery, side, &mut parked, &mut rng);
    }
    (world, report)
}

fn height_field(ctx: &mut Context<'_>, scenery: &Scenery) -> Ground {
    let cell = scenery.ground_cell_m.max(0.5);
    let margin = scenery.ground_margin_m.max(cell);
    let (mut lo, mut hi) = (
        Point2::new(f64::MAX, f64::MAX),
        Point2::new(f64::MIN, f64::MIN),
    );
    for p in &ctx.positions {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let origin = lo - Vector2::new(margin, margin);
    let nx = ((hi.x - lo.x + 2.0 * margin) / cell).ceil() as usize + 1;
    let ny = ((hi.y - lo.y + 2.0 * margin) / cell).ceil() as usize + 1;
    let mut heights = vec![0.0; nx * ny];
    let mut cells = vec![false; (nx - 1) * (ny - 1)];
    for iy in 0..ny - 1 {
        for ix in 0..nx - 1 {
            let c = origin + Vector2::new((ix as f64 + 0.5) * cell, (iy as f64 + 0.5) * cell);
            cells[iy * (nx - 1) + ix] = ctx.path_distance(&c, margin) <= margin;
        }
    }
    for iy in 0..ny {
        for ix in 0..nx {
            let p = origin + Vector2::new(ix as f64 * cell, iy as f64 * cell);
            heights[iy * nx + ix] = ctx.ground_z(&p).unwrap_or(0.0);
        }
    }
    Ground::HeightField {
        origin,
        cell_m: cell,
        nx,
        ny,
        heights,
        cells,
    }
}

fn place_poles(
    ctx: &mut Context<'_>,
    world: &mut World,
    scenery: &Scenery,
    seed: u64,
    report: &mut PlacementReport,
) {
    let total: f64 = scenery.pole_kind_weights.iter().sum();
    for (i, p) in ctx.poles.iter().copied().enumerate() {
        if ctx.path_distance(&p, 1.0) < 1.0 {
            report.poles_on_trajectory.push(i);
            continue;
        }
        let mut rng = rng::stream(seed, DOMAIN_POLES, i as u64);
        let mut pick = rng.random::<f64>() * total;
        let mut kind = PoleKind::SignPost;
        for (k, w) in PoleKind::ALL.iter().zip(scenery.pole_kind_weights) {
            if pick < w {
                kind = *k;
                break;
            }
            pick -= w;
        }
        let (radius_m, height_m) = kind.sample_size(&mut rng);
        // The arm and the sign face the nearest trajectory sample.
        ctx.path_index.near(&p, 30.0, &mut ctx.scratch);
        let nearest = ctx
            .scratch
            .iter()
            .map(|&k| ctx.positions[k as usize])
            .min_by(|a, b| (a - p).norm().total_cmp(&(b - p).norm()));
        let yaw_rad = nearest.map_or(0.0, |q| (q.y - p.y).atan2(q.x - p.x));
        let attachment_m = match kind {
            PoleKind::StreetLight => sample(&mut rng, (1.0, 2.5)),
            PoleKind::SignPost => sample(&mut rng, (0.4, 0.9)),
            _ => 0.0,
        };
        let canopy = (kind == PoleKind::TreeTrunk).then(|| Canopy::sample(radius_m, &mut rng));
        world.poles.push(PoleObject {
            pole: Pole {
                id: i as u32,
                kind,
                x: p.x,
                y: p.y,
                base_z: ctx.ground_z(&p).unwrap_or(0.0),
                radius_m,
                height_m,
            },
            yaw_rad,
            attachment_m,
            canopy,
        });
        report.placed_poles.push(i);
    }
}

/// Road edge offset of sample `i` on `side` (+1 left, −1 right): the configured one, closer
/// where a pole stands in the way.
fn road_edge(ctx: &mut Context<'_>, scenery: &Scenery, i: usize, side: f64) -> f64 {
    let default = if side > 0.0 {
        scenery.left_road_edge_m
    } else {
        scenery.right_road_edge_m
    };
    ctx.pole_offsets(i, 3.0, default + 1.0)
        .into_iter()
        .filter(|l| l * side > 1.0)
        .map(|l| l.abs() - 0.5)
        .fold(default, f64::min)
        .max(1.5)
}

/// Buildings and sidewalks along one side.
fn line_side(
    ctx: &mut Context<'_>,
    world: &mut World,
    scenery: &Scenery,
    side: f64,
    rng: &mut SimRng,
) {
    let n = ctx.samples.len();
    let mut i = 0;
    while i + 1 < n {
        let length = sample(rng, scenery.building_length_m);
        // The samples of this building: up to `length` of path, without sharp turns.
        let start = ctx.samples[i];
        let mut j = i + 1;
        while j + 1 < n
            && (ctx.positions[j] - start.position).norm() < length
            && raypath_geometry::wrap_angle(ctx.samples[j].heading_rad - start.heading_rad).abs()
                < 0.35
        {
            j += 1;
        }
        let sidewalk = sample(rng, scenery.sidewalk_width_m);
        let setback = sample(rng, scenery.setback_m);
        let mut facade: f64 = 0.0;
        let mut edges = Vec::with_capacity(j - i + 1);
        for k in i..=j {
            let edge = road_edge(ctx, scenery, k, side);
            let poles_behind = ctx
                .pole_offsets(k, 3.0, 15.0)
                .into_iter()
                .filter(|l| l * side > edge)
                .map(|l| l.abs() + 1.5)
                .fold(0.0, f64::max);
            facade = facade.max(edge + sidewalk + setback).max(poles_behind);
            edges.push(edge);
        }
        // Sidewalk pieces between consecutive samples, from the road edge to the facade.
        for (k, edge) in (i..j).zip(&edges) {
            let (a, b) = (ctx.samples[k], ctx.samples[k + 1]);
            let d = b.position - a.position;
            let len = d.norm();
            if len < 1e-3 {
                continue;
            }
            let normal = Vector2::new(-d.y, d.x) / len * side;
            let width = (facade - edge).clamp(1.0, 10.0);
            let fp = Footprint {
                center: nalgebra::center(&a.position, &b.position) + normal * (edge + width / 2.0),
                yaw_rad: d.y.atan2(d.x),
                half_length_m: len / 2.0 + 0.05,
                half_width_m: width / 2.0,
            };
            if ctx.footprint_clear_of_path(&fp, 1.0) {
                world.slabs.push(Slab {
                    footprint: fp,
                    base_z: (a.ground_z + b.ground_z) / 2.0 - 0.1,
                    height_m: 0.22,
                    kind: SlabKind::Sidewalk,
                });
            }
        }
        // The building on the chord of its samples.
        let end = ctx.samples[j];
        let chord = end.position - start.position;
        let chord_len = chord.norm();
        if chord_len > 6.0 {
            let dir = chord / chord_len;
            let normal = Vector2::new(-dir.y, dir.x) * side;
            for depth in [sample(rng, (8.0, 14.0)), 6.0] {
                let center = nalgebra::center(&start.position, &end.position)
                    + normal * (facade + depth / 2.0);
                let fp = Footprint {
                    center,
                    yaw_rad: if side > 0.0 {
                        dir.y.atan2(dir.x)
                    } else {
                        (-dir.y).atan2(-dir.x)
                    },
                    half_length_m: chord_len / 2.0,
                    half_width_m: depth / 2.0,
                };
                if ctx.footprint_clear_of_path(&fp, 4.0) && ctx.footprint_clear_of_poles(&fp, 1.0) {
                    let base = ctx.ground_z(&center).unwrap_or(0.0) - 0.5;
                    world.buildings.push(Building {
                        footprint: fp,
                        base_z: base,
                        height_m: sample(rng, scenery.building_height_m) + 0.5,
                        ground_floor_recess_m: if rng.random_bool(0.25) {
                            sample(rng, (1.0, 2.5))
                        } else {
                            0.0
                        },
                        ground_floor_height_m: sample(rng, (4.0, 5.0)),
                        top_floor_height_m: if rng.random_bool(0.2) {
                            sample(rng, (2.5, 3.5))
                        } else {
                            0.0
                        },
                        material: rng.random_range(0..8),
                    });
                    break;
                }
            }
        }
        i = j;
        // A gap: skip some path.
        if rng.random_bool(scenery.gap_probability.clamp(0.0, 1.0)) {
            let gap = sample(rng, (2.0, 12.0));
            let from = ctx.positions[i];
            while i + 1 < n && (ctx.positions[i] - from).norm() < gap {
                i += 1;
            }
        }
    }
}

/// Parked cars along one side, every 6 m where there is room.
fn park_side(
    ctx: &mut Context<'_>,
    world: &mut World,
    scenery: &Scenery,
    side: f64,
    parked: &mut std::collections::BTreeMap<(i64, i64), Vec<Point2<f64>>>,
    rng: &mut SimRng,
) {
    let n = ctx.samples.len();
    let mut last: Option<Point2<f64>> = None;
    let p_car = scenery.parked_car_probability.clamp(0.0, 1.0);
    for i in 0..n {
        let s = ctx.samples[i];
        if last.is_some_and(|q| (q - s.position).norm() < 6.0) {
            continue;
        }
        last = Some(s.position);
        if !rng.random_bool(p_car) {
            continue;
        }
        let edge = road_edge(ctx, scenery, i, side);
        let (sn, cs) = s.heading_rad.sin_cos();
        let normal = Vector2::new(-sn, cs) * side;
        let center = s.position + normal * (edge - 1.1);
        let length = sample(rng, (3.8, 5.0));
        let fp = Footprint {
            center,
            yaw_rad: s.heading_rad
                + if side > 0.0 {
                    std::f64::consts::PI
                } else {
                    0.0
                },
            half_length_m: length / 2.0,
            half_width_m: sample(rng, (1.7, 1.95)) / 2.0,
        };
        let key = |p: &Point2<f64>| ((p.x / 10.0).floor() as i64, (p.y / 10.0).floor() as i64);
        let (kx, ky) = key(&center);
        let free_of_cars = (kx - 1..=kx + 1).all(|x| {
            (ky - 1..=ky + 1).all(|y| {
                parked
                    .get(&(x, y))
                    .is_none_or(|v| v.iter().all(|q: &Point2<f64>| (q - center).norm() > 5.0))
            })
        });
        if free_of_cars
            && ctx.footprint_clear_of_path(&fp, 1.6)
            && ctx.footprint_clear_of_poles(&fp, 0.5)
        {
            parked.entry((kx, ky)).or_default().push(center);
            world.cars.push(Car {
                footprint: fp,
                base_z: ctx.ground_z(&center).unwrap_or(s.ground_z),
                height_m: sample(rng, (1.4, 1.75)),
                reflectivity: rng.random_range(0.1..0.7),
            });
        }
    }
}
