//! Sessions of one world recorded months apart, with the changes long-term localization has to
//! cope with (Schaefer 2020, ch. 12; the NCLT sessions span 15 months): parked cars differ in
//! every session, sign posts and bollards are removed, moved or added, trees are cut, the
//! barrels of construction zones are shifted sideways by metres (or gone), and tree crowns
//! follow the seasons. Changes accumulate: a removed pole stays removed.

use nalgebra::{Point2, Vector2};
use rand::Rng;

use super::kinds::PoleKind;
use super::streets::{ConstructionZone, ParkingSlot, UrbanLayout, sample};
use super::world::{Barrel, Car, Footprint, PoleObject, World};
use crate::rng::{self, SimRng};

const DOMAIN_SESSION: u64 = 0x5552_4253_4553_5331;
const DOMAIN_CARS: u64 = 0x5552_4243_4152_5331;

/// How much changes between consecutive sessions. Fractions are per session.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SessionChanges {
    /// Probability that a parking slot is occupied, drawn per session from this range.
    pub parking_occupancy: (f64, f64),
    /// Fraction of sign posts removed.
    pub sign_post_removal: f64,
    /// Fraction of bollards removed.
    pub bollard_removal: f64,
    /// Fraction of trees cut.
    pub tree_removal: f64,
    /// Fraction of sign posts moved along the street.
    pub sign_post_move: f64,
    /// Distance of a move, metres.
    pub move_distance_m: (f64, f64),
    /// New sign posts, as a fraction of the current number of sign posts.
    pub new_sign_posts: f64,
    /// Sideways shift of a construction zone's barrels, metres (either direction).
    pub barrel_shift_m: (f64, f64),
    /// Probability that a construction zone has no barrels in a later session.
    pub barrels_absent_probability: f64,
}

impl Default for SessionChanges {
    fn default() -> Self {
        Self {
            parking_occupancy: (0.3, 0.75),
            sign_post_removal: 0.03,
            bollard_removal: 0.05,
            tree_removal: 0.01,
            sign_post_move: 0.03,
            move_distance_m: (0.5, 3.0),
            new_sign_posts: 0.03,
            barrel_shift_m: (1.0, 3.5),
            barrels_absent_probability: 0.2,
        }
    }
}

/// What changed in a session with respect to the previous one.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ChangeLog {
    /// Ids of poles removed.
    pub removed: Vec<u32>,
    /// Ids of poles moved, with the distance in metres.
    pub moved: Vec<(u32, f64)>,
    /// Ids of poles added.
    pub added: Vec<u32>,
    /// Parked cars in this session.
    pub parked_cars: usize,
    /// Sideways shift of each construction zone's barrels, metres (`None`: no barrels).
    pub barrel_shifts_m: Vec<Option<f64>>,
    /// Leaf factor of the tree crowns.
    pub foliage: f64,
}

/// Leaf factor of deciduous street trees in `month` (1–12) on the northern hemisphere: 0.6
/// from December to March (bare crowns appear smaller), 1 from June to September, linear in
/// between.
pub fn foliage_for_month(month: u32) -> f64 {
    match month {
        12 | 1..=3 => 0.6,
        4 => 0.73,
        5 => 0.87,
        6..=9 => 1.0,
        10 => 0.87,
        _ => 0.73,
    }
}

/// The worlds of consecutive sessions recorded in `months` (1–12 each), with their changes.
/// Session 0 is the layout with cars and barrels; later sessions change step by step.
pub fn session_worlds(
    layout: &UrbanLayout,
    months: &[u32],
    changes: &SessionChanges,
    seed: u64,
) -> Vec<(World, ChangeLog)> {
    session_worlds_of(
        &layout.world,
        &layout.parking,
        &layout.construction,
        months,
        changes,
        seed,
    )
}

/// [`session_worlds`] of a static world (no cars or barrels) with its parking slots and
/// construction zones, for worlds not built from a street grid.
pub(crate) fn session_worlds_of(
    base: &World,
    parking: &[ParkingSlot],
    construction: &[ConstructionZone],
    months: &[u32],
    changes: &SessionChanges,
    seed: u64,
) -> Vec<(World, ChangeLog)> {
    let mut out: Vec<(World, ChangeLog)> = Vec::with_capacity(months.len());
    let mut poles = base.poles.clone();
    let mut next_id = poles.iter().map(|p| p.pole.id + 1).max().unwrap_or(0);
    for (k, &month) in months.iter().enumerate() {
        let mut rng = rng::stream(seed, DOMAIN_SESSION, k as u64);
        let mut log = ChangeLog {
            foliage: foliage_for_month(month),
            ..ChangeLog::default()
        };
        if k > 0 {
            change_poles(&mut poles, &mut next_id, changes, &mut rng, &mut log);
        }
        let mut world = base.clone();
        world.poles = poles.clone();
        world.foliage = log.foliage;
        let mut car_rng = rng::stream(seed, DOMAIN_CARS, k as u64);
        world.cars = park_cars(parking, changes, &mut car_rng);
        log.parked_cars = world.cars.len();
        for zone in construction {
            let shift = if k == 0 {
                Some(0.0)
            } else if rng.random_bool(changes.barrels_absent_probability) {
                None
            } else {
                let s = sample(&mut rng, changes.barrel_shift_m);
                Some(if rng.random_bool(0.5) { s } else { -s })
            };
            log.barrel_shifts_m.push(shift);
            let Some(shift) = shift else { continue };
            let n = (zone.length_m / 2.5).floor() as usize + 1;
            for i in 0..n {
                let along = i as f64 * 2.5 + sample(&mut rng, (-0.3, 0.3));
                let center = zone.start + zone.direction * along + zone.towards_curb * shift;
                world.barrels.push(Barrel {
                    center,
                    base_z: zone.base_z,
                    radius_m: 0.29,
                    height_m: 1.05,
                });
            }
        }
        out.push((world, log));
    }
    out
}

