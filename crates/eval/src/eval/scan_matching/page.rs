//! The report stage of `eval scan-matching`: the page, its JSON and its headline from the
//! unit results alone.

use std::fmt::Write;

use anyhow::{Context, Result, bail};
use serde::de::DeserializeOwned;
use serde_json::{Value, json};

use super::calibration::{self, CalibrationUnit};
use super::failure::{self, FailureUnit};
use super::generated::{self, LabUnit};
use super::real_calib::{self, KittiUnit};
use super::real_logs::{self, LogUnit};
use super::real_ouster::{self, CaptureUnit};
use super::{CALIBRATION, FAILURE, GENERATED, KITTI, NAME, OUSTER, REAL};
use crate::eval::stages::UnitResults;
use crate::eval::{EvalContext, EvalReport};

const TITLE: &str = "Intensity calibration and Hector-style scan matching (Khan ch. 3)";

/// The unit results decoded, by section.
struct Sections {
    logs: Vec<LogUnit>,
    calibration: CalibrationUnit,
    kitti: KittiUnit,
    ouster: Vec<CaptureUnit>,
    failure: FailureUnit,
    lab: Option<LabUnit>,
}

fn decode<T: DeserializeOwned>(unit: &str, value: &Value) -> Result<T> {
    serde_json::from_value(value.clone()).with_context(|| format!("result of {unit}"))
}

impl Sections {
    fn decode(results: &UnitResults) -> Result<Self> {
        let (mut logs, mut ouster) = (Vec::new(), Vec::new());
        let (mut calibration, mut kitti, mut failure, mut lab) = (None, None, None, None);
        for (unit, value) in results {
            match unit.as_str() {
                u if u.starts_with(REAL) => logs.push(decode(u, value)?),
                u if u.starts_with(OUSTER) => ouster.push(decode(u, value)?),
                CALIBRATION => calibration = Some(decode(unit, value)?),
                KITTI => kitti = Some(decode(unit, value)?),
                FAILURE => failure = Some(decode(unit, value)?),
                GENERATED => lab = Some(decode::<Option<LabUnit>>(unit, value)?),
                _ => bail!("{NAME} has no unit {unit:?}"),
            }
        }
        let missing = |name: &str| format!("no result of the unit {name}");
        Ok(Self {
            logs,
            calibration: calibration.with_context(|| missing(CALIBRATION))?,
            kitti: kitti.with_context(|| missing(KITTI))?,
            ouster,
            failure: failure.with_context(|| missing(FAILURE))?,
            lab: lab.with_context(|| missing(GENERATED))?,
        })
    }
}

/// The page from every unit's result.
pub(super) fn report(ctx: &EvalContext, results: &UnitResults) -> Result<EvalReport> {
    let s = Sections::decode(results)?;
    let mut md = intro(ctx.quick)?;
    md.push_str(&real_logs::markdown(&s.logs)?);
    let _ = writeln!(md, "## Intensity calibration (simulated, Khan Fig. 3.4)\n");
    let _ = writeln!(md, "{}", s.calibration.gap_note);
    md.push_str(&calibration::markdown(&s.calibration)?);
    let _ = writeln!(
        md,
        "## Intensity calibration on real KITTI scans (real, Khan Fig. 3.4 in real form)\n"
    );
    md.push_str(&real_calib::markdown(ctx, &s.kitti)?);
    let (ouster_md, ouster) = real_ouster::section(ctx, &s.ouster)?;
    md.push_str(&ouster_md);
    let _ = writeln!(md, "## Failure case (simulated, Khan Fig. 3.6)\n");
    md.push_str(&failure::markdown(&s.failure)?);
    let _ = writeln!(
        md,
        "## Generated indoor world with remissions (all three residuals)\n"
    );
    md.push_str(&generated::markdown(s.lab.as_ref())?);
    let real = Value::Array(s.logs.iter().flat_map(|l| l.rows.clone()).collect());
    let headline = headline(&real, &s.kitti.json, &ouster);
    Ok(EvalReport {
        name: NAME,
        title: TITLE.into(),
        markdown: md,
        json: json!({
            "real": real,
            "calibration": calibration::json(&s.calibration),
            "real_calibration": s.kitti.json,
            "ouster_calibration": ouster,
            "failure_case": s.failure.rows,
            "generated_lab": generated::json(s.lab.as_ref()),
        }),
        headline,
    })
}

