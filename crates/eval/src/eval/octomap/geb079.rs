//! Scans simulated inside the real building map `octomap/geb079.bt` (Freiburg building 079,
//! a 0.08 m OcTree distributed with OctoMap).
//!
//! The map's occupied leaves become a set of 0.08 m voxels on OctoMap's key lattice (coarser
//! leaves expanded). Sensor positions are drawn (seeded, deterministic) inside free leaves,
//! at least [`CLEARANCE_VOXELS`] voxels from any occupied voxel and with a floor (an
//! occupied voxel) 0.4–2.0 m below. From each position a simple 3-D scanner casts
//! `azimuths × elevations` beams (full turn, elevations evenly spread over ±30°, 20 m range)
//! by exact voxel traversal (raypath-geometry's Amanatides–Woo walk) to the first occupied
//! voxel; the end point is the middle of the ray's path through that voxel, so it quantizes
//! into the hit voxel on both sides. Beams that leave the map or reach 20 m without a hit
//! give no point (a `.graph` holds end points only). The sensor frame is axis-aligned with
//! the map frame (REP-103: x forward, y left, z up; metres).

use std::collections::HashSet;
use std::path::Path;

use anyhow::{Context, Result};
use nalgebra::{Point3, Unit, Vector3};
use raypath_geometry::{Aabb3, Grid3, Pose3};
use raypath_io::octomap::{OcTree, ScanGraph, read_bt};

use super::super::EvalContext;
use super::data::{Dataset, finish, node};

/// OctoMap's key offset: key `k` covers `[(k − 32768)·r, (k − 32767)·r)`.
const KEY_OFFSET: i64 = 32768;
/// Minimal distance of a sensor from occupied voxels, in voxels (0.4 m at 0.08 m).
const CLEARANCE_VOXELS: i64 = 5;
/// Scanner range, metres.
const MAX_RANGE_M: f64 = 20.0;
/// Half the vertical field of view, degrees.
const HALF_FOV_DEG: f64 = 30.0;

fn pack(k: [i64; 3]) -> u64 {
    (k[0] as u64 & 0xffff) | ((k[1] as u64 & 0xffff) << 16) | ((k[2] as u64 & 0xffff) << 32)
}

/// The map's occupied voxels (keys on OctoMap's lattice), expanded from coarser leaves.
struct Voxels {
    occupied: HashSet<u64>,
    /// Smallest and largest key per axis.
    lo: [i64; 3],
    hi: [i64; 3],
    /// Voxel size, metres.
    res: f64,
}

impl Voxels {
    fn of(tree: &OcTree, path: &Path) -> Result<Self> {
        let res = tree.resolution_m;
        anyhow::ensure!(
            res.is_finite() && res > 0.0,
            "{}: bad resolution {res}",
            path.display()
        );
        let mut occupied = HashSet::new();
        let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
        for leaf in tree.leaves.iter().filter(|l| l.occupied) {
            let extent = 1i64 << (16 - i64::from(leaf.depth.clamp(1, 16)));
            let k0 = leaf.key_min.map(i64::from);
            for dz in 0..extent {
                for dy in 0..extent {
                    for dx in 0..extent {
                        let k = [k0[0] + dx, k0[1] + dy, k0[2] + dz];
                        occupied.insert(pack(k));
                        for a in 0..3 {
                            lo[a] = lo[a].min(k[a]);
                            hi[a] = hi[a].max(k[a]);
                        }
                    }
                }
            }
        }
        anyhow::ensure!(
            !occupied.is_empty(),
            "{}: no occupied leaves",
            path.display()
        );
        Ok(Self {
            occupied,
            lo,
            hi,
            res,
        })
    }

    fn is_occ(&self, k: [i64; 3]) -> bool {
        self.occupied.contains(&pack(k))
    }

    fn key_of(&self, p: &Point3<f64>) -> Vector3<i64> {
        p.coords.map(|c| (c / self.res).floor() as i64 + KEY_OFFSET)
    }

    /// Free of occupied voxels within the clearance and with a floor 0.4–2.0 m below.
    fn fits_sensor(&self, p: &Point3<f64>) -> bool {
        let k = self.key_of(p);
        let c = CLEARANCE_VOXELS;
        let clear = (-c..=c).all(|dz| {
            (-c..=c).all(|dy| (-c..=c).all(|dx| !self.is_occ([k[0] + dx, k[1] + dy, k[2] + dz])))
        });
        let floor_lo = (0.4 / self.res).round() as i64;
        let floor_hi = (2.0 / self.res).round() as i64;
        let floor = (floor_lo..=floor_hi).any(|dz| self.is_occ([k[0], k[1], k[2] - dz]));
        clear && floor
    }

    /// The voxel grid spanning the occupied keys.
    fn grid(&self) -> Result<Grid3> {
        let origin = self.lo.map(|k| (k - KEY_OFFSET) as f64 * self.res);
        let dims = [0, 1, 2].map(|a| (self.hi[a] - self.lo[a] + 1) as usize);
        Grid3::new(Point3::from(origin), self.res, dims).context("geb079 voxel grid")
    }
}

