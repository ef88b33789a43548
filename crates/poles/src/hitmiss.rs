//! The local 3-D grid of hit and miss counts, filled by exact ray traversal (Schaefer 2020,
//! §12.4.1; `acschaefer/ray_tracing`): every voxel a ray crosses gets a miss; when the endpoint
//! lies inside the grid, the last voxel's miss becomes a hit. Rays are clipped to the grid.
//!
//! The walk is `raypath-geometry`'s [`SlabWalk`], the counting fast path of
//! [`Grid3::traverse`]: its clipping and end voxels, then slab by slab along the major axis
//! with fixed-point side-axis counters and linear-index stepping (the same voxels up to ties
//! at voxel edges and corners, tested against it there); the cost is linear in the voxels
//! crossed (about 120 per ray of a KITTI local map).
//!
//! The counts are kept here rather than in `raypath-sensor-models`' per-cell statistics
//! (`DenseStats3`, whose `CellStats` hold hits and misses too): those also sum the path
//! length per cell (the decay-rate models need it, the occupancy here does not), in `u32`
//! counts and a `u64` length, 16 bytes per voxel against 4 here. A KITTI local map has
//! 2.7 M voxels and every thread fills its own partial grid, so that memory traffic, and the
//! per-voxel `t` intervals path lengths need (which the slab walk avoids), would dominate
//! the extraction. Their ray rules differ as well: there a zero-length crossing at a voxel
//! edge or corner is no miss and a return beyond the range limit is traced to it as misses;
//! here every voxel walked counts and such points are not traced
//! ([`PoleParams::max_range_m`](crate::PoleParams::max_range_m)).

use nalgebra::Point3;
use rayon::prelude::*;
use raypath_geometry::{Grid3, PointCloud, Pose3, SlabWalk};

use crate::sweep::SweepMotion;

/// Traces the segment from `origin` to `endpoint` (world frame): one miss for every voxel it
/// crosses inside the grid, and when the endpoint's voxel is the last one crossed, that miss
/// becomes a hit (saturating counts).
#[inline]
fn trace(
    walk: &SlabWalk,
    hits: &mut [u16],
    misses: &mut [u16],
    origin: &Point3<f64>,
    endpoint: &Point3<f64>,
) {
    if let Some(end) = walk.count(misses, origin, endpoint)
        && end.contains_endpoint
    {
        if let Some(m) = misses.get_mut(end.last) {
            *m = m.saturating_sub(1);
        }
        if let Some(h) = hits.get_mut(end.last) {
            *h = h.saturating_add(1);
        }
    }
}

/// Hit and miss counts per voxel of a [`Grid3`] (linear index, x fastest), saturating
/// `u16` (half the memory traffic of `u32`; a voxel with 65535 misses is free anyway).
#[derive(Clone, Debug, PartialEq)]
pub struct HitMissGrid {
    grid: Grid3,
    hits: Vec<u16>,
    misses: Vec<u16>,
    rays: u64,
}

impl HitMissGrid {
    /// An empty grid.
    pub fn new(grid: Grid3) -> Self {
        let n = grid.num_cells();
        Self {
            grid,
            hits: vec![0; n],
            misses: vec![0; n],
            rays: 0,
        }
    }

    /// The grid geometry.
    pub fn grid(&self) -> &Grid3 {
        &self.grid
    }

    /// Hits per voxel.
    pub fn hits(&self) -> &[u16] {
        &self.hits
    }

    /// Misses per voxel.
    pub fn misses(&self) -> &[u16] {
        &self.misses
    }

    /// Number of rays traced so far.
    pub fn rays(&self) -> u64 {
        self.rays
    }

    /// Traces one ray from `origin` to `endpoint` (world frame).
    #[inline]
    pub fn insert_ray(&mut self, origin: &Point3<f64>, endpoint: &Point3<f64>) {
        let walk = SlabWalk::new(&self.grid);
        trace(&walk, &mut self.hits, &mut self.misses, origin, endpoint);
        self.rays += 1;
    }

    /// Traces every valid point of every scan (`world_from_sensor`, points in the sensor
    /// frame) from the sensor position, in parallel: the points are split into one
    /// contiguous, equal share per thread; the first share is counted into this grid, the
    /// others into partial grids that are then added (saturating; the counts equal those of
    /// sequential insertion unless a voxel saturates). Points farther than `max_range_m` from
    /// the sensor are skipped.
    pub fn insert_scans_par(&mut self, scans: &[(Pose3, &PointCloud)], max_range_m: f64) {
        self.insert_sweeps_par(scans, None, max_range_m);
    }

