//! Street furniture: street lights, trees, sign posts and bollards along the sides of the
//! street segments, and the parking slots along their curbs (see [`streets`](super::streets)
//! for the distributions).

use nalgebra::{Point2, Vector2};
use rand::Rng;

use super::kinds::{Canopy, Pole, PoleKind};
use super::streets::{ParkingSlot, StreetConfig, StreetGrid, sample};
use super::world::{PoleObject, World};
use crate::rng::SimRng;

/// One side of a street segment between two intersections.
pub(crate) struct StreetSide {
    /// Segment start and end on the street centre line (beyond the cross streets' sidewalks).
    pub(crate) from: Point2<f64>,
    pub(crate) to: Point2<f64>,
    /// Unit normal from the centre line towards this side.
    pub(crate) normal: Vector2<f64>,
    pub(crate) half_width: f64,
    pub(crate) sidewalk: f64,
}

/// Both sides of every street segment between neighbouring intersections.
pub(crate) fn street_sides(grid: &StreetGrid) -> Vec<StreetSide> {
    let mut sides = Vec::new();
    let mut push =
        |from: Point2<f64>, to: Point2<f64>, half: f64, sidewalk: f64, cut0: f64, cut1: f64| {
            let dir = (to - from).normalize();
            let (a, b) = (from + dir * cut0, to - dir * cut1);
            if (b - a).dot(&dir) < 10.0 {
                return;
            }
            for normal in [Vector2::new(-dir.y, dir.x), Vector2::new(dir.y, -dir.x)] {
                sides.push(StreetSide {
                    from: a,
                    to: b,
                    normal,
                    half_width: half,
                    sidewalk,
                });
            }
        };
    for (i, &x) in grid.xs.iter().enumerate() {
        for j in 0..grid.ys.len().saturating_sub(1) {
            let cut0 = grid.half_widths_y[j] + grid.sidewalks_y[j];
            let cut1 = grid.half_widths_y[j + 1] + grid.sidewalks_y[j + 1];
            push(
                Point2::new(x, grid.ys[j]),
                Point2::new(x, grid.ys[j + 1]),
                grid.half_widths_x[i],
                grid.sidewalks_x[i],
                cut0,
                cut1,
            );
        }
    }
    for (j, &y) in grid.ys.iter().enumerate() {
        for i in 0..grid.xs.len().saturating_sub(1) {
            let cut0 = grid.half_widths_x[i] + grid.sidewalks_x[i];
            let cut1 = grid.half_widths_x[i + 1] + grid.sidewalks_x[i + 1];
            push(
                Point2::new(grid.xs[i], y),
                Point2::new(grid.xs[i + 1], y),
                grid.half_widths_y[j],
                grid.sidewalks_y[j],
                cut0,
                cut1,
            );
        }
    }
    sides
}

/// Adds a pole unless it would stand within 1 m of another one; returns whether it was added.
fn try_add_pole(
    world: &mut World,
    kind: PoleKind,
    at: Point2<f64>,
    base_z: f64,
    yaw_rad: f64,
    rng: &mut SimRng,
) -> bool {
    if world
        .poles
        .iter()
        .rev()
        .take(64)
        .any(|p| (Point2::new(p.pole.x, p.pole.y) - at).norm() < 1.0)
    {
        return false;
    }
    let (radius_m, height_m) = kind.sample_size(rng);
    let attachment_m = match kind {
        PoleKind::StreetLight => sample(rng, (1.0, 2.5)),
        PoleKind::SignPost => sample(rng, (0.4, 0.9)),
        _ => 0.0,
    };
    let canopy = (kind == PoleKind::TreeTrunk).then(|| Canopy::sample(radius_m, rng));
    world.poles.push(PoleObject {
        pole: Pole {
            id: world.poles.len() as u32,
            kind,
            x: at.x,
            y: at.y,
            base_z,
            radius_m,
            height_m,
        },
        yaw_rad,
        attachment_m,
        canopy,
    });
    true
}

