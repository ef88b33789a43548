//! The 17 valid tetrominoes around a grid cell (Schaefer 2020, Fig. 11.2).
//!
//! Every way to combine a cell with three 4-connected neighbours inside its 3 × 3
//! neighbourhood except the straight I-tetromino (four collinear endpoints do not
//! determine a plane): 1 O, 4 T, 4 S/Z and 8 L/J shapes. Offsets are `(row, col)` =
//! (first, second) organized-cloud index relative to the centre cell.

/// Offsets of the three other cells of each tetromino, relative to the centre.
pub const TETROMINOES: [[(i8, i8); 3]; 17] = [
    // O: [000;011;011]
    [(0, 1), (1, 0), (1, 1)],
    // T: [010;011;010] [010;110;010] [000;111;010] [010;111;000]
    [(-1, 0), (0, 1), (1, 0)],
    [(-1, 0), (0, -1), (1, 0)],
    [(0, -1), (0, 1), (1, 0)],
    [(-1, 0), (0, -1), (0, 1)],
    // Z: [001;011;010] [100;110;010] [000;110;011] [011;110;000]
    [(-1, 1), (0, 1), (1, 0)],
    [(-1, -1), (0, -1), (1, 0)],
    [(0, -1), (1, 0), (1, 1)],
    [(-1, 0), (-1, 1), (0, -1)],
    // L: [011;010;010] [110;010;010] [000;111;100] [000;111;001]
    //    [100;111;000] [001;111;000] [010;010;011] [010;010;110]
    [(-1, 0), (-1, 1), (1, 0)],
    [(-1, -1), (-1, 0), (1, 0)],
    [(0, -1), (0, 1), (1, -1)],
    [(0, -1), (0, 1), (1, 1)],
    [(-1, -1), (0, -1), (0, 1)],
    [(-1, 1), (0, -1), (0, 1)],
    [(-1, 0), (1, 0), (1, 1)],
    [(-1, 0), (1, -1), (1, 0)],
];

#[cfg(test)]
mod tests {
    use super::TETROMINOES;

    #[test]
    fn tetrominoes_are_connected_distinct_and_not_straight() {
        let mut seen = std::collections::HashSet::new();
        for t in TETROMINOES {
            let mut cells = vec![(0i8, 0i8)];
            cells.extend(t);
            let mut key = cells.clone();
            key.sort();
            assert!(seen.insert(key), "duplicate {t:?}");
            // Connected via 4-neighbourhood.
            let mut reached = vec![(0i8, 0i8)];
            let mut changed = true;
            while changed {
                changed = false;
                for c in &cells {
                    if !reached.contains(c)
                        && reached
                            .iter()
                            .any(|r| (r.0 - c.0).abs() + (r.1 - c.1).abs() == 1)
                    {
                        reached.push(*c);
                        changed = true;
                    }
                }
            }
            assert_eq!(reached.len(), 4, "{t:?} not connected");
            let same_row = cells.iter().all(|c| c.0 == cells[0].0);
            let same_col = cells.iter().all(|c| c.1 == cells[0].1);
            assert!(!same_row && !same_col, "{t:?} is straight");
        }
        assert_eq!(seen.len(), 17);
    }
}
