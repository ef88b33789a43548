//! `raypath calibrate-intensity`: fits the intensity look-up table `I_ref(r, α)` from
//! reference-surface samples (Khan 2017 §3.3.2: Delaunay + barycentric interpolation,
//! resampled to a regular table) or a baseline model.
//!
//! Input CSV: `range_m,incidence_rad,intensity` per line (header, blank and `#` lines
//! skipped). Output JSON: the model (`{"model": "lut", …}`, `{"model": "range", …}` or
//! `{"model": "raw"}`) that `raypath scan-match --lut` reads. `--json` prints a summary
//! `{"samples", "model", "ranges", "angles", "inside_hull", "max_sample_error"}`.

use std::io::BufReader;
use std::path::PathBuf;

use raypath_reflectivity::{
    IntensityCorrection, IntensityLut, LutConfig, RangePolynomial, read_samples_csv,
};
use serde_json::json;

use super::Failure;

/// `--model`: the intensity model to fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelArg {
    /// The thesis: I / I_ref(r, α), a look-up table (--range-step, --angle-step).
    Lut,
    /// Baseline: I / f(r), a polynomial f in the range (--degree).
    Range,
    /// Baseline: the raw intensity.
    Raw,
}

/// Arguments of `raypath calibrate-intensity`.
#[derive(clap::Args)]
pub struct Args {
    /// Samples of the reference surface: range_m,incidence_rad,intensity per line.
    pub samples: PathBuf,
    /// Where to write the model (JSON).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Model.
    #[arg(long, value_enum, default_value_t = ModelArg::Lut, value_name = "NAME")]
    pub model: ModelArg,
    /// LUT range step, metres.
    #[arg(long, default_value_t = 0.01, value_name = "M")]
    pub range_step: f64,
    /// LUT angle step, degrees.
    #[arg(long, default_value_t = 0.5, value_name = "DEG")]
    pub angle_step: f64,
    /// Degree of the range polynomial.
    #[arg(long, default_value_t = 4, value_name = "N")]
    pub degree: usize,
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    let name = args.samples.display().to_string();
    let file =
        std::fs::File::open(&args.samples).map_err(|e| Failure::input(format!("{name}: {e}")))?;
    let samples = read_samples_csv(BufReader::new(file), &name).map_err(Failure::input)?;
    let model = match args.model {
        ModelArg::Lut => {
            let config = LutConfig {
                range_step_m: args.range_step,
                angle_step_rad: args.angle_step.to_radians(),
            };
            IntensityCorrection::Lut(
                IntensityLut::fit(&samples, &config)
                    .map_err(|e| Failure::input(format!("{name}: {e}")))?,
            )
        }
        ModelArg::Range => IntensityCorrection::Range(
            RangePolynomial::fit(&samples, args.degree, 10f64.to_radians())
                .map_err(|e| Failure::input(format!("{name}: {e}")))?,
        ),
        ModelArg::Raw => IntensityCorrection::Raw,
    };
    // How well the model reproduces its own samples (relative error of I_ref).
    let max_sample_error = samples
        .iter()
        .filter(|s| s.intensity > 0.0)
        .filter_map(|s| model.relative(s.intensity, s.range_m, s.incidence_rad))
        .map(|r| (r - 1.0).abs())
        .fold(0.0, f64::max);
    let text = serde_json::to_string(&model).map_err(|e| Failure::internal(e.to_string()))?;
    std::fs::write(&args.out, text)
        .map_err(|e| Failure::internal(format!("{}: {e}", args.out.display())))?;
    let (ranges, angles, inside) = match &model {
        IntensityCorrection::Lut(l) => (
            l.ranges,
            l.angles,
            l.inside_hull.iter().filter(|&&b| b).count() as f64 / l.values.len().max(1) as f64,
        ),
        _ => (0, 0, f64::NAN),
    };
    if super::console::json() {
        println!(
            "{}",
            json!({
                "samples": samples.len(),
                "model": model.name(),
                "ranges": ranges,
                "angles": angles,
                "inside_hull": if inside.is_finite() { json!(inside) } else { json!(null) },
                "max_sample_error": max_sample_error,
                "out": args.out.display().to_string(),
            })
        );
    } else {
        println!(
            "{} samples → {} model in {} (largest relative error at the samples {:.4})",
            samples.len(),
            model.name(),
            args.out.display(),
            max_sample_error
        );
    }
    Ok(())
}
