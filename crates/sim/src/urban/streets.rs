//! Procedural street worlds: an irregular grid of streets with sidewalks and curbs, buildings
//! along the blocks, poles, trees, bollards, fences, parking slots and construction zones.
//!
//! Streets run along x and y; street `i` of the x lines is the vertical street at `x = xs[i]`.
//! Each street has a carriageway half width (including a parking lane on each side) and a
//! sidewalk width; blocks between streets are raised by the curb height. The grid is
//! surrounded by a ring of blocks so that the outer streets have buildings on both sides.

use nalgebra::{Point2, Vector2};
use rand::Rng;

use super::furniture::{furnish_street_side, parking_slots, street_sides};
use super::world::{Building, Fence, Footprint, Ground, Slab, SlabKind, World};
use crate::error::{Result, SimError};
use crate::rng::{self, SimRng};

const DOMAIN_GRID: u64 = 0x5552_4247_5249_4400;
const DOMAIN_BLOCK_SIDE: u64 = 0x5552_4242_4c4f_434b;
const DOMAIN_STREET_SIDE: u64 = 0x5552_4253_5452_4545;
const DOMAIN_CONSTRUCTION: u64 = 0x5552_4243_4f4e_5354;

/// Depth of the ring of blocks around the grid, metres.
const OUTER_BLOCK_M: f64 = 45.0;

/// Parameters of a street world. Ranges `(a, b)` are sampled uniformly.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StreetConfig {
    /// Blocks along x (streets along y: `blocks_x + 1`).
    pub blocks_x: usize,
    /// Blocks along y.
    pub blocks_y: usize,
    /// Distance between neighbouring parallel streets, metres.
    pub block_length_m: (f64, f64),
    /// Half width of a carriageway including its parking lanes, metres.
    pub road_half_width_m: (f64, f64),
    /// Sidewalk width, metres.
    pub sidewalk_width_m: (f64, f64),
    /// Curb height, metres.
    pub curb_height_m: f64,
    /// Building height, metres.
    pub building_height_m: (f64, f64),
    /// Distance between street lights along a street side, metres.
    pub street_light_spacing_m: (f64, f64),
    /// Probability that a street side is lined with trees.
    pub tree_side_probability: f64,
    /// Distance between trees, metres.
    pub tree_spacing_m: (f64, f64),
    /// Sign posts per kilometre of street side, besides those before intersections.
    pub sign_posts_per_km: f64,
    /// Probability of a group of bollards on a street side.
    pub bollard_group_probability: f64,
    /// Probability of a fence across a gap between buildings.
    pub fence_probability: f64,
    /// Number of construction zones (rows of barrels in a parking lane).
    pub construction_zones: usize,
}

impl Default for StreetConfig {
    fn default() -> Self {
        Self {
            blocks_x: 5,
            blocks_y: 4,
            block_length_m: (60.0, 110.0),
            road_half_width_m: (5.0, 7.0),
            sidewalk_width_m: (2.0, 4.0),
            curb_height_m: 0.12,
            building_height_m: (6.0, 24.0),
            street_light_spacing_m: (25.0, 40.0),
            tree_side_probability: 0.5,
            tree_spacing_m: (8.0, 14.0),
            sign_posts_per_km: 12.0,
            bollard_group_probability: 0.25,
            fence_probability: 0.5,
            construction_zones: 1,
        }
    }
}

