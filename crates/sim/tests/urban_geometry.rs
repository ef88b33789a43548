//! Urban worlds: ray hits on poles and facades against analytic answers, the layout's
//! invariants, routes, odometry noise statistics and session changes.

// Test helpers (outside #[test] functions) panic on setup failures too.
#![allow(clippy::unwrap_used)]

use std::f64::consts::{PI, TAU};

use nalgebra::{Point2, Point3, Unit, Vector3};
use rand::Rng;
use raypath_geometry::Pose2;
use raypath_sim::rng;
use raypath_sim::urban::kinds::label;
use raypath_sim::urban::mesh::{equal_area_radius, facets_for_radius};
use raypath_sim::urban::route::{self, DriveConfig, SpeedProfile};
use raypath_sim::urban::sessions::session_worlds;
use raypath_sim::urban::world::{Building, Footprint, Ground, PoleObject};
use raypath_sim::urban::{
    OdometryNoise, Pole, PoleKind, SessionChanges, StreetConfig, World, generate_layout, odometry,
};

fn empty_world() -> World {
    World {
        ground: Ground::Flat {
            min: Point2::new(-50.0, -50.0),
            max: Point2::new(50.0, 50.0),
            z: 0.0,
        },
        slabs: vec![],
        buildings: vec![],
        poles: vec![],
        cars: vec![],
        fences: vec![],
        barrels: vec![],
        foliage: 1.0,
        mesh_seed: 1,
    }
}

fn pole(kind: PoleKind, x: f64, y: f64, radius_m: f64, height_m: f64) -> PoleObject {
    PoleObject {
        pole: Pole {
            id: 0,
            kind,
            x,
            y,
            base_z: 0.0,
            radius_m,
            height_m,
        },
        yaw_rad: 0.0,
        attachment_m: 0.0,
        canopy: None,
    }
}

#[test]
fn rays_hit_a_pole_on_its_cylinder() {
    let (cx, cy, r) = (10.0, 2.0, 0.12);
    let mut world = empty_world();
    world.poles.push(pole(PoleKind::Bollard, cx, cy, r, 3.0));
    let scene = world.build_scene().unwrap();
    let n = facets_for_radius(r);
    let rv = equal_area_radius(r, n);
    // The facets lie between the apothem and the vertex radius; the equal-area prism's
    // mean radius is within 3 % of the true one.
    assert!(rv * (PI / n as f64).cos() < r && r < rv && (rv - r) / r < 0.03);
    let mut rng = rng::stream(3, 3, 3);
    let mut mean_axis_distance = 0.0;
    let trials = 2000;
    for _ in 0..trials {
        let origin = Point3::new(0.0, rng.random_range(-1.0..1.0), rng.random_range(0.2..2.5));
        let target = Point3::new(cx, cy + rng.random_range(-0.5..0.5) * r, origin.z);
        let dir = Unit::new_normalize(target - origin);
        let hit = scene.cast(&origin, &dir, 100.0).unwrap();
        let p = origin + dir.into_inner() * hit.range_m;
        let axis_distance = (p.x - cx).hypot(p.y - cy);
        assert!(
            axis_distance >= rv * (PI / n as f64).cos() - 1e-9 && axis_distance <= rv + 1e-9,
            "{axis_distance}"
        );
        let s = scene.surface(hit.surface).unwrap();
        assert_eq!(label::class(s.label), label::POLE);
        assert_eq!(label::instance(s.label), 1);
        mean_axis_distance += axis_distance / trials as f64;
        // The analytic cylinder hit: the near root of |o + t d − c|² = r² (horizontal).
        let (ox, oy) = (origin.x - cx, origin.y - cy);
        let (dx, dy) = (dir.x, dir.y);
        let a = dx * dx + dy * dy;
        let b = 2.0 * (ox * dx + oy * dy);
        let c = ox * ox + oy * oy - r * r;
        let disc = b * b - 4.0 * a * c;
        if disc > 0.0 {
            let t = (-b - disc.sqrt()) / (2.0 * a);
            assert!((hit.range_m - t).abs() < 0.1 * r, "{} vs {t}", hit.range_m);
        }
    }
    assert!(
        (mean_axis_distance - r).abs() < 0.03 * r,
        "{mean_axis_distance}"
    );
    // Above the pole the ray passes.
    let over = scene.cast(&Point3::new(0.0, cy, 3.2), &Vector3::x_axis(), 100.0);
    assert!(over.is_none_or(|h| scene.surface(h.surface).unwrap().label == label::ROAD));
}

