//! Scene entities of the recordings: poles as cylinders, polylines as line strips, planes as
//! outlines and triangle fans, octree leaves as cubes, loop closures as line segments.

use nalgebra::{Point2, Point3, Vector3};
use raypath_geometry::Pose2;
use raypath_io::foxglove::{Cube, Cylinder, Entity, Line, LineKind, Rgba, Triangles};
use raypath_poles::Pole;
use raypath_polylines::Polylines;
use raypath_rtree_grid::Cuboid;

/// Poles: orange.
const POLE_COLOR: Rgba = [1.0, 0.55, 0.1, 1.0];
/// Polylines: green, 3 cm wide.
const POLYLINE_COLOR: Rgba = [0.1, 0.85, 0.3, 1.0];
const POLYLINE_WIDTH_M: f64 = 0.03;
/// Loop closures: magenta, 5 cm wide.
const LOOP_COLOR: Rgba = [0.9, 0.1, 0.8, 1.0];
const LOOP_WIDTH_M: f64 = 0.05;
/// Plane outlines: 1 cm wide; the filled triangles are half transparent.
const OUTLINE_WIDTH_M: f64 = 0.01;
const FILL_ALPHA: f32 = 0.5;

/// A distinct opaque colour for label `label` (hues a golden angle apart, so neighbouring
/// labels differ clearly).
pub fn label_color(label: usize) -> Rgba {
    let hue = (label as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let (s, v) = (0.75, 0.95);
    let c = v * s;
    let x = c * (1.0 - (hue % 2.0 - 1.0).abs());
    let (r, g, b) = match hue as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [(r + m) as f32, (g + m) as f32, (b + m) as f32, 1.0]
}

/// One entity per pole, `"{prefix} {i}"`: an upright cylinder from `z_start` to `z_end` as wide
/// as the pole, with its width, height and score as metadata.
pub fn pole_entities(poles: &[Pole], prefix: &str) -> Vec<Entity> {
    poles
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut entity = Entity::new(format!("{prefix} {i}"));
            entity.cylinders.push(Cylinder {
                base: Point3::new(p.x, p.y, p.z_start),
                diameter_m: p.width,
                height_m: p.height(),
                color: POLE_COLOR,
            });
            entity.metadata = vec![
                ("width_m".into(), format!("{:.3}", p.width)),
                ("height_m".into(), format!("{:.3}", p.height())),
                ("score".into(), format!("{:.3}", p.score)),
            ];
            entity
        })
        .collect()
}

/// The polylines of one scan as one entity `id` (so the next scan's replaces it): a line strip
/// per polyline, a closed loop per polygon, mapped from the laser frame by `frame_from_laser`.
pub fn polyline_entities(map: &Polylines, frame_from_laser: &Pose2, id: &str) -> Vec<Entity> {
    let mut entity = Entity::new(id);
    for line in &map.lines {
        let points = line
            .vertices
            .iter()
            .map(|v| {
                let p = frame_from_laser.transform_point(v);
                Point3::new(p.x, p.y, 0.0)
            })
            .collect();
        entity.lines.push(Line {
            kind: if line.closed {
                LineKind::Loop
            } else {
                LineKind::Strip
            },
            points,
            thickness_m: POLYLINE_WIDTH_M,
            color: POLYLINE_COLOR,
        });
    }
    entity.metadata = vec![
        ("polylines".into(), map.lines.len().to_string()),
        ("vertices".into(), map.vertex_count().to_string()),
    ];
    vec![entity]
}

/// A plane `label` (1-based) through `points` with unit `normal` at `distance_m` from the
/// origin (`normal · p = distance_m`): the outline of the points' convex hull on the plane and
/// the hull filled with half-transparent triangles, both in [`label_color`]. `None` when the
/// points span no area.
pub fn plane_entity(
    label: usize,
    points: &[Point3<f64>],
    normal: &Vector3<f64>,
    distance_m: f64,
) -> Option<Entity> {
    // An orthonormal basis (u, v) of the plane.
    let helper = if normal.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = normal.cross(&helper).try_normalize(1e-12)?;
    let v = normal.cross(&u);
    let flat: Vec<Point2<f64>> = points
        .iter()
        .map(|p| Point2::new(p.coords.dot(&u), p.coords.dot(&v)))
        .collect();
    let hull = convex_hull(flat);
    if hull.len() < 3 {
        return None;
    }
    let lift = |q: &Point2<f64>| Point3::from(normal * distance_m + u * q.x + v * q.y);
    let outline: Vec<Point3<f64>> = hull.iter().map(lift).collect();
    let mut fill = Vec::with_capacity(3 * (outline.len() - 2));
    for pair in outline[1..].windows(2) {
        fill.extend([outline[0], pair[0], pair[1]]);
    }
    let color = label_color(label);
    let mut entity = Entity::new(format!("plane {label}"));
    entity.triangles.push(Triangles {
        points: fill,
        color: [color[0], color[1], color[2], FILL_ALPHA],
    });
    entity.lines.push(Line {
        kind: LineKind::Loop,
        points: outline,
        thickness_m: OUTLINE_WIDTH_M,
        color,
    });
    entity.metadata = vec![
        ("label".into(), label.to_string()),
        ("points".into(), points.len().to_string()),
        ("distance_m".into(), format!("{distance_m:.4}")),
    ];
    Some(entity)
}

