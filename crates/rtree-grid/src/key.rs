//! Cells on the global lattice: integer keys and inclusive key boxes.
//!
//! Every cell lies on one global lattice of base resolution `r` (metres) anchored at the
//! origin, the same lattice OctoMap uses (`OcTreeKey.h`): the base cube with key `k` spans
//! `[(k − 32768)·r, (k − 32768 + 1)·r)` per axis, i.e. `k = floor(x / r) + 32768`. Keys are
//! `u16`, so a map spans 65 536 base cubes per axis (6.5 km at 0.1 m), like OctoMap's.
//! A fused cell is a [`KeyBox`]: the inclusive range of base keys it covers per axis.

/// The key of coordinate 0 (OctoMap's `tree_max_val`).
pub const KEY_OFFSET: i64 = 32768;

/// How far the lattice reaches from the origin along each axis at resolution `r`:
/// 32 768 · r metres (3.3 km at 0.1 m). Points beyond it have no key.
pub fn lattice_half_extent_m(resolution_m: f64) -> f64 {
    KEY_OFFSET as f64 * resolution_m
}

/// A base-cube key on the global lattice (x, y, z).
pub type Key = [u16; 3];

/// The key of the base cube containing `point_m` at resolution `resolution_m`, or `None`
/// when the point is not finite or lies outside the 16-bit lattice.
#[inline]
pub fn key_of(point_m: [f64; 3], resolution_m: f64) -> Option<Key> {
    let mut key = [0u16; 3];
    for axis in 0..3 {
        let k = (point_m[axis] / resolution_m).floor();
        if !k.is_finite() {
            return None;
        }
        let k = k as i64 + KEY_OFFSET;
        key[axis] = u16::try_from(k).ok()?;
    }
    Some(key)
}

/// Packs a key into 48 bits (x in the low bits).
#[inline]
pub fn pack(key: Key) -> u64 {
    u64::from(key[0]) | (u64::from(key[1]) << 16) | (u64::from(key[2]) << 32)
}

/// Inverse of [`pack`].
#[inline]
pub fn unpack(packed: u64) -> Key {
    [
        (packed & 0xffff) as u16,
        ((packed >> 16) & 0xffff) as u16,
        ((packed >> 32) & 0xffff) as u16,
    ]
}

/// The Morton (Z-order) code of a key: its bits interleaved, x lowest.
#[inline]
pub fn morton(key: Key) -> u64 {
    /// Spreads the 16 bits of `v` to every third bit.
    fn spread(v: u16) -> u64 {
        let mut x = u64::from(v);
        x = (x | (x << 32)) & 0x001F_0000_0000_FFFF;
        x = (x | (x << 16)) & 0x001F_0000_FF00_00FF;
        x = (x | (x << 8)) & 0x100F_00F0_0F00_F00F;
        x = (x | (x << 4)) & 0x10C3_0C30_C30C_30C3;
        (x | (x << 2)) & 0x1249_2492_4924_9249
    }
    spread(key[0]) | (spread(key[1]) << 1) | (spread(key[2]) << 2)
}

/// Inverse of [`morton`].
#[inline]
pub fn from_morton(code: u64) -> Key {
    /// Gathers every third bit of `x` into the low 16 bits.
    fn compact(x: u64) -> u16 {
        let mut x = x & 0x1249_2492_4924_9249;
        x = (x | (x >> 2)) & 0x10C3_0C30_C30C_30C3;
        x = (x | (x >> 4)) & 0x100F_00F0_0F00_F00F;
        x = (x | (x >> 8)) & 0x001F_0000_FF00_00FF;
        x = (x | (x >> 16)) & 0x001F_0000_0000_FFFF;
        x = (x | (x >> 32)) & 0xFFFF;
        x as u16
    }
    [compact(code), compact(code >> 1), compact(code >> 2)]
}

/// An axis-aligned box of base cubes: keys `lo[a] ..= hi[a]` on each axis `a`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct KeyBox {
    /// Smallest key per axis.
    pub lo: Key,
    /// Largest key per axis (inclusive).
    pub hi: Key,
}

