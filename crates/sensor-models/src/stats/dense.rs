//! Dense statistics: one [`CellStats`] per grid cell in a contiguous `Vec`.

use rayon::prelude::*;

use raypath_geometry::{Grid2, Grid3, PointCloud, Pose2, Pose3, Ray3, Scan2};

use crate::SensorModelError;
use crate::dimension::{Crossing, Dimension, Planar, Spatial};
use crate::stats::insert::{StatsSink, insert_ray};
use crate::stats::parallel::insert_parallel;
use crate::stats::{CellStats, MappingConfig, MappingSummary};

/// Per-cell ray statistics on every cell of a grid, stored densely (linear index x fastest,
/// as [`Grid3::linear_index`]). 16 bytes per cell: a 400 × 400 × 80 grid of 0.5 m voxels
/// (200 m × 200 m × 40 m) takes 205 MB; see [`crate::SparseStats`] for larger areas.
///
/// Built by [`DenseStats::insert_ray`] (one ray), [`DenseStats::insert_rays_par`] (a slice
/// of rays) or [`DenseStats::insert_par`] (anything that yields rays: scans, clouds),
/// following algorithm MAP-DECAY (Schaefer 2020, Sec. 7.4.2); rays are in the map frame.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseStats<D: Dimension> {
    grid: D::Grid,
    cells: Vec<CellStats>,
    summary: MappingSummary,
}

/// Dense statistics on a 2-D grid.
pub type DenseStats2 = DenseStats<Planar>;
/// Dense statistics on a 3-D grid.
pub type DenseStats3 = DenseStats<Spatial>;

impl<D: Dimension> DenseStats<D> {
    /// Empty statistics on `grid` (allocates `16 · num_cells` bytes).
    pub fn new(grid: D::Grid) -> Self {
        Self {
            grid,
            cells: vec![CellStats::EMPTY; D::num_cells(&grid)],
            summary: MappingSummary::default(),
        }
    }

    /// Statistics from their parts; fails when `cells` does not have one entry per cell.
    pub fn from_parts(
        grid: D::Grid,
        cells: Vec<CellStats>,
        summary: MappingSummary,
    ) -> Result<Self, SensorModelError> {
        if cells.len() != D::num_cells(&grid) {
            return Err(SensorModelError::GridMismatch {
                reason: format!(
                    "{} cell statistics for a grid of {} cells",
                    cells.len(),
                    D::num_cells(&grid)
                ),
            });
        }
        Ok(Self {
            grid,
            cells,
            summary,
        })
    }

    /// The grid.
    pub fn grid(&self) -> &D::Grid {
        &self.grid
    }

    /// All cells, by linear index.
    pub fn cells(&self) -> &[CellStats] {
        &self.cells
    }

    /// The statistics of the cell with linear index `index` (empty outside the grid).
    pub fn cell(&self, index: usize) -> CellStats {
        self.cells.get(index).copied().unwrap_or_default()
    }

    /// What happened to the rays inserted so far.
    pub fn summary(&self) -> &MappingSummary {
        &self.summary
    }

    /// Inserts one ray given in the map frame.
    pub fn insert_ray(&mut self, ray: &D::Ray, config: &MappingConfig) {
        insert_ray::<D, Self>(self, ray, config);
    }

    /// Inserts rays given in the map frame, in parallel (deterministic result).
    pub fn insert_rays_par(&mut self, rays: &[D::Ray], config: &MappingConfig) {
        self.insert_par(rays, config, |ray, sink| sink(ray));
    }

    /// Inserts the rays that `rays_of` produces for each item (a scan with its pose, a
    /// point cloud, …), in parallel over chunks of items with per-thread partial maps that
    /// are summed at the end. The result is identical for any thread count.
    pub fn insert_par<T: Sync>(
        &mut self,
        items: &[T],
        config: &MappingConfig,
        rays_of: impl Fn(&T, &mut dyn FnMut(&D::Ray)) + Sync,
    ) {
        let grid = self.grid;
        let placeholder = Self {
            grid,
            cells: Vec::new(),
            summary: MappingSummary::default(),
        };
        insert_parallel::<D, Self, T>(
            self,
            placeholder,
            items,
            config,
            || Self::new(grid),
            |into, from| into.merge_unchecked(&from),
            rays_of,
        );
    }

