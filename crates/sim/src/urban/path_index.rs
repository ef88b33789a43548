//! Radius queries over the trajectory samples and poles of a semi-synthetic world.

use nalgebra::{Point2, Vector2};

use super::along_path::PathSample;
use super::world::Footprint;

/// Points in a uniform grid for radius queries (deterministic).
pub(crate) struct GridIndex {
    origin: Point2<f64>,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl GridIndex {
    pub(crate) fn new(points: &[Point2<f64>], cell: f64) -> Self {
        let (mut lo, mut hi) = (
            Point2::new(f64::MAX, f64::MAX),
            Point2::new(f64::MIN, f64::MIN),
        );
        for p in points {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if points.is_empty() {
            lo = Point2::origin();
            hi = Point2::origin();
        }
        let nx = ((hi.x - lo.x) / cell).floor() as usize + 1;
        let ny = ((hi.y - lo.y) / cell).floor() as usize + 1;
        let mut index = Self {
            origin: lo,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        for (i, p) in points.iter().enumerate() {
            let (cx, cy) = index.cell_of(p);
            index.cells[cy * nx + cx].push(i as u32);
        }
        index
    }

    fn cell_of(&self, p: &Point2<f64>) -> (usize, usize) {
        let cx = ((p.x - self.origin.x) / self.cell)
            .floor()
            .clamp(0.0, (self.nx - 1) as f64);
        let cy = ((p.y - self.origin.y) / self.cell)
            .floor()
            .clamp(0.0, (self.ny - 1) as f64);
        (cx as usize, cy as usize)
    }

    /// Indices of the points in the cells overlapping the square of half side `r` at `p`.
    pub(crate) fn near(&self, p: &Point2<f64>, r: f64, out: &mut Vec<u32>) {
        out.clear();
        let lo = self.cell_of(&(p - Vector2::new(r, r)));
        let hi = self.cell_of(&(p + Vector2::new(r, r)));
        let outside = p.x + r < self.origin.x
            || p.y + r < self.origin.y
            || p.x - r > self.origin.x + self.cell * self.nx as f64
            || p.y - r > self.origin.y + self.cell * self.ny as f64;
        if outside {
            return;
        }
        for cy in lo.1..=hi.1 {
            for cx in lo.0..=hi.0 {
                out.extend_from_slice(&self.cells[cy * self.nx + cx]);
            }
        }
    }
}

/// The trajectory and the poles with their indices.
pub(crate) struct Context<'a> {
    pub(crate) samples: &'a [PathSample],
    pub(crate) positions: Vec<Point2<f64>>,
    pub(crate) path_index: GridIndex,
    pub(crate) poles: &'a [Point2<f64>],
    pub(crate) pole_index: GridIndex,
    pub(crate) scratch: Vec<u32>,
}

impl Context<'_> {
    /// Distance from `p` to the nearest trajectory sample within `r` (∞ if none).
    pub(crate) fn path_distance(&mut self, p: &Point2<f64>, r: f64) -> f64 {
        self.path_index.near(p, r, &mut self.scratch);
        self.scratch
            .iter()
            .map(|&i| (self.positions[i as usize] - p).norm())
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether `fp` keeps `clearance` from every trajectory sample.
    pub(crate) fn footprint_clear_of_path(&mut self, fp: &Footprint, clearance: f64) -> bool {
        let r = fp.half_length_m.hypot(fp.half_width_m) + clearance;
        self.path_index.near(&fp.center, r, &mut self.scratch);
        self.scratch
            .iter()
            .all(|&i| fp.distance(&self.positions[i as usize]) >= clearance)
    }

    /// Whether `fp` keeps `clearance` from every pole.
    pub(crate) fn footprint_clear_of_poles(&mut self, fp: &Footprint, clearance: f64) -> bool {
        let r = fp.half_length_m.hypot(fp.half_width_m) + clearance;
        self.pole_index.near(&fp.center, r, &mut self.scratch);
        self.scratch
            .iter()
            .all(|&i| fp.distance(&self.poles[i as usize]) >= clearance)
    }

    /// Lateral offsets (positive to the left) of the poles within `along_m` of sample `i` and
    /// `max_lateral_m` of the trajectory.
    pub(crate) fn pole_offsets(&mut self, i: usize, along_m: f64, max_lateral_m: f64) -> Vec<f64> {
        let s = self.samples[i];
        self.pole_index
            .near(&s.position, along_m.max(max_lateral_m), &mut self.scratch);
        let (sn, cs) = s.heading_rad.sin_cos();
        self.scratch
            .iter()
            .filter_map(|&k| {
                let d = self.poles[k as usize] - s.position;
                let along = d.x * cs + d.y * sn;
                let lateral = -d.x * sn + d.y * cs;
                (along.abs() <= along_m && lateral.abs() <= max_lateral_m).then_some(lateral)
            })
            .collect()
    }

    /// Ground height at `p`: inverse-distance weighted heights of the trajectory samples
    /// within 30 m (the nearest within 100 m otherwise).
    pub(crate) fn ground_z(&mut self, p: &Point2<f64>) -> Option<f64> {
        self.path_index.near(p, 30.0, &mut self.scratch);
        let (mut sum, mut weight) = (0.0, 0.0);
        for &i in &self.scratch {
            let d2 = (self.positions[i as usize] - p).norm_squared();
            if d2 <= 900.0 {
                let w = 1.0 / (d2 + 1.0);
                sum += w * self.samples[i as usize].ground_z;
                weight += w;
            }
        }
        if weight > 0.0 {
            return Some(sum / weight);
        }
        self.path_index.near(p, 100.0, &mut self.scratch);
        self.scratch
            .iter()
            .map(|&i| ((self.positions[i as usize] - p).norm(), i))
            .filter(|(d, _)| *d <= 100.0)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, i)| self.samples[i as usize].ground_z)
    }
}
