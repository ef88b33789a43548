//! Inferring a log's no-return code from its range readings.
//!
//! Laser scanners report "nothing reflected" as a fixed reading at or above their maximum
//! range, and CARMEN logs store that code as if it were a range. The code differs between
//! logs and is rarely stated (`PARAM robot_front_laser_max` says 80.99 m in logs whose code
//! is 81.91 m). In the Radish logs it is 81.91 m (SICK LMS in 8 m/80 m mode: belgioioso,
//! csail, the Freiburg logs), 81.83 m (intel), 50 m (aces), and a cluster of values
//! between 51.05 m and 51.16 m in acapulco, fhw and infinite-corridor.
//!
//! # The rule
//!
//! Readings (positive and finite) are counted per centimetre. A value is *repeated* when it
//! occurs at least `max(10, readings / 20 000)` times. The **code** is found from the top:
//!
//! 1. the highest repeated value starts the *cluster*;
//! 2. the cluster grows downwards over the next lower values that occur in the log while each
//!    is repeated and at most 10 cm below the previous member (SICK scanners report several
//!    error codes just below the no-return code, for example 81.83 m besides 81.91 m);
//! 3. the code is the most frequent cluster member (the higher one on a tie), and the
//!    **threshold** is the lowest member: readings at or above it are no-returns
//!    ([`raypath_geometry::Scan2::max_range_m`]);
//! 4. the cluster is accepted only when almost nothing lies above it: at most
//!    `max(10, cluster / 100)` readings. A no-return code is the top of a log's range
//!    distribution; a repeated value with many readings above it is a real range (for example
//!    a near-circular room scanned from its centre), and treating it as a code would throw away
//!    every reading above it. On the Radish logs at most 2 readings lie above the cluster.
//!
//! A log without a repeated value has no code; the reader then falls back to what the log or
//! the configuration states (see [`crate::carmen::NoReturnRange`]). Real ranges are never
//! repeated to the centimetre often enough at the top of a log's range distribution to be
//! mistaken for a code (a robot standing still sees its nearest walls, not its farthest
//! reading, over and over).
//!
//! # Streaming
//!
//! [`crate::carmen::CarmenReader::open`] runs the rule over the whole file in a first pass
//! (decompressing it twice) and then reads it again; [`crate::carmen::CarmenReader::new`]
//! reads ahead [`crate::carmen::CarmenConfig::lookahead_scans`] laser messages (1000 by
//! default), infers the code from them, and then yields the buffered records first. Both
//! give the codes above on the Radish logs (tested in `crates/io/tests/carmen_real.rs`).

use std::collections::HashMap;

/// Cluster members may be at most this many centimetres apart.
const MAX_GAP_CM: i64 = 10;
/// A value is repeated when it occurs at least this often …
const MIN_REPEATS: u64 = 10;
/// … and at least once per this many readings.
const READINGS_PER_REPEAT: u64 = 20_000;
/// At most this many readings may lie above an accepted cluster …
const MAX_ABOVE: u64 = 10;
/// … or one per this many cluster readings, whichever is larger.
const CLUSTER_PER_ABOVE: u64 = 100;

/// The inferred no-return encoding of a log.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoReturnEstimate {
    /// The no-return code in metres: the most frequent value of the top cluster.
    pub code_m: f64,
    /// How many readings equal the code.
    pub code_count: u64,
    /// The lowest cluster member in metres: readings at or above it are no-returns.
    pub threshold_m: f64,
    /// How many readings fall in the cluster.
    pub cluster_count: u64,
}

/// Counts range readings per centimetre to infer the no-return code.
#[derive(Clone, Debug, Default)]
pub struct NoReturnHistogram {
    counts: HashMap<i64, u64>,
    readings: u64,
}

impl NoReturnHistogram {
    /// An empty histogram.
    pub fn new() -> Self {
        Self::default()
    }

    /// Counts one reading in metres (non-positive and non-finite readings are ignored).
    pub fn add(&mut self, range_m: f64) {
        if range_m.is_finite() && range_m > 0.0 {
            // Saturating float-to-int conversion: absurd values land in the top bin.
            let cm = (range_m * 100.0).round() as i64;
            *self.counts.entry(cm).or_insert(0) += 1;
            self.readings += 1;
        }
    }

