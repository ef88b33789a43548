//! Procedural floor plans: a rectangular building of rooms along one or two corridors, with
//! thick walls, doors, windows, glass partitions, furniture, posters and columns.
//!
//! **Layout.** The interior of a `width × height` building (exterior walls of
//! `exterior_wall_m`) is tiled by axis-aligned *spaces*: a horizontal main corridor, optionally
//! a vertical cross corridor, and rooms of random width in the strips above and below the
//! corridors. Walls of `interior_wall_m` are centred on the boundaries between spaces (none
//! between two corridor spaces); every room gets a door to a corridor, neighbouring rooms a
//! connecting door with some probability. Exterior walls get windows (glass panes in a gap),
//! some room–corridor walls are glass partitions.
//!
//! **Geometry.** Walls are solid rectangles (four segments each; overlapping rectangles at
//! junctions hide their inner segments from every ray that starts in free space), glass is a
//! single segment (so a ray crossing it draws transmission once). Furniture: cabinets against
//! walls (solid), tables (four 5 cm legs: a 2-D laser at knee height sees the legs; the whole
//! table blocks the robot), boxes at random angles, posters (thin strips 1 cm in front of a
//! wall, with their own reflectivity), and columns (16-gons) in wide corridors.
//!
//! **Surfaces.** Every space has its own paint (reflectivity), so walls facing different
//! spaces differ; labels name the surface class ([`SurfaceClass::label`]).

use nalgebra::{Point2, Vector2};
use rand::Rng;
use serde::Serialize;

use super::furniture::{place_box, place_cabinet, place_poster, place_table};
use super::walls::{Aabb, Builder, overlaps, split, uniform};
use crate::error::{Result, SimError};
use crate::scene2::{Scene2, SceneBuilder2, Surface, SurfaceId};

/// Parameters of a floor plan. Ranges `[min, max]` are drawn uniformly.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FloorPlanConfig {
    /// Outer width (x) of the building in metres.
    pub width_m: f64,
    /// Outer height (y) of the building in metres.
    pub height_m: f64,
    /// Thickness of the exterior walls in metres.
    pub exterior_wall_m: f64,
    /// Thickness of the interior walls in metres.
    pub interior_wall_m: f64,
    /// Corridor width between wall centre lines, metres.
    pub corridor_width_m: [f64; 2],
    /// Whether a vertical corridor crosses the main corridor.
    pub cross_corridor: bool,
    /// Room width along the corridor, metres.
    pub room_width_m: [f64; 2],
    /// Door width, metres.
    pub door_width_m: [f64; 2],
    /// Probability of a door between neighbouring rooms.
    pub connecting_door_probability: f64,
    /// Probability that an exterior side of a room has windows.
    pub window_probability: f64,
    /// Probability that a room's corridor wall is a glass partition.
    pub glass_partition_probability: f64,
    /// Probability that glass lets a ray through (it reflects otherwise).
    pub glass_transmission: f64,
    /// Furniture items per square metre of room floor.
    pub furniture_per_m2: f64,
    /// Posters per room wall side, at most.
    pub posters_per_room: usize,
    /// Cabinets along the corridor walls.
    pub corridor_cabinets: usize,
    /// Columns along wide corridors (at least 3.5 m), spaced this far apart; 0: none.
    pub column_spacing_m: f64,
}

impl Default for FloorPlanConfig {
    fn default() -> Self {
        Self {
            width_m: 30.0,
            height_m: 20.0,
            exterior_wall_m: 0.3,
            interior_wall_m: 0.12,
            corridor_width_m: [2.0, 2.6],
            cross_corridor: false,
            room_width_m: [3.0, 5.5],
            door_width_m: [1.0, 1.3],
            connecting_door_probability: 0.3,
            window_probability: 0.6,
            glass_partition_probability: 0.15,
            glass_transmission: 0.7,
            furniture_per_m2: 0.12,
            posters_per_room: 2,
            corridor_cabinets: 3,
            column_spacing_m: 0.0,
        }
    }
}