    /// Adds the statistics of `other` (same grid) cell by cell.
    pub fn merge(&mut self, other: &Self) -> Result<(), SensorModelError> {
        if self.grid != other.grid || self.cells.len() != other.cells.len() {
            return Err(SensorModelError::GridMismatch {
                reason: format!("cannot merge maps on {:?} and {:?}", self.grid, other.grid),
            });
        }
        self.merge_unchecked(other);
        Ok(())
    }

    fn merge_unchecked(&mut self, other: &Self) {
        const CHUNK: usize = 1 << 16;
        self.cells
            .par_chunks_mut(CHUNK)
            .zip(other.cells.par_chunks(CHUNK))
            .for_each(|(into, from)| {
                for (a, b) in into.iter_mut().zip(from) {
                    a.merge(b);
                }
            });
        self.summary.merge(&other.summary);
    }
}

impl<D: Dimension> StatsSink<D> for DenseStats<D> {
    #[inline(always)]
    fn sink_grid(&self) -> &D::Grid {
        &self.grid
    }
    #[inline(always)]
    fn cell_mut(&mut self, crossing: &D::Crossing) -> &mut CellStats {
        // The traversal only yields cells of the grid, so the index is in range.
        &mut self.cells[crossing.index()]
    }
    #[inline(always)]
    fn summary_mut(&mut self) -> &mut MappingSummary {
        &mut self.summary
    }
}

impl DenseStats<Planar> {
    /// Empty statistics on a 2-D grid (same as [`DenseStats::new`]).
    pub fn planar(grid: Grid2) -> Self {
        Self::new(grid)
    }

    /// Inserts 2-D scans, each with its `world_from_sensor` pose, in parallel. Every beam
    /// becomes a ray ([`Scan2::rays`]; readings at or above the scan's `max_range_m` are
    /// no-returns).
    pub fn insert_scans_par(&mut self, scans: &[(Pose2, &Scan2)], config: &MappingConfig) {
        self.insert_par(scans, config, |(world_from_sensor, scan), sink| {
            for ray in scan.rays(*world_from_sensor) {
                sink(&ray);
            }
        });
    }
}

impl DenseStats<Spatial> {
    /// Empty statistics on a 3-D grid (same as [`DenseStats::new`]).
    pub fn spatial(grid: Grid3) -> Self {
        Self::new(grid)
    }

    /// The statistics summed over each vertical column (`H`, `M`, `R` added over z): a 2-D
    /// map of the same x–y grid, e.g. for pictures of a 3-D map.
    pub fn project_z(&self) -> DenseStats2 {
        let [nx, ny, nz] = self.grid.dims();
        let origin = self.grid.origin();
        let mut cells = vec![CellStats::EMPTY; nx * ny];
        for z in 0..nz {
            let layer = self
                .cells
                .get(z * nx * ny..(z + 1) * nx * ny)
                .unwrap_or_default();
            for (into, from) in cells.iter_mut().zip(layer) {
                into.merge(from);
            }
        }
        let grid = Grid2::new(
            nalgebra::Point2::new(origin.x, origin.y),
            self.grid.cell_size(),
            [nx, ny],
        )
        .expect("the x-y grid of a valid 3-D grid is valid");
        DenseStats2 {
            grid,
            cells,
            summary: self.summary,
        }
    }

    /// Inserts point clouds given in the sensor frame, each with its `world_from_sensor`
    /// pose, in parallel: every valid point is a return along the ray from the sensor
    /// origin. Missing points (NaN) are skipped (their direction is unknown), as are points
    /// at the origin.
    pub fn insert_clouds_par(&mut self, clouds: &[(Pose3, &PointCloud)], config: &MappingConfig) {
        self.insert_par(clouds, config, |(world_from_sensor, cloud), sink| {
            for_each_cloud_ray(world_from_sensor, cloud, sink);
        });
    }
}

/// Calls `sink` with the ray (map frame) to every valid point of `cloud` (sensor frame).
pub(crate) fn for_each_cloud_ray(
    world_from_sensor: &Pose3,
    cloud: &PointCloud,
    sink: &mut dyn FnMut(&Ray3),
) {
    let origin = world_from_sensor.transform_point(&nalgebra::Point3::origin());
    for i in 0..cloud.len() {
        if !cloud.is_valid(i) {
            continue;
        }
        let point_in_world = world_from_sensor.transform_point(&cloud.point_f64(i));
        if let Some(ray) = Ray3::between(origin, point_in_world) {
            sink(&ray);
        }
    }
}
