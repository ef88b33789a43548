//! Beam traversal of the global lattice (a scan's keys) and the beam sampler.
//!
//! [`ray_keys`] is the exact voxel traversal of Amanatides & Woo (1987) on the unbounded
//! 16-bit lattice, with OctoMap's conventions (`computeRayKeys`): the keys of every base
//! cube the segment crosses, starting with the origin's cube and excluding the end point's
//! cube, stopping early when accumulated rounding would step past the end. (raypath-geometry's
//! traversal works on bounded `Grid3`s; the grid here has no bounds, so the same stepping
//! runs on integer keys.)

use nalgebra::Point3;
use rand_xoshiro::SplitMix64;
use rand_xoshiro::rand_core::{RngCore, SeedableRng};

use super::{RtreeGrid, ScanUpdate, SensorModel};
use crate::key::{KEY_OFFSET, key_of, pack};

impl RtreeGrid {
    /// Traverses a scan's beams into sorted, de-duplicated packed keys: `occupied` the end
    /// cubes of beams within range, `free` the cubes the beams cross (beam-based model), minus
    /// the occupied ones (occupied wins, OctoMap's `insertPointCloud` rule).
    pub(super) fn gather_keys(
        &mut self,
        origin_m: &Point3<f64>,
        points_m: &[Point3<f64>],
        free: &mut Vec<u64>,
        occupied: &mut Vec<u64>,
        update: &mut ScanUpdate,
    ) {
        let r = self.config.resolution_m;
        let origin = [origin_m.x, origin_m.y, origin_m.z];
        let beam = self.config.model == SensorModel::BeamBased;
        free.clear();
        occupied.clear();
        let recent = &mut self.recent;
        recent.clear();
        for p in points_m {
            let Some((end, hit)) = beam_end(origin, [p.x, p.y, p.z], self.config.max_range_m)
            else {
                continue;
            };
            update.beams += 1;
            match key_of(end, r) {
                Some(k) if hit => occupied.push(pack(k)),
                Some(_) => {}
                None => update.off_lattice += 1,
            }
            if beam {
                ray_keys_with(origin, end, r, |k| {
                    if recent.insert(k) {
                        free.push(k);
                    }
                });
            }
        }
        occupied.sort_unstable();
        occupied.dedup();
        free.sort_unstable();
        free.dedup();
        // Occupied wins: drop free keys that are also hit (both lists are sorted).
        let mut j = 0;
        free.retain(|k| {
            while j < occupied.len() && occupied[j] < *k {
                j += 1;
            }
            !(j < occupied.len() && occupied[j] == *k)
        });
    }
}

/// The end of a beam and whether it is a hit: beams longer than `max_range` are cut there
/// and free only (OctoMap's `maxrange`); `None` for a non-finite end point.
fn beam_end(origin: [f64; 3], end: [f64; 3], max_range: Option<f64>) -> Option<([f64; 3], bool)> {
    if !end.iter().all(|v| v.is_finite()) {
        return None;
    }
    let d = [end[0] - origin[0], end[1] - origin[1], end[2] - origin[2]];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    match max_range {
        Some(max) if len > max => {
            let s = max / len;
            Some((
                [
                    origin[0] + d[0] * s,
                    origin[1] + d[1] * s,
                    origin[2] + d[2] * s,
                ],
                false,
            ))
        }
        _ => Some((end, true)),
    }
}

/// Appends the packed keys of the cubes the segment `origin → end` crosses before the cube
/// of `end`.
pub(crate) fn ray_keys(origin: [f64; 3], end: [f64; 3], resolution_m: f64, out: &mut Vec<u64>) {
    ray_keys_with(origin, end, resolution_m, |k| out.push(k));
}

