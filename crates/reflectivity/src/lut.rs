//! The intensity look-up table `I_ref(r, α)` (Khan 2017 §3.3.2, eqs. (3.4)–(3.5)).
//!
//! 1. The reference surface's samples `(r, α, I)` are triangulated (Delaunay, `spade`) in the
//!    normalised `(r, α)` plane and interpolated linearly inside each triangle with
//!    barycentric weights ([`ScatteredLinear`]: MATLAB `scatteredInterpolant(…, 'linear')`).
//! 2. The interpolant is sampled on a regular grid ([`LutConfig`]: Δr = 0.01 m, Δα = 0.5° by
//!    default; the thesis gives no steps) over the samples' bounding box; grid nodes outside
//!    the convex hull take the value of the nearest sample (clamping) and are flagged.
//! 3. Online, [`IntensityLut::lookup`] interpolates the table bilinearly (ranges and angles
//!    outside the table are clamped to its border), and ϱ̄ = I / I_ref(r, α).

use serde::{Deserialize, Serialize};
use spade::{DelaunayTriangulation, FloatTriangulation, HasPosition, Point2, Triangulation};

use crate::error::{ReflectivityError, Result, require_positive};

/// One calibration observation of the reference surface.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibrationSample {
    /// Range in metres.
    pub range_m: f64,
    /// Angle of incidence in radians, [0, π/2].
    pub incidence_rad: f64,
    /// The measured intensity (sensor units).
    pub intensity: f64,
}

#[derive(Clone, Copy, Debug)]
struct Vertex {
    position: Point2<f64>,
    value: f64,
}

impl HasPosition for Vertex {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.position
    }
}

/// Scattered linear interpolation over `(r, α)`: Delaunay triangulation of the samples and
/// barycentric weights. Coordinates are scaled to the unit square of the samples' bounding
/// box before triangulating, so metres and radians weigh alike. Samples at the same `(r, α)`
/// are averaged.
pub struct ScatteredLinear {
    triangulation: DelaunayTriangulation<Vertex>,
    lo: [f64; 2],
    scale: [f64; 2],
}

impl ScatteredLinear {
    /// Triangulates the samples (at least three, not all collinear, all finite).
    pub fn new(samples: &[CalibrationSample]) -> Result<Self> {
        let bad = |m: String| Err(ReflectivityError::BadInput(m));
        if samples.len() < 3 {
            return bad(format!(
                "need at least 3 calibration samples, got {}",
                samples.len()
            ));
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for (k, s) in samples.iter().enumerate() {
            if !(s.range_m.is_finite() && s.incidence_rad.is_finite() && s.intensity.is_finite()) {
                return bad(format!("calibration sample {k} is not finite: {s:?}"));
            }
            lo = [lo[0].min(s.range_m), lo[1].min(s.incidence_rad)];
            hi = [hi[0].max(s.range_m), hi[1].max(s.incidence_rad)];
        }
        let span = [hi[0] - lo[0], hi[1] - lo[1]];
        if !(span[0] > 0.0 && span[1] > 0.0) {
            return bad("calibration samples must vary in both range and angle".into());
        }
        let scale = [1.0 / span[0], 1.0 / span[1]];
        // Average duplicates (same position after scaling).
        let mut sorted: Vec<(f64, f64, f64)> = samples
            .iter()
            .map(|s| {
                (
                    (s.range_m - lo[0]) * scale[0],
                    (s.incidence_rad - lo[1]) * scale[1],
                    s.intensity,
                )
            })
            .collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut triangulation = DelaunayTriangulation::<Vertex>::new();
        let mut k = 0;
        while let Some(&(u, v, _)) = sorted.get(k) {
            let (mut sum, mut n) = (0.0, 0.0);
            while let Some(&(u2, v2, value)) = sorted.get(k) {
                if u2 != u || v2 != v {
                    break;
                }
                sum += value;
                n += 1.0;
                k += 1;
            }
            let vertex = Vertex {
                position: Point2::new(u, v),
                value: sum / n,
            };
            if triangulation.insert(vertex).is_err() {
                return bad(format!(
                    "calibration sample at ({u}, {v}) cannot be triangulated"
                ));
            }
        }
        if triangulation.num_inner_faces() == 0 {
            return bad("calibration samples are collinear".into());
        }
        Ok(Self {
            triangulation,
            lo,
            scale,
        })
    }

    fn position(&self, range_m: f64, incidence_rad: f64) -> Point2<f64> {
        Point2::new(
            (range_m - self.lo[0]) * self.scale[0],
            (incidence_rad - self.lo[1]) * self.scale[1],
        )
    }

    /// The interpolated intensity, `None` outside the samples' convex hull.
    pub fn evaluate(&self, range_m: f64, incidence_rad: f64) -> Option<f64> {
        if !(range_m.is_finite() && incidence_rad.is_finite()) {
            return None;
        }
        self.triangulation
            .barycentric()
            .interpolate(|v| v.data().value, self.position(range_m, incidence_rad))
    }

    /// The value of the sample nearest to `(r, α)` (in the normalised plane).
    pub fn nearest(&self, range_m: f64, incidence_rad: f64) -> Option<f64> {
        self.triangulation
            .nearest_neighbor(self.position(range_m, incidence_rad))
            .map(|v| v.data().value)
    }
}

/// Table resolution (defaults Δr = 0.01 m, Δα = 0.5°; the thesis gives no steps).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LutConfig {
    /// Range step, metres.
    pub range_step_m: f64,
    /// Angle step, radians.
    pub angle_step_rad: f64,
}

