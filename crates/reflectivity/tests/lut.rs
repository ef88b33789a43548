//! The LUT and its scattered interpolant reproduce their samples; the CSV reader rejects bad rows.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a panic is the failure report

use proptest::prelude::*;
use raypath_reflectivity::lut::{CalibrationSample, IntensityLut, LutConfig, ScatteredLinear};
use raypath_reflectivity::{IntensityCorrection, RangePolynomial, read_samples_csv};

fn reference(r: f64, a: f64) -> f64 {
    let h = 4.0 * 2.25 * r * r / ((r * r + 2.25) * (r * r + 2.25));
    1000.0 * h * a.cos().powf(1.0 + 0.08 * r)
}

fn samples() -> Vec<CalibrationSample> {
    let mut out = Vec::new();
    for i in 0..40 {
        for j in 0..20 {
            // A slightly irregular grid in (r, α).
            let r = 0.3 + 0.45 * i as f64 + 0.07 * ((i * 7 + j * 3) % 5) as f64;
            let a = (j as f64 * 4.0 + ((i + j) % 3) as f64).to_radians();
            out.push(CalibrationSample {
                range_m: r,
                incidence_rad: a,
                intensity: reference(r, a),
            });
        }
    }
    out
}

#[test]
fn scattered_interpolant_is_exact_at_samples() {
    let s = samples();
    let interp = ScatteredLinear::new(&s).unwrap();
    for x in &s {
        let v = interp.evaluate(x.range_m, x.incidence_rad).unwrap();
        assert!(
            (v - x.intensity).abs() < 1e-6 * x.intensity.max(1.0),
            "{v} vs {x:?}"
        );
    }
    assert!(interp.evaluate(100.0, 0.1).is_none());
}

#[test]
fn table_reproduces_its_samples_and_round_trips() {
    let s = samples();
    let lut = IntensityLut::fit(&s, &LutConfig::default()).unwrap();
    lut.validate().unwrap();
    let mut worst: f64 = 0.0;
    for x in &s {
        let v = lut.lookup(x.range_m, x.incidence_rad).unwrap();
        worst = worst.max((v - x.intensity).abs() / x.intensity.max(1.0));
    }
    // Resampling to 1 cm × 0.5° loses at most a few per mille near the steep near range.
    assert!(worst < 0.01, "worst relative error {worst}");
    // ϱ̄ of the reference surface itself is 1; of a 40 % surface, 0.4.
    let rel = lut.relative(0.4 * reference(5.0, 0.5), 5.0, 0.5).unwrap();
    assert!((rel - 0.4).abs() < 0.01, "{rel}");
    let json = serde_json::to_string(&IntensityCorrection::Lut(lut.clone())).unwrap();
    let back: IntensityCorrection = serde_json::from_str(&json).unwrap();
    let IntensityCorrection::Lut(back) = back else {
        panic!("model changed")
    };
    assert_eq!(
        (back.ranges, back.angles, &back.inside_hull),
        (lut.ranges, lut.angles, &lut.inside_hull)
    );
    let max_diff = back
        .values
        .iter()
        .zip(&lut.values)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        max_diff < 1e-9,
        "JSON round trip changed values by {max_diff}"
    );
    // The range-only baseline fits the near-normal samples better than their mean.
    let poly = RangePolynomial::fit(&s, 4, 5f64.to_radians()).unwrap();
    let near: Vec<_> = s
        .iter()
        .filter(|x| x.incidence_rad <= 5f64.to_radians())
        .collect();
    let mean = near.iter().map(|x| x.intensity).sum::<f64>() / near.len() as f64;
    let sse_poly: f64 = near
        .iter()
        .map(|x| (poly.evaluate(x.range_m) - x.intensity).powi(2))
        .sum();
    let sse_mean: f64 = near.iter().map(|x| (mean - x.intensity).powi(2)).sum();
    assert!(sse_poly < 0.5 * sse_mean, "{sse_poly} vs {sse_mean}");
}

#[test]
fn csv_reader_errors_name_the_line() {
    let ok = "range_m,incidence_rad,intensity\n# c\n1.0,0.1,300\n2,0.2,200\n";
    assert_eq!(read_samples_csv(ok.as_bytes(), "s.csv").unwrap().len(), 2);
    let err = read_samples_csv("1,0.1,3\n2,x,4\n".as_bytes(), "s.csv")
        .unwrap_err()
        .to_string();
    assert!(err.contains("s.csv:2"), "{err}");
    let err = read_samples_csv("1,0.1,3\n2,3.0,4\n".as_bytes(), "s.csv")
        .unwrap_err()
        .to_string();
    assert!(err.contains("s.csv:2"), "{err}");
    assert!(read_samples_csv("".as_bytes(), "e.csv").is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]
    #[test]
    fn csv_reader_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = read_samples_csv(bytes.as_slice(), "fuzz.csv");
    }
}

#[test]
fn covers_the_samples_hull_only() {
    // Samples on a triangle in (r, α): r ∈ [1, 10] m, α ≤ (10 − r)·5°.
    let mut s = Vec::new();
    for i in 0..=18 {
        let r = 1.0 + 0.5 * i as f64;
        for j in 0..=10 {
            let a = ((10.0 - r) * 5.0 * j as f64 / 10.0).to_radians();
            s.push(CalibrationSample {
                range_m: r,
                incidence_rad: a,
                intensity: reference(r, a),
            });
        }
    }
    let lut = IntensityLut::fit(&s, &LutConfig::default()).unwrap();
    assert!(lut.covers(2.0, 10f64.to_radians()));
    assert!(lut.covers(9.0, 2f64.to_radians()));
    // Above the hypotenuse, outside the table, not finite.
    assert!(!lut.covers(9.0, 40f64.to_radians()));
    assert!(!lut.covers(12.0, 0.0));
    assert!(!lut.covers(0.5, 0.0));
    assert!(!lut.covers(f64::NAN, 0.0));
}