/// Calls `push` with the packed key of every cube the segment `origin → end` crosses before
/// the cube of `end`.
#[inline]
pub(crate) fn ray_keys_with(
    origin: [f64; 3],
    end: [f64; 3],
    resolution_m: f64,
    mut push: impl FnMut(u64),
) {
    let (Some(start), Some(stop)) = (key_of(origin, resolution_m), key_of(end, resolution_m))
    else {
        return;
    };
    if start == stop {
        return;
    }
    let d = [end[0] - origin[0], end[1] - origin[1], end[2] - origin[2]];
    let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let mut step = [0i32; 3];
    let mut t_max = [f64::INFINITY; 3];
    let mut t_delta = [f64::INFINITY; 3];
    let mut current = [
        i32::from(start[0]),
        i32::from(start[1]),
        i32::from(start[2]),
    ];
    let target = [i32::from(stop[0]), i32::from(stop[1]), i32::from(stop[2])];
    for a in 0..3 {
        let dir = d[a] / length;
        if dir > 0.0 {
            step[a] = 1;
        } else if dir < 0.0 {
            step[a] = -1;
        }
        if step[a] != 0 {
            let mut border = (i64::from(current[a]) - KEY_OFFSET) as f64 * resolution_m;
            if step[a] > 0 {
                border += resolution_m;
            }
            t_max[a] = (border - origin[a]) / dir;
            t_delta[a] = resolution_m / dir.abs();
        }
    }
    let max_steps: i32 = (0..3).map(|a| (target[a] - current[a]).abs()).sum::<i32>() + 3;
    push(pack(start));
    for _ in 0..max_steps {
        let a = if t_max[0] < t_max[1] {
            if t_max[0] < t_max[2] { 0 } else { 2 }
        } else if t_max[1] < t_max[2] {
            1
        } else {
            2
        };
        current[a] += step[a];
        t_max[a] += t_delta[a];
        if current == target {
            return;
        }
        let dist = t_max[0].min(t_max[1]).min(t_max[2]);
        if dist > length || !(0..=65535).contains(&current[a]) {
            return;
        }
        push(pack(current.map(|c| c as u16)));
    }
}

/// A direct-mapped cache of recently emitted keys: neighbouring beams of a scan cross the
/// same cubes near the sensor, so most repeats are dropped before the per-scan sort.
#[derive(Clone, Debug)]
pub(crate) struct RecentKeys {
    pub(crate) slots: Vec<u64>,
}

impl RecentKeys {
    const BITS: u32 = 14;

    /// An empty cache.
    pub(crate) fn new() -> Self {
        Self {
            slots: vec![u64::MAX; 1 << Self::BITS],
        }
    }

    /// Forgets everything.
    pub(crate) fn clear(&mut self) {
        self.slots.fill(u64::MAX);
    }

    /// Whether `key` is new (and remembers it).
    #[inline]
    pub(crate) fn insert(&mut self, key: u64) -> bool {
        let i = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - Self::BITS)) as usize;
        let slot = &mut self.slots[i];
        if *slot == key {
            false
        } else {
            *slot = key;
            true
        }
    }
}

/// The seeded generator of the beam samples: SplitMix64 (`rand_xoshiro`), 8 bytes of state.
pub(crate) struct SplitMix(SplitMix64);

impl SplitMix {
    /// The generator with state `seed`.
    pub(crate) fn new(seed: u64) -> Self {
        Self(SplitMix64::seed_from_u64(seed))
    }

    /// Next value in `[0, 1)` (the top 53 bits of the next output).
    #[inline]
    pub(crate) fn next_f64(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::key::unpack;

    #[test]
    fn axis_ray_crosses_every_cube_before_the_end() {
        let mut out = Vec::new();
        ray_keys([0.05, 0.05, 0.05], [0.55, 0.05, 0.05], 0.1, &mut out);
        let xs: Vec<u16> = out.iter().map(|&k| unpack(k)[0]).collect();
        assert_eq!(xs, vec![32768, 32769, 32770, 32771, 32772]);
    }

    #[test]
    fn diagonal_ray_steps_face_neighbours() {
        let mut out = Vec::new();
        ray_keys([0.01, 0.02, 0.03], [-1.37, 2.11, 0.77], 0.1, &mut out);
        let end = key_of([-1.37, 2.11, 0.77], 0.1).unwrap();
        assert!(!out.contains(&pack(end)));
        for w in out.windows(2) {
            let (a, b) = (unpack(w[0]), unpack(w[1]));
            let diff: i32 = (0..3)
                .map(|i| (i32::from(a[i]) - i32::from(b[i])).abs())
                .sum();
            assert_eq!(diff, 1);
        }
        // The last cube is a face neighbour of the end cube.
        let last = unpack(*out.last().unwrap());
        let diff: i32 = (0..3)
            .map(|i| (i32::from(last[i]) - i32::from(end[i])).abs())
            .sum();
        assert_eq!(diff, 1);
    }
}