impl FloorPlanConfig {
    /// Checks sizes and probabilities.
    pub fn validate(&self) -> Result<()> {
        let bad =
            |name: &'static str, reason: String| Err(SimError::InvalidParameter { name, reason });
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let range_ok = |r: [f64; 2]| positive(r[0]) && r[1].is_finite() && r[1] >= r[0];
        if !(positive(self.exterior_wall_m) && positive(self.interior_wall_m)) {
            return bad(
                "exterior_wall_m",
                "wall thicknesses must be positive".into(),
            );
        }
        for (name, r) in [
            ("corridor_width_m", self.corridor_width_m),
            ("room_width_m", self.room_width_m),
            ("door_width_m", self.door_width_m),
        ] {
            if !range_ok(r) {
                return bad(name, format!("need 0 < min ≤ max, got {r:?}"));
            }
        }
        if self.door_width_m[0] < 0.9 {
            return bad(
                "door_width_m",
                "doors narrower than 0.9 m block the robot".into(),
            );
        }
        let depth = (self.height_m - 2.0 * self.exterior_wall_m - self.corridor_width_m[1]) / 2.0;
        if depth.is_nan() || depth < 2.5 || !self.height_m.is_finite() {
            return bad(
                "height_m",
                format!("rooms would be {depth:.2} m deep; make the building taller"),
            );
        }
        // With a cross corridor at 35–65 % of the width, each side must hold a room.
        let min_width = if self.cross_corridor {
            (self.room_width_m[0] + self.corridor_width_m[1] / 2.0) / 0.35
        } else {
            self.room_width_m[0]
        } + 2.0 * self.exterior_wall_m;
        if !self.width_m.is_finite() || self.width_m < min_width {
            return bad(
                "width_m",
                format!("need at least {min_width:.1} m for one room per strip"),
            );
        }
        for (name, p) in [
            (
                "connecting_door_probability",
                self.connecting_door_probability,
            ),
            ("window_probability", self.window_probability),
            (
                "glass_partition_probability",
                self.glass_partition_probability,
            ),
            ("glass_transmission", self.glass_transmission),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return bad(name, format!("must be a probability, got {p}"));
            }
        }
        let density_ok = |v: f64| v.is_finite() && v >= 0.0;
        if !density_ok(self.furniture_per_m2) || !density_ok(self.column_spacing_m) {
            return bad(
                "furniture_per_m2",
                "densities must be finite and ≥ 0".into(),
            );
        }
        Ok(())
    }
}

/// What a surface is; its [`SurfaceClass::label`] is the ground-truth label of the hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SurfaceClass {
    /// The outside of the exterior walls (never seen from inside).
    Facade,
    /// A painted wall face (interior side of any wall, door jambs).
    Wall,
    /// A window or glass partition: transmits rays with some probability.
    Glass,
    /// Cabinets, table legs, boxes.
    Furniture,
    /// Columns.
    Column,
    /// Posters on walls (high or low reflectivity markers).
    Poster,
}

impl SurfaceClass {
    /// The label written for hits on this class: façade 1, wall 2, glass 3, furniture 4,
    /// column 5, poster 6.
    pub fn label(self) -> u32 {
        match self {
            SurfaceClass::Facade => 1,
            SurfaceClass::Wall => 2,
            SurfaceClass::Glass => 3,
            SurfaceClass::Furniture => 4,
            SurfaceClass::Column => 5,
            SurfaceClass::Poster => 6,
        }
    }
}

/// A surface of the world: class, label, reflectivity and transmission.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Material {
    /// The class.
    pub class: SurfaceClass,
    /// Ground-truth label ([`SurfaceClass::label`]).
    pub label: u32,
    /// Diffuse reflectivity in [0, 1].
    pub reflectivity: f64,
    /// Probability that a ray passes through (glass only; 0 otherwise).
    pub transmission: f64,
}

/// Kind of a space.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpaceKind {
    /// A corridor.
    Corridor,
    /// A room.
    Room,
}

/// An axis-aligned space of the tiling (between wall centre lines).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Space {
    /// Corridor or room.
    pub kind: SpaceKind,
    /// Lower corner `[x, y]`, metres.
    pub min: [f64; 2],
    /// Upper corner `[x, y]`, metres.
    pub max: [f64; 2],
    /// The surface of its walls' faces.
    pub paint: SurfaceId,
}