#[test]
fn rays_hit_a_facade_on_its_plane() {
    let mut world = empty_world();
    // Front (the −width side) at y = 10, facing −y; 20 m long, 12 m high.
    world.buildings.push(Building {
        footprint: Footprint {
            center: Point2::new(0.0, 15.0),
            yaw_rad: 0.0,
            half_length_m: 10.0,
            half_width_m: 5.0,
        },
        base_z: 0.0,
        height_m: 12.0,
        ground_floor_recess_m: 2.0,
        ground_floor_height_m: 4.0,
        top_floor_height_m: 0.0,
        material: 3,
    });
    let scene = world.build_scene().unwrap();
    let origin = Point3::new(1.0, 0.0, 1.73);
    let mut rng = rng::stream(4, 4, 4);
    for _ in 0..500 {
        // Rays at the upper floors (z from 5 to 11 m at the facade) hit the plane y = 10.
        let x = rng.random_range(-7.0..7.0);
        let z = rng.random_range(5.0..11.0);
        let dir = Unit::new_normalize(Point3::new(x, 10.0, z) - origin);
        let hit = scene.cast(&origin, &dir, 100.0).expect("upper floors");
        let expected = 10.0 / dir.y;
        assert!(
            (hit.range_m - expected).abs() < 1e-9,
            "{} {expected}",
            hit.range_m
        );
        assert!((hit.normal.y + 1.0).abs() < 1e-9);
        assert_eq!(scene.surface(hit.surface).unwrap().label, label::BUILDING);
        // The recessed ground floor is 2 m further back.
        let dir = Unit::new_normalize(Point3::new(x, 10.0, 1.73) - origin);
        let hit = scene.cast(&origin, &dir, 100.0).expect("ground floor");
        assert!((hit.range_m - 12.0 / dir.y).abs() < 1e-9);
    }
}

#[test]
fn layout_keeps_poles_free_and_out_of_buildings() {
    let layout = generate_layout(&StreetConfig::quick(), 11).unwrap();
    let world = &layout.world;
    let counts = world.pole_counts();
    assert!(counts.iter().all(|&c| c > 5), "{counts:?}");
    for (i, a) in world.poles.iter().enumerate() {
        let pa = Point2::new(a.pole.x, a.pole.y);
        // Sizes within the documented distributions.
        let (r, h) = (a.pole.radius_m, a.pole.height_m);
        let ok = match a.pole.kind {
            PoleKind::StreetLight => (0.08..=0.15).contains(&r) && (6.0..=10.0).contains(&h),
            PoleKind::SignPost => (0.03..=0.05).contains(&r) && (2.0..=3.0).contains(&h),
            PoleKind::TreeTrunk => (0.1..=0.4).contains(&r) && (2.0..=4.0).contains(&h),
            PoleKind::Bollard => (0.05..=0.1).contains(&r) && (0.8..=1.2).contains(&h),
        };
        assert!(ok, "{a:?}");
        assert_eq!(a.canopy.is_some(), a.pole.kind == PoleKind::TreeTrunk);
        for b in &world.poles[i + 1..] {
            assert!((Point2::new(b.pole.x, b.pole.y) - pa).norm() >= 1.0);
        }
        for building in &world.buildings {
            assert!(
                building.footprint.distance(&pa) > 1.0,
                "{a:?} in {building:?}"
            );
        }
        // On a sidewalk slab, not on the road.
        assert!(world.slabs.iter().any(|s| s.footprint.distance(&pa) == 0.0));
    }
    // Parking slots are on the road, off the sidewalks.
    for slot in &layout.parking {
        assert!(
            world
                .slabs
                .iter()
                .all(|s| s.footprint.distance(&slot.center) > 0.0)
        );
    }
}

#[test]
fn routes_are_smooth_and_stay_in_the_lane() {
    let layout = generate_layout(&StreetConfig::quick(), 5).unwrap();
    let grid = &layout.grid;
    let drive = DriveConfig::default();
    let mut rng = rng::stream(5, 5, 5);
    let nodes = route::random_route(grid, (1, 1), 800.0, &mut rng);
    assert!(nodes.windows(3).all(|w| w[0] != w[2]), "no U-turns");
    let path = route::lane_path(grid, &nodes, &drive, &mut rng).unwrap();
    let profile = SpeedProfile::new(&path, &drive);
    let states = route::sample_states(&path, &profile, 0.1, (profile.duration_s() * 10.0) as usize);
    assert!(states.len() > 100);
    for w in states.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let step = (b.pose.translation() - a.pose.translation()).norm();
        assert!(step <= drive.speed_m_s.1 * 0.1 + 1e-6, "{step}");
        let turn = raypath_geometry::wrap_angle(b.pose.theta() - a.pose.theta()).abs();
        assert!(
            turn <= step / drive.turn_radius_m * 1.01 + 1e-6,
            "{turn} over {step} m"
        );
        let accel = (b.speed_m_s - a.speed_m_s).abs() / 0.1;
        assert!(
            accel <= drive.longitudinal_accel_m_s2 * 1.05 + 0.05,
            "{accel}"
        );
    }
    for s in &states {
        assert!(s.speed_m_s <= drive.speed_m_s.1 + 1e-9);
        // On the road: off every sidewalk slab.
        let p = Point2::new(s.pose.x(), s.pose.y());
        assert!(
            layout
                .world
                .slabs
                .iter()
                .all(|slab| slab.footprint.distance(&p) > 0.5),
            "{p}"
        );
    }
}

