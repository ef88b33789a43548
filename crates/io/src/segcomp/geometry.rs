//! The Perceptron scanner geometry: from a range-image pixel to a 3-D point (`sc2cart`).

use nalgebra::{Point3, Unit, Vector3};

/// The constants of the SegComp Perceptron range-to-Cartesian conversion.
///
/// Source: `range-to-coords.c` of the USF segmentation-comparison distribution (Hoover et al.
/// 1996), as used by the PPE reference implementation (`sc2cart`). For pixel (row `r`, column `c`)
/// of an `nr × nc` image with raw range `ra` (12-bit counts):
///
/// ```text
/// α = α0 + H·(255.5 − c)/nc,   β = β0 + V·(255.5 − r)/nr        (degrees → radians)
/// dz = −h1·(1 − cos α)/tan γ,   dy = dz·tan(θ + β/2),   dx = (h2 + dy)·tan α
/// r1 = (dz − h2)/δ,   r2 = √(dx² + (h2 + dy)²)/δ,   r3 = (ra + r0 − (r1 + r2))·δ
/// X = dx + r3·sin α,   Y = dy + r3·cos α·sin β,   Z = dz + r3·cos α·cos β
/// ```
///
/// `(X, Y, Z)` is the scanner frame of the original code — X to the left as seen from the
/// scanner (α > 0), Y up (β > 0), Z out of the scanner — in the file's length unit, which the
/// reference implementation takes as millimetres ([`PerceptronGeometry::unit_m`] = 0.001). The
/// original C code divides by the nominal 512 instead of `nc`/`nr`; for the 512 × 512 SegComp
/// images this is the same. (A ROS port of the code scales by 1/100 instead, i.e. reads
/// centimetres: the unit is an assumption of the benchmark users, not part of the files.)
///
/// The laser leaves the scanner at `(dx, dy, dz)`, not at the origin; like the reference
/// implementation, raypath treats the points as seen from the origin of the sensor frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerceptronGeometry {
    /// Distance between the rotating-mirror axis and the laser beam, `h1`.
    pub h1: f64,
    /// Distance between the nodding-mirror axis and the rotating-mirror intersection, `h2`.
    pub h2: f64,
    /// Slope of the rotating mirror, `γ`, degrees.
    pub gamma_deg: f64,
    /// Slope of the nodding mirror in mid position, `θ`, degrees.
    pub theta_deg: f64,
    /// Horizontal angle offset `α0`, degrees.
    pub alpha0_deg: f64,
    /// Vertical angle offset `β0`, degrees.
    pub beta0_deg: f64,
    /// Horizontal field of view `H`, degrees.
    pub horizontal_fov_deg: f64,
    /// Vertical field of view `V`, degrees.
    pub vertical_fov_deg: f64,
    /// Stand-off distance `r0` (range counts).
    pub r0: f64,
    /// Length per range count, `δ`.
    pub delta: f64,
    /// Metres per unit of `X, Y, Z` (0.001: millimetres).
    pub unit_m: f64,
}

impl Default for PerceptronGeometry {
    fn default() -> Self {
        Self {
            h1: 3.0,
            h2: 5.5,
            gamma_deg: 45.0,
            theta_deg: 45.0,
            alpha0_deg: 0.0,
            beta0_deg: 0.0,
            horizontal_fov_deg: 51.65,
            vertical_fov_deg: 36.73,
            r0: 830.3,
            delta: 0.20236,
            unit_m: 1e-3,
        }
    }
}

/// One beam of the scanner: the straight line on which the point of a pixel lies for every
/// raw range, in the REP-103 sensor frame, metres ([`PerceptronGeometry::beam`]).
///
/// `sc2cart` is affine in the raw range: the point of raw range `ra` is
/// `origin + (offset_m + ra · metres_per_count) · direction`. A simulator casts the beam from
/// `origin` along `direction` and turns the distance of the hit back into a raw range with
/// [`PerceptronBeam::range_of_distance`], so that [`PerceptronGeometry::point`] puts the
/// reading on the surface that was hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerceptronBeam {
    /// Where the laser leaves the scanner (`(dx, dy, dz)` of `sc2cart`), metres.
    pub origin: Point3<f64>,
    /// Unit direction of the beam.
    pub direction: Unit<Vector3<f64>>,
    /// Distance from `origin` of raw range 0, metres.
    pub offset_m: f64,
    /// Metres per raw range count (`δ` in metres).
    pub metres_per_count: f64,
}

impl PerceptronBeam {
    /// The point of raw range `range` (counts), metres.
    pub fn point(&self, range: f64) -> Point3<f64> {
        self.origin + self.direction.into_inner() * self.distance_m(range)
    }

    /// Distance from `origin` of raw range `range`, metres.
    pub fn distance_m(&self, range: f64) -> f64 {
        self.offset_m + range * self.metres_per_count
    }

