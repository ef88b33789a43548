//! Section 2: the 40 real KITTI frames (sequences 00, 01, 04, 07, frames 0–9 each, real
//! intensity) and the 5 real Ouster frames (reflectivity as intensity) in one database,
//! kidnapped mode: is each frame's best match (itself excluded) a neighbour of the same
//! source? And the real intensity images beside simulated ones at the
//! same poses (semi-synthetic drive of the same sequence).

use std::fmt::Write;
use std::sync::Arc;

use anyhow::{Context, Result};
use image::GrayImage;
use rayon::prelude::*;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::sequence::{SweepOptions, SweepSequence};
use raypath_place_recognition::{
    AngularSpan, BinaryVocabulary, EquirectConfig, Exclusion, GroundTruth, equirectangular,
};
use raypath_sim::datasets::DEFAULT_SEED;
use raypath_sim::semi_kitti::SemiKittiDrive;
use serde_json::json;

use super::camera::{ImageStats, image_stats};
use super::methods;
use super::report::pct;
use super::runner::{Input, MethodResult, Views};
use super::{Section, truth};
use crate::eval::EvalContext;
use crate::table::{Table, fmt_num};

/// The real sequences and frames.
pub const SEQUENCES: [&str; 4] = ["00", "01", "04", "07"];
const FRAMES: usize = 10;

/// The real Ouster captures that join the database: name, capture, elevation span of the
/// images in degrees (the sensors' vertical fields of view: OS-1 ±22.5°, OS-2 ±11.25°).
const OUSTER: [(&str, &str, f64); 3] = [
    (
        "ouster-os1",
        "ouster/OS-1-128_v2.3.0_1024x10_lb_n3.pcap",
        22.5,
    ),
    (
        "ouster-os2",
        "ouster/OS-2-128-U1_v2.3.0_1024x10.pcap",
        11.25,
    ),
    (
        "ouster-os1-dual",
        "ouster/OS-1-128_767798045_1024x10_20230712_120049.pcap",
        22.5,
    ),
];