/// Street lights, trees, sign posts and bollards along one street side.
pub(crate) fn furnish_street_side(
    world: &mut World,
    config: &StreetConfig,
    side: &StreetSide,
    rng: &mut SimRng,
) {
    let dir = (side.to - side.from).normalize();
    let len = (side.to - side.from).norm();
    let z = config.curb_height_m;
    let at = |t: f64, offset: f64| side.from + dir * t + side.normal * (side.half_width + offset);
    let towards_road = (-side.normal.y).atan2(-side.normal.x);
    // Traffic on this side drives with the side on its right: it approaches `to` when the
    // normal is to the right of `dir`.
    let right_of_dir = Vector2::new(dir.y, -dir.x);
    let traffic = if side.normal.dot(&right_of_dir) > 0.0 {
        dir
    } else {
        -dir
    };
    let facing_traffic = (-traffic.y).atan2(-traffic.x);
    // Street lights (both sides or one, decided by the side's stream).
    let mut lights = Vec::new();
    if rng.random_bool(0.7) {
        let mut t = sample(rng, (2.0, 15.0));
        while t < len - 2.0 {
            if try_add_pole(
                world,
                PoleKind::StreetLight,
                at(t, 0.5),
                z,
                towards_road,
                rng,
            ) {
                lights.push(t);
            }
            t += sample(rng, config.street_light_spacing_m);
        }
    }
    // Trees in the sidewalk, away from the lights.
    if rng.random_bool(config.tree_side_probability) {
        let offset = (side.sidewalk / 2.0).max(1.0);
        let mut t = sample(rng, (3.0, 8.0));
        while t < len - 3.0 {
            if lights.iter().all(|l| (l - t).abs() > 3.0) {
                try_add_pole(world, PoleKind::TreeTrunk, at(t, offset), z, 0.0, rng);
            }
            t += sample(rng, config.tree_spacing_m);
        }
    }
    // Sign posts before the intersection traffic on this side approaches, and at random.
    if rng.random_bool(0.5) {
        let d = sample(rng, (3.0, 8.0));
        let t = if traffic == dir { len - d } else { d };
        try_add_pole(
            world,
            PoleKind::SignPost,
            at(t, 0.4),
            z,
            facing_traffic,
            rng,
        );
    }
    let expected = config.sign_posts_per_km * len / 1000.0;
    let count = expected.floor() as usize + usize::from(rng.random_bool(expected.fract()));
    for _ in 0..count {
        let t = sample(rng, (2.0, len - 2.0));
        try_add_pole(
            world,
            PoleKind::SignPost,
            at(t, 0.4),
            z,
            facing_traffic,
            rng,
        );
    }
    // A group of bollards.
    if rng.random_bool(config.bollard_group_probability) {
        let n = rng.random_range(3..=6);
        let spacing = sample(rng, (1.2, 1.8));
        let t0 = sample(rng, (2.0, (len - 2.0 - spacing * n as f64).max(2.0 + 1e-9)));
        for k in 0..n {
            try_add_pole(
                world,
                PoleKind::Bollard,
                at(t0 + spacing * k as f64, 0.3),
                z,
                0.0,
                rng,
            );
        }
    }
}

/// Parking slots along the curb of a street side, 6 m apart, none within 8 m of the ends.
pub(crate) fn parking_slots(side: &StreetSide) -> Vec<ParkingSlot> {
    let dir = (side.to - side.from).normalize();
    let len = (side.to - side.from).norm();
    let right_of_dir = Vector2::new(dir.y, -dir.x);
    let forward = if side.normal.dot(&right_of_dir) > 0.0 {
        dir
    } else {
        -dir
    };
    let yaw_rad = forward.y.atan2(forward.x);
    let mut slots = Vec::new();
    let mut t = 8.0;
    while t < len - 8.0 {
        slots.push(ParkingSlot {
            center: side.from + dir * t + side.normal * (side.half_width - 1.1),
            yaw_rad,
            base_z: 0.0,
        });
        t += 6.0;
    }
    slots
}
