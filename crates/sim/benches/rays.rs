//! Simulated rays per second (Criterion `Throughput::Elements` = rays cast per scan).
//!
//! Workloads:
//! * `street/hdl64e`: an HDL-64E (64 × 2083 beams) 1.73 m above a 200 m street built here from
//!   boxes and cylinders: road and sidewalks, facades of varying height on both sides, poles,
//!   tree trunks with box canopies and parked cars (body + cabin).
//! * `urban/hdl64e`: an HDL-64E 1.73 m above the road in the middle of a street of the
//!   procedural urban world (`raypath_sim::urban`, default 5 × 4 blocks, one session: buildings,
//!   poles, trees with canopies, parked cars, fences) — the workload of the KITTI-style sets.
//! * `synpeb/500x500`: the organized 500 × 500 scanner of the SynPEB-style generator in one of
//!   its rooms (≈ 6 × 7 × 3 m with polyhedral objects).
//!
//! * `urban/cast-bvh` and `urban/cast-parry-trimesh`: ray casting alone (no noise, intensity or
//!   output) of the HDL-64E's beams in the urban scene, with the simulator's own BVH
//!   (`Scene3::cast`) and with parry3d's `TriMesh` over the same triangles — the comparison
//!   that decided for the own BVH.
//!
//! Each scan is run on one thread (a one-thread rayon pool) and on all cores (the global pool).
//! Run with `cargo bench -p raypath-sim --bench rays`.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_main};
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use raypath_geometry::Pose3;
use raypath_sim::lidar3::Lidar3;
use raypath_sim::scene3::{Scene3, SceneBuilder3, Surface};
use raypath_sim::synpeb::{self, SynpebConfig};
use raypath_sim::urban::sessions::session_worlds;
use raypath_sim::urban::{StreetConfig, generate_layout};

/// A straight 200 m street along x: road, sidewalks, facades, poles, trees and parked cars.
fn street_scene() -> Scene3 {
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let mut b = SceneBuilder3::new();
    let surface = |b: &mut SceneBuilder3, label: u32, reflectivity: f32| {
        b.add_surface(Surface {
            label,
            reflectivity,
        })
    };
    let road = surface(&mut b, 1, 0.15);
    let walk = surface(&mut b, 2, 0.3);
    let facade = surface(&mut b, 3, 0.45);
    let pole = surface(&mut b, 4, 0.6);
    let trunk = surface(&mut b, 5, 0.25);
    let canopy = surface(&mut b, 6, 0.35);
    let car = surface(&mut b, 7, 0.7);
    let half_len = 100.0;
    let slab = |b: &mut SceneBuilder3, y0: f64, y1: f64, z: f64, s| {
        b.add_polygon(
            &[
                Point3::new(-half_len, y0, z),
                Point3::new(half_len, y0, z),
                Point3::new(half_len, y1, z),
                Point3::new(-half_len, y1, z),
            ],
            s,
        );
    };
    slab(&mut b, -5.0, 5.0, 0.0, road);
    slab(&mut b, 5.0, 9.0, 0.15, walk);
    slab(&mut b, -9.0, -5.0, 0.15, walk);
    for side in [-1.0, 1.0] {
        // Facades: buildings 8–25 m wide and 6–20 m high, set back 9–11 m.
        let mut x = -half_len;
        while x < half_len {
            let width: f64 = rng.random_range(8.0..25.0);
            let height: f64 = rng.random_range(6.0..20.0);
            let depth = 10.0;
            let setback: f64 = rng.random_range(9.0..11.0);
            let center = Vector3::new(
                x + width / 2.0,
                side * (setback + depth / 2.0),
                height / 2.0,
            );
            b.add_box(
                &Pose3::from_parts(center, Default::default()),
                Vector3::new(width / 2.0, depth / 2.0, height / 2.0),
                [facade; 6],
            );
            x += width + rng.random_range(0.0..3.0);
        }
        // Poles every ~15 m, trees in between, cars parked along the curb.
        let mut x = -half_len + 5.0;
        while x < half_len {
            let r: f64 = rng.random_range(0.06..0.2);
            b.add_cylinder(
                Point3::new(x, side * 5.6, 0.15),
                r,
                rng.random_range(3.0..8.0),
                16,
                pole,
            );
            let tx = x + 7.5;
            b.add_cylinder(Point3::new(tx, side * 7.0, 0.15), 0.2, 3.0, 12, trunk);
            b.add_box(
                &Pose3::from_parts(Vector3::new(tx, side * 7.0, 4.5), Default::default()),
                Vector3::new(1.8, 1.8, 1.5),
                [canopy; 6],
            );
            x += rng.random_range(12.0..18.0);
        }
        let mut x = -half_len + 3.0;
        while x < half_len {
            if rng.random_bool(0.7) {
                let y = side * 3.9;
                let body = Pose3::from_xyz_rpy(x, y, 0.65, 0.0, 0.0, rng.random_range(-0.05..0.05));
                b.add_box(&body, Vector3::new(2.2, 0.9, 0.45), [car; 6]);
                let cabin = body * Pose3::from_xyz_rpy(-0.2, 0.0, 0.75, 0.0, 0.0, 0.0);
                b.add_box(&cabin, Vector3::new(1.2, 0.8, 0.3), [car; 6]);
            }
            x += 5.5;
        }
    }
    b.build().expect("the street has triangles")
}