    /// The raw range (counts, not rounded) of a point `distance_m` from `origin`.
    pub fn range_of_distance(&self, distance_m: f64) -> f64 {
        (distance_m - self.offset_m) / self.metres_per_count
    }
}

/// The parts of `sc2cart` that do not depend on the range, in the file's unit: the laser exit
/// `(dx, dy, dz)`, the unit direction `(sin α, cos α sin β, cos α cos β)` and `r1 + r2`.
struct ScannerBeam {
    exit: Vector3<f64>,
    direction: Vector3<f64>,
    r12: f64,
}

impl PerceptronGeometry {
    /// The range-independent part of `sc2cart` at fractional pixel `(row, col)`.
    fn scanner_beam(&self, row: f64, col: f64, rows: usize, cols: usize) -> ScannerBeam {
        let alpha =
            (self.alpha0_deg + self.horizontal_fov_deg * (255.5 - col) / cols as f64).to_radians();
        let beta =
            (self.beta0_deg + self.vertical_fov_deg * (255.5 - row) / rows as f64).to_radians();
        let gamma = self.gamma_deg.to_radians();
        let theta = self.theta_deg.to_radians();
        let dz = -self.h1 * (1.0 - alpha.cos()) / gamma.tan();
        let dy = dz * (theta + 0.5 * beta).tan();
        let dx = (self.h2 + dy) * alpha.tan();
        let r1 = (dz - self.h2) / self.delta;
        let r2 = (dx * dx + (self.h2 + dy) * (self.h2 + dy)).sqrt() / self.delta;
        ScannerBeam {
            exit: Vector3::new(dx, dy, dz),
            direction: Vector3::new(
                alpha.sin(),
                alpha.cos() * beta.sin(),
                alpha.cos() * beta.cos(),
            ),
            r12: r1 + r2,
        }
    }

    /// `sc2cart`: the scanner-frame coordinates `(X, Y, Z)` of pixel `(row, col)` of a
    /// `rows × cols` image with raw range `range`, in the file's unit (see the type docs).
    pub fn scanner_xyz(
        &self,
        row: usize,
        col: usize,
        rows: usize,
        cols: usize,
        range: f64,
    ) -> Vector3<f64> {
        let b = self.scanner_beam(row as f64, col as f64, rows, cols);
        let r3 = (range + self.r0 - b.r12) * self.delta;
        b.exit + b.direction * r3
    }

    /// The point of pixel `(row, col)` in the REP-103 sensor frame (x forward = Z, y left = X,
    /// z up = Y), in metres.
    pub fn point(
        &self,
        row: usize,
        col: usize,
        rows: usize,
        cols: usize,
        range: f64,
    ) -> Point3<f64> {
        let s = self.scanner_xyz(row, col, rows, cols, range);
        Point3::new(s.z, s.x, s.y) * self.unit_m
    }

    /// The beam of pixel `(row, col)` in the REP-103 sensor frame, metres: the line
    /// [`PerceptronGeometry::point`] moves along as the raw range grows.
    pub fn beam(&self, row: usize, col: usize, rows: usize, cols: usize) -> PerceptronBeam {
        self.beam_at(row as f64, col as f64, rows, cols)
    }

    /// [`PerceptronGeometry::beam`] at a fractional pixel position (for beams that sample a
    /// footprint around the pixel centre).
    pub fn beam_at(&self, row: f64, col: f64, rows: usize, cols: usize) -> PerceptronBeam {
        let b = self.scanner_beam(row, col, rows, cols);
        let rep103 = |v: &Vector3<f64>| Vector3::new(v.z, v.x, v.y);
        PerceptronBeam {
            origin: Point3::from(rep103(&b.exit) * self.unit_m),
            direction: Unit::new_normalize(rep103(&b.direction)),
            offset_m: (self.r0 - b.r12) * self.delta * self.unit_m,
            metres_per_count: self.delta * self.unit_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beams_follow_the_points_and_invert_the_range() {
        let g = PerceptronGeometry::default();
        for (row, col) in [
            (0, 0),
            (0, 511),
            (255, 256),
            (511, 0),
            (511, 511),
            (100, 400),
        ] {
            let beam = g.beam(row, col, 512, 512);
            assert!((beam.direction.norm() - 1.0).abs() < 1e-12);
            for range in [0.0, 1.0, 1234.0, 4095.0] {
                let p = g.point(row, col, 512, 512, range);
                assert!(
                    (beam.point(range) - p).norm() < 1e-12,
                    "{row} {col} {range}"
                );
                let back = beam.range_of_distance((p - beam.origin).norm());
                assert!((back - range).abs() < 1e-6, "{row} {col} {range}: {back}");
            }
        }
        // The fractional beam at a pixel centre is the pixel's beam.
        assert_eq!(g.beam_at(7.0, 9.0, 512, 512), g.beam(7, 9, 512, 512));
    }
}