fn change_poles(
    poles: &mut Vec<PoleObject>,
    next_id: &mut u32,
    changes: &SessionChanges,
    rng: &mut SimRng,
    log: &mut ChangeLog,
) {
    poles.retain(|p| {
        let fraction = match p.pole.kind {
            PoleKind::SignPost => changes.sign_post_removal,
            PoleKind::Bollard => changes.bollard_removal,
            PoleKind::TreeTrunk => changes.tree_removal,
            PoleKind::StreetLight => 0.0,
        };
        let remove = fraction > 0.0 && rng.random_bool(fraction.min(1.0));
        if remove {
            log.removed.push(p.pole.id);
        }
        !remove
    });
    let positions: Vec<Point2<f64>> = poles
        .iter()
        .map(|p| Point2::new(p.pole.x, p.pole.y))
        .collect();
    let free = |at: Point2<f64>, skip: Option<usize>, positions: &[Point2<f64>]| {
        positions
            .iter()
            .enumerate()
            .all(|(i, q)| Some(i) == skip || (q - at).norm() >= 1.0)
    };
    let mut positions = positions;
    for i in 0..poles.len() {
        let p = poles[i];
        if p.pole.kind != PoleKind::SignPost || !rng.random_bool(changes.sign_post_move.min(1.0)) {
            continue;
        }
        let d =
            sample(rng, changes.move_distance_m) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let along = Vector2::new(p.yaw_rad.cos(), p.yaw_rad.sin());
        let to = Point2::new(p.pole.x, p.pole.y) + along * d;
        if free(to, Some(i), &positions) {
            poles[i].pole.x = to.x;
            poles[i].pole.y = to.y;
            positions[i] = to;
            log.moved.push((p.pole.id, d.abs()));
        }
    }
    let signs = poles
        .iter()
        .filter(|p| p.pole.kind == PoleKind::SignPost)
        .count();
    let expected = changes.new_sign_posts * signs as f64;
    let count = expected.floor() as usize + usize::from(rng.random_bool(expected.fract()));
    for _ in 0..count {
        // Next to an existing street light or sign post, along the street.
        let anchors: Vec<usize> = (0..poles.len())
            .filter(|&i| {
                matches!(
                    poles[i].pole.kind,
                    PoleKind::SignPost | PoleKind::StreetLight
                )
            })
            .collect();
        if anchors.is_empty() {
            break;
        }
        let a = poles[anchors[rng.random_range(0..anchors.len())]];
        let along_yaw = match a.pole.kind {
            PoleKind::StreetLight => a.yaw_rad + std::f64::consts::FRAC_PI_2,
            _ => a.yaw_rad,
        };
        let d = sample(rng, (3.0, 10.0)) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let to =
            Point2::new(a.pole.x, a.pole.y) + Vector2::new(along_yaw.cos(), along_yaw.sin()) * d;
        if !free(to, None, &positions) {
            continue;
        }
        let (radius_m, height_m) = PoleKind::SignPost.sample_size(rng);
        let mut object = a;
        object.pole.id = *next_id;
        object.pole.kind = PoleKind::SignPost;
        object.pole.x = to.x;
        object.pole.y = to.y;
        object.pole.radius_m = radius_m;
        object.pole.height_m = height_m;
        object.yaw_rad = if a.pole.kind == PoleKind::SignPost {
            a.yaw_rad
        } else {
            along_yaw
        };
        object.attachment_m = sample(rng, (0.4, 0.9));
        object.canopy = None;
        log.added.push(*next_id);
        *next_id += 1;
        positions.push(to);
        poles.push(object);
    }
}

/// Cars in a random subset of the parking slots.
fn park_cars(parking: &[ParkingSlot], changes: &SessionChanges, rng: &mut SimRng) -> Vec<Car> {
    let occupancy = sample(rng, changes.parking_occupancy).clamp(0.0, 1.0);
    let mut cars = Vec::new();
    for slot in parking {
        if !rng.random_bool(occupancy) {
            continue;
        }
        let (s, c) = slot.yaw_rad.sin_cos();
        let (along, across) = (sample(rng, (-0.5, 0.5)), sample(rng, (-0.15, 0.15)));
        let center = slot.center + Vector2::new(c * along - s * across, s * along + c * across);
        let length = sample(rng, (3.8, 5.0));
        cars.push(Car {
            footprint: Footprint {
                center,
                yaw_rad: slot.yaw_rad + sample(rng, (-0.035, 0.035)),
                half_length_m: length / 2.0,
                half_width_m: sample(rng, (1.7, 1.95)) / 2.0,
            },
            base_z: slot.base_z,
            height_m: sample(rng, (1.4, 1.75)),
            reflectivity: rng.random_range(0.1..0.7),
        });
    }
    cars
}
