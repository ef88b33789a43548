//! Arc length along a track's ground-plane projection, and time at a given arc length.

use crate::state::FilterState;
use crate::track::PoseTrack;

/// Cumulative planar arc length of a [`PoseTrack`] at each of its samples.
#[derive(Clone, Debug, PartialEq)]
pub struct ArcLengthIndex {
    stamps_secs: Vec<f64>,
    cumulative_m: Vec<f64>,
}

impl ArcLengthIndex {
    /// The arc lengths of `track`'s ground-plane projection.
    pub fn new<S: FilterState>(track: &PoseTrack<S>) -> Self {
        let mut cumulative_m = Vec::with_capacity(track.len());
        let mut total = 0.0;
        let mut previous: Option<nalgebra::Vector2<f64>> = None;
        for pose in track.poses() {
            let position = pose.to_planar().translation();
            if let Some(p) = previous {
                total += (position - p).norm();
            }
            cumulative_m.push(total);
            previous = Some(position);
        }
        Self {
            stamps_secs: track.stamps_secs().to_vec(),
            cumulative_m,
        }
    }

    /// The total arc length in metres.
    pub fn total_m(&self) -> f64 {
        self.cumulative_m.last().copied().unwrap_or(0.0)
    }

    /// The cumulative arc length at each sample, in metres.
    pub fn cumulative_m(&self) -> &[f64] {
        &self.cumulative_m
    }

    /// The time at which the track has travelled `arc_m` metres (linear in arc length between
    /// samples; the first time the length is reached when the track stands still). `None`
    /// beyond the end (a tolerance of 1e-9 m absorbs rounding) or for NaN.
    pub fn time_at(&self, arc_m: f64) -> Option<f64> {
        if arc_m.is_nan() {
            return None;
        }
        let total = self.total_m();
        if arc_m > total + 1e-9 {
            return None;
        }
        let arc_m = arc_m.min(total);
        // First sample whose cumulative length reaches `arc_m`.
        let after = self.cumulative_m.partition_point(|&c| c < arc_m);
        if after == 0 {
            return self.stamps_secs.first().copied();
        }
        let before = after - 1;
        let (s0, s1) = (
            *self.cumulative_m.get(before)?,
            *self.cumulative_m.get(after)?,
        );
        let (t0, t1) = (
            *self.stamps_secs.get(before)?,
            *self.stamps_secs.get(after)?,
        );
        // s0 < arc_m ≤ s1, so the segment has positive length.
        Some(t0 + (arc_m - s0) / (s1 - s0) * (t1 - t0))
    }
}

/// Most evaluation points one call may produce (guards against absurd spacings).
const MAX_POINTS: f64 = 1e8;

/// The number of points `0, spacing, 2·spacing, …` up to `total_m` (1e-9 m tolerance).
pub(crate) fn point_count(total_m: f64, spacing_m: f64) -> Result<usize, crate::LocalizerError> {
    let count = (total_m / spacing_m + 1e-9).floor() + 1.0;
    if !(count.is_finite() && count <= MAX_POINTS) {
        return Err(crate::LocalizerError::InvalidParameter {
            name: "spacing_m",
            reason: format!("{spacing_m} m over {total_m} m gives more than {MAX_POINTS} points"),
        });
    }
    Ok(count as usize)
}