impl Space {
    fn width(&self) -> f64 {
        self.max[0] - self.min[0]
    }
    fn height(&self) -> f64 {
        self.max[1] - self.min[1]
    }
    /// Area in m².
    pub fn area_m2(&self) -> f64 {
        self.width() * self.height()
    }
    /// The centre.
    pub fn center(&self) -> Point2<f64> {
        Point2::new(
            0.5 * (self.min[0] + self.max[0]),
            0.5 * (self.min[1] + self.max[1]),
        )
    }
}

/// A door: an opening in a wall between two spaces.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Door {
    /// Centre of the opening `[x, y]`.
    pub center: [f64; 2],
    /// Width of the opening, metres.
    pub width_m: f64,
    /// Whether the wall runs along x.
    pub horizontal_wall: bool,
    /// The two spaces it connects.
    pub spaces: [usize; 2],
}

/// One segment of the world as written to `<name>-world.json`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WorldSegment {
    /// Start `[x, y]`, metres.
    pub a: [f64; 2],
    /// End `[x, y]`, metres.
    pub b: [f64; 2],
    /// Its surface.
    pub surface: SurfaceId,
}

/// A generated world: the geometry the laser sees and what the robot must avoid.
#[derive(Clone)]
pub struct World {
    /// The plan's parameters.
    pub config: FloorPlanConfig,
    /// Corridors and rooms.
    pub spaces: Vec<Space>,
    /// Doors.
    pub doors: Vec<Door>,
    /// Number of windows.
    pub windows: usize,
    /// Surfaces, indexed by [`SurfaceId`].
    pub materials: Vec<Material>,
    /// All segments the laser sees.
    pub segments: Vec<WorldSegment>,
    /// Extra obstacles for the robot only (table footprints), as closed polygons.
    pub footprints: Vec<Vec<[f64; 2]>>,
    /// The scene the laser scans.
    pub scene: Scene2,
    /// The scene plus the footprints, for planning.
    pub planning_scene: Scene2,
}