/// Up to `scans` sensor positions: seeded random points in free leaves that
/// [fit a sensor](Voxels::fits_sensor), at least 2 m apart.
fn sensor_positions(
    tree: &OcTree,
    voxels: &Voxels,
    scans: usize,
    path: &Path,
) -> Result<Vec<Point3<f64>>> {
    let mut state = 0x0790_0790_5eed_0001u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let free: Vec<_> = tree.leaves.iter().filter(|l| !l.occupied).collect();
    anyhow::ensure!(!free.is_empty(), "{}: no free leaves", path.display());
    let mut sensors: Vec<Point3<f64>> = Vec::new();
    let mut attempts = 0;
    while sensors.len() < scans && attempts < 200_000 {
        attempts += 1;
        let i = ((next() * free.len() as f64) as usize).min(free.len() - 1);
        let Some(leaf) = free.get(i) else { continue };
        let (a, b) = leaf.corners();
        let p = Point3::new(
            a.x + next() * (b.x - a.x),
            a.y + next() * (b.y - a.y),
            a.z + next() * (b.z - a.z),
        );
        // Spread the positions: at least 2 m apart.
        let apart = sensors.iter().all(|s| (s - p).norm() > 2.0);
        if voxels.fits_sensor(&p) && apart {
            sensors.push(p);
        }
    }
    anyhow::ensure!(
        !sensors.is_empty(),
        "{}: found no free sensor position",
        path.display()
    );
    Ok(sensors)
}

/// One scan from `sensor`: the end point (sensor frame) of every beam that hits an occupied
/// voxel within range.
fn scan(
    voxels: &Voxels,
    grid: &Grid3,
    sensor: &Point3<f64>,
    azimuths: usize,
    elevations: usize,
) -> Vec<Point3<f32>> {
    let mut points = Vec::with_capacity(azimuths * elevations);
    for e in 0..elevations {
        let elevation = if elevations > 1 {
            (-HALF_FOV_DEG + 2.0 * HALF_FOV_DEG * e as f64 / (elevations - 1) as f64).to_radians()
        } else {
            0.0
        };
        for a in 0..azimuths {
            let azimuth = std::f64::consts::TAU * a as f64 / azimuths as f64;
            let direction = Unit::new_normalize(Vector3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            ));
            let hit = grid
                .traverse(sensor, &direction, MAX_RANGE_M)
                .find(|c| {
                    voxels.is_occ([0, 1, 2].map(|ax| voxels.lo[ax] + c.cell[ax] as i64))
                        && c.t_exit > c.t_enter
                })
                .map(|c| 0.5 * (c.t_enter + c.t_exit));
            if let Some(t) = hit {
                let v = direction.into_inner() * t;
                points.push(Point3::new(v.x as f32, v.y as f32, v.z as f32));
            }
        }
    }
    points
}

/// `scans` scans of `azimuths × elevations` beams inside geb079; `None` when the map is absent.
pub fn geb079(
    ctx: &EvalContext,
    scans: usize,
    azimuths: usize,
    elevations: usize,
) -> Result<Option<Dataset>> {
    let path = ctx.data("octomap/geb079.bt");
    if !path.exists() {
        eprintln!("octomap: {} is absent, skipping geb079", path.display());
        return Ok(None);
    }
    let tree = read_bt(&path)?;
    let voxels = Voxels::of(&tree, &path)?;
    let sensors = sensor_positions(&tree, &voxels, scans, &path)?;
    let grid = voxels.grid()?;
    let nodes = sensors
        .iter()
        .enumerate()
        .map(|(id, sensor)| {
            let pose = Pose3::from_xyz_rpy(sensor.x, sensor.y, sensor.z, 0.0, 0.0, 0.0);
            node(
                id as u32,
                pose,
                scan(&voxels, &grid, sensor, azimuths, elevations),
            )
        })
        .collect();
    let graph = ScanGraph {
        nodes,
        edges: Vec::new(),
    };
    let bbox = Aabb3::from_points(sensors.iter());
    let res = voxels.res;
    let about = format!(
        "{} scans simulated inside the real building map `geb079.bt` ({} occupied {res} m \
         voxels): {azimuths} × {elevations} beams (±{HALF_FOV_DEG}° elevation, {MAX_RANGE_M} m \
         range) from seeded free positions (≥ {:.2} m from walls, floor below, ≥ 2 m apart; \
         sensors within x ∈ [{:.1}, {:.1}], y ∈ [{:.1}, {:.1}] m), exact voxel traversal to \
         the first occupied voxel, {} points",
        graph.nodes.len(),
        voxels.occupied.len(),
        CLEARANCE_VOXELS as f64 * res,
        bbox.min.x,
        bbox.max.x,
        bbox.min.y,
        bbox.max.y,
        graph.num_points()
    );
    finish(ctx, "geb079", about, graph).map(Some)
}