    /// [`insert_scans_par`](Self::insert_scans_par) for de-skewed sweeps: with `motions`
    /// (one per scan), the ray of every point starts where the sensor was when it measured
    /// the point ([`SweepMotion::origin`]), not at the scan's origin.
    pub fn insert_sweeps_par(
        &mut self,
        scans: &[(Pose3, &PointCloud)],
        motions: Option<&[SweepMotion]>,
        max_range_m: f64,
    ) {
        let total: usize = scans.iter().map(|(_, c)| c.len()).sum();
        if total == 0 {
            return;
        }
        let threads = rayon::current_num_threads().max(1);
        let shares = split_points(scans, total.div_ceil(threads).max(1));
        let Some((first, rest)) = shares.split_first() else {
            return;
        };
        let n = self.grid.num_cells();
        let walk = SlabWalk::new(&self.grid);
        let max_sq = max_range_m * max_range_m;
        let trace_share = |share: &[Piece], hits: &mut [u16], misses: &mut [u16]| -> u64 {
            let mut rays = 0u64;
            for &(s, start, end) in share {
                let Some((pose, cloud)) = scans.get(s) else {
                    continue;
                };
                let fixed_origin = Point3::from(pose.translation());
                let motion = motions.and_then(|m| m.get(s));
                let Some(points) = cloud.points.get(start..end) else {
                    continue;
                };
                for p in points {
                    if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                        continue;
                    }
                    let local = Point3::new(p.x as f64, p.y as f64, p.z as f64);
                    if local.coords.norm_squared() > max_sq {
                        continue;
                    }
                    let endpoint = pose.transform_point(&local);
                    let origin = match motion {
                        Some(m) => pose.transform_point(&m.origin(&local)),
                        None => fixed_origin,
                    };
                    trace(&walk, hits, misses, &origin, &endpoint);
                    rays += 1;
                }
            }
            rays
        };
        let (hits, misses) = (&mut self.hits, &mut self.misses);
        let (rays, partials) = rayon::join(
            || trace_share(first, hits, misses),
            || {
                rest.par_iter()
                    .map(|share| {
                        let (mut hits, mut misses) = (vec![0u16; n], vec![0u16; n]);
                        let rays = trace_share(share, &mut hits, &mut misses);
                        (hits, misses, rays)
                    })
                    .collect::<Vec<_>>()
            },
        );
        self.rays += rays;
        for (hits, misses, rays) in partials {
            add_into(&mut self.hits, &hits);
            add_into(&mut self.misses, &misses);
            self.rays += rays;
        }
    }
}

/// Points `start..end` of scan `s`.
type Piece = (usize, usize, usize);

/// Splits the points of all scans, in order, into shares of `share` points (the last one
/// shorter), each a list of pieces of scans.
fn split_points(scans: &[(Pose3, &PointCloud)], share: usize) -> Vec<Vec<Piece>> {
    let mut shares = vec![Vec::new()];
    let mut room = share;
    for (s, (_, cloud)) in scans.iter().enumerate() {
        let mut start = 0;
        while start < cloud.len() {
            if room == 0 {
                shares.push(Vec::new());
                room = share;
            }
            let end = (start + room).min(cloud.len());
            if let Some(last) = shares.last_mut() {
                last.push((s, start, end));
            }
            room -= end - start;
            start = end;
        }
    }
    shares
}

