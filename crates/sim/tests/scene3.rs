//! Ray hits on the scene primitives against analytic answers: plane, box, cylinder, wedge,
//! prism, stairs and sphere, with the surface (label) of every face.

#![allow(clippy::unwrap_used)]

use std::f64::consts::FRAC_PI_2;

use nalgebra::{Point2, Point3, Unit, Vector3};
use raypath_geometry::Pose3;
use raypath_sim::scene3::{Scene3, SceneBuilder3, Surface, SurfaceId};

fn surfaces(builder: &mut SceneBuilder3, labels: std::ops::Range<u32>) -> Vec<SurfaceId> {
    labels
        .map(|label| {
            builder.add_surface(Surface {
                label,
                reflectivity: 0.5,
            })
        })
        .collect()
}

fn hit(scene: &Scene3, origin: [f64; 3], dir: [f64; 3]) -> Option<(f64, u32, Vector3<f64>)> {
    let dir = Unit::new_normalize(Vector3::from(dir));
    scene.cast(&Point3::from(origin), &dir, 1000.0).map(|h| {
        (
            h.range_m,
            scene.surface(h.surface).unwrap().label,
            h.normal.into_inner(),
        )
    })
}

fn assert_hit(scene: &Scene3, origin: [f64; 3], dir: [f64; 3], range: f64, label: u32) {
    let (r, l, _) = hit(scene, origin, dir).unwrap_or_else(|| panic!("{origin:?} {dir:?}: miss"));
    assert!(
        (r - range).abs() < 1e-9,
        "{origin:?} {dir:?}: range {r}, expected {range}"
    );
    assert_eq!(l, label, "{origin:?} {dir:?}");
}

#[test]
fn inclined_plane_matches_the_point_normal_form() {
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 10..11);
    // The plane n·x = 2 with n = (1, 1, 1)/√3, as a large square around its closest point.
    let n = Vector3::new(1.0, 1.0, 1.0).normalize();
    let c = Point3::from(n * 2.0);
    let u = Vector3::new(1.0, -1.0, 0.0).normalize() * 50.0;
    let v = n.cross(&u);
    b.add_polygon(&[c - u - v, c + u - v, c + u + v, c - u + v], s[0]);
    let scene = b.build().unwrap();
    for dir in [[1.0, 0.0, 0.0], [0.3, 0.5, 0.8], [1.0, 1.0, -0.2]] {
        let d = Vector3::from(dir).normalize();
        let (r, label, normal) = hit(&scene, [0.0; 3], dir).unwrap();
        assert!((r - 2.0 / n.dot(&d)).abs() < 1e-9);
        assert_eq!(label, 10);
        assert!((normal + n).norm() < 1e-9, "the normal faces the ray");
    }
    assert!(hit(&scene, [0.0; 3], [-1.0, -1.0, 0.0]).is_none());
}

#[test]
fn rotated_box_faces() {
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 10..16);
    let pose = Pose3::from_xyz_rpy(5.0, 0.0, 0.0, 0.0, 0.0, FRAC_PI_2);
    // After the yaw of 90°, the box's x half extent (1) lies along world y, y (2) along x.
    b.add_box(
        &pose,
        Vector3::new(1.0, 2.0, 0.5),
        [s[0], s[1], s[2], s[3], s[4], s[5]],
    );
    let scene = b.build().unwrap();
    assert_hit(&scene, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 3.0, 13); // +y face of the box
    assert_hit(&scene, [5.0, 10.0, 0.0], [0.0, -1.0, 0.0], 9.0, 11); // +x face
    assert_hit(&scene, [5.5, 0.3, 4.0], [0.0, 0.0, -1.0], 3.5, 15); // top
}

#[test]
fn capped_cylinder_side_and_caps() {
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 1..4);
    b.add_capped_cylinder(
        Point3::new(0.0, 0.0, 0.0),
        0.5,
        2.0,
        256,
        [s[0], s[1], s[2]],
    );
    let scene = b.build().unwrap();
    // Along x a vertex of the 256-gon: exactly the radius.
    assert_hit(&scene, [-3.0, 0.0, 1.0], [1.0, 0.0, 0.0], 2.5, 1);
    // Off-axis: within the facets' sagitta, 0.5 · (1 − cos(π/256)) ≈ 4e-5, along the ray.
    let (r, label, _) = hit(&scene, [-3.0, 0.3, 1.0], [1.0, 0.0, 0.0]).unwrap();
    assert!(r >= 2.6 - 1e-12 && r - 2.6 < 1e-4, "{r}");
    assert_eq!(label, 1);
    assert_hit(&scene, [0.1, 0.1, 5.0], [0.0, 0.0, -1.0], 3.0, 3);
    assert_hit(&scene, [0.1, -0.2, -1.0], [0.0, 0.0, 1.0], 1.0, 2);
}

