//! The organized grid: 4-neighbour links of every ray and the 3 × 3 neighbourhood masks of
//! the 17 tetrominoes (Schaefer 2020, Fig. 11.2), so that testing a seed needs neither
//! divisions nor repeated edge look-ups.

use nalgebra::Vector3;

use crate::tetromino::TETROMINOES;

/// Link bit: the ray above (previous row) may be joined.
pub const UP: u8 = 1;
/// Link bit: the ray below (next row) may be joined.
pub const DOWN: u8 = 2;
/// Link bit: the ray to the left (previous column) may be joined.
pub const LEFT: u8 = 4;
/// Link bit: the ray to the right (next column) may be joined.
pub const RIGHT: u8 = 8;

/// Bit of 3 × 3 cell `(dr, dc)` (each in −1..=1).
const fn cell_bit(dr: i8, dc: i8) -> u16 {
    1 << ((dr + 1) * 3 + dc + 1)
}

/// Bit of the edge between 3 × 3 cells `a` and `b` (4-adjacent, `a` before `b` in row-major
/// order): bits 0–5 join `(dr, dc)` to `(dr, dc + 1)`, bits 6–11 join `(dr, dc)` to `(dr + 1, dc)`.
const fn edge_bit(a: (i8, i8), b: (i8, i8)) -> u16 {
    if a.0 == b.0 {
        1 << ((a.0 + 1) * 2 + a.1 + 1)
    } else {
        1 << (6 + (a.0 + 1) * 3 + a.1 + 1)
    }
}

/// The cells and the 4-adjacencies among them of each tetromino, as bits of the 3 × 3
/// neighbourhood ([`cell_bit`], [`edge_bit`]).
pub const SHAPES: [(u16, u16); 17] = shapes();

const fn shapes() -> [(u16, u16); 17] {
    let mut out = [(0u16, 0u16); 17];
    let mut m = 0;
    while m < 17 {
        let o = TETROMINOES[m];
        let cells = [(0i8, 0i8), o[0], o[1], o[2]];
        let (mut c, mut e) = (0u16, 0u16);
        let mut i = 0;
        while i < 4 {
            c |= cell_bit(cells[i].0, cells[i].1);
            let mut j = 0;
            while j < 4 {
                let (a, b) = (cells[i], cells[j]);
                let right = a.0 == b.0 && b.1 == a.1 + 1;
                let down = a.1 == b.1 && b.0 == a.0 + 1;
                if right || down {
                    e |= edge_bit(a, b);
                }
                j += 1;
            }
            i += 1;
        }
        out[m] = (c, e);
        m += 1;
    }
    out
}

/// The link bits of every ray: 4-neighbours that are both returns within `l_max` of each
/// other (the outlier filter `d`).
pub fn links(valid: &[bool], points: &[Vector3<f64>], width: usize, l_max: f64) -> Vec<u8> {
    let n = points.len();
    let mut links = vec![0u8; n];
    let near = |a: usize, b: usize| valid[a] && valid[b] && (points[a] - points[b]).norm() <= l_max;
    for k in 0..n {
        if k % width + 1 < width && near(k, k + 1) {
            links[k] |= RIGHT;
            links[k + 1] |= LEFT;
        }
        if k + width < n && near(k, k + width) {
            links[k] |= DOWN;
            links[k + width] |= UP;
        }
    }
    links
}

/// The cells of the 3 × 3 neighbourhood of ray `k` (of a `width` × `height` grid) that
/// exist and satisfy `ok`, as bits.
pub fn cells(k: usize, (width, height): (usize, usize), ok: impl Fn(usize) -> bool) -> u16 {
    let (row, col) = (k / width, k % width);
    let mut bits = 0u16;
    for dr in -1i8..=1 {
        for dc in -1i8..=1 {
            if inside((row, col), (width, height), (dr, dc)) && ok(offset(k, width, (dr, dc))) {
                bits |= cell_bit(dr, dc);
            }
        }
    }
    bits
}

/// The 12 inner edges of the 3 × 3 neighbourhood of ray `k` that are links, as bits.
pub fn edges(k: usize, (width, height): (usize, usize), links: &[u8]) -> u16 {
    let (row, col) = (k / width, k % width);
    let mut bits = 0u16;
    for dr in -1i8..=1 {
        for dc in -1i8..=1 {
            if !inside((row, col), (width, height), (dr, dc)) {
                continue;
            }
            let cell = links[offset(k, width, (dr, dc))];
            if dc < 1 && cell & RIGHT != 0 {
                bits |= edge_bit((dr, dc), (dr, dc + 1));
            }
            if dr < 1 && cell & DOWN != 0 {
                bits |= edge_bit((dr, dc), (dr + 1, dc));
            }
        }
    }
    bits
}

/// Whether the cell `d` away from `(row, col)` is inside the grid.
fn inside((row, col): (usize, usize), (width, height): (usize, usize), d: (i8, i8)) -> bool {
    let r = row as isize + d.0 as isize;
    let c = col as isize + d.1 as isize;
    r >= 0 && c >= 0 && r < height as isize && c < width as isize
}

/// The cell `d = (rows, cols)` away from `k` (which must exist).
pub fn offset(k: usize, width: usize, d: (i8, i8)) -> usize {
    (k as isize + d.0 as isize * width as isize + d.1 as isize) as usize
}

/// The 4-neighbours of `k` in the order up, down, left, right, with their link bits; an
/// index is meaningful only when `links[k]` has its bit.
pub fn neighbours(k: usize, width: usize) -> [(u8, usize); 4] {
    [
        (UP, k.wrapping_sub(width)),
        (DOWN, k + width),
        (LEFT, k.wrapping_sub(1)),
        (RIGHT, k + 1),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_cover_four_cells_and_their_adjacencies() {
        for (mask, &(cells, edges)) in SHAPES.iter().enumerate() {
            assert_eq!(cells.count_ones(), 4, "tetromino {mask}");
            assert_ne!(cells & cell_bit(0, 0), 0);
            // Four connected cells without a cycle have three adjacencies, the O four.
            let want = if mask == 0 { 4 } else { 3 };
            assert_eq!(edges.count_ones(), want, "tetromino {mask}");
        }
    }
}