impl KeyBox {
    /// The box of one base cube.
    #[inline]
    pub fn cube(key: Key) -> Self {
        Self { lo: key, hi: key }
    }

    /// Number of base cubes per axis.
    #[inline]
    pub fn widths(&self) -> [u32; 3] {
        [
            u32::from(self.hi[0]) - u32::from(self.lo[0]) + 1,
            u32::from(self.hi[1]) - u32::from(self.lo[1]) + 1,
            u32::from(self.hi[2]) - u32::from(self.lo[2]) + 1,
        ]
    }

    /// Volume in base cubes.
    #[inline]
    pub fn volume(&self) -> u64 {
        let w = self.widths();
        u64::from(w[0]) * u64::from(w[1]) * u64::from(w[2])
    }

    /// The smallest box containing both.
    #[inline]
    pub fn union(&self, other: &Self) -> Self {
        Self {
            lo: [
                self.lo[0].min(other.lo[0]),
                self.lo[1].min(other.lo[1]),
                self.lo[2].min(other.lo[2]),
            ],
            hi: [
                self.hi[0].max(other.hi[0]),
                self.hi[1].max(other.hi[1]),
                self.hi[2].max(other.hi[2]),
            ],
        }
    }

    /// Whether the boxes share at least one base cube (positive volume).
    #[inline]
    pub fn intersects(&self, other: &Self) -> bool {
        (0..3).all(|a| self.lo[a] <= other.hi[a] && other.lo[a] <= self.hi[a])
    }

    /// Whether `other` lies completely inside `self`.
    #[inline]
    pub fn contains_box(&self, other: &Self) -> bool {
        (0..3).all(|a| self.lo[a] <= other.lo[a] && other.hi[a] <= self.hi[a])
    }

    /// Whether the base cube `key` lies inside.
    #[inline]
    pub fn contains_key(&self, key: Key) -> bool {
        (0..3).all(|a| self.lo[a] <= key[a] && key[a] <= self.hi[a])
    }

    /// Volume the union with `other` adds to `self` (least-expansion criterion).
    #[inline]
    pub fn enlargement(&self, other: &Self) -> u64 {
        self.union(other).volume() - self.volume()
    }

    /// Lower corner in metres at resolution `resolution_m`.
    pub fn min_m(&self, resolution_m: f64) -> [f64; 3] {
        self.lo
            .map(|k| (i64::from(k) - KEY_OFFSET) as f64 * resolution_m)
    }

    /// Upper corner in metres at resolution `resolution_m`.
    pub fn max_m(&self, resolution_m: f64) -> [f64; 3] {
        self.hi
            .map(|k| (i64::from(k) + 1 - KEY_OFFSET) as f64 * resolution_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_follow_octomap() {
        assert_eq!(key_of([0.0, -0.05, 0.2], 0.1), Some([32768, 32767, 32770]));
        assert_eq!(key_of([f64::NAN, 0.0, 0.0], 0.1), None);
        assert_eq!(key_of([1e9, 0.0, 0.0], 0.1), None);
        let k = [1, 65535, 32768];
        assert_eq!(unpack(pack(k)), k);
        let b = KeyBox {
            lo: [32768; 3],
            hi: [32769, 32768, 32768],
        };
        assert_eq!(b.volume(), 2);
        assert_eq!(b.min_m(0.5), [0.0; 3]);
        assert_eq!(b.max_m(0.5), [1.0, 0.5, 0.5]);
    }

    #[test]
    fn morton_interleaves_the_bits() {
        for key in [
            [0, 0, 0],
            [1, 0, 0],
            [0, 1, 0],
            [0, 0, 1],
            [65535, 1234, 40000],
        ] {
            let mut naive = 0u64;
            for bit in 0..16 {
                for (axis, k) in key.iter().enumerate() {
                    naive |= u64::from((k >> bit) & 1) << (3 * bit + axis);
                }
            }
            assert_eq!(morton(key), naive, "{key:?}");
            assert_eq!(from_morton(naive), key);
        }
    }
}
