//! Sparse statistics: blocks of 8 × 8 (× 8) cells in a hash map, for large outdoor maps.

use std::collections::HashMap;

use raypath_geometry::{PointCloud, Pose3};

use crate::SensorModelError;
use crate::dimension::{Crossing, Dimension, Planar, Spatial};
use crate::stats::dense::for_each_cloud_ray;
use crate::stats::insert::{StatsSink, insert_ray};
use crate::stats::parallel::insert_parallel;
use crate::stats::{CellStats, DenseStats, MappingConfig, MappingSummary};
use rustc_hash::FxBuildHasher;

/// Edge of a block in cells.
pub const BLOCK_EDGE: usize = 8;

/// Per-cell ray statistics on a grid, stored in blocks of `8^d` cells (8³ = 512 voxels,
/// 8 KiB, in 3-D) that exist only where a ray passed: a `HashMap` from the block's linear
/// index in the block lattice to the block's position in a `Vec` of blocks.
///
/// The grid bounds the region (up to 2^40 cells, e.g. 50 km × 50 km × 100 m at 0.5 m) and
/// drives the same exact traversal as [`DenseStats`]; only touched blocks cost memory.
/// Consecutive crossings of a ray mostly stay in one block, so the hash map is consulted
/// about once per block entered, not per cell. The cost compared with dense storage is
/// measured in `benches/mapping.rs` (see the crate docs).
#[derive(Clone, Debug)]
pub struct SparseStats<D: Dimension> {
    grid: D::Grid,
    /// Blocks per axis (padded to three axes).
    blocks_per_axis: [usize; 3],
    index: HashMap<u64, usize, FxBuildHasher>,
    blocks: Vec<Box<[CellStats]>>,
    keys: Vec<u64>,
    /// The last block used: (key, position in `blocks`).
    cached: Option<(u64, usize)>,
    summary: MappingSummary,
}

/// Sparse statistics on a 2-D grid.
pub type SparseStats2 = SparseStats<Planar>;
/// Sparse statistics on a 3-D grid.
pub type SparseStats3 = SparseStats<Spatial>;

impl<D: Dimension> SparseStats<D> {
    /// Cells in one block: `8^d`.
    pub const BLOCK_CELLS: usize = BLOCK_EDGE.pow(D::AXES as u32);

    /// Empty statistics on `grid` (no blocks allocated).
    pub fn new(grid: D::Grid) -> Self {
        let dims = D::dims3(&grid);
        Self {
            grid,
            blocks_per_axis: dims.map(|d| d.div_ceil(BLOCK_EDGE)),
            index: HashMap::default(),
            blocks: Vec::new(),
            keys: Vec::new(),
            cached: None,
            summary: MappingSummary::default(),
        }
    }

    /// The grid.
    pub fn grid(&self) -> &D::Grid {
        &self.grid
    }

    /// What happened to the rays inserted so far.
    pub fn summary(&self) -> &MappingSummary {
        &self.summary
    }

    /// Number of allocated blocks.
    pub fn num_blocks(&self) -> usize {
        self.blocks.len()
    }

    /// Approximate heap memory in bytes (blocks plus index).
    pub fn memory_bytes(&self) -> usize {
        self.blocks.len() * (Self::BLOCK_CELLS * size_of::<CellStats>() + 24)
            + self.index.capacity() * 24
    }

    /// The statistics of the cell at `cell` (padded to three axes; empty when unallocated
    /// or outside the grid).
    pub fn cell(&self, cell: [usize; 3]) -> CellStats {
        let (key, offset) = self.locate(cell);
        self.index
            .get(&key)
            .and_then(|&position| self.blocks.get(position))
            .and_then(|block| block.get(offset))
            .copied()
            .unwrap_or_default()
    }

    /// Inserts one ray given in the map frame.
    pub fn insert_ray(&mut self, ray: &D::Ray, config: &MappingConfig) {
        insert_ray::<D, Self>(self, ray, config);
    }

    /// Inserts rays given in the map frame, in parallel (deterministic result).
    pub fn insert_rays_par(&mut self, rays: &[D::Ray], config: &MappingConfig) {
        self.insert_par(rays, config, |ray, sink| sink(ray));
    }

    /// Inserts the rays `rays_of` produces for each item, in parallel with per-thread
    /// partial maps whose blocks are merged at the end (deterministic result).
    pub fn insert_par<T: Sync>(
        &mut self,
        items: &[T],
        config: &MappingConfig,
        rays_of: impl Fn(&T, &mut dyn FnMut(&D::Ray)) + Sync,
    ) {
        let grid = self.grid;
        insert_parallel::<D, Self, T>(
            self,
            Self::new(grid),
            items,
            config,
            || Self::new(grid),
            |into, from| into.merge_unchecked(&from),
            rays_of,
        );
    }