/// Generates a world from `config` with `rng`.
pub fn generate_world<R: Rng + ?Sized>(config: &FloorPlanConfig, rng: &mut R) -> Result<World> {
    config.validate()?;
    let (w, h, e) = (config.width_m, config.height_m, config.exterior_wall_m);
    let t = config.interior_wall_m;
    let (x0, x1, y0, y1) = (e, w - e, e, h - e);
    let mut b = Builder {
        materials: Vec::new(),
        segments: Vec::new(),
        footprints: Vec::new(),
    };
    let facade = b.material(SurfaceClass::Facade, 0.5, 0.0);
    let glass = b.material(SurfaceClass::Glass, 0.15, config.glass_transmission);

    // The tiling: corridors, then rooms.
    let wc = uniform(rng, config.corridor_width_m);
    let max_shift = ((y1 - y0 - wc) / 2.0 - 2.5).max(0.0);
    let yc = 0.5 * (y0 + y1) + rng.random_range(-1.0..=1.0) * max_shift.min(0.1 * (y1 - y0));
    let (ylo, yhi) = (yc - wc / 2.0, yc + wc / 2.0);
    let mut spaces = Vec::new();
    let mut space =
        |b: &mut Builder, kind: SpaceKind, min: [f64; 2], max: [f64; 2], rng: &mut R| {
            let paint = b.material(SurfaceClass::Wall, uniform(rng, [0.45, 0.9]), 0.0);
            spaces.push(Space {
                kind,
                min,
                max,
                paint,
            });
        };
    space(&mut b, SpaceKind::Corridor, [x0, ylo], [x1, yhi], rng);
    let strips_x: Vec<[f64; 2]> = if config.cross_corridor {
        let xv = x0 + (x1 - x0) * rng.random_range(0.35..0.65);
        space(
            &mut b,
            SpaceKind::Corridor,
            [xv - wc / 2.0, y0],
            [xv + wc / 2.0, ylo],
            rng,
        );
        space(
            &mut b,
            SpaceKind::Corridor,
            [xv - wc / 2.0, yhi],
            [xv + wc / 2.0, y1],
            rng,
        );
        vec![[x0, xv - wc / 2.0], [xv + wc / 2.0, x1]]
    } else {
        vec![[x0, x1]]
    };
    for [sx0, sx1] in &strips_x {
        for [sy0, sy1] in [[y0, ylo], [yhi, y1]] {
            let cuts = split(rng, *sx0, *sx1, config.room_width_m);
            for pair in cuts.windows(2) {
                if let [a, c] = pair {
                    space(&mut b, SpaceKind::Room, [*a, sy0], [*c, sy1], rng);
                }
            }
        }
    }

    // Interior walls between adjacent spaces, with doors.
    let mut doors = Vec::new();
    let mut room_has_corridor_door = vec![false; spaces.len()];
    let mut keepouts: Vec<Aabb> = Vec::new();
    // Glass (partitions and windows): no posters in front of it.
    let mut glass_zones: Vec<Aabb> = Vec::new();
    let adjacency = adjacent_pairs(&spaces);
    // Corridor boundaries first, longest first per room, so every room gets a door.
    let mut order: Vec<usize> = (0..adjacency.len()).collect();
    order.sort_by(|&i, &j| {
        let (a, b_) = (&adjacency[i], &adjacency[j]);
        let corridor = |p: &Adjacent| {
            u8::from(
                spaces[p.low].kind == SpaceKind::Corridor
                    || spaces[p.high].kind == SpaceKind::Corridor,
            )
        };
        corridor(b_)
            .cmp(&corridor(a))
            .then((b_.span[1] - b_.span[0]).total_cmp(&(a.span[1] - a.span[0])))
            .then(i.cmp(&j))
    });
    for idx in order {
        let adj = adjacency[idx];
        let (sl, sh) = (spaces[adj.low], spaces[adj.high]);
        let corridors = [sl.kind, sh.kind]
            .iter()
            .filter(|k| **k == SpaceKind::Corridor)
            .count();
        if corridors == 2 {
            // Corridors open into each other: keep the opening free of furniture.
            let (a, c) = (adj.span[0] - 1.3, adj.span[1] + 1.3);
            keepouts.push(if adj.horizontal {
                ([a, adj.coord - 1.3], [c, adj.coord + 1.3])
            } else {
                ([adj.coord - 1.3, a], [adj.coord + 1.3, c])
            });
            continue;
        }
        let room = if sl.kind == SpaceKind::Room {
            adj.low
        } else {
            adj.high
        };
        let door_probability = if corridors == 1 {
            if room_has_corridor_door[room] {
                0.5
            } else {
                1.0
            }
        } else {
            config.connecting_door_probability
        };
        let len = adj.span[1] - adj.span[0];
        let mut gaps = Vec::new();
        if rng.random::<f64>() < door_probability {
            let width = uniform(rng, config.door_width_m).min(len - 0.6);
            if width >= 0.9 {
                let lo = adj.span[0] + 0.3 + width / 2.0;
                let hi = adj.span[1] - 0.3 - width / 2.0;
                let s = if hi > lo {
                    rng.random_range(lo..hi)
                } else {
                    0.5 * (lo + hi)
                };
                gaps.push((s - width / 2.0, s + width / 2.0, None));
                let center = if adj.horizontal {
                    [s, adj.coord]
                } else {
                    [adj.coord, s]
                };
                doors.push(Door {
                    center,
                    width_m: width,
                    horizontal_wall: adj.horizontal,
                    spaces: [adj.low, adj.high],
                });
                let (along, across) = (width / 2.0 + 0.6, 1.3);
                keepouts.push(if adj.horizontal {
                    (
                        [s - along, adj.coord - across],
                        [s + along, adj.coord + across],
                    )
                } else {
                    (
                        [adj.coord - across, s - along],
                        [adj.coord + across, s + along],
                    )
                });
                if corridors == 1 {
                    room_has_corridor_door[room] = true;
                }
            }
        }
        let glass_wall = corridors == 1 && rng.random::<f64>() < config.glass_partition_probability;
        if glass_wall {
            glass_zones.push(wall_box(adj.horizontal, adj.coord, adj.span, t));
        }
        b.wall(
            adj.horizontal,
            [adj.coord - t / 2.0, adj.coord + t / 2.0],
            [adj.span[0] - t / 2.0, adj.span[1] + t / 2.0],
            &gaps,
            sl.paint,
            sh.paint,
            sl.paint,
            glass_wall.then_some(glass),
        );
    }

    // Exterior walls: one piece per space side on the building boundary, with windows.
    let mut windows = 0;
    for s in &spaces {
        let sides: [(bool, f64, [f64; 2], bool); 4] = [
            (true, y0, [s.min[0], s.max[0]], s.min[1] <= y0 + 1e-9),
            (true, y1, [s.min[0], s.max[0]], s.max[1] >= y1 - 1e-9),
            (false, x0, [s.min[1], s.max[1]], s.min[0] <= x0 + 1e-9),
            (false, x1, [s.min[1], s.max[1]], s.max[0] >= x1 - 1e-9),
        ];
        for (horizontal, coord, span, on_boundary) in sides {
            if !on_boundary {
                continue;
            }
            let (lo_end, hi_end) = if horizontal { (x0, x1) } else { (y0, y1) };
            let (outer_lo, outer_hi) = if horizontal { (0.0, w) } else { (0.0, h) };
            let span_ext = [
                if span[0] <= lo_end + 1e-9 {
                    outer_lo
                } else {
                    span[0]
                },
                if span[1] >= hi_end - 1e-9 {
                    outer_hi
                } else {
                    span[1]
                },
            ];
            let len = span[1] - span[0];
            let mut gaps = Vec::new();
            let window_p = match s.kind {
                SpaceKind::Room => config.window_probability,
                SpaceKind::Corridor => 0.5 * config.window_probability,
            };
            if len > 2.0 && rng.random::<f64>() < window_p {
                let k = ((len / 3.5) as usize).max(1);
                let pitch = len / k as f64;
                let width = (pitch - 0.8).min(uniform(rng, [1.0, 2.0]));
                if width >= 0.6 {
                    for i in 0..k {
                        let c = span[0] + (i as f64 + 0.5) * pitch;
                        gaps.push((c - width / 2.0, c + width / 2.0, Some(glass)));
                        glass_zones.push(wall_box(
                            horizontal,
                            coord,
                            [c - width / 2.0, c + width / 2.0],
                            0.1,
                        ));
                        windows += 1;
                    }
                }
            }
            // The outward side is the façade; the thickness lies outside the interior.
            let low_outside = coord == y0 || coord == x0;
            let thickness = if low_outside {
                [coord - e, coord]
            } else {
                [coord, coord + e]
            };
            let (low, high) = if low_outside {
                (facade, s.paint)
            } else {
                (s.paint, facade)
            };
            b.wall(
                horizontal, thickness, span_ext, &gaps, low, high, s.paint, None,
            );
        }
    }

    // Furniture, posters, columns.
    let furniture_paint = |b: &mut Builder, rng: &mut R| {
        b.material(SurfaceClass::Furniture, uniform(rng, [0.1, 0.7]), 0.0)
    };
    let mut items: Vec<Aabb> = keepouts.clone();
    for (si, s) in spaces.iter().enumerate() {
        let inner: Aabb = (
            [
                if s.min[0] <= x0 + 1e-9 {
                    x0
                } else {
                    s.min[0] + t / 2.0
                },
                if s.min[1] <= y0 + 1e-9 {
                    y0
                } else {
                    s.min[1] + t / 2.0
                },
            ],
            [
                if s.max[0] >= x1 - 1e-9 {
                    x1
                } else {
                    s.max[0] - t / 2.0
                },
                if s.max[1] >= y1 - 1e-9 {
                    y1
                } else {
                    s.max[1] - t / 2.0
                },
            ],
        );
        match s.kind {
            SpaceKind::Room => {
                let count = (s.area_m2() * config.furniture_per_m2).round() as usize;
                for _ in 0..count {
                    let kind = rng.random::<f64>();
                    let paint = furniture_paint(&mut b, rng);
                    if kind < 0.5 {
                        place_cabinet(&mut b, rng, &inner, &mut items, paint, 0.6);
                    } else if kind < 0.8 {
                        place_table(&mut b, rng, &inner, &mut items, paint);
                    } else {
                        place_box(&mut b, rng, &inner, &mut items, paint);
                    }
                }
                for _ in 0..config.posters_per_room {
                    if rng.random::<f64>() < 0.6 {
                        let paint =
                            b.material(SurfaceClass::Poster, uniform(rng, [0.05, 1.0]), 0.0);
                        place_poster(&mut b, rng, &inner, &keepouts, &glass_zones, paint);
                    }
                }
            }
            SpaceKind::Corridor => {
                if si == 0 {
                    for _ in 0..config.corridor_cabinets {
                        let depth_limit = s.height() - t - 1.4;
                        if depth_limit >= 0.35 {
                            let paint = furniture_paint(&mut b, rng);
                            place_cabinet(
                                &mut b,
                                rng,
                                &inner,
                                &mut items,
                                paint,
                                depth_limit.min(0.5),
                            );
                        }
                    }
                }
                let horizontal = s.width() >= s.height();
                let (along, across) = if horizontal {
                    (s.width(), s.height())
                } else {
                    (s.height(), s.width())
                };
                if config.column_spacing_m > 0.0 && across >= 3.5 {
                    let column = b.material(SurfaceClass::Column, uniform(rng, [0.4, 0.8]), 0.0);
                    let k = (along / config.column_spacing_m).floor() as usize;
                    for i in 1..k {
                        for frac in [0.25, 0.75] {
                            let a = i as f64 * along / k as f64;
                            let c = frac * across;
                            let center = if horizontal {
                                Point2::new(s.min[0] + a, s.min[1] + c)
                            } else {
                                Point2::new(s.min[0] + c, s.min[1] + a)
                            };
                            let r = uniform(rng, [0.2, 0.25]);
                            let bbox: Aabb =
                                ([center.x - r, center.y - r], [center.x + r, center.y + r]);
                            if items.iter().any(|o| overlaps(o, &bbox, 0.3)) {
                                continue;
                            }
                            items.push(bbox);
                            let corners: Vec<Point2<f64>> = (0..16)
                                .map(|j| {
                                    let ang = std::f64::consts::TAU * j as f64 / 16.0;
                                    center + Vector2::new(r * ang.cos(), r * ang.sin())
                                })
                                .collect();
                            for j in 0..16 {
                                b.segment(corners[j], corners[(j + 1) % 16], column);
                            }
                        }
                    }
                }
            }
        }
    }

    // Scenes.
    let mut builder = SceneBuilder2::new();
    for m in &b.materials {
        builder.add_surface(Surface {
            label: m.label,
            reflectivity: m.reflectivity as f32,
        });
    }
    for s in &b.segments {
        builder.add_segment(
            Point2::new(s.a[0], s.a[1]),
            Point2::new(s.b[0], s.b[1]),
            s.surface,
        );
    }
    let mut planning = builder.clone();
    for f in &b.footprints {
        let corners: Vec<Point2<f64>> = f.iter().map(|p| Point2::new(p[0], p[1])).collect();
        planning.add_polygon(&corners, facade);
    }
    Ok(World {
        config: config.clone(),
        spaces,
        doors,
        windows,
        materials: b.materials,
        segments: b.segments,
        footprints: b.footprints,
        scene: builder.build()?,
        planning_scene: planning.build()?,
    })
}

