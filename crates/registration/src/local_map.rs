//! The local map of the odometry: a voxel hash map holding a few points (with normals) per
//! voxel around the sensor (the local map of KISS-ICP, Vizzo et al. 2023, with normals added
//! for point-to-plane matching).

use std::collections::HashMap;
use std::collections::hash_map::DefaultHasher;
use std::hash::BuildHasherDefault;

use nalgebra::{Point3, Vector3};
use raypath_geometry::Pose3;

/// A fixed-key hasher: the map iterates in the same order in every run.
type Cells = HashMap<[i64; 3], Vec<(Point3<f64>, Vector3<f64>)>, BuildHasherDefault<DefaultHasher>>;

/// Points with normals in world coordinates, at most `max_points` per voxel, each at least
/// `√(v² / max_points)` from the others in its voxel (KISS-ICP's spacing rule).
#[derive(Clone, Debug)]
pub(crate) struct LocalMap {
    voxel_m: f64,
    max_points: usize,
    min_spacing_2: f64,
    cells: Cells,
}

impl LocalMap {
    pub(crate) fn new(voxel_m: f64, max_points: usize) -> Self {
        Self {
            voxel_m,
            max_points,
            min_spacing_2: voxel_m * voxel_m / max_points as f64,
            cells: Cells::default(),
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Number of points.
    pub(crate) fn len(&self) -> usize {
        self.cells.values().map(Vec::len).sum()
    }

    fn key(&self, p: &Point3<f64>) -> [i64; 3] {
        // Points are finite and within the map radius of a finite pose: the casts are exact.
        [p.x, p.y, p.z].map(|c| (c / self.voxel_m).floor() as i64)
    }

    /// Adds points given in the sensor frame (with their normals) at `world_from_sensor`.
    pub(crate) fn add(
        &mut self,
        world_from_sensor: &Pose3,
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
    ) {
        for (p, n) in points.iter().zip(normals) {
            let p = world_from_sensor.transform_point(p);
            let n = world_from_sensor.transform_vector(n);
            let key = self.key(&p);
            let cell = self.cells.entry(key).or_default();
            if cell.len() >= self.max_points
                || cell
                    .iter()
                    .any(|(q, _)| (q - p).norm_squared() < self.min_spacing_2)
            {
                continue;
            }
            cell.push((p, n));
        }
    }

    /// Drops the voxels whose first point is `max_distance_m` or more from `origin`.
    pub(crate) fn remove_far(&mut self, origin: &Point3<f64>, max_distance_m: f64) {
        let max_2 = max_distance_m * max_distance_m;
        self.cells.retain(|_, cell| {
            cell.first()
                .is_some_and(|(p, _)| (p - origin).norm_squared() < max_2)
        });
    }

    /// All points and normals, in the map's (fixed) iteration order.
    pub(crate) fn points_and_normals(&self) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
        let mut points = Vec::with_capacity(self.len());
        let mut normals = Vec::with_capacity(points.capacity());
        for cell in self.cells.values() {
            for (p, n) in cell {
                points.push(*p);
                normals.push(*n);
            }
        }
        (points, normals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn caps_spaces_and_forgets() {
        let mut map = LocalMap::new(1.0, 4);
        let up = Vector3::z();
        // 100 points in one voxel: at most 4 kept, each ≥ 0.5 m from the others.
        let points: Vec<Point3<f64>> = (0..100)
            .map(|i| Point3::new(0.01 * i as f64 * 0.99, 0.5, 0.5))
            .collect();
        map.add(&Pose3::identity(), &points, &vec![up; points.len()]);
        assert!(map.len() <= 4 && map.len() >= 2, "{}", map.len());
        let (kept, _) = map.points_and_normals();
        for a in &kept {
            for b in &kept {
                assert!(a == b || (a - b).norm() >= 0.5);
            }
        }
        // A far voxel is dropped once the sensor moves away.
        map.add(
            &Pose3::from_xyz_rpy(50.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            &[Point3::origin()],
            &[up],
        );
        map.remove_far(&Point3::new(50.0, 0.0, 0.0), 10.0);
        let (kept, normals) = map.points_and_normals();
        assert_eq!(kept, vec![Point3::new(50.0, 0.0, 0.0)]);
        assert_eq!(normals, vec![up]);
    }
}