/// The scene's triangles as one parry3d `TriMesh` (for the comparison).
fn parry_mesh(scene: &Scene3) -> parry3d_f64::shape::TriMesh {
    let mut vertices = Vec::with_capacity(3 * scene.num_triangles());
    let mut indices = Vec::with_capacity(scene.num_triangles());
    for i in 0..scene.num_triangles() {
        if let Some(corners) = scene.triangle(i) {
            let base = vertices.len() as u32;
            vertices.extend_from_slice(&corners);
            indices.push([base, base + 1, base + 2]);
        }
    }
    parry3d_f64::shape::TriMesh::new(vertices, indices).expect("a triangle mesh")
}

fn bench_rays(c: &mut Criterion) {
    let mut group = c.benchmark_group("rays");
    group.sample_size(10);

    let street = street_scene();
    let hdl64e = Lidar3::hdl64e();
    let pose = Pose3::from_xyz_rpy(0.0, 0.0, 1.73, 0.0, 0.0, 0.0);
    group.throughput(Throughput::Elements(hdl64e.num_rays() as u64));
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    group.bench_function("street/hdl64e/1-thread", |b| {
        b.iter(|| one_thread.install(|| black_box(hdl64e.scan(&street, &pose, 1, 0))))
    });
    group.bench_function(
        format!("street/hdl64e/{}-threads", rayon::current_num_threads()),
        |b| b.iter(|| black_box(hdl64e.scan(&street, &pose, 1, 0))),
    );

    let layout = generate_layout(&StreetConfig::default(), 2020).expect("a street world");
    let (world, _) = session_worlds(&layout, &[9], &Default::default(), 2020)
        .into_iter()
        .next()
        .expect("a session");
    let urban = world.build_scene().expect("the urban scene");
    let grid = &layout.grid;
    let urban_pose = Pose3::from_xyz_rpy(
        grid.xs[2] - 1.5,
        (grid.ys[1] + grid.ys[2]) / 2.0,
        1.73,
        0.0,
        0.0,
        std::f64::consts::FRAC_PI_2,
    );
    group.throughput(Throughput::Elements(hdl64e.num_rays() as u64));
    group.bench_function("urban/hdl64e/1-thread", |b| {
        b.iter(|| one_thread.install(|| black_box(hdl64e.scan(&urban, &urban_pose, 1, 0))))
    });
    group.bench_function(
        format!("urban/hdl64e/{}-threads", rayon::current_num_threads()),
        |b| b.iter(|| black_box(hdl64e.scan(&urban, &urban_pose, 1, 0))),
    );

    // Ray casting alone, the scene's BVH against parry3d's TriMesh on the same triangles:
    // the HDL-64E's nominal beams from the urban pose, one thread.
    let origin = Point3::from(urban_pose.translation());
    let beams: Vec<nalgebra::Unit<Vector3<f64>>> = hdl64e
        .elevations_rad
        .iter()
        .flat_map(|&el| hdl64e.azimuths_rad.iter().map(move |&az| (el, az)))
        .map(|(el, az)| urban_pose.rotation() * raypath_geometry::spherical_direction(el, az))
        .collect();
    group.bench_function("urban/cast-bvh/1-thread", |b| {
        b.iter(|| {
            beams
                .iter()
                .filter_map(|d| urban.cast(&origin, d, hdl64e.max_range_m))
                .count()
        })
    });
    let mesh = parry_mesh(&urban);
    group.bench_function("urban/cast-parry-trimesh/1-thread", |b| {
        b.iter(|| {
            beams
                .iter()
                .filter_map(|d| {
                    let ray = parry3d_f64::query::Ray::new(origin, d.into_inner());
                    parry3d_f64::query::RayCast::cast_local_ray_and_get_normal(
                        &mesh,
                        &ray,
                        hdl64e.max_range_m,
                        false,
                    )
                })
                .count()
        })
    });

    let config = SynpebConfig::default();
    let room = synpeb::build_room(&config, 7, 0).expect("a room");
    let world_from_sensor = room.sensor_pose(&config, 7, 0).expect("a sensor pose");
    let room = room.scene;
    let scanner = synpeb::scanner(&config).expect("the SynPEB scanner");
    group.throughput(Throughput::Elements(scanner.num_rays() as u64));
    group.bench_function("synpeb/500x500/1-thread", |b| {
        b.iter(|| one_thread.install(|| black_box(scanner.scan(&room, &world_from_sensor, 1, 0))))
    });
    group.bench_function(
        format!("synpeb/500x500/{}-threads", rayon::current_num_threads()),
        |b| b.iter(|| black_box(scanner.scan(&room, &world_from_sensor, 1, 0))),
    );
    group.finish();
}

/// The Criterion group (in a private module: the macro's function has no docs).
mod group {
    criterion::criterion_group!(benches, super::bench_rays);
}
criterion_main!(group::benches);