/// Convex hull of `points` counter-clockwise (Andrew's monotone chain); collinear points are
/// dropped.
fn convex_hull(mut points: Vec<Point2<f64>>) -> Vec<Point2<f64>> {
    points.retain(|p| p.x.is_finite() && p.y.is_finite());
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>| {
        (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
    };
    let mut hull: Vec<Point2<f64>> = Vec::with_capacity(2 * points.len());
    for pass in [false, true] {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &Point2<f64>>> = if pass {
            Box::new(points.iter().rev())
        } else {
            Box::new(points.iter())
        };
        for p in ordered {
            while hull.len() >= start + 2
                && cross(&hull[hull.len() - 2], &hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(*p);
        }
        hull.pop();
    }
    hull
}

/// Octree leaves as one entity `id` of cubes, coloured from blue (low) to red (high) by height
/// within the leaves' vertical span.
pub fn cube_entities(cuboids: &[Cuboid], id: &str) -> Vec<Entity> {
    let (lo, hi) = cuboids
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(c.min_m[2]), hi.max(c.max_m[2]))
        });
    let span = (hi - lo).max(1e-9);
    let mut entity = Entity::new(id);
    entity.cubes = cuboids
        .iter()
        .map(|c| {
            let (min, max) = (c.min_m, c.max_m);
            let center = Point3::new(
                (min[0] + max[0]) / 2.0,
                (min[1] + max[1]) / 2.0,
                (min[2] + max[2]) / 2.0,
            );
            let t = (((center.z - lo) / span) as f32).clamp(0.0, 1.0);
            Cube {
                center,
                size_m: [max[0] - min[0], max[1] - min[1], max[2] - min[2]],
                color: [t, 0.3, 1.0 - t, 1.0],
            }
        })
        .collect();
    entity.metadata = vec![("cubes".into(), cuboids.len().to_string())];
    vec![entity]
}

/// Loop closures as one entity `"loops"`: a line list with a segment between the poses of each
/// matched pair `(query position, match position)`.
pub fn loop_lines(pairs: &[(Point3<f64>, Point3<f64>)]) -> Vec<Entity> {
    let mut entity = Entity::new("loops");
    entity.lines.push(Line {
        kind: LineKind::List,
        points: pairs.iter().flat_map(|(a, b)| [*a, *b]).collect(),
        thickness_m: LOOP_WIDTH_M,
        color: LOOP_COLOR,
    });
    entity.metadata = vec![("loops".into(), pairs.len().to_string())];
    vec![entity]
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn hull_of_a_square_with_inner_points_is_its_corners() {
        let mut points = vec![
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
            Point2::new(0.5, 0.5),
            Point2::new(0.5, 0.0),
        ];
        points.extend((0..10).map(|i| Point2::new(0.1 * i as f64, 0.3)));
        let hull = convex_hull(points);
        assert_eq!(
            hull,
            vec![
                Point2::new(0.0, 0.0),
                Point2::new(1.0, 0.0),
                Point2::new(1.0, 1.0),
                Point2::new(0.0, 1.0)
            ]
        );
    }

    #[test]
    fn a_plane_entity_lies_on_its_plane() {
        // The plane z = 2 (normal +z), a 2 m × 1 m rectangle of points.
        let points: Vec<Point3<f64>> = (0..=20)
            .flat_map(|i| (0..=10).map(move |j| Point3::new(0.1 * i as f64, 0.1 * j as f64, 2.0)))
            .collect();
        let entity = plane_entity(3, &points, &Vector3::z(), 2.0).unwrap();
        let outline = &entity.lines[0].points;
        assert_eq!(outline.len(), 4);
        assert!(outline.iter().all(|p| (p.z - 2.0).abs() < 1e-12));
        // Two triangles covering 2 m².
        let fill = &entity.triangles[0].points;
        assert_eq!(fill.len(), 6);
        let area: f64 = fill
            .chunks(3)
            .map(|t| (t[1] - t[0]).cross(&(t[2] - t[0])).norm() / 2.0)
            .sum();
        assert!((area - 2.0).abs() < 1e-9, "{area}");
        // Collinear points span no area.
        let line: Vec<Point3<f64>> = (0..5).map(|i| Point3::new(i as f64, 0.0, 2.0)).collect();
        assert!(plane_entity(1, &line, &Vector3::z(), 2.0).is_none());
    }

    #[test]
    fn label_colors_differ() {
        let colors: Vec<Rgba> = (0..8).map(label_color).collect();
        for (i, a) in colors.iter().enumerate() {
            assert!(a.iter().all(|c| (0.0..=1.0).contains(c)));
            for b in &colors[i + 1..] {
                let d: f32 = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum();
                assert!(d > 0.1, "{a:?} {b:?}");
            }
        }
    }
}
