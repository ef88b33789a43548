//! Furniture of the floor plans: cabinets against walls, tables (four legs, a footprint
//! for the robot), boxes at random angles, posters in front of walls.

use nalgebra::{Point2, Vector2};
use rand::Rng;
use raypath_geometry::Pose2;

use super::walls::{Aabb, Builder, inside, overlaps, uniform};
use crate::scene2::SurfaceId;

/// A cabinet flush against one side of `inner`.
pub(super) fn place_cabinet<R: Rng + ?Sized>(
    b: &mut Builder,
    rng: &mut R,
    inner: &Aabb,
    items: &mut Vec<Aabb>,
    surface: SurfaceId,
    max_depth: f64,
) {
    for _ in 0..30 {
        let side = rng.random_range(0..4);
        let depth = uniform(rng, [0.35, max_depth.max(0.35)]).min(max_depth);
        let length = uniform(rng, [0.8, 2.0]);
        let (ix0, iy0, ix1, iy1) = (inner.0[0], inner.0[1], inner.1[0], inner.1[1]);
        let gap = 0.02;
        let horizontal = side < 2;
        let along_len = if horizontal { ix1 - ix0 } else { iy1 - iy0 };
        if along_len < length + 0.2 {
            continue;
        }
        let start = rng.random_range(0.0..(along_len - length));
        let bbox: Aabb = match side {
            0 => (
                [ix0 + start, iy0 + gap],
                [ix0 + start + length, iy0 + gap + depth],
            ),
            1 => (
                [ix0 + start, iy1 - gap - depth],
                [ix0 + start + length, iy1 - gap],
            ),
            2 => (
                [ix0 + gap, iy0 + start],
                [ix0 + gap + depth, iy0 + start + length],
            ),
            _ => (
                [ix1 - gap - depth, iy0 + start],
                [ix1 - gap, iy0 + start + length],
            ),
        };
        if !inside(&bbox, inner) || items.iter().any(|o| overlaps(o, &bbox, 0.05)) {
            continue;
        }
        items.push(bbox);
        b.rect(bbox.0, bbox.1, [surface; 4]);
        return;
    }
}

/// A table (four legs) standing free with room around it, or against a wall.
pub(super) fn place_table<R: Rng + ?Sized>(
    b: &mut Builder,
    rng: &mut R,
    inner: &Aabb,
    items: &mut Vec<Aabb>,
    surface: SurfaceId,
) {
    for _ in 0..30 {
        let (mut lx, mut ly) = (uniform(rng, [1.2, 1.8]), uniform(rng, [0.7, 0.9]));
        if rng.random::<bool>() {
            std::mem::swap(&mut lx, &mut ly);
        }
        let (w, h) = (inner.1[0] - inner.0[0], inner.1[1] - inner.0[1]);
        if w < lx + 0.1 || h < ly + 0.1 {
            continue;
        }
        let x = inner.0[0] + 0.05 + rng.random_range(0.0..(w - lx - 0.1));
        let y = inner.0[1] + 0.05 + rng.random_range(0.0..(h - ly - 0.1));
        let bbox: Aabb = ([x, y], [x + lx, y + ly]);
        if items.iter().any(|o| overlaps(o, &bbox, 0.7)) {
            continue;
        }
        items.push(bbox);
        let leg = 0.05;
        for (cx, cy) in [
            (x + 0.05, y + 0.05),
            (x + lx - 0.05 - leg, y + 0.05),
            (x + 0.05, y + ly - 0.05 - leg),
            (x + lx - 0.05 - leg, y + ly - 0.05 - leg),
        ] {
            b.rect([cx, cy], [cx + leg, cy + leg], [surface; 4]);
        }
        b.footprints
            .push(vec![[x, y], [x + lx, y], [x + lx, y + ly], [x, y + ly]]);
        return;
    }
}

/// A box at a random angle.
pub(super) fn place_box<R: Rng + ?Sized>(
    b: &mut Builder,
    rng: &mut R,
    inner: &Aabb,
    items: &mut Vec<Aabb>,
    surface: SurfaceId,
) {
    for _ in 0..30 {
        let half = Vector2::new(uniform(rng, [0.2, 0.4]), uniform(rng, [0.2, 0.4]));
        let r = half.norm();
        let (w, h) = (inner.1[0] - inner.0[0], inner.1[1] - inner.0[1]);
        if w < 2.0 * r + 0.1 || h < 2.0 * r + 0.1 {
            continue;
        }
        let cx = inner.0[0] + r + 0.05 + rng.random_range(0.0..(w - 2.0 * r - 0.1));
        let cy = inner.0[1] + r + 0.05 + rng.random_range(0.0..(h - 2.0 * r - 0.1));
        let bbox: Aabb = ([cx - r, cy - r], [cx + r, cy + r]);
        if items.iter().any(|o| overlaps(o, &bbox, 0.5)) {
            continue;
        }
        items.push(bbox);
        let angle = rng.random_range(0.0..std::f64::consts::PI);
        b.oriented_rect(&Pose2::new(cx, cy, angle), half, surface);
        return;
    }
}

/// A poster 1 cm in front of a wall face of `inner`, away from doors.
pub(super) fn place_poster<R: Rng + ?Sized>(
    b: &mut Builder,
    rng: &mut R,
    inner: &Aabb,
    keepouts: &[Aabb],
    glass_zones: &[Aabb],
    surface: SurfaceId,
) {
    for _ in 0..20 {
        let side = rng.random_range(0..4);
        let length = uniform(rng, [0.5, 1.2]);
        let (ix0, iy0, ix1, iy1) = (inner.0[0], inner.0[1], inner.1[0], inner.1[1]);
        let horizontal = side < 2;
        let along_len = if horizontal { ix1 - ix0 } else { iy1 - iy0 };
        if along_len < length + 0.4 {
            continue;
        }
        let s = rng.random_range(0.2..(along_len - length - 0.2));
        let off = 0.01;
        let (a, c) = match side {
            0 => (
                Point2::new(ix0 + s, iy0 + off),
                Point2::new(ix0 + s + length, iy0 + off),
            ),
            1 => (
                Point2::new(ix0 + s, iy1 - off),
                Point2::new(ix0 + s + length, iy1 - off),
            ),
            2 => (
                Point2::new(ix0 + off, iy0 + s),
                Point2::new(ix0 + off, iy0 + s + length),
            ),
            _ => (
                Point2::new(ix1 - off, iy0 + s),
                Point2::new(ix1 - off, iy0 + s + length),
            ),
        };
        let bbox: Aabb = ([a.x.min(c.x), a.y.min(c.y)], [a.x.max(c.x), a.y.max(c.y)]);
        if keepouts
            .iter()
            .chain(glass_zones)
            .any(|o| overlaps(o, &bbox, 0.05))
        {
            continue;
        }
        b.segment(a, c, surface);
        return;
    }
}