impl StreetConfig {
    /// A smaller world (3 × 3 blocks) for quick sets and tests.
    pub fn quick() -> Self {
        Self {
            blocks_x: 3,
            blocks_y: 3,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        let ranges = [
            ("block_length_m", self.block_length_m, 30.0),
            ("road_half_width_m", self.road_half_width_m, 4.0),
            ("sidewalk_width_m", self.sidewalk_width_m, 1.0),
            ("building_height_m", self.building_height_m, 2.0),
            ("street_light_spacing_m", self.street_light_spacing_m, 5.0),
            ("tree_spacing_m", self.tree_spacing_m, 3.0),
        ];
        for (name, (a, b), min) in ranges {
            if !(a.is_finite() && b.is_finite() && min <= a && a <= b) {
                return Err(SimError::InvalidParameter {
                    name,
                    reason: format!("({a}, {b}) must be a finite range with {min} ≤ a ≤ b"),
                });
            }
        }
        if self.blocks_x == 0 || self.blocks_y == 0 || self.blocks_x > 50 || self.blocks_y > 50 {
            return Err(SimError::InvalidParameter {
                name: "blocks_x/blocks_y",
                reason: "must be 1–50".into(),
            });
        }
        Ok(())
    }
}

/// The street lines of a world.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StreetGrid {
    /// x of the streets running along y, increasing.
    pub xs: Vec<f64>,
    /// y of the streets running along x, increasing.
    pub ys: Vec<f64>,
    /// Carriageway half widths of the streets at `xs`.
    pub half_widths_x: Vec<f64>,
    /// Carriageway half widths of the streets at `ys`.
    pub half_widths_y: Vec<f64>,
    /// Sidewalk widths of the streets at `xs`.
    pub sidewalks_x: Vec<f64>,
    /// Sidewalk widths of the streets at `ys`.
    pub sidewalks_y: Vec<f64>,
}

impl StreetGrid {
    /// The intersection `(i, j)`.
    pub fn node(&self, i: usize, j: usize) -> Point2<f64> {
        Point2::new(
            self.xs.get(i).copied().unwrap_or(0.0),
            self.ys.get(j).copied().unwrap_or(0.0),
        )
    }
}

/// A place where a car may be parked (in a parking lane along a curb).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ParkingSlot {
    /// Centre, metres.
    pub center: Point2<f64>,
    /// Direction of the street (cars face along it), radians.
    pub yaw_rad: f64,
    /// Height of the road, metres.
    pub base_z: f64,
}

/// A row of barrels in a parking lane, shifted between sessions.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ConstructionZone {
    /// Start of the row, metres.
    pub start: Point2<f64>,
    /// Unit direction of the row.
    pub direction: Vector2<f64>,
    /// Unit normal towards the curb.
    pub towards_curb: Vector2<f64>,
    /// Length of the row, metres.
    pub length_m: f64,
    /// Height of the road, metres.
    pub base_z: f64,
}

/// The static layout of a world; sessions add cars and barrels and apply changes.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct UrbanLayout {
    /// The streets.
    pub grid: StreetGrid,
    /// The static world (no cars or barrels yet, full foliage).
    pub world: World,
    /// Parking slots.
    pub parking: Vec<ParkingSlot>,
    /// Construction zones.
    pub construction: Vec<ConstructionZone>,
}