    /// Counts all readings of a scan.
    pub fn add_all(&mut self, ranges_m: &[f64]) {
        for &r in ranges_m {
            self.add(r);
        }
    }

    /// Number of readings counted.
    pub fn readings(&self) -> u64 {
        self.readings
    }

    /// The no-return code by the rule of this module, `None` when no value repeats.
    pub fn estimate(&self) -> Option<NoReturnEstimate> {
        let min_repeats = MIN_REPEATS.max(self.readings / READINGS_PER_REPEAT);
        let mut values: Vec<(i64, u64)> = self.counts.iter().map(|(&v, &n)| (v, n)).collect();
        values.sort_unstable_by_key(|&(value, _)| std::cmp::Reverse(value));
        let top = values.iter().position(|&(_, n)| n >= min_repeats)?;
        let above: u64 = values.get(..top)?.iter().map(|&(_, n)| n).sum();
        let mut code = values.get(top).copied()?;
        let mut lowest = code.0;
        let mut cluster_count = 0;
        for &(value, count) in values.get(top..)? {
            if count < min_repeats || lowest - value > MAX_GAP_CM {
                break;
            }
            lowest = value;
            cluster_count += count;
            if count > code.1 {
                code = (value, count);
            }
        }
        if above > MAX_ABOVE.max(cluster_count / CLUSTER_PER_ABOVE) {
            return None;
        }
        Some(NoReturnEstimate {
            code_m: code.0 as f64 / 100.0,
            code_count: code.1,
            threshold_m: lowest as f64 / 100.0,
            cluster_count,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn histogram(pairs: &[(f64, u64)]) -> NoReturnHistogram {
        let mut h = NoReturnHistogram::new();
        for &(value, count) in pairs {
            for _ in 0..count {
                h.add(value);
            }
        }
        h
    }

    #[test]
    fn repeated_real_range_with_readings_above_is_not_a_code() {
        // A near-circular room: one range repeats, but hundreds of readings lie above it.
        let mut pairs: Vec<(f64, u64)> =
            (0..900).map(|i| (12.62 + f64::from(i) * 0.01, 1)).collect();
        pairs.push((12.61, 12));
        pairs.push((5.0, 3000));
        assert!(histogram(&pairs).estimate().is_none());
        // A real code with a couple of stray readings above it is still found.
        let h = histogram(&[(81.91, 5000), (82.5, 2), (3.0, 500)]);
        assert_eq!(h.estimate().unwrap().code_m, 81.91);
    }

    #[test]
    fn single_code() {
        let h = histogram(&[
            (81.83, 4172),
            (25.38, 1),
            (3.0, 500),
            (f64::NAN, 9),
            (0.0, 5),
        ]);
        assert_eq!(h.readings(), 4673);
        let e = h.estimate().unwrap();
        assert_eq!((e.code_m, e.code_count), (81.83, 4172));
        assert_eq!((e.threshold_m, e.cluster_count), (81.83, 4172));
    }

    #[test]
    fn cluster_below_code() {
        // Like freiburg-campus: 81.91 plus the 81.83 error code, then a lone reading.
        let h = histogram(&[(81.91, 1843), (81.83, 27), (81.82, 1), (10.0, 5000)]);
        let e = h.estimate().unwrap();
        assert_eq!(
            (e.code_m, e.threshold_m, e.cluster_count),
            (81.91, 81.83, 1870)
        );
        // Like acapulco: lone readings above the cluster, the mode inside it.
        let h = histogram(&[
            (51.25, 1),
            (51.16, 37),
            (51.15, 926),
            (51.14, 302),
            (50.0, 9),
        ]);
        let e = h.estimate().unwrap();
        assert_eq!(
            (e.code_m, e.threshold_m, e.cluster_count),
            (51.15, 51.14, 1265)
        );
    }

    #[test]
    fn no_code_without_repeats() {
        let h = histogram(&[(12.0, 9), (3.5, 9), (1.0, 9)]);
        assert_eq!(h.estimate(), None);
        assert_eq!(NoReturnHistogram::new().estimate(), None);
    }

    #[test]
    fn absurd_values_do_not_overflow() {
        let h = histogram(&[(1e300, 20), (5.0, 20)]);
        assert!(h.estimate().unwrap().code_m > 1e16);
    }
}
