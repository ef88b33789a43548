//! Queries: occupancy at a point, ray casting, iteration over cuboids.

use nalgebra::{Point3, Vector3};

use super::RtreeGrid;
use crate::config::probability;
use crate::key::{KeyBox, key_of};

/// Classification of a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Occupancy {
    /// No cell covers the point.
    Unknown,
    /// Probability at or below the occupancy threshold.
    Free,
    /// Probability above the occupancy threshold.
    Occupied,
}

/// A leaf cell in metric form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    /// Lower corner, metres (world frame).
    pub min_m: [f64; 3],
    /// Upper corner, metres.
    pub max_m: [f64; 3],
    /// The cell in base-cube keys.
    pub keys: KeyBox,
    /// Occupancy probability `P(g_i | z_1:t)`.
    pub probability: f64,
    /// Whether the probability exceeds the occupancy threshold.
    pub occupied: bool,
}

impl RtreeGrid {
    fn cuboid(&self, id: u32, bx: &KeyBox) -> Cuboid {
        let r = self.config.resolution_m;
        let l = self.lo(id);
        Cuboid {
            min_m: bx.min_m(r),
            max_m: bx.max_m(r),
            keys: *bx,
            probability: probability(f64::from(l)),
            occupied: l > self.l_threshold,
        }
    }

    /// The leaf containing `point_m`, if any.
    pub fn cell_at(&self, point_m: &Point3<f64>) -> Option<Cuboid> {
        let key = key_of([point_m.x, point_m.y, point_m.z], self.config.resolution_m)?;
        let id = self.cell_id_of_key(key)?;
        Some(self.cuboid(id, &self.cell(id).bx))
    }

    /// Occupancy probability at `point_m` (`None`: unknown space).
    pub fn occupancy_at(&self, point_m: &Point3<f64>) -> Option<f64> {
        self.cell_at(point_m).map(|c| c.probability)
    }

    /// Unknown, free or occupied at `point_m`.
    pub fn classify(&self, point_m: &Point3<f64>) -> Occupancy {
        match self.cell_at(point_m) {
            None => Occupancy::Unknown,
            Some(c) if c.occupied => Occupancy::Occupied,
            Some(_) => Occupancy::Free,
        }
    }

    /// Casts a ray from `origin_m` along `direction` (need not be unit) up to `max_range_m`
    /// and returns the first occupied leaf it enters, with the distance in metres to the
    /// entry face of the base cube where it is entered.
    pub fn cast_ray(
        &self,
        origin_m: &Point3<f64>,
        direction: &Vector3<f64>,
        max_range_m: f64,
    ) -> Option<(Cuboid, f64)> {
        let norm = direction.norm();
        if !(norm > 0.0 && norm.is_finite() && max_range_m > 0.0) {
            return None;
        }
        let dir = direction / norm;
        let end = origin_m + dir * max_range_m;
        let mut keys = Vec::new();
        super::ray::ray_keys(
            [origin_m.x, origin_m.y, origin_m.z],
            [end.x, end.y, end.z],
            self.config.resolution_m,
            &mut keys,
        );
        if let Some(k) = key_of([end.x, end.y, end.z], self.config.resolution_m) {
            keys.push(crate::key::pack(k));
        }
        for packed in keys {
            let key = crate::key::unpack(packed);
            let Some(id) = self.cell_id_of_key(key) else {
                continue;
            };
            if self.lo(id) > self.l_threshold {
                let cube = KeyBox::cube(key);
                let r = self.config.resolution_m;
                let (lo, hi) = (cube.min_m(r), cube.max_m(r));
                // Entry distance: slab method on the base cube.
                let o = [origin_m.x, origin_m.y, origin_m.z];
                let mut t_enter = 0.0f64;
                for a in 0..3 {
                    if dir[a] != 0.0 {
                        let t1 = (lo[a] - o[a]) / dir[a];
                        let t2 = (hi[a] - o[a]) / dir[a];
                        t_enter = t_enter.max(t1.min(t2));
                    }
                }
                return Some((self.cuboid(id, &self.cell(id).bx), t_enter));
            }
        }
        None
    }

    /// Calls `visit` for every leaf, walking the R-tree.
    pub fn for_each_cuboid(&self, mut visit: impl FnMut(&Cuboid)) {
        self.tree
            .for_each_item(&mut |id, bx| visit(&self.cuboid(id, bx)));
    }

    /// All leaves (occupied and free).
    pub fn cuboids(&self) -> Vec<Cuboid> {
        let mut out = Vec::with_capacity(self.tree.len());
        self.for_each_cuboid(|c| out.push(*c));
        out
    }

    /// Calls `visit(box)` for every occupied leaf, walking the whole hierarchy (the thesis'
    /// access-time measurement); returns how many there are.
    pub fn for_each_occupied(&self, mut visit: impl FnMut(&KeyBox)) -> usize {
        let mut n = 0;
        let threshold = self.l_threshold;
        self.tree.for_each_item(&mut |id, bx| {
            if self.lo(id) > threshold {
                n += 1;
                visit(bx);
            }
        });
        n
    }
}