/// Generates a street world.
pub fn generate_layout(config: &StreetConfig, seed: u64) -> Result<UrbanLayout> {
    config.validate()?;
    let mut rng = rng::stream(seed, DOMAIN_GRID, 0);
    let lines = |n: usize, rng: &mut SimRng| {
        let mut v = vec![0.0];
        for _ in 0..n {
            let last = v.last().copied().unwrap_or(0.0);
            v.push(last + sample(rng, config.block_length_m));
        }
        v
    };
    let xs = lines(config.blocks_x, &mut rng);
    let ys = lines(config.blocks_y, &mut rng);
    let mut widths = |n: usize, range| (0..n).map(|_| sample(&mut rng, range)).collect::<Vec<_>>();
    let grid = StreetGrid {
        half_widths_x: widths(xs.len(), config.road_half_width_m),
        half_widths_y: widths(ys.len(), config.road_half_width_m),
        sidewalks_x: widths(xs.len(), config.sidewalk_width_m),
        sidewalks_y: widths(ys.len(), config.sidewalk_width_m),
        xs,
        ys,
    };
    let (x_min, x_max) = (
        grid.xs[0] - OUTER_BLOCK_M,
        grid.xs[grid.xs.len() - 1] + OUTER_BLOCK_M,
    );
    let (y_min, y_max) = (
        grid.ys[0] - OUTER_BLOCK_M,
        grid.ys[grid.ys.len() - 1] + OUTER_BLOCK_M,
    );
    let mut world = World {
        ground: Ground::Flat {
            min: Point2::new(x_min - 100.0, y_min - 100.0),
            max: Point2::new(x_max + 100.0, y_max + 100.0),
            z: 0.0,
        },
        slabs: Vec::new(),
        buildings: Vec::new(),
        poles: Vec::new(),
        cars: Vec::new(),
        fences: Vec::new(),
        barrels: Vec::new(),
        foliage: 1.0,
        mesh_seed: seed,
    };
    // Blocks: between the road edges of neighbouring streets, plus the outer ring.
    let edges = |lines: &[f64],
                 half: &[f64],
                 lo: f64,
                 hi: f64|
     -> Vec<(f64, f64, Option<usize>, Option<usize>)> {
        let mut out = Vec::new();
        let n = lines.len();
        out.push((lo, lines[0] - half[0], None, Some(0)));
        for k in 0..n - 1 {
            out.push((
                lines[k] + half[k],
                lines[k + 1] - half[k + 1],
                Some(k),
                Some(k + 1),
            ));
        }
        out.push((lines[n - 1] + half[n - 1], hi, Some(n - 1), None));
        out
    };
    let bx = edges(&grid.xs, &grid.half_widths_x, x_min, x_max);
    let by = edges(&grid.ys, &grid.half_widths_y, y_min, y_max);
    let mut side_index = 0u64;
    for &(x0, x1, left, right) in &bx {
        for &(y0, y1, bottom, top) in &by {
            world.slabs.push(Slab {
                footprint: Footprint {
                    center: Point2::new((x0 + x1) / 2.0, (y0 + y1) / 2.0),
                    yaw_rad: 0.0,
                    half_length_m: (x1 - x0) / 2.0,
                    half_width_m: (y1 - y0) / 2.0,
                },
                base_z: 0.0,
                height_m: config.curb_height_m,
                kind: SlabKind::Sidewalk,
            });
            // Block sides facing a street: (start, end, inward normal, sidewalk, sidewalks
            // of the neighbouring sides at the start and end).
            let sw = |k: Option<usize>, v: &[f64]| k.and_then(|k| v.get(k).copied());
            let (s_left, s_right) = (sw(left, &grid.sidewalks_x), sw(right, &grid.sidewalks_x));
            let (s_bottom, s_top) = (sw(bottom, &grid.sidewalks_y), sw(top, &grid.sidewalks_y));
            let sides = [
                (
                    s_bottom,
                    Point2::new(x0, y0),
                    Point2::new(x1, y0),
                    s_left,
                    s_right,
                ),
                (
                    s_right,
                    Point2::new(x1, y0),
                    Point2::new(x1, y1),
                    s_bottom,
                    s_top,
                ),
                (
                    s_top,
                    Point2::new(x1, y1),
                    Point2::new(x0, y1),
                    s_right,
                    s_left,
                ),
                (
                    s_left,
                    Point2::new(x0, y1),
                    Point2::new(x0, y0),
                    s_top,
                    s_bottom,
                ),
            ];
            for (sidewalk, from, to, s_start, s_end) in sides {
                side_index += 1;
                let Some(sidewalk) = sidewalk else { continue };
                let mut rng = rng::stream(seed, DOMAIN_BLOCK_SIDE, side_index);
                let margins = (s_start.unwrap_or(0.0) + 1.0, s_end.unwrap_or(0.0) + 1.0);
                line_block_side(&mut world, config, from, to, sidewalk, margins, &mut rng);
            }
        }
    }
    // Street furniture and parking along every street segment side.
    let mut parking = Vec::new();
    let sides = street_sides(&grid);
    for (k, side) in sides.iter().enumerate() {
        let mut rng = rng::stream(seed, DOMAIN_STREET_SIDE, k as u64);
        furnish_street_side(&mut world, config, side, &mut rng);
        parking.extend(parking_slots(side));
    }
    // Construction zones replace parking on a stretch of a street side.
    let mut rng = rng::stream(seed, DOMAIN_CONSTRUCTION, 0);
    let mut construction = Vec::new();
    for _ in 0..config.construction_zones {
        let Some(side) = sides.get(rng.random_range(0..sides.len().max(1))) else {
            break;
        };
        let dir = (side.to - side.from).normalize();
        let len = (side.to - side.from).norm();
        let zone_len = rng.random_range(20.0..35.0_f64).min(len - 10.0);
        if zone_len < 8.0 {
            continue;
        }
        let t0 = rng.random_range(5.0..(len - zone_len - 5.0).max(5.0 + 1e-9));
        let zone = ConstructionZone {
            start: side.from + dir * t0 + side.normal * (side.half_width - 1.6),
            direction: dir,
            towards_curb: side.normal,
            length_m: zone_len,
            base_z: 0.0,
        };
        parking.retain(|slot: &ParkingSlot| {
            let d = slot.center - zone.start;
            let along = d.dot(&zone.direction);
            let across = d.dot(&zone.towards_curb).abs();
            !(across < 3.0 && along > -4.0 && along < zone.length_m + 4.0)
        });
        construction.push(zone);
    }
    Ok(UrbanLayout {
        grid,
        world,
        parking,
        construction,
    })
}