fn add_into(total: &mut [u16], part: &[u16]) {
    total
        .par_chunks_mut(1 << 16)
        .zip(part.par_chunks(1 << 16))
        .for_each(|(t, p)| {
            for (a, b) in t.iter_mut().zip(p) {
                *a = a.saturating_add(*b);
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweep_rays_start_where_the_sensor_was() {
        use crate::sweep::{SweepMotion, SweepTiming};
        use nalgebra::Vector3;
        // 0.1 m voxels over x −1..1, y −6..1, z −0.5..0.5; one point 5 m to the right.
        let grid = Grid3::new(Point3::new(-1.0, -6.0, -0.5), 0.1, [20, 70, 10]).expect("grid");
        let cloud = PointCloud::from_points(vec![Point3::new(0.05, -5.0, 0.05)]);
        let scans = [(Pose3::identity(), &cloud)];
        let motion = [SweepMotion {
            translation_m: Vector3::new(0.8, 0.0, 0.0),
            timing: SweepTiming::kitti(),
        }];
        let voxel = |x: f64, y: f64| {
            let cell = grid.cell_of(&Point3::new(x, y, 0.05)).expect("inside");
            grid.linear_index(cell)
        };
        let mut fixed = HitMissGrid::new(grid);
        fixed.insert_sweeps_par(&scans, None, 100.0);
        let mut moving = HitMissGrid::new(grid);
        moving.insert_sweeps_par(&scans, Some(&motion), 100.0);
        // Fired a quarter turn after facing forward: from (0.2, 0, 0), not the origin; half
        // way to the point the ray is at x = 0.125 instead of 0.05.
        let half = |x: f64| voxel(x, -2.45);
        assert_eq!(fixed.misses()[half(0.05)], 1);
        assert_eq!(fixed.misses()[half(0.125)], 0);
        assert_eq!(moving.misses()[half(0.05)], 0);
        assert_eq!(moving.misses()[half(0.125)], 1);
        // The hit is the point either way.
        let end = voxel(0.05, -4.95);
        assert_eq!((fixed.hits()[end], moving.hits()[end]), (1, 1));
        assert_eq!(moving.rays(), 1);
    }

    #[test]
    fn a_ray_misses_the_way_and_hits_the_end() {
        let grid = Grid3::new(Point3::origin(), 1.0, [10, 1, 1]).expect("grid");
        let mut map = HitMissGrid::new(grid);
        map.insert_ray(&Point3::new(0.5, 0.5, 0.5), &Point3::new(4.5, 0.5, 0.5));
        assert_eq!(&map.misses()[..6], &[1, 1, 1, 1, 0, 0]);
        assert_eq!(&map.hits()[..6], &[0, 0, 0, 0, 1, 0]);
        // A ray leaving the grid only misses.
        map.insert_ray(&Point3::new(0.5, 0.5, 0.5), &Point3::new(20.0, 0.5, 0.5));
        assert_eq!(map.misses()[9], 1);
        assert_eq!(map.hits().iter().map(|&h| h as u32).sum::<u32>(), 1);
    }

    #[test]
    fn parallel_insertion_equals_sequential() {
        let grid = Grid3::new(Point3::new(-5.0, -5.0, -1.0), 0.25, [40, 40, 8]).expect("grid");
        let points: Vec<Point3<f32>> = (0..500)
            .map(|i| {
                let a = i as f32 * 0.1;
                Point3::new(4.0 * a.cos(), 4.0 * a.sin(), (i % 7) as f32 * 0.2 - 0.5)
            })
            .collect();
        let cloud = PointCloud::from_points(points.clone());
        let pose = Pose3::from_xyz_rpy(0.3, -0.2, 0.1, 0.0, 0.0, 0.4);
        let mut par = HitMissGrid::new(grid);
        par.insert_scans_par(&[(pose, &cloud)], 100.0);
        let mut seq = HitMissGrid::new(grid);
        let origin = Point3::from(pose.translation());
        for p in &points {
            let e = pose.transform_point(&Point3::new(p.x as f64, p.y as f64, p.z as f64));
            seq.insert_ray(&origin, &e);
        }
        assert_eq!(par.hits(), seq.hits());
        assert_eq!(par.misses(), seq.misses());
        assert_eq!(par.rays(), 500);
    }

    #[test]
    fn shares_cover_every_point_once_in_order() {
        let clouds: Vec<PointCloud> = [3usize, 0, 7, 5]
            .iter()
            .map(|&n| PointCloud::from_points(vec![Point3::new(1.0f32, 0.0, 0.0); n]))
            .collect();
        let scans: Vec<(Pose3, &PointCloud)> = clouds
            .iter()
            .map(|c| (Pose3::from_xyz_rpy(0.0, 0.0, 0.0, 0.0, 0.0, 0.0), c))
            .collect();
        let shares = split_points(&scans, 4);
        let sizes: Vec<usize> = shares
            .iter()
            .map(|s| s.iter().map(|&(_, a, b)| b - a).sum())
            .collect();
        assert_eq!(sizes, [4, 4, 4, 3]);
        let pieces: Vec<Piece> = shares.concat();
        assert_eq!(
            pieces,
            [
                (0, 0, 3),
                (2, 0, 1),
                (2, 1, 5),
                (2, 5, 7),
                (3, 0, 2),
                (3, 2, 5)
            ]
        );
    }
}