/// The page up to the real logs' table: what was run, the protocol and the anchors.
fn intro(quick: bool) -> Result<String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Khan (2017) ch. 3: Hector-style multi-resolution scan matching (3 levels, \
         finest 5 cm, update factors 0.4 / 0.9, 3 + 3 + 5 Gauss–Newton iterations, map updates \
         after 0.4 m or 0.9 rad) with occupancy, reflectivity or combined residuals; intensity \
         calibration by LUT. Release build, one thread; the machine was shared with other jobs, \
         so absolute speeds are lower bounds — compare rows of one run.{}\n",
        if quick {
            " **Quick run**: the first 600 scans of Intel, one lap of the room, fewer calibration samples."
        } else {
            ""
        }
    );
    let _ = writeln!(md, "## Real logs (occupancy residual)\n");
    let _ = writeln!(
        md,
        "Relations join consecutive scans of the corrected log (the benchmark's own relation \
         files are not in the data set, so the numbers are comparable in kind, not identical in \
         protocol); the raw scans are paired with them by identical readings. Anchors: Kümmerle \
         et al. (2009) as recalled — the issue recalls ≈ 0.22 ± 0.30 m for scan matching on \
         Intel; the other values are from memory of the paper's table and were **not \
         re-checked** (the paper is not available offline).\n"
    );
    let _ = writeln!(md, "{}", real_logs::anchors_markdown()?);
    Ok(md)
}

