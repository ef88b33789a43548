//! A short, format-independent description of a file: what `raypath info` prints.

use std::collections::BTreeMap;

use raypath_geometry::Aabb3;
use serde::Serialize;

/// What a file holds, in counts. Fields that do not apply to a format stay `None` and are left
/// out of the JSON. The JSON keys are a contract for scripts: `format`, `scans`, `beams`,
/// `points`, `poses`, `odometry`, `width`, `height`, `labels`, `bbox`, `time_span`, plus
/// `nodes` for tree and graph files and format-specific entries under their own names.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Summary {
    /// The detected format, for example `carmen`, `pcd`, `octomap-bt` (see [`crate::Format`]).
    pub format: String,
    /// Number of scans (laser messages, point-cloud files or ScanGraph nodes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scans: Option<u64>,
    /// Beams per scan; the most common count when scans differ (see `beams_min`/`beams_max`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beams: Option<u64>,
    /// Smallest beams per scan, present only when scans differ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beams_min: Option<u64>,
    /// Largest beams per scan, present only when scans differ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beams_max: Option<u64>,
    /// Number of points (all points of all scans; organized clouds count every pixel).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub points: Option<u64>,
    /// Number of poses (laser poses, ground-truth poses, graph nodes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub poses: Option<u64>,
    /// Number of odometry records.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub odometry: Option<u64>,
    /// Columns of an organized cloud or image.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<u64>,
    /// Rows of an organized cloud or image.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<u64>,
    /// Distinct labels, sorted ascending.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub labels: Option<Vec<u32>>,
    /// Bounding box of the points (world frame where poses are known) in metres.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bbox: Option<BoundingBox>,
    /// First and last timestamp in seconds.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_span: Option<TimeSpan>,
    /// Number of tree nodes (OctoMap `.bt`) or graph nodes (ScanGraph).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nodes: Option<u64>,
    /// Format-specific facts (resolution, no-return code, edges, …), by name.
    #[serde(flatten)]
    pub extra: BTreeMap<String, serde_json::Value>,
}

impl Summary {
    /// An empty summary of the given format.
    pub fn new(format: impl Into<String>) -> Self {
        Self {
            format: format.into(),
            ..Self::default()
        }
    }

    /// Adds a format-specific entry.
    pub fn with_extra(mut self, key: &str, value: impl Into<serde_json::Value>) -> Self {
        self.extra.insert(key.to_owned(), value.into());
        self
    }

    /// Sets `beams` from per-scan beam counts: the most common count, with `beams_min` and
    /// `beams_max` when they differ. Does nothing for no scans.
    pub fn set_beams_from_counts(&mut self, counts: &BTreeMap<u64, u64>) {
        let Some((&mode, _)) = counts
            .iter()
            .max_by_key(|&(beams, n)| (*n, std::cmp::Reverse(*beams)))
        else {
            return;
        };
        self.beams = Some(mode);
        if counts.len() > 1 {
            self.beams_min = counts.keys().next().copied();
            self.beams_max = counts.keys().next_back().copied();
        }
    }
}

/// An axis-aligned bounding box in metres, `[x, y, z]` corners.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BoundingBox {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

impl BoundingBox {
    /// The box of an [`Aabb3`], `None` when it is empty.
    pub fn from_aabb(aabb: &Aabb3) -> Option<Self> {
        (!aabb.is_empty()).then(|| Self {
            min: [aabb.min.x, aabb.min.y, aabb.min.z],
            max: [aabb.max.x, aabb.max.y, aabb.max.z],
        })
    }
}

/// First and last timestamp in seconds (as stored in the file: UNIX time or time since start).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TimeSpan {
    /// Earliest timestamp in seconds.
    pub start: f64,
    /// Latest timestamp in seconds.
    pub end: f64,
    /// `end − start` in seconds.
    pub duration: f64,
}

impl TimeSpan {
    /// The span of a set of timestamps; `None` when there is no finite one.
    pub fn from_times(times: impl IntoIterator<Item = f64>) -> Option<Self> {
        let (mut start, mut end) = (f64::INFINITY, f64::NEG_INFINITY);
        for t in times.into_iter().filter(|t| t.is_finite()) {
            start = start.min(t);
            end = end.max(t);
        }
        (start <= end).then_some(Self {
            start,
            end,
            duration: end - start,
        })
    }

    /// Extends the span by one timestamp (ignored when not finite).
    pub fn extend(span: &mut Option<Self>, t: f64) {
        if !t.is_finite() {
            return;
        }
        match span {
            Some(s) => {
                s.start = s.start.min(t);
                s.end = s.end.max(t);
                s.duration = s.end - s.start;
            }
            None => {
                *span = Some(Self {
                    start: t,
                    end: t,
                    duration: 0.0,
                })
            }
        }
    }
}
