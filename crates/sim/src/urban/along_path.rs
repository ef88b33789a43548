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

use super::path_index::{Context, GridIndex};
use super::roadside::{line_side, park_side};

use super::kinds::{Canopy, Pole, PoleKind};
use super::streets::sample;
use super::world::{Ground, PoleObject, World};
use crate::rng;

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