    /// Adds the statistics of `other` (same grid).
    pub fn merge(&mut self, other: &Self) -> Result<(), SensorModelError> {
        if self.grid != other.grid {
            return Err(SensorModelError::GridMismatch {
                reason: format!("cannot merge maps on {:?} and {:?}", self.grid, other.grid),
            });
        }
        self.merge_unchecked(other);
        Ok(())
    }

    fn merge_unchecked(&mut self, other: &Self) {
        for (key, block) in other.keys.iter().zip(&other.blocks) {
            let position = self.block_position(*key);
            if let Some(into) = self.blocks.get_mut(position) {
                for (a, b) in into.iter_mut().zip(block.iter()) {
                    a.merge(b);
                }
            }
        }
        self.summary.merge(&other.summary);
    }

    /// Visits every allocated cell that a ray touched, in increasing linear index of the
    /// grid, with its linear index.
    pub fn for_each_cell(&self, mut visit: impl FnMut(usize, &CellStats)) {
        let dims = D::dims3(&self.grid);
        let mut order: Vec<(u64, usize)> = self
            .keys
            .iter()
            .copied()
            .zip(0..self.blocks.len())
            .collect();
        order.sort_unstable();
        for (key, position) in order {
            let Some(block) = self.blocks.get(position) else {
                continue;
            };
            let [bx, by, bz] = self.block_coords(key);
            for (offset, stats) in block.iter().enumerate() {
                if stats.is_empty() {
                    continue;
                }
                let x = bx * BLOCK_EDGE + offset % BLOCK_EDGE;
                let y = by * BLOCK_EDGE + (offset / BLOCK_EDGE) % BLOCK_EDGE;
                let z = bz * BLOCK_EDGE + offset / (BLOCK_EDGE * BLOCK_EDGE);
                if x < dims[0] && y < dims[1] && z < dims[2] {
                    visit(x + dims[0] * (y + dims[1] * z), stats);
                }
            }
        }
    }

    /// The same statistics stored densely (allocates `16 · num_cells` bytes).
    pub fn to_dense(&self) -> DenseStats<D> {
        let mut cells = vec![CellStats::EMPTY; D::num_cells(&self.grid)];
        self.for_each_cell(|index, stats| {
            if let Some(cell) = cells.get_mut(index) {
                *cell = *stats;
            }
        });
        // `cells` has exactly one entry per cell, so this cannot fail.
        DenseStats::from_parts(self.grid, cells, self.summary)
            .unwrap_or_else(|_| DenseStats::new(self.grid))
    }

    /// Block key and offset within the block of a cell.
    #[inline(always)]
    fn locate(&self, cell: [usize; 3]) -> (u64, usize) {
        let b = cell.map(|c| c / BLOCK_EDGE);
        let key = b[0] + self.blocks_per_axis[0] * (b[1] + self.blocks_per_axis[1] * b[2]);
        let o = cell.map(|c| c % BLOCK_EDGE);
        (key as u64, o[0] + BLOCK_EDGE * (o[1] + BLOCK_EDGE * o[2]))
    }

    fn block_coords(&self, key: u64) -> [usize; 3] {
        let key = key as usize;
        let [nx, ny, _] = self.blocks_per_axis;
        [key % nx, (key / nx) % ny, key / (nx * ny)]
    }

    /// Position of the block `key` in `blocks`, allocating it when new.
    #[inline]
    fn block_position(&mut self, key: u64) -> usize {
        if let Some((cached_key, position)) = self.cached
            && cached_key == key
        {
            return position;
        }
        let next = self.blocks.len();
        let position = *self.index.entry(key).or_insert(next);
        if position == next {
            self.blocks
                .push(vec![CellStats::EMPTY; Self::BLOCK_CELLS].into_boxed_slice());
            self.keys.push(key);
        }
        self.cached = Some((key, position));
        position
    }
}

impl<D: Dimension> StatsSink<D> for SparseStats<D> {
    #[inline(always)]
    fn sink_grid(&self) -> &D::Grid {
        &self.grid
    }
    #[inline(always)]
    fn cell_mut(&mut self, crossing: &D::Crossing) -> &mut CellStats {
        let (key, offset) = self.locate(crossing.cell3());
        let position = self.block_position(key);
        // Blocks hold `BLOCK_CELLS` entries and `offset < BLOCK_CELLS`.
        &mut self.blocks[position][offset]
    }
    #[inline(always)]
    fn summary_mut(&mut self) -> &mut MappingSummary {
        &mut self.summary
    }
}

impl SparseStats<Spatial> {
    /// Inserts point clouds (sensor frame) with their `world_from_sensor` poses in
    /// parallel, like [`DenseStats::insert_clouds_par`].
    pub fn insert_clouds_par(&mut self, clouds: &[(Pose3, &PointCloud)], config: &MappingConfig) {
        self.insert_par(clouds, config, |(world_from_sensor, cloud), sink| {
            for_each_cloud_ray(world_from_sensor, cloud, sink);
        });
    }
}
