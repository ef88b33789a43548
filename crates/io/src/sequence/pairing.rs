//! Raw-to-corrected log pairing: the one place that joins a raw log's scans (with odometry)
//! to the reference poses of its corrected copy.
//!
//! The corrected logs of the SLAM benchmark are subsampled copies of the raw logs with the
//! same range readings, so each reference scan is paired with the next raw scan whose readings
//! agree to the centimetre, in order.

use std::collections::HashMap;

use raypath_geometry::Scan2;

use crate::sequence::PlanarFrame;

fn key(scan: &Scan2) -> Vec<i64> {
    scan.ranges
        .iter()
        .map(|r| (r * 100.0).round() as i64)
        .collect()
}

/// Pairs each reference scan with a raw scan of the same readings (to 1 cm), in order:
/// returns `(raw index, reference index)` pairs, both increasing.
pub fn pair_by_ranges<'a>(
    raw: impl IntoIterator<Item = &'a Scan2>,
    reference: impl IntoIterator<Item = &'a Scan2>,
) -> Vec<(usize, usize)> {
    let mut by_key: HashMap<Vec<i64>, Vec<usize>> = HashMap::new();
    for (i, scan) in raw.into_iter().enumerate() {
        by_key.entry(key(scan)).or_default().push(i);
    }
    let mut pairs = Vec::new();
    let mut next = 0;
    for (j, scan) in reference.into_iter().enumerate() {
        if let Some(list) = by_key.get(&key(scan))
            && let Some(&i) = list.iter().find(|&&i| i >= next)
        {
            pairs.push((i, j));
            next = i + 1;
        }
    }
    pairs
}

/// Sets [`PlanarFrame::reference`] of the raw frames that pair with a reference frame (its
/// logged `world_from_laser`, see [`pair_by_ranges`]); returns the number of paired frames.
pub fn pair_reference(raw: &mut [PlanarFrame], reference: &[PlanarFrame]) -> usize {
    let pairs = pair_by_ranges(
        raw.iter().map(|f| &f.scan),
        reference.iter().map(|f| &f.scan),
    );
    for &(i, j) in &pairs {
        raw[i].reference = Some(reference[j].world_from_laser);
    }
    pairs.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(ranges: &[f64]) -> Scan2 {
        Scan2 {
            angle_min_rad: -1.0,
            angle_increment_rad: 0.1,
            max_range_m: 80.0,
            ranges: ranges.to_vec(),
            intensities: None,
        }
    }

    #[test]
    fn pairs_in_order_and_skips_unmatched() {
        let raw = [scan(&[1.0]), scan(&[2.0]), scan(&[1.0]), scan(&[3.0])];
        let reference = [scan(&[1.004]), scan(&[1.0]), scan(&[3.0]), scan(&[9.0])];
        let pairs = pair_by_ranges(raw.iter(), reference.iter());
        assert_eq!(pairs, vec![(0, 0), (2, 1), (3, 2)]);
    }
}
