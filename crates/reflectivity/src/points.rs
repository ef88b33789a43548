//! A prepared scan for matching: end points in the sensor frame with their relative
//! reflectivity ϱ̄ (the thesis' `z_t = {(s_i, ϱ̄_i)}`, Khan 2017 §3.4.1).

use raypath_geometry::Scan2;

use crate::calibration::IntensityCorrection;
use crate::normals::scan_incidence_angles;

/// End points (metres, sensor frame: x forward, y left) and per-point relative reflectivity
/// (`NaN` where unknown). The buffers are reused between scans: [`ScanPoints::clear`] keeps
/// their capacity, so filling one per scan does not allocate after the first scans.
#[derive(Clone, Debug, Default)]
pub struct ScanPoints {
    points: Vec<[f64; 2]>,
    reflectivity: Vec<f64>,
    incidence: Vec<f64>,
}

/// Which readings of a [`Scan2`] become points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointFilter {
    /// Readings below this range are dropped (the robot itself), metres.
    pub min_range_m: f64,
    /// Readings at or above this range are dropped (far, sparse returns), metres.
    pub max_range_m: f64,
    /// Half window (in beams) of the PCA normal used for the angle of incidence.
    pub normal_half_window: usize,
    /// Neighbours farther than this from the centre point are left out of the PCA, metres.
    pub normal_radius_m: f64,
}

impl Default for PointFilter {
    /// 0.1 m … 30 m (a Hokuyo UTM-30LX or SICK LMS range), normals over ±3 beams within
    /// 0.3 m (k = 5–9 neighbours; the thesis does not say how 2-D normals are found).
    fn default() -> Self {
        Self {
            min_range_m: 0.1,
            max_range_m: 30.0,
            normal_half_window: 3,
            normal_radius_m: 0.3,
        }
    }
}

impl ScanPoints {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Removes all points, keeping the buffers.
    pub fn clear(&mut self) {
        self.points.clear();
        self.reflectivity.clear();
    }

    /// Adds a point (sensor frame, metres) with its relative reflectivity (`NaN`: unknown).
    pub fn push(&mut self, point: [f64; 2], reflectivity: f64) {
        self.points.push(point);
        self.reflectivity.push(reflectivity);
    }

    /// The end points.
    pub fn points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// The relative reflectivities, one per point (`NaN`: unknown).
    pub fn reflectivity(&self) -> &[f64] {
        &self.reflectivity
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Number of points with a finite reflectivity.
    pub fn with_reflectivity(&self) -> usize {
        self.reflectivity.iter().filter(|r| r.is_finite()).count()
    }

    /// Replaces the contents with the returns of `scan` that pass `filter`. With `correction`
    /// and intensities in the scan, each point gets ϱ̄ = correction(I, r, α), α from the 2-D
    /// PCA normal over neighbouring returns (as Khan 2017 §3.3.1 for 3-D); otherwise `NaN`.
    pub fn fill_from_scan(
        &mut self,
        scan: &Scan2,
        filter: &PointFilter,
        correction: Option<&IntensityCorrection>,
    ) {
        self.clear();
        // Beam-indexed end points first (NaN for dropped beams) for the normals.
        let n = scan.ranges.len();
        self.points.reserve(n);
        for (i, &r) in scan.ranges.iter().enumerate() {
            let ok = r.is_finite()
                && r >= filter.min_range_m
                && r < filter.max_range_m
                && r < scan.max_range_m;
            let a = scan.angle(i);
            self.points.push(if ok {
                [r * a.cos(), r * a.sin()]
            } else {
                [f64::NAN, f64::NAN]
            });
        }
        let intensities = scan.intensities.as_deref().filter(|v| v.len() == n);
        if let (Some(corr), Some(intensities)) = (correction, intensities) {
            scan_incidence_angles(
                &self.points,
                filter.normal_half_window,
                filter.normal_radius_m,
                &mut self.incidence,
            );
            for ((p, &alpha), &intensity) in
                self.points.iter().zip(&self.incidence).zip(intensities)
            {
                let range = (p[0] * p[0] + p[1] * p[1]).sqrt();
                self.reflectivity
                    .push(corr.relative(intensity, range, alpha).unwrap_or(f64::NAN));
            }
        } else {
            self.reflectivity.resize(n, f64::NAN);
        }
        // Compact: keep the returns.
        let mut k = 0;
        for i in 0..n {
            if let (Some(&p), Some(&r)) = (self.points.get(i), self.reflectivity.get(i)) {
                if p[0].is_finite() {
                    self.points[k] = p;
                    self.reflectivity[k] = r;
                    k += 1;
                }
            }
        }
        self.points.truncate(k);
        self.reflectivity.truncate(k);
    }
}
