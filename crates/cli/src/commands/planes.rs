//! `raypath planes`: maximum-likelihood finite planes (PPE; Schaefer 2020 ch. 11) from an
//! organized PCD scan, in the sensor frame (every ray starts at the origin).
//!
//! `--method ppe|msac|peac` picks PPE (default), the iterative MSAC baseline or the
//! PEAC-style block-graph baseline (Feng et al. 2014); `--preset` applies to PPE (the
//! baselines use their SynPEB parameters).
//!
//! `--out FILE` writes one integer label per point in file order (`0` = no plane, planes
//! `1..=J`, largest first). Prints per plane its label, unit normal (pointing away from the
//! sensor), distance from the sensor (m), number of points and radial RMSE (m).
//!
//! `--json` prints `{"planes": [{"label", "normal": [x, y, z], "distance", "points",
//! "rmse"}, …]}` plus `scan`, `width`, `height`, `method`, `preset`, `rmse` (all planes,
//! per point) and `seconds` (extraction time).

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use raypath_io::pcd::{ReadOptions, read_pcd};
use raypath_planes::{MsacParams, PeacParams, PpeParams, extract, msac, peac};
use serde_json::json;

use super::Failure;

/// Arguments of `raypath planes`.
#[derive(clap::Args)]
pub struct Args {
    /// An organized PCD scan (width × height, NaN = no return).
    pub scan: PathBuf,
    /// Extraction method: ppe (default), msac or peac.
    #[arg(long, default_value = "ppe", value_name = "NAME")]
    pub method: String,
    /// PPE parameter preset: synpeb (default; σ = 2 cm), synpeb-0.0, synpeb-0.5,
    /// synpeb-1.0, synpeb-2.0, synpeb-4.0, segcomp or default.
    #[arg(long, default_value = "synpeb", value_name = "NAME")]
    pub preset: String,
    /// Override the preset's stopping rule e (largest error increment per step, m²).
    #[arg(long, value_name = "M2")]
    pub max_increment: Option<f64>,
    /// Override the preset's neighbour-distance filter l_max (m).
    #[arg(long, value_name = "M")]
    pub l_max: Option<f64>,
    /// Write one label per point (0 = no plane) to this file.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print one JSON document on standard output.
    #[arg(long)]
    pub json: bool,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    let Some(mut params) = PpeParams::preset(&args.preset) else {
        return Err(Failure::input(
            format!(
                "unknown preset {:?}; choose one of {}",
                args.preset,
                PpeParams::PRESETS.join(", ")
            ),
            args.json,
        ));
    };
    if let Some(e) = args.max_increment {
        params.max_increment_m2 = e;
    }
    if let Some(l) = args.l_max {
        params.l_max_m = l;
    }
    params
        .validate()
        .map_err(|e| Failure::input(e, args.json))?;
    if !["ppe", "msac", "peac"].contains(&args.method.as_str()) {
        return Err(Failure::input(
            format!("unknown method {:?}; choose ppe, msac or peac", args.method),
            args.json,
        ));
    }
    let options = ReadOptions {
        label_from: raypath_io::pcd::LabelSource::None,
    };
    let pcd = read_pcd(&args.scan, &options).map_err(|e| Failure::input(e, args.json))?;
    let cloud = pcd.cloud;
    let started = Instant::now();
    let result = match args.method.as_str() {
        "msac" | "peac" => {
            let points: Vec<nalgebra::Vector3<f64>> = cloud
                .points
                .iter()
                .map(|p| p.coords.cast::<f64>())
                .collect();
            if args.method == "msac" {
                msac(&points, cloud.width, cloud.height, &MsacParams::synpeb())
            } else {
                peac(&points, cloud.width, cloud.height, &PeacParams::synpeb())
            }
        }
        _ => extract(&cloud, &params),
    };
    let seg =
        result.map_err(|e| Failure::input(format!("{}: {e}", args.scan.display()), args.json))?;
    let seconds = started.elapsed().as_secs_f64();
    if let Some(out) = &args.out {
        let write = || -> std::io::Result<()> {
            let mut w = std::io::BufWriter::new(std::fs::File::create(out)?);
            for l in &seg.labels {
                writeln!(w, "{}", l.map_or(0, |l| l + 1))?;
            }
            w.flush()
        };
        write().map_err(|e| Failure {
            message: format!("{}: {e}", out.display()),
            bad_input: false,
            json: args.json,
        })?;
    }
    if args.json {
        let planes: Vec<_> = seg
            .planes
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let n = p.fit.normal();
                json!({"label": i + 1, "normal": [n.x, n.y, n.z], "distance": p.fit.distance_m(),
                       "points": p.index.len(), "rmse": p.fit.rmse_m()})
            })
            .collect();
        let doc = json!({"scan": args.scan.display().to_string(), "width": cloud.width,
            "height": cloud.height, "method": args.method, "preset": args.preset, "planes": planes,
            "rmse": seg.rmse_m(), "seconds": seconds});
        println!("{doc}");
    } else {
        println!(
            "{}: {} × {}, {} planes, RMSE {:.4} m, {:.3} s",
            args.scan.display(),
            cloud.width,
            cloud.height,
            seg.planes.len(),
            seg.rmse_m(),
            seconds
        );
        println!("label  normal                      distance_m  points  rmse_m");
        for (i, p) in seg.planes.iter().enumerate() {
            let n = p.fit.normal();
            println!(
                "{:>5}  [{:>7.4}, {:>7.4}, {:>7.4}]  {:>10.4}  {:>6}  {:.4}",
                i + 1,
                n.x,
                n.y,
                n.z,
                p.fit.distance_m(),
                p.index.len(),
                p.fit.rmse_m()
            );
        }
    }
    Ok(())
}