#[test]
fn wedge_slope_back_and_sides() {
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 10..15);
    let pose = Pose3::from_xyz_rpy(2.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    b.add_wedge(
        &pose,
        Vector3::new(2.0, 1.0, 1.0),
        [s[0], s[1], s[2], s[3], s[4]],
    )
    .unwrap();
    let scene = b.build().unwrap();
    // The slope: z = (x − 1) / 2 for x ∈ [1, 3]. A ray down at x = 2 meets it at z = 0.5.
    assert_hit(&scene, [2.0, 0.0, 3.0], [0.0, 0.0, -1.0], 2.5, 12);
    // Horizontally at z = 0.25 from −x: the slope at x = 1.5.
    assert_hit(&scene, [0.0, 0.1, 0.25], [1.0, 0.0, 0.0], 1.5, 12);
    // From +x: the back face at x = 3.
    assert_hit(&scene, [5.0, 0.0, 0.5], [-1.0, 0.0, 0.0], 2.0, 11);
    // From −y and +y: the triangular sides at y = ∓0.5.
    assert_hit(&scene, [2.5, -4.0, 0.2], [0.0, 1.0, 0.0], 3.5, 13);
    assert_hit(&scene, [2.5, 4.0, 0.2], [0.0, -1.0, 0.0], 3.5, 14);
    // Above the slope's top edge (x = 2.2, z = 0.8 > 0.6): nothing.
    assert!(hit(&scene, [2.2, -4.0, 0.8], [0.0, 1.0, 0.0]).is_none());
    assert_hit(&scene, [2.0, 0.0, -1.0], [0.0, 0.0, 1.0], 1.0, 10);
}

#[test]
fn hexagonal_prism_faces() {
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 10..18);
    let hexagon: Vec<Point2<f64>> = (0..6)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / 6.0;
            Point2::new(a.cos(), a.sin())
        })
        .collect();
    let pose = Pose3::from_xyz_rpy(0.0, 0.0, 1.0, 0.0, 0.0, 0.0);
    b.add_prism(&pose, &hexagon, 2.0, &s).unwrap();
    let scene = b.build().unwrap();
    assert_hit(&scene, [0.2, 0.1, 10.0], [0.0, 0.0, -1.0], 7.0, 11); // top at z = 3
    assert_hit(&scene, [0.2, 0.1, -10.0], [0.0, 0.0, 1.0], 11.0, 10); // bottom at z = 1
    // Side 0 joins (1, 0) and (cos 60°, sin 60°): apothem √3/2 along azimuth 30°.
    let d = [30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0];
    let o = [-5.0 * d[0], -5.0 * d[1], 2.0];
    // From the opposite side the ray passes the centre and exits through side 0: first hit is
    // side 3 at distance 5 − √3/2.
    assert_hit(&scene, o, d, 5.0 - 3f64.sqrt() / 2.0, 15);
    assert_hit(
        &scene,
        [5.0 * d[0], 5.0 * d[1], 2.0],
        [-d[0], -d[1], 0.0],
        5.0 - 3f64.sqrt() / 2.0,
        12,
    );
    // A non-convex base or a wrong number of surfaces is an error.
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 10..16);
    let notch = [
        Point2::new(0.0, 0.0),
        Point2::new(2.0, 0.0),
        Point2::new(1.0, 0.3),
        Point2::new(1.0, 2.0),
    ];
    assert!(b.add_prism(&Pose3::identity(), &notch, 1.0, &s).is_err());
    assert!(b.add_prism(&Pose3::identity(), &hexagon, 1.0, &s).is_err());
    assert!(
        b.add_prism(&Pose3::identity(), &hexagon[..4], -1.0, &s)
            .is_err()
    );
}

#[test]
fn stairs_treads_risers_and_sides() {
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 10..20); // 3 steps: 3 treads, 3 risers, 4 more faces
    b.add_stairs(&Pose3::identity(), 3, 0.3, 0.2, 1.0, &s)
        .unwrap();
    let scene = b.build().unwrap();
    // Straight down onto each tread.
    for k in 0..3 {
        let x = 0.15 + 0.3 * k as f64;
        assert_hit(
            &scene,
            [x, 0.0, 2.0],
            [0.0, 0.0, -1.0],
            2.0 - 0.2 * (k + 1) as f64,
            10 + k as u32,
        );
    }
    // Horizontally from −x at the height of each riser.
    for k in 0..3 {
        let z = 0.1 + 0.2 * k as f64;
        assert_hit(
            &scene,
            [-1.0, 0.2, z],
            [1.0, 0.0, 0.0],
            1.0 + 0.3 * k as f64,
            13 + k as u32,
        );
    }
    assert_hit(&scene, [0.75, -3.0, 0.3], [0.0, 1.0, 0.0], 2.5, 16); // −y side
    assert_hit(&scene, [0.75, 3.0, 0.3], [0.0, -1.0, 0.0], 2.5, 17); // +y side
    assert_hit(&scene, [3.0, 0.0, 0.5], [-1.0, 0.0, 0.0], 2.1, 18); // back at x = 0.9
    assert_hit(&scene, [0.5, 0.0, -1.0], [0.0, 0.0, 1.0], 1.0, 19); // bottom
    // Above the second step's side profile (z = 0.5 > 0.4 at x = 0.45): the ray passes.
    assert!(hit(&scene, [0.45, -3.0, 0.5], [0.0, 1.0, 0.0]).is_none());
    // A wrong number of surfaces is an error.
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 10..15);
    assert!(
        b.add_stairs(&Pose3::identity(), 3, 0.3, 0.2, 1.0, &s)
            .is_err()
    );
}