#[test]
fn odometry_noise_has_the_configured_statistics() {
    // A straight drive at 10 m/s sampled at 100 Hz: steps of 0.1 m.
    let truth: Vec<Pose2> = (0..20_001)
        .map(|i| Pose2::new(0.1 * i as f64, 0.0, 0.0))
        .collect();
    let noise = OdometryNoise {
        longitudinal_per_m: 0.02,
        lateral_per_m: 0.01,
        heading_per_rad: 0.0,
        heading_per_m_rad: 0.001,
    };
    let odo = odometry::simulate(&truth, &noise, &mut rng::stream(6, 6, 6));
    let mut errors = [Vec::new(), Vec::new(), Vec::new()];
    for k in 1..truth.len() {
        let (step, var) = odo.between(k - 1, k).unwrap();
        errors[0].push(step.x() - 0.1);
        errors[1].push(step.y());
        errors[2].push(step.theta());
        assert!((var[0] - (0.002f64).powi(2)).abs() < 1e-15);
    }
    for (e, sigma) in errors.iter().zip([0.002, 0.001, 1e-4]) {
        let n = e.len() as f64;
        let mean = e.iter().sum::<f64>() / n;
        let std = (e.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        assert!((std / sigma - 1.0).abs() < 0.03, "std {std} vs {sigma}");
        assert!(mean.abs() < 4.0 * sigma / n.sqrt());
    }
    // Noise-free odometry integrates to the truth relative to the start.
    let exact = odometry::simulate(&truth, &OdometryNoise::none(), &mut rng::stream(6, 6, 7));
    let last = exact.poses.last().unwrap();
    assert!((last.x() - 2000.0).abs() < 1e-6 && last.y().abs() < 1e-9);
}

#[test]
fn sessions_change_the_world_consistently() {
    let layout = generate_layout(&StreetConfig::quick(), 8).unwrap();
    let changes = SessionChanges {
        sign_post_removal: 0.2,
        sign_post_move: 0.2,
        new_sign_posts: 0.2,
        ..SessionChanges::default()
    };
    let sessions = session_worlds(&layout, &[1, 7, 2], &changes, 8);
    assert_eq!(sessions.len(), 3);
    assert_eq!(sessions[0].0.poles, layout.world.poles);
    assert!((sessions[0].1.foliage - 0.6).abs() < 1e-12 && sessions[1].1.foliage == 1.0);
    for k in 1..3 {
        let (before, after, log) = (&sessions[k - 1].0, &sessions[k].0, &sessions[k].1);
        assert!(!log.removed.is_empty() && !log.moved.is_empty() && !log.added.is_empty());
        let ids_before: Vec<u32> = before.poles.iter().map(|p| p.pole.id).collect();
        let ids_after: Vec<u32> = after.poles.iter().map(|p| p.pole.id).collect();
        for id in &log.removed {
            assert!(ids_before.contains(id) && !ids_after.contains(id));
        }
        for id in &log.added {
            assert!(!ids_before.contains(id) && ids_after.contains(id));
        }
        assert_eq!(
            ids_after.len(),
            ids_before.len() - log.removed.len() + log.added.len()
        );
        for (id, distance) in &log.moved {
            let a = before.poles.iter().find(|p| p.pole.id == *id).unwrap().pole;
            let b = after.poles.iter().find(|p| p.pole.id == *id).unwrap().pole;
            let moved = (a.x - b.x).hypot(a.y - b.y);
            assert!((moved - distance).abs() < 1e-9 && (0.5..=3.0).contains(distance));
        }
        // Street lights never change; parked cars do.
        let lights = |w: &World| {
            w.poles
                .iter()
                .filter(|p| p.pole.kind == PoleKind::StreetLight)
                .map(|p| p.pole)
                .collect::<Vec<_>>()
        };
        assert_eq!(lights(before), lights(after));
        assert_ne!(before.cars, after.cars);
    }
    // Barrels exist in the first session along the zone, and shift later.
    assert!(!sessions[0].0.barrels.is_empty());
    assert_eq!(sessions[0].1.barrel_shifts_m, vec![Some(0.0)]);
    let _ = TAU;
}