impl Default for LutConfig {
    fn default() -> Self {
        Self {
            range_step_m: 0.01,
            angle_step_rad: 0.5f64.to_radians(),
        }
    }
}

/// The regular table `I_ref(r, α)`; serialisable (JSON via serde).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IntensityLut {
    /// Range of the first row, metres.
    pub range_min_m: f64,
    /// Range step, metres.
    pub range_step_m: f64,
    /// Number of range rows.
    pub ranges: usize,
    /// Angle of the first column, radians.
    pub angle_min_rad: f64,
    /// Angle step, radians.
    pub angle_step_rad: f64,
    /// Number of angle columns.
    pub angles: usize,
    /// `ranges × angles` values, row-major (range rows).
    pub values: Vec<f64>,
    /// Per value: whether the node lies inside the samples' convex hull (else clamped).
    pub inside_hull: Vec<bool>,
}

impl IntensityLut {
    /// Fits the table to reference-surface samples (module docs).
    pub fn fit(samples: &[CalibrationSample], config: &LutConfig) -> Result<Self> {
        require_positive("range_step_m", config.range_step_m)?;
        require_positive("angle_step_rad", config.angle_step_rad)?;
        let interp = ScatteredLinear::new(samples)?;
        let (mut r0, mut r1, mut a0, mut a1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for s in samples {
            r0 = r0.min(s.range_m);
            r1 = r1.max(s.range_m);
            a0 = a0.min(s.incidence_rad);
            a1 = a1.max(s.incidence_rad);
        }
        let ranges = ((r1 - r0) / config.range_step_m).ceil() as usize + 1;
        let angles = ((a1 - a0) / config.angle_step_rad).ceil() as usize + 1;
        if ranges.saturating_mul(angles) > 50_000_000 {
            return Err(ReflectivityError::InvalidParameter {
                name: "range_step_m",
                reason: format!("a table of {ranges} × {angles} values is too large"),
            });
        }
        let mut values = Vec::with_capacity(ranges * angles);
        let mut inside_hull = Vec::with_capacity(ranges * angles);
        for i in 0..ranges {
            let r = (r0 + i as f64 * config.range_step_m).min(r1);
            for j in 0..angles {
                let a = (a0 + j as f64 * config.angle_step_rad).min(a1);
                match interp.evaluate(r, a) {
                    Some(v) => {
                        values.push(v);
                        inside_hull.push(true);
                    }
                    None => {
                        values.push(interp.nearest(r, a).unwrap_or(f64::NAN));
                        inside_hull.push(false);
                    }
                }
            }
        }
        Ok(Self {
            range_min_m: r0,
            range_step_m: config.range_step_m,
            ranges,
            angle_min_rad: a0,
            angle_step_rad: config.angle_step_rad,
            angles,
            values,
            inside_hull,
        })
    }

    /// Checks the table's shape (after deserialising).
    pub fn validate(&self) -> Result<()> {
        require_positive("range_step_m", self.range_step_m)?;
        require_positive("angle_step_rad", self.angle_step_rad)?;
        let n = self.ranges.checked_mul(self.angles);
        if self.ranges == 0
            || self.angles == 0
            || n != Some(self.values.len())
            || self.inside_hull.len() != self.values.len()
        {
            return Err(ReflectivityError::BadInput(format!(
                "LUT shape {} × {} does not match {} values / {} hull flags",
                self.ranges,
                self.angles,
                self.values.len(),
                self.inside_hull.len()
            )));
        }
        if !(self.range_min_m.is_finite() && self.angle_min_rad.is_finite())
            || self.values.iter().any(|v| !v.is_finite())
        {
            return Err(ReflectivityError::BadInput(
                "LUT has non-finite entries".into(),
            ));
        }
        Ok(())
    }

    fn at(&self, i: usize, j: usize) -> f64 {
        self.values
            .get(i * self.angles + j)
            .copied()
            .unwrap_or(f64::NAN)
    }

    /// `I_ref(r, α)` by bilinear interpolation in the table, clamped to its border; `None`
    /// for non-finite input.
    pub fn lookup(&self, range_m: f64, incidence_rad: f64) -> Option<f64> {
        if !(range_m.is_finite() && incidence_rad.is_finite()) {
            return None;
        }
        let fi =
            ((range_m - self.range_min_m) / self.range_step_m).clamp(0.0, (self.ranges - 1) as f64);
        let fj = ((incidence_rad - self.angle_min_rad) / self.angle_step_rad)
            .clamp(0.0, (self.angles - 1) as f64);
        let (i, j) = (fi.floor() as usize, fj.floor() as usize);
        let (i1, j1) = ((i + 1).min(self.ranges - 1), (j + 1).min(self.angles - 1));
        let (u, v) = (fi - i as f64, fj - j as f64);
        let value = (1.0 - u) * (1.0 - v) * self.at(i, j)
            + u * (1.0 - v) * self.at(i1, j)
            + (1.0 - u) * v * self.at(i, j1)
            + u * v * self.at(i1, j1);
        value.is_finite().then_some(value)
    }

    /// Whether `(r, α)` lies in the calibrated domain: inside the table and nearest to a node
    /// inside the reference samples' convex hull (elsewhere [`lookup`](Self::lookup) clamps).
    pub fn covers(&self, range_m: f64, incidence_rad: f64) -> bool {
        let fi = (range_m - self.range_min_m) / self.range_step_m;
        let fj = (incidence_rad - self.angle_min_rad) / self.angle_step_rad;
        let inside_table = |f: f64, n: usize| f.is_finite() && f >= -0.5 && f <= n as f64 - 0.5;
        if !(inside_table(fi, self.ranges) && inside_table(fj, self.angles)) {
            return false;
        }
        let (i, j) = (fi.round().max(0.0) as usize, fj.round().max(0.0) as usize);
        self.inside_hull
            .get(i.min(self.ranges - 1) * self.angles + j.min(self.angles - 1))
            .copied()
            .unwrap_or(false)
    }

    /// The relative reflectivity ϱ̄ = I / I_ref(r, α) (eq. 3.5); `None` where the table is not
    /// positive or the input is not finite.
    pub fn relative(&self, intensity: f64, range_m: f64, incidence_rad: f64) -> Option<f64> {
        let reference = self.lookup(range_m, incidence_rad)?;
        (reference > 0.0 && intensity.is_finite()).then(|| intensity / reference) // Eq. (3.5)
    }
}