#[test]
fn sphere_hits_within_the_facet_tolerance() {
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 2..3);
    b.add_sphere(Point3::new(0.0, 0.0, 5.0), 1.0, 64, 128, s[0]);
    let scene = b.build().unwrap();
    for dir in [[0.013, 0.021, 1.0], [0.05, 0.1, 1.0], [-0.1, 0.02, 1.0]] {
        let d = Vector3::from(dir).normalize();
        // Analytic first intersection of the ray from the origin with the unit sphere at z = 5.
        let c = Vector3::<f64>::new(0.0, 0.0, 5.0);
        let b_: f64 = d.dot(&c);
        let t = b_ - (b_ * b_ - (c.norm_squared() - 1.0)).sqrt();
        let (r, label, _) = hit(&scene, [0.0; 3], dir).unwrap();
        assert!((r - t).abs() < 2e-3, "{r} vs {t}");
        assert_eq!(label, 2);
    }
}

/// The scene's own BVH against parry3d's `TriMesh` on 20 000 random rays through a cluttered
/// scene with long triangles (split into pieces inside the BVH): same hits, same ranges.
#[test]
fn bvh_agrees_with_parry_trimesh() {
    use parry3d_f64::query::{Ray, RayCast};
    use parry3d_f64::shape::TriMesh;
    use rand::{Rng, SeedableRng};

    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut b = SceneBuilder3::new();
    let s = surfaces(&mut b, 10..60);
    b.add_polygon(
        &[
            Point3::new(-300.0, -40.0, 0.0),
            Point3::new(300.0, -40.0, 0.0),
            Point3::new(300.0, 40.0, 0.0),
            Point3::new(-300.0, 40.0, 0.0),
        ],
        s[0],
    );
    for i in 0..300 {
        let pose = Pose3::from_xyz_rpy(
            rng.random_range(-100.0..100.0),
            rng.random_range(-30.0..30.0),
            rng.random_range(0.0..5.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-3.0..3.0),
        );
        let half = Vector3::new(
            rng.random_range(0.1..8.0),
            rng.random_range(0.1..3.0),
            rng.random_range(0.1..2.0),
        );
        let faces = [0; 6].map(|_| s[rng.random_range(1..50)]);
        if i % 3 == 0 {
            let base = Point3::new(pose.translation().x, pose.translation().y, 0.0);
            b.add_cylinder(base, half.y / 4.0, half.z * 3.0, 24, faces[0]);
        } else {
            b.add_box(&pose, half, faces);
        }
    }
    let scene = b.build().unwrap();
    let (vertices, indices): (Vec<Point3<f64>>, Vec<[u32; 3]>) = (0..scene.num_triangles())
        .map(|i| {
            let corners = scene.triangle(i).unwrap();
            let base = 3 * i as u32;
            (corners, [base, base + 1, base + 2])
        })
        .fold((Vec::new(), Vec::new()), |(mut v, mut t), (c, idx)| {
            v.extend_from_slice(&c);
            t.push(idx);
            (v, t)
        });
    let mesh = TriMesh::new(vertices, indices).unwrap();
    let (mut hits, mut mismatches) = (0, 0);
    for _ in 0..20_000 {
        let origin = Point3::new(
            rng.random_range(-120.0..120.0),
            rng.random_range(-35.0..35.0),
            rng.random_range(0.5..6.0),
        );
        let dir = Unit::new_normalize(Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-0.5..0.3),
        ));
        let ours = scene.cast(&origin, &dir, 150.0);
        let theirs = mesh.cast_local_ray(&Ray::new(origin, dir.into_inner()), 150.0, false);
        match (ours, theirs) {
            (Some(h), Some(t)) => {
                hits += 1;
                if (h.range_m - t).abs() > 1e-7 {
                    mismatches += 1;
                }
            }
            (None, None) => {}
            _ => mismatches += 1,
        }
    }
    assert!(hits > 10_000, "{hits}");
    assert!(mismatches <= 2, "{mismatches} of 20 000 rays disagree");
}