/// Uniform sample of a range (the lower bound for an empty range).
pub(crate) fn sample(rng: &mut SimRng, (a, b): (f64, f64)) -> f64 {
    if b > a { rng.random_range(a..b) } else { a }
}

/// Buildings (and fences across some gaps) along one side of a block. `from → to` runs along
/// the road edge with the block on the left.
fn line_block_side(
    world: &mut World,
    config: &StreetConfig,
    from: Point2<f64>,
    to: Point2<f64>,
    sidewalk: f64,
    (m0, m1): (f64, f64),
    rng: &mut SimRng,
) {
    let dir = (to - from).normalize();
    let inward = Vector2::new(-dir.y, dir.x);
    let yaw = dir.y.atan2(dir.x);
    let len = (to - from).norm();
    let z = config.curb_height_m;
    // Each block side has a style: a height range within the configured one.
    let (h0, h1) = config.building_height_m;
    let style_lo = sample(rng, (h0, (h0 + h1) / 2.0));
    let style_hi = sample(rng, (style_lo, h1));
    let mut t = m0;
    let mut previous_end: Option<Point2<f64>> = None;
    while t + 8.0 < len - m1 {
        let length = sample(rng, (10.0, 30.0)).min(len - m1 - t);
        let setback = if rng.random_bool(0.5) {
            sample(rng, (0.0, 3.0))
        } else {
            0.0
        };
        let depth = sample(rng, (8.0, 14.0));
        let front = sidewalk + setback;
        let center = from + dir * (t + length / 2.0) + inward * (front + depth / 2.0);
        let recess = if rng.random_bool(0.3) {
            sample(rng, (1.0, 3.0))
        } else {
            0.0
        };
        world.buildings.push(Building {
            footprint: Footprint {
                center,
                yaw_rad: yaw,
                half_length_m: length / 2.0,
                half_width_m: depth / 2.0,
            },
            base_z: z,
            height_m: sample(rng, (style_lo, style_hi)),
            ground_floor_recess_m: recess,
            ground_floor_height_m: sample(rng, (3.5, 4.5)),
            top_floor_height_m: if rng.random_bool(0.25) {
                sample(rng, (2.5, 3.5))
            } else {
                0.0
            },
            material: rng.random_range(0..8),
        });
        let start = from + dir * t + inward * front;
        if let Some(end) = previous_end
            && (start - end).norm() > 3.0
            && rng.random_bool(config.fence_probability)
        {
            world.fences.push(Fence {
                from: end,
                to: start,
                base_z: z,
                height_m: sample(rng, (1.0, 2.0)),
            });
        }
        previous_end = Some(from + dir * (t + length) + inward * front);
        t += length;
        if rng.random_bool(0.35) {
            t += sample(rng, (2.0, 10.0));
        }
    }
}