/// The page's headline: Hector-style matching on the real logs, then the intensity
/// calibration on the real KITTI and Ouster frames.
fn headline(real: &Value, kitti: &Value, ouster: &Value) -> Option<String> {
    let logs: Vec<String> = real
        .as_array()
        .into_iter()
        .flatten()
        .filter(|r| r["method"] == "Hector, odometry prior")
        .filter_map(|r| {
            let t = r["errors"]["relative"]["translation_m"]["mean"].as_f64()?;
            let a = r["errors"]["relative"]["rotation_rad"]["mean"].as_f64()?;
            Some(format!(
                "{} {:.3} m / {:.2}°",
                r["log"].as_str()?,
                t,
                a.to_degrees()
            ))
        })
        .collect();
    let mut parts = Vec::new();
    if !logs.is_empty() {
        parts.push(format!(
            "Real logs, Hector-style matching with odometry prior, mean relative error: {}",
            logs.join(", ")
        ));
    }
    let cv = |rows: &Value, model: &str| -> Vec<f64> {
        rows.as_array()
            .into_iter()
            .flatten()
            .find(|r| r["model"] == model)
            .and_then(|r| r["cv"].as_array())
            .map(|v| v.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default()
    };
    let rows = &kitti["models_covered_only"];
    let (raw, lut) = (cv(rows, "raw"), cv(rows, "lut"));
    if !raw.is_empty() && raw.len() == lut.len() {
        parts.push(format!(
            "real KITTI intensity calibration (LUT fitted on the road): lower CV than the raw \
             reflectance for {} of {} classes",
            raw.iter().zip(&lut).filter(|(r, l)| l < r).count(),
            raw.len()
        ));
    }
    let ground: Vec<String> = ouster["rows"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|r| r["channel"] == "signal")
        .filter_map(|r| Some((r["model"].as_str()?, r["cv"].as_f64()?)))
        .map(|(model, cv)| format!("{model} {cv:.2}"))
        .collect();
    if !ground.is_empty() {
        parts.push(format!(
            "real Ouster raw signal, CV on held-back ground: {}",
            ground.join(", ")
        ));
    }
    (!parts.is_empty()).then(|| format!("{}.", parts.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::scan_matching::Num;
    use crate::eval::scan_matching::calibration::ModelScores;
    use crate::eval::scan_matching::real_calib::FitFacts;

    /// The headline from known rows: the real logs' odometry-prior errors, the KITTI classes
    /// where the LUT lowers the CV, the Ouster ground CVs; nothing when nothing ran.
    #[test]
    fn headline_from_known_rows() {
        let real = json!([
            {"log": "intel", "method": "Hector, odometry prior",
             "errors": {"relative": {"translation_m": {"mean": 0.03},
                                     "rotation_rad": {"mean": 0.5f64.to_radians()}}}},
            {"log": "intel", "method": "Hector alone",
             "errors": {"relative": {"translation_m": {"mean": 9.0},
                                     "rotation_rad": {"mean": 1.0}}}},
        ]);
        let kitti = json!({"models_covered_only": [
            {"model": "raw", "cv": [0.5, 0.4]},
            {"model": "lut", "cv": [0.4, 0.6]},
        ]});
        let ouster = json!({"rows": [
            {"channel": "signal", "model": "raw", "cv": 0.79},
            {"channel": "reflectivity", "model": "raw", "cv": 1.38},
        ]});
        let h = headline(&real, &kitti, &ouster).unwrap();
        assert_eq!(
            h,
            "Real logs, Hector-style matching with odometry prior, mean relative error: intel \
             0.030 m / 0.50°; real KITTI intensity calibration (LUT fitted on the road): lower \
             CV than the raw reflectance for 1 of 2 classes; real Ouster raw signal, CV on \
             held-back ground: raw 0.79."
        );
        assert!(headline(&json!([]), &json!({}), &json!({})).is_none());
    }

    /// Relative and aligned errors as the matcher's JSON has them.
    fn errors(transl_m: f64, rot_rad: f64) -> (Value, Value) {
        let stats = |mean: f64| {
            json!({"count": 99, "mean": mean, "std": mean / 2.0,
                                      "rms": mean, "max": 2.0 * mean})
        };
        (
            json!({"translation_m": stats(transl_m), "rotation_rad": stats(rot_rad)}),
            json!({"position_m": stats(0.1), "heading_rad": stats(0.01),
                   "alignment": [0.0, 0.0, 0.0]}),
        )
    }

    fn log_row(method: &str, transl_m: f64, sps: Value) -> Value {
        let (relative, aligned) = errors(transl_m, 0.01);
        json!({"log": "intel", "scans": 600, "pairs": 100, "method": method,
               "errors": {"relative": relative, "aligned": aligned, "scans_per_s": sps}})
    }

    fn to_value<T: serde::Serialize>(unit: &T) -> Value {
        serde_json::to_value(unit).unwrap()
    }

    /// Every unit by hand: a log measured and a log missing, the calibrations (KITTI skipped),
    /// one Ouster capture with a signal channel and one absent, the failure case and no
    /// generated world.
    fn known_units() -> Vec<(String, Value)> {
        let intel = LogUnit {
            skipped: None,
            rows: vec![
                log_row("odometry", 0.2, Value::Null),
                log_row("Hector, odometry prior", 0.03, json!(900.0)),
            ],
        };
        let fr079 = LogUnit {
            skipped: Some("* `fr079` missing: fr079 skipped.".into()),
            rows: Vec::new(),
        };
        let model = |name: &str, mean: f64| ModelScores {
            model: name.into(),
            overlap: vec![Num(0.5), Num(0.4), Num(0.3)],
            cv: vec![Num(0.2), Num(f64::INFINITY), Num(0.1)],
            mean: vec![Num(mean), Num(f64::NAN), Num(mean / 2.0)],
        };
        let calibration = CalibrationUnit {
            gap_note: "**Simulated scans.** A note.\n".into(),
            reference_samples: 4000,
            surface_samples: 3000,
            lut_ranges: 1881,
            lut_angles: 165,
            inside_percent: 87.6,
            lut_fit_s: 0.19,
            models: vec![model("raw", 1234.4), model("lut", 0.7)],
        };
        let kitti = KittiUnit {
            json: json!({"skipped": "no labelled KITTI frames"}),
            fit: None,
        };
        let signal = |model: &str, cv: f64| {
            json!({"capture": "a.pcap", "channel": "signal", "model": model, "fit": 10,
                   "held_back": 9, "cv": cv, "spearman_range": -0.5,
                   "spearman_reflectivity": 0.7})
        };
        let capture = CaptureUnit {
            sensor: "OS-2-128".into(),
            absent: false,
            rows: vec![
                signal("raw", 0.79),
                signal("range", 0.6),
                signal("lut", 0.62),
            ],
            notes: vec!["OS-2-128: too little ground for the reflectivity channel.".into()],
        };
        let (relative, aligned) = errors(0.004, 0.001);
        let failure = FailureUnit {
            scans: 700,
            laps: 1,
            rows: vec![json!({"run": "occupancy, ±60°", "relative": relative,
                              "aligned": aligned, "final_error_m": 0.25, "scans_per_s": 80.0})],
        };
        vec![
            ("real/intel".into(), to_value(&intel)),
            ("real/fr079".into(), to_value(&fr079)),
            (CALIBRATION.into(), to_value(&calibration)),
            (KITTI.into(), to_value(&kitti)),
            ("ouster/a".into(), to_value(&capture)),
            (
                "ouster/b".into(),
                to_value(&CaptureUnit {
                    absent: true,
                    ..CaptureUnit::default()
                }),
            ),
            (FAILURE.into(), to_value(&failure)),
            (GENERATED.into(), to_value(&None::<LabUnit>)),
        ]
    }

    /// The page from known unit results: every section in order, the rows and figures of
    /// each (non-finite ones through the unit results), the JSON keys and the headline.
    #[test]
    fn report_from_known_units() {
        let ctx = EvalContext::scratch(&std::env::temp_dir().join("raypath-sm-report-test"));
        let results = known_units();
        let page = report(&ctx, &results).unwrap();
        let md = &squeeze(&page.markdown);
        let order = [
            "**Quick run**",
            "## Real logs (occupancy residual)",
            "| intel | 0.220 ± 0.296 m, 1.7 ± 4.8° |",
            "* `fr079` missing: fr079 skipped.",
            "| intel | 600 | 99 | Hector, odometry prior | 0.030 ± 0.015 | 0.57 ± 0.29 | 0.100 | 0.200 | 900 |",
            "**Speed** (aim ≥ 200 scans/s for 180-beam scans at 5 cm): slowest run intel / Hector, odometry prior at 900 scans/s",
            "## Intensity calibration (simulated, Khan Fig. 3.4)",
            "**Simulated scans.** A note.",
            "LUT: 1881 × 165 entries (Δr = 1 cm, Δα = 0.5°), 87.6 % inside the samples' hull, fitted in 0.19 s",
            "| raw | 0.500 | 0.400 | 0.300 | 0.200 | — | 0.100 | 1234 / NaN / 617 |",
            "| lut | 0.500 | 0.400 | 0.300 | 0.200 | — | 0.100 | 0.700 / NaN / 0.350 |",
            "## Intensity calibration on real KITTI scans",
            "*Skipped: no labelled real KITTI frames under",
            "**Real data, Ouster.**",
            "| OS-2-128 | signal | 10 / 9 | lut | 0.620 | -0.50 | 0.70 |",
            "* OS-2-128: too little ground for the reflectivity channel.",
            "the LUT changes the raw signal's CV from 0.79 to 0.62 (range-only polynomial: 0.60)",
            "## Failure case (simulated, Khan Fig. 3.6)",
            "700 scans at 20 Hz (1 lap(s))",
            "| occupancy, ±60° | 4.0 ± 2.0 | 0.057 ± 0.029 | 0.100 | 0.200 | 0.250 | 80 |",
            "![reflectivity map](scan-matching/room-combined-60-reflectivity.png)",
            "## Generated indoor world with remissions (all three residuals)",
            "* the generated `indoor/lab` logs are missing: skipped.",
        ];
        let mut from = 0;
        for text in order {
            let at = md[from..]
                .find(text)
                .unwrap_or_else(|| panic!("{text:?} not after byte {from}:\n{md}"));
            from += at + text.len();
        }
        assert!(
            md.contains("| intel | 600 | 99 | odometry | 0.200 ± 0.100 "),
            "{md}"
        );
        assert!(md.contains("| 0.200 | — |\n"), "{md}");
        let json = &page.json;
        let keys: Vec<&str> = json
            .as_object()
            .unwrap()
            .keys()
            .map(|k| k.as_str())
            .collect();
        assert_eq!(
            keys,
            [
                "calibration",
                "failure_case",
                "generated_lab",
                "ouster_calibration",
                "real",
                "real_calibration"
            ]
        );
        assert_eq!(json["real"].as_array().unwrap().len(), 2);
        assert!(json["real"][0]["errors"]["scans_per_s"].is_null());
        assert_eq!(json["calibration"]["models"][0]["mean"][0], 1234.4);
        assert!(json["calibration"]["models"][0]["cv"][1].is_null());
        assert_eq!(json["calibration"]["lut_fit_s"], 0.19);
        assert_eq!(
            json["real_calibration"]["skipped"],
            "no labelled KITTI frames"
        );
        assert_eq!(
            json["ouster_calibration"]["rows"].as_array().unwrap().len(),
            3
        );
        assert_eq!(
            json["ouster_calibration"]["notes"]
                .as_array()
                .unwrap()
                .len(),
            1
        );
        assert_eq!(json["failure_case"][0]["final_error_m"], 0.25);
        assert!(json["generated_lab"].is_null());
        assert_eq!(
            page.headline.unwrap(),
            "Real logs, Hector-style matching with odometry prior, mean relative error: intel \
             0.030 m / 0.57°; real Ouster raw signal, CV on held-back ground: raw 0.79, range \
             0.60, lut 0.62."
        );
        // A unit missing, and a result that does not decode.
        let error = report(&ctx, &results[..2]).err().unwrap();
        assert!(format!("{error:#}").contains("calibration"), "{error:#}");
        let mut bad = known_units();
        bad[2].1 = json!({"gap_note": 3});
        let error = report(&ctx, &bad).err().unwrap();
        assert!(
            format!("{error:#}").contains("result of calibration"),
            "{error:#}"
        );
    }

    /// The markdown with the tables' padding squeezed to one space.
    fn squeeze(md: &str) -> String {
        let mut out = String::with_capacity(md.len());
        for c in md.chars() {
            if !(c == ' ' && out.ends_with(' ')) {
                out.push(c);
            }
        }
        out
    }

    /// The KITTI section from a known result: its counts, tables and verdict.
    #[test]
    fn kitti_section_from_known_result() {
        let ctx = EvalContext::scratch(&std::env::temp_dir().join("raypath-sm-kitti-test"));
        let row = |model: &str, cv: [f64; 4]| json!({"model": model, "cv": cv, "overlap": [0.9, 0.8, 0.7]});
        let unit = KittiUnit {
            json: json!({
                "coverage": [1.0, 0.5, 0.25, 0.0],
                "models": [row("raw", [0.5; 4]), row("lut", [0.6; 4])],
                "models_covered_only": [row("raw", [0.5; 4]), row("lut", [0.4, 0.6, 0.6, 0.6])],
                "sequences": ["00"],
                "reference_samples": 4000,
                "reference_bins": 120,
                "samples": [{"class": 40, "name": "road", "fit": 10, "held_back": 20}],
            }),
            fit: Some(FitFacts {
                stride: 8,
                lut_ranges: 30,
                lut_angles: 40,
                inside_percent: 51.14,
            }),
        };
        let md = squeeze(&real_calib::markdown(&ctx, &unit).unwrap());
        assert!(md.contains("sequences 00 (every 8th"), "{md}");
        assert!(
            md.contains("samples fit / held back: road 10 / 20)"),
            "{md}"
        );
        assert!(md.contains("4000 samples averaged"), "{md}");
        assert!(md.contains("(120 bins;"), "{md}");
        assert!(md.contains("LUT 30 × 40 entries, 51.1 % inside"), "{md}");
        assert!(md.contains("road 100.0 %, sidewalk 50.0 %, building 25.0 %, vegetation 0.0 %"));
        assert!(md.contains("| lut | 0.400 | 0.600 | 0.600 | 0.600 | 0.900 | 0.800 | 0.700 |"));
        assert!(
            md.contains("lowers the CV of 1 of 4 classes against the raw reflectance: on real")
        );
    }
}