#[derive(Clone, Copy, Debug)]
struct Adjacent {
    low: usize,
    high: usize,
    horizontal: bool,
    coord: f64,
    span: [f64; 2],
}

/// The box of a wall of thickness `t` centred on `coord`, along `span`.
fn wall_box(horizontal: bool, coord: f64, span: [f64; 2], t: f64) -> Aabb {
    if horizontal {
        ([span[0], coord - t], [span[1], coord + t])
    } else {
        ([coord - t, span[0]], [coord + t, span[1]])
    }
}

/// Pairs of spaces that share a boundary of positive length; `low` is below/left of it.
fn adjacent_pairs(spaces: &[Space]) -> Vec<Adjacent> {
    let mut out = Vec::new();
    for (i, a) in spaces.iter().enumerate() {
        for (j, c) in spaces.iter().enumerate() {
            if i == j {
                continue;
            }
            // c is right of a.
            if (a.max[0] - c.min[0]).abs() < 1e-9 {
                let span = [a.min[1].max(c.min[1]), a.max[1].min(c.max[1])];
                if span[1] - span[0] > 1e-6 {
                    out.push(Adjacent {
                        low: i,
                        high: j,
                        horizontal: false,
                        coord: a.max[0],
                        span,
                    });
                }
            }
            // c is above a.
            if (a.max[1] - c.min[1]).abs() < 1e-9 {
                let span = [a.min[0].max(c.min[0]), a.max[0].min(c.max[0])];
                if span[1] - span[0] > 1e-6 {
                    out.push(Adjacent {
                        low: i,
                        high: j,
                        horizontal: true,
                        coord: a.max[1],
                        span,
                    });
                }
            }
        }
    }
    out
}