/// The real frames (sequence index, views), their velodyne poses and the sequences found.
type Loaded = (Vec<(usize, Views)>, Vec<Pose3>, Vec<&'static str>);

/// Reads the real frames and their sensor poses (`SweepSequence`: for KITTI `poses.txt`
/// through the `Tr` of `calib.txt`, for Ouster the vendor's poses beside the capture or the
/// identity for a single frame); the sources found.
fn load(ctx: &EvalContext) -> Result<Loaded> {
    let mut frames = Vec::new();
    let mut poses = Vec::new();
    let mut found = Vec::new();
    let kitti = SEQUENCES.iter().map(|seq| {
        (
            *seq,
            format!("kitti/sequences/{seq}"),
            EquirectConfig::default(),
        )
    });
    let ouster = OUSTER.iter().map(|(name, path, half_fov_deg)| {
        let config = EquirectConfig {
            span: AngularSpan::Fixed {
                elevation_min_rad: -half_fov_deg.to_radians(),
                elevation_max_rad: half_fov_deg.to_radians(),
            },
            ..EquirectConfig::default()
        };
        (*name, (*path).to_owned(), config)
    });
    for (k, (name, relative, config)) in kitti.chain(ouster).enumerate() {
        let dir = ctx.data(&relative);
        if !dir.exists() {
            continue;
        }
        let sequence = SweepSequence::open(&dir, &SweepOptions::default())?;
        let n = sequence.len().min(FRAMES);
        let seq_poses = match sequence.reference.as_deref() {
            Some(p) if p.len() >= n => p[..n].to_vec(),
            _ if n == 1 => vec![Pose3::identity()],
            _ => continue,
        };
        if n == 0 || (k < SEQUENCES.len() && n < FRAMES) {
            continue;
        }
        let clouds: Vec<PointCloud> = (0..n)
            .map(|i| sequence.sweep(i))
            .collect::<std::result::Result<_, _>>()
            .with_context(|| format!("reading {}", dir.display()))?;
        let views: Vec<(usize, Views)> = clouds
            .into_par_iter()
            .map(|cloud| {
                let images = equirectangular(&cloud, &config)?;
                Ok((
                    k,
                    Views {
                        cloud: Some(cloud),
                        intensity: images.intensity,
                        range: images.range,
                        camera: None,
                        features: [None, None, None],
                    },
                ))
            })
            .collect::<Result<_>>()?;
        frames.extend(views);
        poses.extend_from_slice(&seq_poses);
        found.push(name);
    }
    Ok((frames, poses, found))
}

/// Intensity images of simulated scans at the poses of the real frames (frames 0–9 of
/// `kitti-poles/NN`).
fn simulated_images(ctx: &EvalContext, seq: &str) -> Result<Option<Vec<GrayImage>>> {
    let Some(mut config) = ctx.semi_kitti_config(seq, Some(FRAMES))? else {
        return Ok(None);
    };
    config.labels = false;
    let drive = SemiKittiDrive::new(&config, DEFAULT_SEED)?;
    let images = (0..drive.len())
        .into_par_iter()
        .map(|i| Ok(equirectangular(&drive.scan(i)?, &EquirectConfig::default())?.intensity))
        .collect::<Result<Vec<_>>>()?;
    Ok(Some(images))
}

fn stats_row(seq: &str, data: &str, s: &ImageStats) -> Vec<String> {
    vec![
        seq.to_string(),
        data.to_string(),
        fmt_num(s.mean, 1),
        fmt_num(s.std, 1),
        fmt_num(100.0 * s.empty_share, 1),
        s.percentiles
            .iter()
            .map(u8::to_string)
            .collect::<Vec<_>>()
            .join(" / "),
    ]
}

/// Runs the section.
pub fn run(ctx: &EvalContext, vocabulary: Option<&Arc<BinaryVocabulary>>) -> Result<Section> {
    let mut md = String::new();
    let (frames, poses, found) = load(ctx)?;
    if frames.is_empty() {
        writeln!(
            md,
            "`kitti/sequences/{{00,01,04,07}}` (real frames) not found under the data \
             directory: section skipped.\n"
        )?;
        return Ok(Section {
            markdown: md,
            json: json!(null),
            summary: vec!["Real 3-D: the real KITTI frames are missing.".into()],
        });
    }
    // Sequences are far apart in this frame: 10 km per sequence.
    let positions: Vec<[f64; 3]> = frames
        .iter()
        .zip(&poses)
        .map(|(f, p)| {
            let t = p.translation();
            [t.x + 1e4 * f.0 as f64, t.y, t.z]
        })
        .collect();
    let truth =
        GroundTruth::from_positions(&positions, None, truth::RADIUS_3D_M, Exclusion::none())?;
    let mut runners = methods::kitti_real(vocabulary, !ctx.quick)?;
    let feature_inputs: Vec<Input> = runners
        .iter()
        .filter(|r| r.uses_features())
        .map(|r| r.input())
        .collect();
    let mut frames = frames;
    frames
        .par_iter_mut()
        .map(|f| f.1.extract(&feature_inputs))
        .collect::<Result<()>>()?;
    for frame in &frames {
        let sample = frame.1.sample();
        runners.par_iter_mut().for_each(|r| r.step(&sample, 0));
    }
    let results: Vec<MethodResult> = runners
        .par_iter_mut()
        .map(|r| r.evaluate(&truth, true))
        .collect();
    let mut table = Table::new([
        "method",
        "input",
        "data",
        "best match in same sequence",
        "best match < 5 m",
        "kidnapped R@100P %",
        "kidnapped P@100R %",
        "ms/frame (describe)",
        "note",
    ]);
    // Queries with a neighbour: frames of sources with more than one frame (the single
    // Ouster frames are in the database as distractors only).
    let has_neighbour: Vec<bool> = frames
        .iter()
        .map(|f| frames.iter().filter(|g| g.0 == f.0).count() > 1)
        .collect();
    let n = has_neighbour.iter().filter(|&&h| h).count();
    let mut json_methods = Vec::new();
    let mut fractions = Vec::new();
    for r in &results {
        let same = r
            .best_match
            .iter()
            .enumerate()
            .filter(|(i, b)| has_neighbour[*i] && b.is_some_and(|j| frames[j].0 == frames[*i].0))
            .count();
        let near = r
            .best_match
            .iter()
            .enumerate()
            .filter(|(i, b)| has_neighbour[*i] && b.is_some_and(|j| truth.is_revisit(*i, j)))
            .count();
        let kid = r.kidnapped_summary();
        fractions.push(format!("{} {same}/{n}", r.key()));
        table.row([
            r.label.clone(),
            r.input.name().to_string(),
            "real".into(),
            format!("{same}/{n} ({:.0} %)", 100.0 * same as f64 / n as f64),
            format!("{near}/{n} ({:.0} %)", 100.0 * near as f64 / n as f64),
            pct(kid.map(|s| s.recall_at_100_precision)),
            pct(kid.map(|s| s.precision_at_100_recall)),
            fmt_num(r.ms_per_query, 1),
            r.error.clone().unwrap_or_default(),
        ]);
        json_methods.push(json!({
            "result": r.json(),
            "best_in_same_sequence": same,
            "best_within_5m": near,
            "frames": n,
        }));
    }
    writeln!(
        md,
        "Real sources {} in one database of {} frames: the KITTI sequences (frames 0–9 each, \
         real HDL-64E scans with real intensity; velodyne poses from `poses.txt` and \
         `calib.txt`) and the real Ouster captures (OS-1-128: 3 frames with the vendor's poses, \
         0.25 m apart; one OS-2-128 and one dual-return OS-1-128 frame, in the database as \
         distractors; reflectivity as the intensity channel). Every frame is queried against \
         all (kidnapped, no temporal consistency); the counts are over the {n} frames that \
         have another frame of their own source. A best match counts as a neighbour when it is \
         another frame of the same source, and as correct when it is also less than 5 m away \
         (the true pairs: {}). Images: equirectangular 1024 × 64 over the sensor's vertical \
         field of view (HDL-64E −24.9°…+2°, OS-1 ±22.5°, OS-2 ±11.25°), intensity scaled \
         automatically, range by 80 m.\n",
        found.join(", "),
        frames.len(),
        truth.true_pairs()
    )?;
    writeln!(md, "{}", table.to_markdown()?)?;
    if ctx.quick {
        writeln!(
            md,
            "SHOT (with and without intensity) runs in full mode only (≈ 0.2–0.3 s per real \
             cloud).\n"
        )?;
    }
    // Intensity statistics, real beside simulated.
    let mut stats = Table::new([
        "sequence",
        "data",
        "mean (non-empty)",
        "std",
        "empty pixels %",
        "percentiles 5/25/50/75/95",
    ]);
    let mut json_stats = Vec::new();
    for (k, seq) in SEQUENCES.iter().enumerate() {
        let real: Vec<&GrayImage> = frames
            .iter()
            .filter(|f| f.0 == k)
            .map(|f| &f.1.intensity)
            .collect();
        if real.is_empty() {
            continue;
        }
        let r = image_stats(real.iter().copied());
        stats.row(stats_row(seq, "real", &r));
        let sim = simulated_images(ctx, seq)?;
        let s = sim.as_ref().map(|images| image_stats(images.iter()));
        if let Some(s) = &s {
            stats.row(stats_row(seq, "simulated", s));
        }
        json_stats.push(json!({ "sequence": seq, "real": r, "simulated": s }));
    }
    let pooled = |data: &str| {
        let v: Vec<f64> = json_stats
            .iter()
            .filter_map(|s| s[data]["mean"].as_f64())
            .collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    writeln!(
        md,
        "Mean grey level of the non-empty pixels over the sequences: real {:.1}, simulated \
         {:.1} — the simulator's intensities are {} than KITTI's (its reflectivity model is not \
         calibrated to the HDL-64E's remission scale), so the semi-synthetic intensity images of \
         section 3 have less contrast than real ones would.\n",
        pooled("real"),
        pooled("simulated"),
        if pooled("simulated") < pooled("real") {
            "darker"
        } else {
            "brighter"
        }
    )?;
    writeln!(
        md,
        "Intensity images (8-bit, 0 = no return) of the real frames beside simulated HDL-64E \
         scans (`raypath-sim` semi-synthetic KITTI, world seed {DEFAULT_SEED}) at frames 0–9 of \
         the same sequence's `kitti-poles` trajectory (the KITTI poses, within about a metre of \
         the SemanticKITTI poses of the real frames). Statistics pooled over the 10 frames.\n\n{}",
        stats.to_markdown()?
    )?;
    let summary = vec![format!(
        "Real 3-D, no revisits (a sanity check, not a place-recognition result; {} real \
         frames of {}, kidnapped; counted over the {n} with another frame of their own source): \
         best match in the same source — {}.",
        frames.len(),
        found.join(", "),
        fractions.join(", ")
    )];
    Ok(Section {
        summary,
        markdown: md,
        json: json!({ "methods": json_methods, "intensity_stats": json_stats, "sequences": found }),
    })
}
