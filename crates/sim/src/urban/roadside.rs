//! The roadside of a semi-synthetic world: road edges, sidewalks, facades and parked cars
//! along each side of the trajectory (see [`along_path`](super::along_path)).

use nalgebra::{Point2, Vector2};
use rand::Rng;

use super::along_path::Scenery;
use super::path_index::Context;
use super::streets::sample;
use super::world::{Building, Car, Footprint, Slab, SlabKind, World};
use crate::rng::SimRng;

/// Road edge offset of sample `i` on `side` (+1 left, −1 right): the configured one, closer
/// where a pole stands in the way.
pub(crate) fn road_edge(ctx: &mut Context<'_>, scenery: &Scenery, i: usize, side: f64) -> f64 {
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
pub(crate) fn line_side(
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
pub(crate) fn park_side(
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
